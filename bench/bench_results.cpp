// Results: --method none, paper and global (each objective) on the bundled demo and on
// generated sine surfaces (with their parts), at 250 and 2000 mm/min and on a machine with slow
// rotary axes, and the runtime of each as the points grow. Prints the markdown tables
// of docs/results.md.
// Run from the source folder: build/release/bench/bench_results [data folder, default data]
//   [largest number of points of the runtime table, default 100000] [runtime: that table only]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "taxopt/geometry/raster_generator.hpp"
#include "taxopt/geometry/surface.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;

namespace {

struct Case {
  std::string name;
  Toolpath toolpath;
  TriangleMesh mesh;
  Machine machine;
  ToolOverrides tool;
  /// --feed-schedule (a machine whose limits the programmed feed exceeds needs it).
  bool feed_schedule = false;
};

/// The same case on a machine with slow rotary axes: A and C at 20 deg/s and 40 deg/s^2 (the
/// linear axes the defaults'), the feed scheduled.
Case slow_rotary(Case k) {
  k.name += ", slow A/C";
  k.machine.limits = default_joint_limits();
  for (Joint j : {Joint::Tilt, Joint::C}) {
    k.machine.limits[static_cast<std::size_t>(j)] = {20.0, 40.0, 0.0};
  }
  k.feed_schedule = true;
  return k;
}

/// A sine surface (the paper's case with other proportions), its raster passes and its part.
Case sine_case(const std::string& name, double height_mm, double wavelength_mm, double width_mm,
               double length_mm, double tilt_deg, double yaw_deg, double feed_mm_min = 250.0) {
  SineSurfaced sine;
  sine.height_mm = height_mm;
  sine.wavelength_mm = wavelength_mm;
  sine.x1_mm = width_mm;
  sine.y1_mm = length_mm;
  RasterOptions raster;
  raster.tilt_deg = tilt_deg;
  raster.yaw_deg = yaw_deg;
  Operationd op;
  op.name = name;
  op.tool = Tool::ball_end_mill(6.0, 15.0);
  op.tool.number = 1;
  op.spindle_rpm = 3000.0;
  for (const GeneratedPoint& p : generate_raster(sine, raster)) {
    CLPointd c;
    c.tip_mm = p.tip_mm;
    c.axis = p.axis;
    c.motion = p.rapid ? Motion::Rapid : Motion::Feed;
    c.feed_mm_per_min = p.rapid ? 0.0 : feed_mm_min;
    op.points.push_back(c);
  }
  SineSurfaced big = sine;
  const double margin = 12.0;
  big.x0_mm -= margin, big.x1_mm += margin, big.y0_mm -= margin, big.y1_mm += margin;
  Case k;
  k.name = name;
  k.toolpath = parse_cl(format_new_cl({op}), name + ".cls");
  k.mesh = tessellate(big, static_cast<int>((big.x1_mm - big.x0_mm) / 0.5),
                      static_cast<int>((big.y1_mm - big.y0_mm) / 0.5));
  k.machine = default_machine();
  k.tool.gauge_length_mm = 15.0;
  return k;
}

struct Row {
  JobResult result;
  double seconds = 0.0;
};

Row run(const Case& k, Method method, GlobalObjective objective = GlobalObjective::SumSquares) {
  const Part part(k.mesh);
  JobOptions o;
  o.method = method;
  o.global.objective = objective;
  if (const char* it = std::getenv("TAXOPT_BENCH_GLOBAL_ITERATIONS")) {
    o.global.max_iterations = std::atoi(it);
  }
  o.part = &part;
  o.tool = k.tool;
  o.feed_schedule = k.feed_schedule;
  const auto t0 = std::chrono::steady_clock::now();
  Row r;
  r.result = run_job(k.toolpath, k.machine, o);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace

int run_bench(int argc, char** argv) {
  const std::string data = argc > 1 ? argv[1] : "data";
  const std::size_t largest = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 100000;
  const bool runtime_only = argc > 3 && std::string(argv[3]) == "runtime";
  std::vector<Case> cases;
  {
    Case demo;
    demo.name = "demo (data/demo/sine.cls)";
    demo.toolpath = read_cl_file(data + "/demo/sine.cls");
    demo.mesh = read_mesh_file(data + "/demo/sine.stl");
    demo.machine = read_machine_file(data + "/machines/paper-ac.toml");
    demo.tool.gauge_length_mm = 15.0;
    cases.push_back(std::move(demo));
  }
  cases.push_back(sine_case("sine h10 tilt15 yaw10", 10.0, 40.0, 20.0, 80.0, 15.0, 10.0));
  cases.push_back(sine_case("sine h6 tilt5 yaw30", 6.0, 40.0, 20.0, 80.0, 5.0, 30.0));
  cases.push_back(sine_case("sine h4 wl30 tilt0 yaw5", 4.0, 30.0, 20.0, 60.0, 0.0, 5.0));
  // The same at a finishing feed of 2000 mm/min, where the machine's limits bind.
  cases.push_back(
      sine_case("sine h10 tilt15 yaw10, F2000", 10.0, 40.0, 20.0, 80.0, 15.0, 10.0, 2000.0));
  cases.push_back(
      sine_case("sine h6 tilt5 yaw30, F2000", 6.0, 40.0, 20.0, 80.0, 5.0, 30.0, 2000.0));
  cases.push_back(
      sine_case("sine h4 wl30 tilt0 yaw5, F2000", 4.0, 30.0, 20.0, 60.0, 0.0, 5.0, 2000.0));
  // A machine with slow rotary axes, at both feeds.
  for (std::size_t c = 1; c < 7; ++c) cases.push_back(slow_rotary(cases[c]));

  std::printf("bench_results %s (one run each, all threads)\n\n", data.c_str());
  if (!runtime_only) {
    std::printf(
        "| case | method | points | peak ω °/s | RMS ω °/s | RMS a °/s² | peak a °/s² | C jumps | "
        "colliding "
        "points | max dev ° | cycle s | feed-limited | tip path mm | runtime s |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  }
  struct Variant {
    Method method;
    GlobalObjective objective;
    const char* name;
  };
  const std::vector<Variant> variants = {
      {Method::None, GlobalObjective::SumSquares, "none"},
      {Method::Paper, GlobalObjective::SumSquares, "paper"},
      {Method::Global, GlobalObjective::SumSquares, "global"},
      {Method::Global, GlobalObjective::Peak, "global --objective peak"},
      {Method::Global, GlobalObjective::Time, "global --objective time"}};
  for (const Case& k : cases) {
    if (runtime_only) break;
    for (const Variant& var : variants) {
      const Row r = run(k, var.method, var.objective);
      for (const OperationResult& op : r.result.operations) {
        std::printf(
            "| %s | %s%s | %zu | %.1f | %.1f | %.1f | %.1f | %d | %ld | %.1f | %.1f | %.0f %% | "
            "%.0f | "
            "%.2f |\n",
            k.name.c_str(), var.name, r.result.ok() ? "" : " (exit 1)", op.points,
            op.after.max_omega_deg_s, op.after.rms_omega_deg_s, op.after.rms_accel_deg_s2,
            op.after.max_accel_deg_s2, op.after.c_jumps, op.colliding_after.value_or(-1),
            op.max_axis_change_deg, op.feed_after.cycle_time_s,
            100.0 * op.feed_after.feed_limited_fraction, op.feed_after.feed_path_mm, r.seconds);
      }
    }
  }

  std::printf(
      "\nRuntime as the points grow (sine h10, tilt 15, yaw 10, with the part; the whole run: "
      "contact recovery, optimisation, posting, feed schedule and verification):\n\n");
  std::printf(
      "| points | none s | paper s | global s | global --objective time s | paper µs/point | "
      "global µs/point | time µs/point |\n"
      "|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  struct Staged {
    std::size_t points;
    const char* method;
    Row row;
  };
  std::vector<Staged> stages;
  for (const auto& [width, length] :
       {std::pair<double, double>{18.0, 45.0}, {57.0, 143.0}, {180.0, 454.0}}) {
    const Case k = sine_case("scale", 10.0, 40.0, width, length, 15.0, 10.0);
    const std::size_t n = k.toolpath.operations.front().points.size();
    if (n > largest) break;
    const Row none = run(k, Method::None), paper = run(k, Method::Paper),
              global = run(k, Method::Global), time = run(k, Method::Global, GlobalObjective::Time);
    const double per = 1e6 / static_cast<double>(n);
    std::printf("| %zu | %.2f | %.2f | %.2f | %.2f | %.0f | %.0f | %.0f |%s\n", n, none.seconds,
                paper.seconds, global.seconds, time.seconds, per * paper.seconds,
                per * global.seconds, per * time.seconds,
                paper.result.ok() && global.result.ok() && time.result.ok() ? "" : " (problems)");
    stages.push_back({n, "paper", paper});
    stages.push_back({n, "global", global});
    stages.push_back({n, "global --objective time", time});
  }
  // Where the time goes: each stage's own wall time (the report's timings_s); "other" is the
  // rest of run_job (pose planning of the input, G-code written and read back, the schedule,
  // the report's rows).
  std::printf(
      "\nStages of the same runs (s; the report's timings_s):\n\n| points | method | run_job | "
      "contacts | optimise | post | verify | other |\n|---:|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [n, method, row] : stages) {
    double contacts = 0, optimise = 0, post = 0, verify = 0;
    for (const OperationResult& op : row.result.operations) {
      contacts += op.time_contacts_s;
      optimise += op.time_optimise_s;
      post += op.time_post_s;
      verify += op.time_verify_s;
    }
    std::printf("| %zu | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", n, method, row.seconds,
                contacts, optimise, post, verify,
                row.seconds - contacts - optimise - post - verify);
  }
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run_bench(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_results: %s\n", e.what());
    return 1;
  }
}
