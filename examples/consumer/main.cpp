// Loads a CL file (and, when given, the part mesh), optimises the tool axes with the paper's
// method for the built-in A/C machine, schedules the feeds at the machine's limits and writes
// LinuxCNC G-code through taxopt's public API. Ctrl-C stops the job (JobOptions::stop): nothing
// is written. The output is written atomically (OutputTransaction).
// Usage: taxopt_consumer IN.cls [PART.stl] OUT.ngc
#include <csignal>
#include <cstdio>
#include <iostream>
#include <optional>
#include <taxopt/core/error.hpp>
#include <taxopt/geometry/part.hpp>
#include <taxopt/io/atomic_file.hpp>
#include <taxopt/io/cl_file.hpp>
#include <taxopt/io/mesh_file.hpp>
#include <taxopt/job.hpp>

namespace {
// The job's stop, for the SIGINT handler (a lock-free atomic store: safe in a handler).
const taxopt::StopSource* g_stop = nullptr;
extern "C" void on_interrupt(int) {
  if (g_stop) g_stop->request_stop();
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::cerr << "usage: taxopt_consumer IN.cls [PART.stl] OUT.ngc\n";
    return 2;
  }
  try {
    const taxopt::Toolpath toolpath = taxopt::read_cl_file(argv[1]);
    taxopt::JobOptions options;
    // Ctrl-C from here on: building a big part's search structures takes seconds, and looks at
    // the same stop as the job.
    g_stop = &options.stop;
    std::signal(SIGINT, on_interrupt);
    std::optional<taxopt::Part> part;
    if (argc == 4) part.emplace(taxopt::read_mesh_file(argv[2]), options.stop);
    options.method = taxopt::Method::Paper;
    options.part = part ? &*part : nullptr;
    options.feed_schedule = true;
    // Where the CL file calls no tool or starts no spindle (NX files often do neither: the
    // post supplies them), the caller says which; without them run_job refuses the file.
    options.tool_number = 1;
    options.spindle_rpm = 1000.0;
    options.progress = [](const std::string& stage, std::size_t done, std::size_t total) {
      if (done == total && total > 0) std::fprintf(stderr, "%s: done\n", stage.c_str());
    };
    options.threads = 2;  // the job's own arena; the result is the same for any count
    const taxopt::JobResult result = taxopt::run_job(toolpath, taxopt::default_machine(), options);
    for (const auto& w : result.warnings) std::cerr << "warning: " << w << "\n";
    if (!result.ok()) {
      for (const auto& p : result.problems) std::cerr << p << "\n";
      return 1;
    }
    taxopt::OutputTransaction out;
    out.stage(argv[argc - 1], result.gcode.text);
    out.commit();
    for (const auto& op : result.operations) {
      std::printf(
          "%s: %zu points, peak omega %.1f -> %.1f deg/s, peak a %.1f -> %.1f deg/s^2, "
          "cycle %.1f -> %.1f s\n",
          op.name.c_str(), op.points, op.before.max_omega_deg_s, op.after.max_omega_deg_s,
          op.before.max_accel_deg_s2, op.after.max_accel_deg_s2, op.feed_before.cycle_time_s,
          op.feed_after.cycle_time_s);
    }
    return 0;
  } catch (const taxopt::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const taxopt::Cancelled& e) {
    std::cerr << "stopped: " << e.what() << " -- nothing written\n";
    return 130;
  }
}
