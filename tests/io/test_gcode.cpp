#include <catch2/catch.hpp>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/kinematics/pose_planner.hpp"

using namespace taxopt;

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
  op.poses = plan_poses(m.ac, axes, rapid).poses;
  return op;
}

}  // namespace

TEST_CASE("gcode: what is written reads back as the same tips and axes", "[io][gcode]") {
  for (GcodeMode mode : {GcodeMode::Tcp, GcodeMode::Machine}) {
    for (FeedMode fm : {FeedMode::UnitsPerMinute, FeedMode::InverseTime}) {
      for (LengthUnit u : {LengthUnit::Millimetre, LengthUnit::Inch}) {
        Machine m = default_machine();
        m.gcode.mode = mode;
        m.gcode.feed_mode = fm;
        m.gcode.decimals = 5;
        m.ac.c_axis_point_mm = Vec3d(20, 5, 0);
        m.ac.a_axis_point_mm = Vec3d(0, -3, 40);
        const PostedOperation op = simple_op();
        const GcodeProgram prog = write_gcode({op}, m, u, {"test"});
        const auto moves = read_gcode_moves(prog.text, "t.ngc");
        REQUIRE(moves.size() == op.points.size());
        for (std::size_t i = 0; i < moves.size(); ++i) {
          const Posed pose{deg_to_rad(moves[i].a_deg), deg_to_rad(moves[i].c_deg)};
          const Vec3d tip = mode == GcodeMode::Machine ? m.ac.from_machine_mm(moves[i].xyz_mm, pose)
                                                       : moves[i].xyz_mm;
          CHECK((tip - op.points[i].tip_mm).norm() < 2e-4);
          CHECK(rad_to_deg(angle_between(m.ac.forward(pose), op.points[i].axis)) < 1e-4);
          CHECK(moves[i].rapid == (i == 0));
          CHECK(moves[i].line == prog.emitted[0][i]);
          if (i > 0) {
            // The block takes the time of the tip at the programmed feed.
            const double tip_mm = (op.points[i].tip_mm - op.points[i - 1].tip_mm).norm();
            const double want_min = tip_mm / 600.0;
            const double f = moves[i].feed;
            double got_min;
            if (fm == FeedMode::InverseTime) {
              got_min = 1.0 / f;
            } else if (mode == GcodeMode::Machine) {
              const Posed prev{deg_to_rad(moves[i - 1].a_deg), deg_to_rad(moves[i - 1].c_deg)};
              (void)prev;
              got_min = (moves[i].xyz_mm - moves[i - 1].xyz_mm).norm() / mm_per_unit(u) / f;
            } else {
              got_min = tip_mm / mm_per_unit(u) / f;
            }
            CHECK(got_min == Approx(want_min).epsilon(1e-3));
          }
        }
        CHECK(prog.text.find(u == LengthUnit::Inch ? "G20" : "G21") != std::string::npos);
        CHECK(prog.text.find("-0.00000") == std::string::npos);
        CHECK(prog.text.find("(operation op [1])") != std::string::npos);
        CHECK(prog.text.find("T3 M6") != std::string::npos);
      }
    }
  }
}

TEST_CASE("gcode: a block that moves nothing is not written", "[io][gcode]") {
  PostedOperation op = simple_op();
  op.points.insert(op.points.begin() + 2, op.points[2]);
  op.poses.insert(op.poses.begin() + 2, op.poses[2]);
  const GcodeProgram prog = write_gcode({op}, default_machine(), LengthUnit::Millimetre, {});
  CHECK(prog.emitted[0][3] == 0);
  CHECK(read_gcode_moves(prog.text, "t").size() == op.points.size() - 1);
}

TEST_CASE("gcode: the reader rejects what taxopt never writes", "[io][gcode][bad-input]") {
  CHECK_THROWS_AS(read_gcode_moves("G2 X1 Y1 I1\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("G1 X1 Q3\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("G1 X1..2\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("(open\nG1 X1\n", "t"), InputError);
  CHECK_THROWS_AS(read_gcode_moves("X1 Y2\n", "t"), InputError);
}
