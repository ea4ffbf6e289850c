// The block time model (controller/block_time.hpp): the rules the schedule, the guard, the
// global objective, the post and the report share.
#include <catch2/catch.hpp>

#include "controller/block_time.hpp"
#include "taxopt/io/gcode.hpp"

using namespace taxopt;

TEST_CASE(
    "block time: a kept block time holds, but never shorter than its own over the feed "
    "ratio",
    "[controller][model]") {
  using controller::kept_time_s;
  CHECK(kept_time_s(2.0, 1.0, 2.0) == 2.0);  // slower than its own: as the input ran it
  CHECK(kept_time_s(0.3, 1.0, 2.0) == 0.5);  // would need F at 3.3x: held at 2x
  CHECK(kept_time_s(0.0, 1.0, 2.0) == 1.0);  // nothing kept: its own
  std::size_t capped = 0;
  const std::vector<double> t =
      controller::kept_block_times_s({0.0, 0.3, 2.0, 0.6}, {0.0, 1.0, 1.0, 1.0}, 2.0, &capped);
  CHECK(t == std::vector<double>{0.0, 0.5, 2.0, 0.6});
  CHECK(capped == 1);
}

TEST_CASE(
    "block time: the tip rule is the tip's distance over the feed, the turn's in deg/min "
    "where the tip stands still",
    "[controller][model]") {
  controller::BlockTiming tip;
  tip.feed_mm_per_min = {0.0, 600.0, 600.0};
  const Posed p0{0.0, 0.0}, p1{deg_to_rad(3.0), deg_to_rad(4.0)};
  // 10 mm at 600 mm/min: 1 s.
  CHECK(tip.move_time_s(1, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == Approx(1.0));
  // A and C alone, 5 deg at 600 deg/min: 0.5 s.
  CHECK(tip.move_time_s(2, Vec3d(1, 1, 1), p0, Vec3d(1, 1, 1), p1) == Approx(0.5));
  CHECK(tip.move_time_s(0, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == 0.0);  // no feed
  // "cutter-path": the input's 4 s block kept; its 0.1 s block held at the ratio (1 s / 2).
  controller::BlockTiming kept = tip;
  kept.kept_s = {0.0, 4.0, 0.1};
  kept.max_feed_ratio = 2.0;
  CHECK(kept.move_time_s(1, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == Approx(4.0));
  CHECK(kept.move_time_s(2, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == Approx(0.5));
}

TEST_CASE(
    "block time: the F the writer sets is the F the time models read, a turn of A and C alone "
    "in deg/min (one rule: controller/feed_word.hpp)",
    "[controller][model]") {
  // Three feed blocks: X Y Z and A C, A and C alone (the tip stands still), X Y Z alone.
  PostedOperation op;
  op.name = "turns";
  op.tool.number = 1;
  op.spindle_rpm = 1000.0;
  const Vec3d tips[] = {Vec3d(0, 0, 5), Vec3d(6, 8, 5), Vec3d(6, 8, 5), Vec3d(6, 8, -5)};
  const Posed poses[] = {{0.0, 0.0},
                         {deg_to_rad(3.0), deg_to_rad(4.0)},
                         {deg_to_rad(9.0), deg_to_rad(12.0)},
                         {deg_to_rad(9.0), deg_to_rad(12.0)}};
  Machine machine = default_machine();
  for (int i = 0; i < 4; ++i) {
    CLPointd p;
    p.tip_mm = tips[i];
    p.axis = machine.rotary.forward(poses[i]);
    p.motion = i == 0 ? Motion::Rapid : Motion::Feed;
    p.feed_mm_per_min = 600.0;
    op.points.push_back(p);
    op.poses.push_back(poses[i]);
  }
  const std::vector<double> programmed = programmed_block_times_s(op.points, op.poses);
  CHECK(programmed[2] == Approx(1.0));  // 10 deg at 600 deg/min
  for (LengthUnit units : {LengthUnit::Millimetre, LengthUnit::Inch}) {
    const GcodeProgram prog = write_gcode({op}, machine, units, {});
    const std::vector<GcodeMove> moves = read_gcode_moves(prog.text, "t");
    for (std::size_t i = 1; i < 4; ++i) {
      const int line = prog.emitted[0][i];
      const GcodeMove* to = nullptr;
      const GcodeMove* from = nullptr;
      for (std::size_t j = 1; j < moves.size(); ++j) {
        if (moves[j].line == line) {
          to = &moves[j];
          from = &moves[j - 1];
        }
      }
      REQUIRE(to);
      INFO("point " << i << (units == LengthUnit::Inch ? ", in" : ", mm"));
      // The written words' time: within their rounding of the planned time.
      CHECK(block_time_s(*from, *to, units) == Approx(programmed[i]).epsilon(2e-3));
    }
  }
}
