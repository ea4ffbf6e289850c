// Loads a CL file (and, when given, the part mesh), optimises the tool axes with the paper's
// method for the built-in A/C machine, schedules the feeds at the machine's limits and writes
// LinuxCNC G-code through taxopt's public API.
// Usage: taxopt_consumer IN.cls [PART.stl] OUT.ngc
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <taxopt/core/error.hpp>
#include <taxopt/geometry/part.hpp>
#include <taxopt/io/cl_file.hpp>
#include <taxopt/io/mesh_file.hpp>
#include <taxopt/job.hpp>

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::cerr << "usage: taxopt_consumer IN.cls [PART.stl] OUT.ngc\n";
    return 2;
  }
  try {
    const taxopt::Toolpath toolpath = taxopt::read_cl_file(argv[1]);
    std::optional<taxopt::Part> part;
    if (argc == 4) part.emplace(taxopt::read_mesh_file(argv[2]));
    taxopt::JobOptions options;
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
    const taxopt::JobResult result = taxopt::run_job(toolpath, taxopt::default_machine(), options);
    for (const auto& w : result.warnings) std::cerr << "warning: " << w << "\n";
    if (!result.ok()) {
      for (const auto& p : result.problems) std::cerr << p << "\n";
      return 1;
    }
    std::ofstream(argv[argc - 1]) << result.gcode.text;
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
  }
}
