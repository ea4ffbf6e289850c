// An in-house post built on taxopt's library with no file read: the CL points of a ball-end
// finishing path over a wavy surface are made in code, so is the part (a triangle mesh of the
// same surface) and so are two machines -- the built-in A/C table-table machine and a B/C
// head-head bridge mill (LinuxCNC's 5axiskins sample). The tool axes are planned once, for the
// first machine (plan_axes); the same axes are then posted and verified on each machine
// (run_job with Method::None: the planned axes are the input, the verification checks every
// block of each program). Ctrl-C stops either stage (JobOptions::stop): nothing is written.
// Usage: taxopt_in_memory_post OUT_AC.ngc OUT_HEAD.ngc
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <taxopt/core/error.hpp>
#include <taxopt/geometry/part.hpp>
#include <taxopt/io/atomic_file.hpp>
#include <taxopt/job.hpp>

namespace {

const taxopt::StopSource* g_stop = nullptr;
extern "C" void on_interrupt(int) {
  if (g_stop) g_stop->request_stop();
}

// The surface z = 3 sin(x / 12) cos(y / 15), mm, and its upward unit normal.
double height(double x, double y) { return 3.0 * std::sin(x / 12.0) * std::cos(y / 15.0); }
taxopt::Vec3d normal_at(double x, double y) {
  const double dx = 0.25 * std::cos(x / 12.0) * std::cos(y / 15.0);
  const double dy = -0.2 * std::sin(x / 12.0) * std::sin(y / 15.0);
  return taxopt::Vec3d(-dx, -dy, 1.0).normalized();
}

// Eight zig-zag passes of a 6 mm ball-end mill, the tool leaning 10 deg from the normal
// towards -X; a rapid in, a rapid between passes.
taxopt::Toolpath toolpath_in_code() {
  const double r = 3.0;
  taxopt::Operationd op;
  op.name = "WAVE_FINISH";
  op.tool = taxopt::Tool::ball_end_mill(2.0 * r, 25.0);
  op.tool.number = 1;
  op.tool.from_file = true;
  op.spindle_rpm = 12000.0;
  const double lean = 10.0 * std::acos(-1.0) / 180.0;
  for (int pass = 0; pass < 8; ++pass) {
    const double y = -28.0 + 8.0 * pass;
    for (int i = 0; i <= 60; ++i) {
      const double x = pass % 2 ? 30.0 - i : -30.0 + i;
      const taxopt::Vec3d n = normal_at(x, y);
      const taxopt::Vec3d axis =
          (std::cos(lean) * n - std::sin(lean) * taxopt::Vec3d::UnitX()).normalized();
      const taxopt::Vec3d centre = taxopt::Vec3d(x, y, height(x, y)) + r * n;
      taxopt::CLPointd p;
      p.tip_mm = centre - r * axis;  // the tip: the ball's centre back along the axis
      p.axis = axis;
      p.feed_mm_per_min = 1500.0;
      p.motion = i == 0 ? taxopt::Motion::Rapid : taxopt::Motion::Feed;
      op.points.push_back(p);
    }
  }
  taxopt::Toolpath tp;
  tp.source = "in-memory wave";
  tp.operations.push_back(op);
  return tp;
}

// The part: the surface over [-40, 40] x [-40, 40] at 1 mm, closed below by a floor at z = -10.
taxopt::TriangleMesh part_in_code() {
  taxopt::TriangleMesh m;
  const int n = 81;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = -40.0 + i, y = -40.0 + j;
      m.vertices.emplace_back(x, y, height(x, y));
    }
  }
  const auto at = [n](int i, int j) { return j * n + i; };
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      m.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  // The sides and the floor: a closed solid.
  const int base = static_cast<int>(m.vertices.size());
  for (const auto& c : {taxopt::Vec3d(-40, -40, -10), taxopt::Vec3d(40, -40, -10),
                        taxopt::Vec3d(40, 40, -10), taxopt::Vec3d(-40, 40, -10)}) {
    m.vertices.push_back(c);
  }
  m.faces.push_back({base, base + 2, base + 1});
  m.faces.push_back({base, base + 3, base + 2});
  const auto side = [&](int corner_a, int corner_b, auto edge) {
    for (int k = 0; k + 1 < n; ++k) m.faces.push_back({edge(k + 1), edge(k), corner_a});
    m.faces.push_back({edge(n - 1), corner_a, corner_b});
  };
  side(base + 0, base + 1, [&](int k) { return at(k, 0); });
  side(base + 1, base + 2, [&](int k) { return at(n - 1, k); });
  side(base + 2, base + 3, [&](int k) { return at(n - 1 - k, n - 1); });
  side(base + 3, base + 0, [&](int k) { return at(0, n - 1 - k); });
  return m;
}

