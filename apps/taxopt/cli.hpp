#pragma once
// The command line's pieces (cli.md is the contract): its options, the generate subcommand,
// the main job's wiring of the library, and what it prints. Parsing and printing only: the
// work is the library's (taxopt/job.hpp).
#include <CLI/CLI.hpp>
#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "taxopt/geometry/raster_generator.hpp"
#include "taxopt/job.hpp"

namespace taxopt::cli {

/// The main job's options as typed.
struct Args {
  std::string objective = "sum-squares";
  std::optional<double> jerk_weight;
  std::string in, gcode, machine, method = "paper", report, points_csv, out_cls, units, units_out,
                                  part_units, part_frame = "auto";
  std::string arc_direction = "auto", msys = "ignore", dialect;
  std::vector<std::string> skip_records;
  std::optional<double> feed_mm_per_min, tool_radius, contact_tolerance, spindle_rpm;
  std::optional<int> tool_number;
  std::optional<double> shank_clearance_mm, holder_clearance_mm, part_tolerance;
  int threads = 0;
  bool force = false, quiet = false, feed_schedule = false;
  int verbose = 0;
  std::string part, plots, html;
  std::optional<double> grid, max_deviation, min_tilt, shank_radius, flute_length, holder_radius,
      holder_length, gauge_length;
  std::vector<double> work_offset;
};

/// Options of `taxopt generate` (lengths mm, angles deg), defaults = the paper's case.
struct GenerateArgs {
  std::string surface = "sine", out_cls, out_mesh;
  double height_mm = 10.0, wavelength_mm = 40.0, width_mm = 20.0, length_mm = 80.0;
  double mesh_step_mm = 0.5, feed_mm_per_min = 250.0, spindle_rpm = 3000.0;
  RasterOptions raster;
};

/// The subcommands and their own options.
struct Commands {
  GenerateArgs generate;
  std::string ini_in, machine_out, demo_out = "taxopt-demo";
  CLI::App *generate_cmd = nullptr, *machine_cmd = nullptr, *demo_cmd = nullptr;
};

/// "taxopt: error: what" on stderr; returns `code`.
int error(const std::string& what, int code);
/// --units / --units-out: in, mm or nothing.
std::optional<LengthUnit> parse_unit(const std::string& s, const char* option);

/// Every option, subcommand, help text and the footer of taxopt's command line.
void define_command_line(CLI::App& app, Args& a, Commands& c);

/// taxopt generate: a built-in surface's CL file and mesh.
int run_generate(const GenerateArgs& g);

/// Folder of the bundled data: $TAXOPT_DATA_DIR, else the installed share/taxopt/data beside
/// the executable, else the source tree this binary was built from.
std::string data_dir(const char* argv0);

/// How the run was started, for the report and the page.
struct Invocation {
  std::string command_line, started_utc;
  bool demo = false;
  std::string demo_out;
};
/// The main job: checks the outputs, reads the inputs, runs the library's job, prints what it
/// found and writes the outputs. The exit code (cli.md).
int run_main_job(Args& a, const Invocation& how);

/// Progress on stderr: a bar for each long stage when stderr is a terminal, and with -v the
/// time each stage took. Never on stdout (scripts read the summary table there).
class ProgressPrinter {
 public:
  ProgressPrinter(bool bar, bool timings) : bar_(bar), timings_(timings) {}
  void operator()(const std::string& stage, std::size_t done, std::size_t total) {
    if (total == 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (stage != stage_ || done == 0) stage_ = stage, start_ = now;
    if (bar_) {
      const std::size_t width = 30, filled = width * done / total;
      std::fprintf(stderr, "\r%-18s [%s%s] %3zu%%", stage.c_str(), std::string(filled, '#').c_str(),
                   std::string(width - filled, ' ').c_str(), 100 * done / total);
      if (done == total) std::fputc('\n', stderr);
      std::fflush(stderr);
    }
    if (timings_ && done == total) {
      std::fprintf(stderr, "taxopt: %s: %.2f s\n", stage.c_str(),
                   std::chrono::duration<double>(now - start_).count());
    }
  }

 private:
  bool bar_, timings_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
};

/// The table printed at the end of a run: per operation, before -> after.
void print_summary(const JobResult& result);
/// The job's errors, what was not checked, how the file was read and the warnings, on stderr.
void print_messages(const JobResult& result, const Toolpath& toolpath, const Args& a);

}  // namespace taxopt::cli
