#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/kinematics/pose_planner.hpp"

using namespace taxopt;
using taxopt::test::line_of;
using taxopt::test::lines_of;

namespace {

PostedOperation simple_op() {
  PostedOperation op;
  op.name = "op (1)";
  op.tool.number = 3;
  op.spindle_rpm = 3000;
  const Machine m = default_machine();
  const double tilt[] = {0.0, 10.0, 20.0, 20.0, -5.0};
  for (int i = 0; i < 5; ++i) {
    CLPointd p;
    p.tip_mm = Vec3d(10.0 * i, -0.00001, 2.0);
    p.axis = Eigen::AngleAxisd(deg_to_rad(tilt[i]), Vec3d::UnitX()) * Vec3d::UnitZ();
    p.motion = i == 0 ? Motion::Rapid : Motion::Feed;
    p.feed_mm_per_min = 600.0;
    op.points.push_back(p);
  }
  std::vector<Vec3d> axes;
  std::vector<bool> rapid;
  for (const auto& p : op.points) {
    axes.push_back(p.axis);
    rapid.push_back(p.motion == Motion::Rapid);
  }
  op.poses = plan_poses(m.rotary, axes, rapid).poses;
  return op;
}

}  // namespace

TEST_CASE("gcode: what is written reads back as the same tips and axes, in every dialect",
          "[io][gcode]") {
  for (GcodeDialect dialect : {GcodeDialect::LinuxCNC, GcodeDialect::Fanuc, GcodeDialect::Siemens,
                               GcodeDialect::Heidenhain}) {
    for (GcodeMode mode : {GcodeMode::Tcp, GcodeMode::Machine}) {
      for (FeedMode fm : {FeedMode::UnitsPerMinute, FeedMode::InverseTime}) {
        if (dialect == GcodeDialect::Heidenhain && fm == FeedMode::InverseTime) continue;
        for (LengthUnit u : {LengthUnit::Millimetre, LengthUnit::Inch}) {
          INFO(to_string(dialect));
          Machine m = default_machine();
          m.gcode.dialect = dialect;
          m.gcode.mode = mode;
          m.gcode.feed_mode = fm;
          m.gcode.decimals = std::min(5, max_decimals(dialect));
          m.rotary.c_axis_point_mm = Vec3d(20, 5, 0);
          m.rotary.tilt_axis_point_mm = Vec3d(0, -3, 40);
          const PostedOperation op = simple_op();
          const GcodeProgram prog = write_gcode({op}, m, u, {"test"});
          std::vector<GcodeMove> moves;  // the point's blocks and those between (linearised)
          for (const GcodeMove& g : read_gcode_moves(prog.text, "t.ngc", dialect)) {
            if (!g.positioning) moves.push_back(g);
          }
          std::vector<std::size_t> at;  // the block of each point
          for (std::size_t j = 0; j < moves.size(); ++j) {
            if (std::find(prog.emitted[0].begin(), prog.emitted[0].end(), moves[j].line) !=
                prog.emitted[0].end()) {
              at.push_back(j);
            }
          }
          REQUIRE(at.size() == op.points.size());
          CHECK(at.front() == 0);
          if (mode == GcodeMode::Tcp) CHECK(moves.size() == op.points.size());
          const double tip_tol =
              std::sqrt(3.0) * 0.5 * std::pow(10.0, -m.gcode.decimals) * mm_per_unit(u) + 1e-4;
          for (std::size_t i = 0; i < at.size(); ++i) {
            const GcodeMove& w = moves[at[i]];
            const Posed pose{deg_to_rad(w.tilt_deg), deg_to_rad(w.c_deg)};
            const Vec3d tip =
                mode == GcodeMode::Machine ? m.rotary.from_machine_mm(w.xyz_mm, pose) : w.xyz_mm;
            CHECK((tip - op.points[i].tip_mm).norm() < tip_tol);
            CHECK(rad_to_deg(angle_between(m.rotary.forward(pose), op.points[i].axis)) < 1e-4);
            CHECK(w.rapid == (i == 0));
            CHECK(w.line == prog.emitted[0][i]);
            CHECK(w.length_offset);
            CHECK(w.tcp == (mode == GcodeMode::Tcp || dialect == GcodeDialect::LinuxCNC));
            if (i > 0) {
              // The blocks into the point take the time of the tip at the programmed feed.
              const double tip_mm = (op.points[i].tip_mm - op.points[i - 1].tip_mm).norm();
              const double want_min = tip_mm / 600.0;
              double got_min = 0.0;
              for (std::size_t j = at[i - 1] + 1; j <= at[i]; ++j) {
                const double f = moves[j].feed;
                if (fm == FeedMode::InverseTime) {
                  got_min += 1.0 / f;
                } else if (mode == GcodeMode::Machine) {
                  got_min += (moves[j].xyz_mm - moves[j - 1].xyz_mm).norm() / mm_per_unit(u) / f;
                } else {
                  got_min += tip_mm / mm_per_unit(u) / f;
                }
                // Machine mode: every block between keeps the tip on the straight line.
                const Posed pj{deg_to_rad(moves[j].tilt_deg), deg_to_rad(moves[j].c_deg)};
                const Vec3d tj = mode == GcodeMode::Machine
                                     ? m.rotary.from_machine_mm(moves[j].xyz_mm, pj)
                                     : moves[j].xyz_mm;
                const Vec3d a = op.points[i - 1].tip_mm, b = op.points[i].tip_mm;
                CHECK((tj - a).cross(b - a).norm() / (b - a).norm() < tip_tol);
              }
              CHECK(got_min == Approx(want_min).epsilon(1e-3));
            }
          }
          const bool iso = dialect == GcodeDialect::LinuxCNC || dialect == GcodeDialect::Fanuc;
          const char* unit_word = iso ? (u == LengthUnit::Inch ? "G20" : "G21")
                                  : dialect == GcodeDialect::Siemens
                                      ? (u == LengthUnit::Inch ? "G700" : "G710")
                                      : (u == LengthUnit::Inch ? "G70 *" : "G71 *");
          CHECK(prog.text.find(unit_word) != std::string::npos);
          CHECK(prog.text.find("-0.00000") == std::string::npos);
          CHECK(prog.text.find("operation op [1]") != std::string::npos);
          CHECK(prog.text.find("T3") != std::string::npos);
        }
      }
    }
  }
}

