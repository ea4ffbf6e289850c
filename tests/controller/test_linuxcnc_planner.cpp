// LinuxCNC's planner model with TCP on (controller/linuxcnc_planner.hpp), against its analytic
// trapezoid and its own bisection's promise; the model against the real controller is
// tests/controller (label controller).
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <string>

#include "controller/linuxcnc_planner.hpp"
#include "support.hpp"

using namespace taxopt;
using taxopt::controller::TcpBlock;

namespace {

TcpBlock x_block(double length_mm, double v_max, double a_max) {
  TcpBlock b;
  b.from = {0.0, 0.0, 0.0, 0.0, 0.0};
  b.to = {length_mm, 0.0, 0.0, 0.0, 0.0};
  for (auto& l : b.limits) l = {1e6, 1e6, 0.0};
  b.limits[0] = {v_max, a_max, 0.0};
  b.rate_per_s = 1e6;
  b.line = 7;
  return b;
}

}  // namespace

TEST_CASE("linuxcnc planner: a rest-to-rest block of X alone is the trapezoid of X's limits",
          "[controller][model]") {
  const Machine m = default_machine();
  // 100 mm at 50 mm/s and 500 mm/s^2: 0.1 s ramps, a 1.9 s cruise; the 10 ms window sees the
  // cruise's velocity and the ramps' acceleration exactly.
  std::vector<JointPeak> peaks;
  controller::tcp_block_peaks(m, x_block(100.0, 50.0, 500.0), 1.0, peaks);
  REQUIRE(peaks.size() == kJointCount);
  CHECK(peaks[0].velocity_per_s == Approx(50.0).epsilon(1e-9));
  CHECK(peaks[0].accel_per_s2 == Approx(500.0).epsilon(1e-6));
  CHECK(peaks[0].velocity_line == 7);
  for (std::size_t j = 1; j < kJointCount; ++j) CHECK(peaks[j].velocity_per_s < 1e-9);
  // The written F below X's limit is the cruise; half the share (a chain's first block,
  // blended parabolically) and half the axes' scale both halve the ramps.
  TcpBlock slow = x_block(100.0, 50.0, 500.0);
  slow.rate_per_s = 0.2;  // 20 mm/s
  peaks.clear();
  controller::tcp_block_peaks(m, slow, 1.0, peaks);
  CHECK(peaks[0].velocity_per_s == Approx(20.0).epsilon(1e-9));
  TcpBlock half = x_block(100.0, 50.0, 500.0);
  half.accel_share = 0.5;
  peaks.clear();
  controller::tcp_block_peaks(m, half, 1.0, peaks);
  CHECK(peaks[0].accel_per_s2 == Approx(250.0).epsilon(1e-6));
  peaks.clear();
  controller::tcp_block_peaks(m, x_block(100.0, 50.0, 500.0), 0.5, peaks);
  CHECK(peaks[0].accel_per_s2 == Approx(250.0).epsilon(1e-6));
  // A block too short for its ramps: the triangle, top speed sqrt(a L) = sqrt(500 * 2).
  peaks.clear();
  controller::tcp_block_peaks(m, x_block(2.0, 50.0, 500.0), 1.0, peaks);
  CHECK(peaks[0].velocity_per_s < std::sqrt(1000.0));
  CHECK(peaks[0].velocity_per_s > 0.9 * std::sqrt(1000.0));
  // In a chain (neither end at rest) the schedule's joint rates hold: nothing to add.
  TcpBlock chained = x_block(100.0, 50.0, 500.0);
  chained.start_rest = chained.end_rest = false;
  peaks.clear();
  controller::tcp_block_peaks(m, chained, 1.0, peaks);
  CHECK(peaks.empty());
}

