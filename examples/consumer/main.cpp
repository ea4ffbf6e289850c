// Loads a CL file, plans the A/C axes of the built-in machine and writes LinuxCNC G-code
// through taxopt's public API. Usage: taxopt_consumer IN.cls OUT.ngc
#include <cstdio>
#include <fstream>
#include <iostream>
#include <taxopt/core/error.hpp>
#include <taxopt/io/cl_file.hpp>
#include <taxopt/job.hpp>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: taxopt_consumer IN.cls OUT.ngc\n";
    return 2;
  }
  try {
    const taxopt::Toolpath toolpath = taxopt::read_cl_file(argv[1]);
    taxopt::JobOptions options;
    options.method = taxopt::Method::None;
    const taxopt::JobResult result = taxopt::run_job(toolpath, taxopt::default_machine(), options);
    if (!result.ok()) {
      for (const auto& p : result.problems) std::cerr << p << "\n";
      return 1;
    }
    std::ofstream(argv[2]) << result.gcode.text;
    for (const auto& op : result.operations) {
      std::printf("%s: %zu points, max omega %.1f deg/s, max a %.1f deg/s^2\n", op.name.c_str(),
                  op.points, op.after.max_omega_deg_s, op.after.max_accel_deg_s2);
    }
    return 0;
  } catch (const taxopt::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
}