TEST_CASE("gcode: each dialect reads only its own program", "[io][gcode][bad-input]") {
  PostedOperation op = simple_op();
  for (GcodeDialect writer :
       {GcodeDialect::Fanuc, GcodeDialect::Siemens, GcodeDialect::Heidenhain}) {
    Machine m = default_machine();
    m.gcode.dialect = writer;
    const std::string text = write_gcode({op}, m, LengthUnit::Millimetre, {}).text;
    // LinuxCNC's subset has no G43.4, TRAORI, N..* blocks: its reader refuses them.
    CHECK_THROWS_AS(read_gcode_moves(text, "t"), InputError);
  }
  // Fanuc reads a coordinate without a decimal point in least increments: always a point.
  Machine fanuc = default_machine();
  fanuc.gcode.dialect = GcodeDialect::Fanuc;
  fanuc.gcode.decimals = 0;
  const std::string text = write_gcode({op}, fanuc, LengthUnit::Millimetre, {}).text;
  CHECK(text.find("X10. ") != std::string::npos);
  // Heidenhain without G93.
  Machine heidenhain = default_machine();
  heidenhain.gcode.dialect = GcodeDialect::Heidenhain;
  heidenhain.gcode.feed_mode = FeedMode::InverseTime;
  CHECK_THROWS_AS(write_gcode({op}, heidenhain, LengthUnit::Millimetre, {}), std::invalid_argument);
}

TEST_CASE("gcode: a block that moves nothing is not written", "[io][gcode]") {
  PostedOperation op = simple_op();
  op.points.insert(op.points.begin() + 2, op.points[2]);
  op.poses.insert(op.poses.begin() + 2, op.poses[2]);
  const GcodeProgram prog = write_gcode({op}, default_machine(), LengthUnit::Millimetre, {});
  CHECK(prog.emitted[0][3] == 0);
  std::size_t written = 0;
  for (const GcodeMove& g : read_gcode_moves(prog.text, "t")) written += g.positioning ? 0 : 1;
  CHECK(written == op.points.size() - 1);
}