TEST_CASE(
    "linuxcnc planner: the axes' acceleration share is the largest (0.001 steps) that keeps "
    "the joints within theirs as the table turns under a tip off its axis",
    "[controller][model]") {
  Machine m = default_machine();
  const JointLimits limits = effective_limits(m);
  // C turns 90 deg under a tip 150 mm off its axis: the joints X Y swing on that radius.
  TcpBlock b;
  b.from = {150.0, 0.0, 20.0, 0.0, 0.0};
  b.to = {150.0, 0.0, 20.0, 0.0, 90.0};
  b.limits = limits;
  b.rate_per_s = 1e6;
  std::vector<JointPeak> full;
  controller::tcp_block_peaks(m, b, 1.0, full);
  REQUIRE(full.size() == kJointCount);
  const double swing = std::max(full[0].accel_per_s2, full[1].accel_per_s2);
  REQUIRE(swing > 100.0);
  // The joints X and Y allowed a third of that swing.
  m.joint_max_accel_per_s2[0] = m.joint_max_accel_per_s2[1] = swing / 3.0;
  const double scale = controller::tcp_axis_accel_scale(m, limits, {b});
  INFO("scale " << scale << ", swing " << swing << " mm/s^2");
  REQUIRE(scale > 0.05);
  REQUIRE(scale < 1.0);
  const auto worst = [&](double s) {
    const std::vector<JointPeak> p = controller::tcp_joint_peaks(m, {b}, s);
    double r = 0.0;
    for (std::size_t j = 0; j < p.size(); ++j) {
      r = std::max(r, p[j].accel_per_s2 / joint_accel_limit(m, limits, j));
    }
    return r;
  };
  CHECK(worst(scale) <= 1.0 + 1e-9);
  CHECK(worst(scale + 0.002) > 1.0);
  // Within the joints' limits at the full share: 1.
  m.joint_max_accel_per_s2[0] = m.joint_max_accel_per_s2[1] = 2.0 * swing;
  CHECK(controller::tcp_axis_accel_scale(m, limits, {b}) == 1.0);
}

TEST_CASE(
    "linuxcnc planner: a rapid runs at half its acceleration where it keeps its parabolic end "
    "(a turn, or no move before the queue stops)",
    "[controller][model]") {
  // Lines: 3 a turn with M428's synch after it, 6 a rapid on to a feed block, 8 and 9 rapids
  // where 9 turns B, 10 a rapid of X alone on to 11 (X alone, a comment between), the last
  // rapid before the end.
  const std::string text =
      "G21 G90 G17\n"
      "G53 G0 Z100\n"
      "G0 B-20 C90\n"
      "M428\n"
      "G0 X0 Y0 Z30 B-20 C90\n"
      "G0 X0 Y0 Z20 B-20 C90\n"
      "G1 X0 Y10 Z20 B-20 C90 F500\n"
      "G0 X0 Y10 Z30 B-20 C90\n"
      "G0 X0 Y20 Z30 B-25 C90\n"
      "G0 X5 Y20 Z30 B-25 C90\n"
      "(a comment) ; and another\n"
      "G0 X9 Y20 Z30 B-25 C90\n"
      "M2\n";
  const std::vector<GcodeMove> moves = read_gcode_moves(text, "t", GcodeDialect::LinuxCNC, {}, 'B');
  const std::vector<bool> half = controller::half_accel_rapids(moves, text);
  REQUIRE(half.size() == moves.size());
  std::map<int, bool> by_line;
  for (std::size_t k = 0; k < moves.size(); ++k) by_line[moves[k].line] = half[k];
  CHECK(by_line.at(2));    // G53 retract, then a move-less line: the queue stops
  CHECK(by_line.at(3));    // the turn, then M428
  CHECK(!by_line.at(5));   // on to a rapid, neither turns: a blend arc or tangent
  CHECK(!by_line.at(6));   // on to a feed block: stops at the full acceleration
  CHECK(!by_line.at(7));   // a feed block
  CHECK(by_line.at(8));    // on to a rapid that turns
  CHECK(by_line.at(9));    // turns itself
  CHECK(!by_line.at(10));  // X alone on to X alone, the comment not a stop
  CHECK(by_line.at(12));   // the last move before the end
}
