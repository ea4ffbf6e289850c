// A stop inside the single steps after the optimisation (issue 64): planning the poses,
// writing and reading back the program, scheduling the feeds, writing the new CL file. Each
// looks at the job's stop as it goes; a stop requested ends it with Cancelled, and without one
// it gives what the public function gives (the same bytes).
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cl/cl_writer.hpp"
#include "gcode/program_writer.hpp"
#include "kinematics/pose_planning.hpp"
#include "pipeline/stages.hpp"
#include "support.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;

namespace {

struct Planned {
  Toolpath tp = read_cl_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls");
  Machine machine = default_machine();
  AxisPlan plan;
  Planned() {
    JobOptions o;
    o.method = Method::Paper;
    plan = plan_axes(tp, machine, o);
  }
};

}  // namespace

TEST_CASE(
    "stop inside: the poses, the program written and read back, the feed schedule and the new CL "
    "file each end with Cancelled on a stop and give the public function's result without one",
    "[library][cancel]") {
  const Planned p;
  REQUIRE(p.plan.ok());
  const std::vector<PostedOperation>& ops = p.plan.operations;
  REQUIRE(ops.size() == 1);
  REQUIRE(ops[0].points.size() > 2 * detail::kPointStride);  // past the first look
  StopSource stopped, running;
  stopped.request_stop();

  std::vector<Vec3d> axes;
  for (const CLPointd& q : ops[0].points) axes.push_back(q.axis);
  const std::vector<bool> rapid_into(axes.size(), false);
  const PosePlan poses = plan_poses(p.machine.rotary, axes, rapid_into);
  CHECK_THROWS_AS(detail::plan_poses(p.machine.rotary, axes, rapid_into, {}, {}, {}, &stopped),
                  Cancelled);
  const PosePlan again =
      detail::plan_poses(p.machine.rotary, axes, rapid_into, {}, {}, {}, &running);
  REQUIRE(again.poses.size() == poses.poses.size());
  for (std::size_t i = 0; i < poses.poses.size(); ++i) {
    CHECK(again.poses[i].tilt_rad == poses.poses[i].tilt_rad);
    CHECK(again.poses[i].c_rad == poses.poses[i].c_rad);
  }

  const GcodeProgram program = write_gcode(ops, p.machine, LengthUnit::Millimetre, {});
  CHECK_THROWS_AS(gcode::write_program(ops, p.machine, LengthUnit::Millimetre, {}, &stopped),
                  Cancelled);
  CHECK(gcode::write_program(ops, p.machine, LengthUnit::Millimetre, {}, &running).text ==
        program.text);

  const std::vector<GcodeMove> moves = read_gcode_moves(program.text, "out.nc");
  REQUIRE(moves.size() > 2 * detail::kPointStride);
  CHECK_THROWS_AS(
      gcode::read_moves(program.text, "out.nc", GcodeDialect::LinuxCNC, {}, 'A', {}, &stopped),
      Cancelled);
  CHECK(gcode::read_moves(program.text, "out.nc", GcodeDialect::LinuxCNC, {}, 'A', {}, &running)
            .size() == moves.size());

  std::vector<Vec3d> tips;
  for (const CLPointd& q : ops[0].points) tips.push_back(q.tip_mm);
  const std::vector<JointPosition> joints =
      pipeline::joints_of(p.machine.rotary, tips, ops[0].poses);
  const std::vector<double> programmed = programmed_block_times_s(ops[0].points, ops[0].poses);
  const JointLimits limits = effective_limits(p.machine);
  const pipeline::OperationSchedule schedule =
      pipeline::schedule_operation(ops[0].points, joints, programmed, limits, p.machine.rotary);
  CHECK_THROWS_AS(pipeline::schedule_operation(ops[0].points, joints, programmed, limits,
                                               p.machine.rotary, nullptr, nullptr, &stopped),
                  Cancelled);
  CHECK(pipeline::schedule_operation(ops[0].points, joints, programmed, limits, p.machine.rotary,
                                     nullptr, nullptr, &running)
            .time_s == schedule.time_s);

  std::vector<Operationd> changed = p.tp.operations;
  for (std::size_t i = 0; i < changed[0].points.size(); ++i) {
    changed[0].points[i].axis = ops[0].points[i].axis;
    changed[0].points[i].tip_mm = ops[0].points[i].tip_mm;
  }
  CHECK_THROWS_AS(cl::format_cl(p.tp, changed, &stopped), Cancelled);
  CHECK(cl::format_cl(p.tp, changed, &running) == format_cl(p.tp, changed));
}

TEST_CASE(
    "stop inside: a stop at any moment of a Part's build, the distance search tree's single "
    "call included, ends it with Cancelled or a whole Part, and the build left behind frees "
    "itself",
    "[library][cancel]") {
  // 2 x 300 x 300 faces: a few tenths of a second to build.
  test::Heightfield wavy{"wavy",
                         [](double x, double y) { return std::sin(0.3 * x) * std::cos(0.2 * y); },
                         [](double, double) { return Vec3d::UnitZ(); }};
  const TriangleMesh mesh = test::heightfield_mesh(wavy, 0.2, 0.0, 60.0, 0.0, 60.0);
  const auto t0 = std::chrono::steady_clock::now();
  const Part whole(mesh);
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  int cancelled = 0, built = 0;
  for (int k = 1; k <= 9; ++k) {
    StopSource s;
    std::thread stopper([&] {
      std::this_thread::sleep_for(std::chrono::duration<double>(build_s * k / 10.0));
      s.request_stop();
    });
    try {
      const Part part(mesh, s);
      ++built;
      const Vec3d q(10.0, 20.0, 5.0);
      CHECK(part.closest(q).point == whole.closest(q).point);
    } catch (const Cancelled&) {
      ++cancelled;
    }
    stopper.join();
  }
  CHECK(cancelled + built == 9);
  CHECK(cancelled > 0);
}

TEST_CASE(
    "stop inside: a Part's build reports its progress from 0 to the end in steps a bar can "
    "show, and a progress callback that throws ends the build with its exception",
    "[library][cancel]") {
  const TriangleMesh mesh = read_mesh_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.stl");
  std::vector<std::size_t> done_seen;
  std::size_t total_seen = 0;
  const Part part(mesh, StopSource(),
                  [&](const std::string& stage, std::size_t done, std::size_t total) {
                    CHECK(stage == "building the part");
                    done_seen.push_back(done);
                    total_seen = total;
                  });
  REQUIRE(done_seen.size() >= 7);  // 0, then each of its six steps
  CHECK(done_seen.front() == 0);
  CHECK(std::is_sorted(done_seen.begin(), done_seen.end()));
  CHECK(done_seen.back() == total_seen);
  CHECK(total_seen > 0);
  const auto halfway = [](const std::string&, std::size_t done, std::size_t total) {
    if (2 * done >= total && done < total) throw std::runtime_error("closed by the user");
  };
  CHECK_THROWS_WITH(Part(mesh, StopSource(), halfway), "closed by the user");
}