// A B/C head-head bridge mill made in code: LinuxCNC's 5axiskins sample (B sense -1, C +1, a
// 250 mm pivot), whose kinematics start as the bridge mill's (TCP): no switch written.
taxopt::Machine bridge_mill() {
  taxopt::Machine m = taxopt::make_machine("bc-head-head", 250.0);
  m.name = "bridge-mill-in-code";
  const double deg = std::acos(-1.0) / 180.0;
  m.rotary.tilt.min_rad = -120.0 * deg;
  m.rotary.tilt.max_rad = 120.0 * deg;
  m.rotary.tilt.sense = -1;
  m.rotary.c.continuous = true;
  m.rotary.c.sense = 1;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: taxopt_in_memory_post OUT_AC.ngc OUT_HEAD.ngc\n";
    return 2;
  }
  try {
    const taxopt::Toolpath toolpath = toolpath_in_code();
    const taxopt::Part part(part_in_code());
    taxopt::JobOptions options;
    options.part = &part;
    options.method = taxopt::Method::Global;
    options.feed_schedule = true;
    options.threads = 2;
    g_stop = &options.stop;
    std::signal(SIGINT, on_interrupt);
    // One plan of the tool axes (in the workpiece: any machine that reaches them can run it).
    const taxopt::AxisPlan plan = taxopt::plan_axes(toolpath, taxopt::default_machine(), options);
    if (!plan.ok() || plan.operations.empty()) {
      for (const auto& f : plan.findings) std::cerr << f.message << "\n";
      return 1;
    }
    taxopt::Toolpath planned = toolpath;
    for (std::size_t k = 0; k < planned.operations.size(); ++k) {
      for (std::size_t i = 0; i < planned.operations[k].points.size(); ++i) {
        planned.operations[k].points[i].tip_mm = plan.operations[k].points[i].tip_mm;
        planned.operations[k].points[i].axis = plan.operations[k].points[i].axis;
      }
    }
    // The planned axes posted and verified on each machine, both programs or neither.
    taxopt::JobOptions post = options;
    post.method = taxopt::Method::None;
    taxopt::OutputTransaction out;
    const taxopt::Machine machines[] = {taxopt::default_machine(), bridge_mill()};
    for (int k = 0; k < 2; ++k) {
      const taxopt::JobResult result = taxopt::run_job(planned, machines[k], post);
      for (const auto& p : result.problems) std::cerr << machines[k].name << ": " << p << "\n";
      if (!result.ok()) return 1;
      out.stage(argv[1 + k], result.gcode.text);
      const auto& op = result.operations.front();
      // With a part every block the writer added was swept against it (empty: not checked).
      std::printf("%s (%s): %zu points, peak %c %.1f deg/s^2, %ld blocks swept, program %.1f s\n",
                  machines[k].name.c_str(), machines[k].kinematics.c_str(), op.points,
                  machines[k].rotary.tilt_letter(), op.after.max_accel_deg_s2,
                  op.verification.blocks_swept.value_or(0), result.gcode.time_s);
    }
    out.commit();
    return 0;
  } catch (const taxopt::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const taxopt::Cancelled& e) {
    std::cerr << "stopped: " << e.what() << " -- nothing written\n";
    return 130;
  }
}