TEST_CASE("gcode: the reader rejects what taxopt never writes", "[io][gcode][bad-input]") {
  CHECK_THROWS_AS(read_gcode_moves("G2 X1 Y1 I1\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("G1 X1 Q3\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("G1 X1..2\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("(open\nG1 X1\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("X1 Y2\n", "t"), InputError);
}

namespace {

/// Compares `text` with the golden file tests/data/golden/`name`; TAXOPT_UPDATE_GOLDEN=1
/// writes it instead (then review the diff before committing).
void check_golden(const std::string& name, const std::string& text) {
  const std::string path = std::string(TAXOPT_TEST_DATA) + "/golden/" + name;
  if (std::getenv("TAXOPT_UPDATE_GOLDEN")) {
    std::ofstream(path, std::ios::binary) << text;
  }
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in);
  const std::string want((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(text == want);
}

}  // namespace

TEST_CASE("gcode: golden programs of each dialect, mode and feed mode", "[io][gcode][golden]") {
  struct Case {
    const char* file;
    GcodeDialect dialect;
    GcodeMode mode;
    FeedMode feed;
    LengthUnit units;
    bool scheduled;
  };
  const Case cases[] = {
      {"linuxcnc-tcp-g94.ngc", GcodeDialect::LinuxCNC, GcodeMode::Tcp, FeedMode::UnitsPerMinute,
       LengthUnit::Millimetre, false},
      {"linuxcnc-machine-g93-scheduled.ngc", GcodeDialect::LinuxCNC, GcodeMode::Machine,
       FeedMode::InverseTime, LengthUnit::Millimetre, true},
      {"fanuc-tcp-g94.nc", GcodeDialect::Fanuc, GcodeMode::Tcp, FeedMode::UnitsPerMinute,
       LengthUnit::Millimetre, false},
      {"fanuc-machine-g93-inch.nc", GcodeDialect::Fanuc, GcodeMode::Machine, FeedMode::InverseTime,
       LengthUnit::Inch, false},
      {"siemens-tcp-g94-scheduled.mpf", GcodeDialect::Siemens, GcodeMode::Tcp,
       FeedMode::UnitsPerMinute, LengthUnit::Millimetre, true},
      {"siemens-machine-g93.mpf", GcodeDialect::Siemens, GcodeMode::Machine, FeedMode::InverseTime,
       LengthUnit::Millimetre, false},
      {"heidenhain-tcp-g94.i", GcodeDialect::Heidenhain, GcodeMode::Tcp, FeedMode::UnitsPerMinute,
       LengthUnit::Millimetre, false},
      {"heidenhain-machine-g94-inch.i", GcodeDialect::Heidenhain, GcodeMode::Machine,
       FeedMode::UnitsPerMinute, LengthUnit::Inch, false},
  };
  for (const Case& c : cases) {
    INFO(c.file);
    Machine m = default_machine();
    m.name = "golden";
    m.gcode.dialect = c.dialect;
    m.gcode.mode = c.mode;
    m.gcode.feed_mode = c.feed;
    m.rotary.c_axis_point_mm = Vec3d(20, 5, 0);
    m.rotary.tilt_axis_point_mm = Vec3d(0, -3, 40);
    PostedOperation op = simple_op();
    if (c.scheduled) op.block_time_s = {0.0, 1.5, 2.25, 3.0, 4.0};  // slower than programmed
    const GcodeProgram prog = write_gcode({op}, m, c.units, {"golden " + std::string(c.file)});
    check_golden(c.file, prog.text);
    // And it reads back with the dialect's reader, point for point.
    std::size_t written = 0;
    for (const GcodeMove& g : read_gcode_moves(prog.text, c.file, c.dialect)) {
      written += g.positioning ? 0 : 1;
    }
    CHECK(written == op.points.size() + prog.linearised_blocks);
    test::check_blocks(prog, c.dialect);
  }
}

TEST_CASE("gcode: every dialect starts and ends safe, in its own words", "[io][gcode]") {
  struct Want {
    GcodeDialect dialect;
    const char* retract;
    const char* length_on;  // the block that switches the tool length (and TCP) on
    const char* tcp_off;
  };
  const Want wants[] = {
      {GcodeDialect::LinuxCNC, "G53 G0 Z25.0000", "G43 H3", "G49"},
      {GcodeDialect::Fanuc, "G91 G28 Z0.", "G43.4 H3 G0", "G49"},
      {GcodeDialect::Siemens, "G0 SUPA Z25.0000 D0", "TRAORI", "TRAFOOF"},
      {GcodeDialect::Heidenhain, "G00 Z25.0000 M91 *", "M128 *", "M129 *"},
  };
  for (const Want& w : wants) {
    INFO(to_string(w.dialect));
    Machine m = default_machine();
    m.gcode.dialect = w.dialect;
    m.gcode.program.retract_z_mm = 25.0;
    PostedOperation a = simple_op(), b = simple_op();
    b.tool.number = 4;
    const GcodeProgram prog = write_gcode({a, b}, m, LengthUnit::Millimetre, {});
    const auto lines = lines_of(prog.text);
    const std::size_t first_move = static_cast<std::size_t>(prog.emitted[0][0] - 1);
    const std::size_t last_move = static_cast<std::size_t>(prog.emitted[1].back() - 1);
    // Before the first point: retract, tool change, the table turned, then length/TCP on.
    const std::size_t retract = line_of(lines, w.retract);
    const std::size_t tool = line_of(lines, "T3", retract);
    const std::size_t turn =
        line_of(lines, std::string(w.dialect == GcodeDialect::Heidenhain ? "G00 A" : "G0 A"), tool);
    const std::size_t on = line_of(lines, w.length_on, turn);
    REQUIRE(retract != std::string::npos);
    CHECK(retract < tool);
    CHECK(tool < turn);
    CHECK(turn < on);
    CHECK(on <= first_move);
    // The second operation retracts before its tool change; the program retracts at its end,
    // after TCP is off, and nothing moves after that.
    const std::size_t second = line_of(lines, w.retract, first_move);
    CHECK(second < line_of(lines, "T4", first_move));
    const std::size_t off = line_of(lines, w.tcp_off, last_move);
    const std::size_t end_retract = line_of(lines, w.retract, last_move);
    REQUIRE(off != std::string::npos);
    REQUIRE(end_retract != std::string::npos);
    CHECK(off < end_retract);
    // Read back: the retracts, table turns and the positioning blocks are positioning moves,
    // no point's: per operation retract, turn, positioning; at the end retract and the
    // rotaries home.
    const auto moves = read_gcode_moves(prog.text, "t", w.dialect);
    std::size_t positioning = 0;
    for (const GcodeMove& g : moves) positioning += g.positioning ? 1 : 0;
    CHECK(positioning == 2 * 3 + 2);
    CHECK(moves.back().positioning);
    CHECK(moves.back().tilt_deg == 0.0);
    CHECK(moves.back().c_deg == 0.0);
    // From the retract: a complete positioning (under TCP X, Y and Z at the clearance height;
    // Fanuc, whose G43.4 comes with it, X and Y), then down to the first point with the same
    // X Y (tests/test_program.cpp: no diagonal rapid from the retract height).
    for (std::size_t k = 0; k < 2; ++k) {
      const int point_line = prog.emitted[k][0];
      std::size_t at = 0;
      while (moves[at].line != point_line) ++at;
      REQUIRE(at > 0);
      const GcodeMove& xy = moves[at - 1];
      CHECK(xy.given == (w.dialect == GcodeDialect::Fanuc ? 3u : 7u));
      CHECK(xy.positioning);
      if (xy.given == 7u) CHECK(xy.xyz_mm.z() >= moves[at].xyz_mm.z());
      CHECK(moves[at].xyz_mm.x() == xy.xyz_mm.x());
      CHECK(moves[at].xyz_mm.y() == xy.xyz_mm.y());
      CHECK(moves[at].tilt_deg == xy.tilt_deg);
      CHECK(moves[at].c_deg == xy.c_deg);
      CHECK(moves[at].tool == (k == 0 ? 3 : 4));
      CHECK(moves[at].spindle_on);
    }
  }
}

TEST_CASE("gcode: the program template of the machine file", "[io][gcode]") {
  for (GcodeDialect d : {GcodeDialect::LinuxCNC, GcodeDialect::Fanuc, GcodeDialect::Siemens,
                         GcodeDialect::Heidenhain}) {
    INFO(to_string(d));
    Machine m = default_machine();
    m.gcode.dialect = d;
    ProgramTemplate& t = m.gcode.program;
    t.name = "PART_42";
    t.number = 42;
    t.work_offset = "G55";
    t.coolant = Coolant::Flood;
    t.header = {"M98 P9000 (warm up)", "#100 = 1"};
    t.footer = {"M140 MB MAX"};
    t.tool_change = {"T{tool} M6", "M98 P{tool}0"};
    t.tcp_on = {"M428"};
    t.tcp_off = {"M429"};
    const PostedOperation op = simple_op();
    const GcodeProgram prog = write_gcode({op}, m, LengthUnit::Millimetre, {});
    const auto lines = lines_of(prog.text);
    CHECK(line_of(lines, "PART_42") != std::string::npos);
    if (d == GcodeDialect::Fanuc) CHECK(lines[1].rfind("O0042 (PART_42)", 0) == 0);
    if (d == GcodeDialect::Heidenhain) CHECK(lines[0] == "%PART_42 G71 *");
    CHECK(line_of(lines, "G55") < line_of(lines, "M98 P9000"));
    CHECK(line_of(lines, "M98 P30") == line_of(lines, "T3 M6") + 1);
    CHECK(line_of(lines, "M8") < static_cast<std::size_t>(prog.emitted[0][0] - 1));
    const std::size_t last = static_cast<std::size_t>(prog.emitted[0].back() - 1);
    const std::size_t end = line_of(lines, d == GcodeDialect::LinuxCNC ? "M2" : "M30", last);
    REQUIRE(end != std::string::npos);
    CHECK(line_of(lines, "M9", last) < end);
    CHECK(line_of(lines, "M428") < static_cast<std::size_t>(prog.emitted[0][0] - 1));
    // TCP off in the set-up (after the header: a controller may start in its TCP
    // kinematics), and after the last point.
    CHECK(line_of(lines, "M429") > line_of(lines, "M98 P9000"));
    CHECK(line_of(lines, "M429") < line_of(lines, "M428"));
    const std::size_t off = line_of(lines, "M429", last);
    CHECK(off > last);
    CHECK(line_of(lines, "M140 MB MAX") > off);
    // The template's blocks are stepped over by the reader, told by the writer.
    CHECK(prog.verbatim_lines.size() == 1 + 1 + 2 + 1 + 2 + 1 + 1);
    CHECK_THROWS_AS(read_gcode_moves(prog.text, "t", d), InputError);
    std::size_t points = 0;
    for (const GcodeMove& g : read_gcode_moves(prog.text, "t", d, prog.verbatim_lines)) {
      points += g.positioning ? 0 : 1;
    }
    CHECK(points == op.points.size());
  }
  // Heidenhain: F with 3 decimals, also under a schedule (rounded down).
  Machine tnc = default_machine();
  tnc.gcode.dialect = GcodeDialect::Heidenhain;
  PostedOperation op = simple_op();
  op.block_time_s = {0.0, 1.5, 2.25, 3.0, 4.0};
  const std::string text = write_gcode({op}, tnc, LengthUnit::Millimetre, {}).text;
  CHECK(text.find("F400.000 *") != std::string::npos);
  CHECK(text.find("F266.666 *") != std::string::npos);  // 10 mm in 2.25 s: 266.6667 down
}

TEST_CASE(
    "A tcp rapid that turns the table gets a rate that keeps every joint within its "
    "velocity limit, checked at 4000 steps along the move (LinuxCNC plans it in the "
    "program's axes, measured on LinuxCNC's motion controller)",
    "[gcode][tcp]") {
  // LinuxCNC's sample machine: pivot, senses and limits as its preset gives them.
  const Machine m =
      read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml");
  const JointLimits limits = effective_limits(m);
  REQUIRE(limits[0].max_velocity_per_s == 20.0);
  // The joints' largest velocity when the move runs at `rate` (fraction per second).
  const auto peak_ratio = [&](const Vec3d& t0, const Posed& p0, const Vec3d& t1, const Posed& p1,
                              double rate) {
    double worst = 0.0;
    constexpr int kSteps = 4000;
    Vec3d prev = m.rotary.to_machine_mm(t0, p0);
    for (int s = 1; s <= kSteps; ++s) {
      const double u = static_cast<double>(s) / kSteps;
      const Posed pose{p0.tilt_rad + u * (p1.tilt_rad - p0.tilt_rad),
                       p0.c_rad + u * (p1.c_rad - p0.c_rad)};
      const Vec3d q = m.rotary.to_machine_mm(t0 + u * (t1 - t0), pose);
      for (int j = 0; j < 3; ++j) {
        worst = std::max(worst, std::abs(q[j] - prev[j]) * kSteps * rate /
                                    limits[static_cast<std::size_t>(j)].max_velocity_per_s);
      }
      prev = q;
    }
    return worst;
  };
  // The axis rate of the rapid: every program axis within its own limit.
  const auto axis_rate = [&](const Vec3d& t0, const Posed& p0, const Vec3d& t1, const Posed& p1) {
    const double d[5] = {t1.x() - t0.x(), t1.y() - t0.y(), t1.z() - t0.z(),
                         rad_to_deg(p1.tilt_rad - p0.tilt_rad), rad_to_deg(p1.c_rad - p0.c_rad)};
    double r = 1e300;
    for (std::size_t k = 0; k < 5; ++k) {
      if (d[k] != 0.0) r = std::min(r, limits[k].max_velocity_per_s / std::abs(d[k]));
    }
    return r;
  };
  SECTION("a lift with a small tilt far from the pivot (the test program's pass end)") {
    const Vec3d t0(1.4, 18.8, -9.7), t1(1.4, 19.6, 0.24);
    const Posed p0{deg_to_rad(-23.75), deg_to_rad(-180.0)},
        p1{deg_to_rad(-24.76), deg_to_rad(-179.76)};
    CHECK(peak_ratio(t0, p0, t1, p1, axis_rate(t0, p0, t1, p1)) > 1.0);  // G0 would breach
    const std::optional<double> rate = joint_safe_rate_per_s(m.rotary, limits, t0, p0, t1, p1);
    REQUIRE(rate);
    CHECK(peak_ratio(t0, p0, t1, p1, *rate) <= 1.0);
    CHECK(peak_ratio(t0, p0, t1, p1, *rate) > 0.99);  // not slower than it needs
  }
  SECTION("a half turn of C with the tip 60 mm off its axis") {
    const Vec3d t0(60.0, 0.0, 5.0), t1(60.0, 0.0, 5.0);
    const Posed p0{deg_to_rad(-30.0), 0.0}, p1{deg_to_rad(-30.0), deg_to_rad(180.0)};
    CHECK(peak_ratio(t0, p0, t1, p1, axis_rate(t0, p0, t1, p1)) > 1.0);
    const std::optional<double> rate = joint_safe_rate_per_s(m.rotary, limits, t0, p0, t1, p1);
    REQUIRE(rate);
    CHECK(peak_ratio(t0, p0, t1, p1, *rate) <= 1.0);
  }
  SECTION("no turn, the table level: the joints move as the axes, the rapid stays") {
    const Posed p{0.0, 0.0};
    CHECK_FALSE(joint_safe_rate_per_s(m.rotary, limits, Vec3d(0, 0, 5), p, Vec3d(30, 10, 50), p));
  }
  SECTION("no turn, the table tilted and turned: the joints' lines at their limits") {
    // Z and X at their limits move joints Y and Z, turned with the table, past theirs.
    const Posed p{deg_to_rad(-30.0), deg_to_rad(40.0)};
    const Vec3d t0(0, 0, 5), t1(30, 10, 50);
    CHECK(peak_ratio(t0, p, t1, p, axis_rate(t0, p, t1, p)) > 1.0);
    const std::optional<double> rate = joint_safe_rate_per_s(m.rotary, limits, t0, p, t1, p);
    REQUIRE(rate);
    CHECK(peak_ratio(t0, p, t1, p, *rate) <= 1.0);
    CHECK(peak_ratio(t0, p, t1, p, *rate) > 0.99);
  }
  SECTION("a turn about the tip on the pivot: slow enough already") {
    const Vec3d t(0.0, 0.0, 0.0);
    Machine c = m;
    c.rotary.tilt_axis_point_mm = Vec3d::Zero();
    CHECK_FALSE(joint_safe_rate_per_s(c.rotary, limits, t, Posed{0.0, 0.0}, t,
                                      Posed{deg_to_rad(-20.0), deg_to_rad(90.0)}));
  }
}

TEST_CASE(
    "gcode: a small arc in inches at 4 decimals is written as G2/G3 only where its rounded "
    "words keep one radius -- 3000 random 0.05 in MOVARCs read back, in inches and in mm",
    "[io][gcode][arcs]") {
  // A Fusion inch file's 0.05 in arcs: rounded to 4 decimals some ended 1.2723 mm from their
  // centre and began 1.2677 mm from it, and taxopt refused its own program.
  using namespace taxopt::test;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> sweep(20.0, 170.0), heading(0.0, 360.0);
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(6);
  os << "UNITS/INCHES\nMULTAX/ON\nLOADTL/1\nCUTTER/0.25, 0.125, 0, 0.125, 0, 0, 1\n"
        "SPINDL/RPM, 20000, CLW\nFEDRAT/20, IPM\nRAPID\nGOTO/0.1, 0.1, 0.5, 0, 0, 1\n"
        "GOTO/0.1, 0.1, 0.0, 0, 0, 1\n";
  double x = 0.1, y = 0.1;
  const double r = 0.05;
  for (int k = 0; k < 3000; ++k) {
    const double phi = deg_to_rad(heading(rng)), th = sweep(rng);
    x += 0.03 * std::cos(phi);
    y += 0.03 * std::sin(phi);
    os << "GOTO/" << x << ", " << y << ", 0.0, 0, 0, 1\n";
    const double cx = x - r * std::sin(phi), cy = y + r * std::cos(phi);
    const double a1 = std::atan2(y - cy, x - cx) + deg_to_rad(th);
    const double ex = cx + r * std::cos(a1), ey = cy + r * std::sin(a1);
    os << "MOVARC/" << cx << ", " << cy << ", 0.0, 0, 0, 1, " << r << ", ANGLE, " << th << "\nGOTO/"
       << ex << ", " << ey << ", 0.0, 0, 0, 1\n";
    x = ex - 0.02 * std::sin(a1);
    y = ey + 0.02 * std::cos(a1);
    os << "GOTO/" << x << ", " << y << ", 0.0, 0, 0, 1\n";
    if (std::abs(x) > 3.0 || std::abs(y) > 3.0) {
      x = y = 0.1;
      os << "GOTO/0.1, 0.1, 0.0, 0, 0, 1\n";
    }
  }
  TempDir t;
  write_file(t.path("inch.apt"), os.str());
  for (const char* units : {"", " --units-out mm"}) {
    INFO("units:" << units);
    const RunResult res =
        run_taxopt("--in " + t.path("inch.apt") + " --method none -q --tool-number 1 --gcode " +
                   t.path("i.ngc") + units);
    CHECK(res.code == 0);
    CHECK_THAT(res.err, !Catch::Contains("differs from the radius"));
    const std::string nc = read_file(t.path("i.ngc"));
    CHECK(count_of(nc, " G3 X") > 100);  // arcs that round well stay arcs
    if (have_rs274()) {
      std::vector<CanonMove> moves;
      CHECK(run_rs274(t.path("i.ngc"), moves).code == 0);
    }
  }
}
