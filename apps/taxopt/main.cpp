// taxopt command line: option parsing and wiring only (CLI.md is the contract).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>

#include "taxopt/core/digest.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/core/version.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/geometry/raster_generator.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"
#include "taxopt/io/atomic_file.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/html_page.hpp"
#include "taxopt/io/linuxcnc_ini.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/io/plots.hpp"
#include "taxopt/job.hpp"

namespace {

struct Args {
  std::string objective = "sum-squares";
  std::optional<double> jerk_weight;
  std::string in, gcode, machine, method = "paper", report, points_csv, out_cls, units, units_out;
  std::string arc_direction = "auto", msys = "ignore", dialect;
  std::vector<std::string> skip_records;
  std::optional<double> feed_mm_per_min, tool_radius, contact_tolerance, spindle_rpm;
  std::optional<int> tool_number;
  std::optional<double> shank_clearance_mm, holder_clearance_mm, part_tolerance;
  int threads = 0;
  bool force = false, quiet = false, feed_schedule = false;
  int verbose = 0;
  std::string part, plots, html;
  std::optional<double> grid, max_deviation, shank_radius, flute_length, holder_radius,
      holder_length, gauge_length;
};

int error(const std::string& what, int code) {
  std::cerr << "taxopt: error: " << what << "\n";
  return code;
}

std::optional<taxopt::LengthUnit> parse_unit(const std::string& s, const char* option) {
  if (s.empty()) return std::nullopt;
  if (s == "mm") return taxopt::LengthUnit::Millimetre;
  if (s == "in") return taxopt::LengthUnit::Inch;
  throw taxopt::InputError(std::string(option) + " expects 'in' or 'mm', got '" + s + "'");
}

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

/// "before -> after (-x %)".
std::string before_after(double before, double after, const char* format) {
  char b[32], a[32], pct[32] = "";
  std::snprintf(b, sizeof b, format, before);
  std::snprintf(a, sizeof a, format, after);
  if (before > 0.0) std::snprintf(pct, sizeof pct, " (%+.0f %%)", 100.0 * (after / before - 1.0));
  return std::string(b) + " -> " + a + pct;
}

/// The table printed at the end of a run: per operation, before -> after.
void print_summary(const taxopt::JobResult& result) {
  std::printf("%-20s %7s %-28s %-30s %-9s %-9s %7s %-26s %-26s %7s\n", "operation", "points",
              "peak omega deg/s", "peak a deg/s^2", "C jumps", "collide", "dev deg", "feed time s",
              "cycle time s", "time s");
  for (const auto& r : result.operations) {
    const auto count = [](long before, long after) {
      return before < 0 ? std::string("-") : std::to_string(before) + "->" + std::to_string(after);
    };
    const std::string collide = result.collision_checked
                                    ? count(r.colliding_before, r.colliding_after)
                                    : std::string("unchecked");
    std::printf(
        "%-20.20s %7zu %-28s %-30s %-9s %-9s %7.2f %-26s %-26s %7.2f\n", r.name.c_str(), r.points,
        before_after(r.before.max_omega_deg_s, r.after.max_omega_deg_s, "%.1f").c_str(),
        before_after(r.before.max_accel_deg_s2, r.after.max_accel_deg_s2, "%.1f").c_str(),
        count(r.before.c_jumps, r.after.c_jumps).c_str(), collide.c_str(), r.max_axis_change_deg,
        before_after(r.feed_before.feed_time_s, r.feed_after.feed_time_s, "%.1f").c_str(),
        before_after(r.feed_before.cycle_time_s, r.feed_after.cycle_time_s, "%.1f").c_str(),
        r.time_contacts_s + r.time_cspace_s + r.time_optimise_s + r.time_post_s + r.time_verify_s);
  }
}

/// Options of `taxopt generate` (lengths mm, angles deg), defaults = the paper's case.
struct GenerateArgs {
  std::string surface = "sine", out_cls, out_mesh;
  double height_mm = 10.0, wavelength_mm = 40.0, width_mm = 20.0, length_mm = 80.0;
  double mesh_step_mm = 0.5, feed_mm_per_min = 250.0, spindle_rpm = 3000.0;
  taxopt::RasterOptions raster;
};

/// Folder of the bundled data: $TAXOPT_DATA_DIR, else the installed share/taxopt/data beside
/// the executable, else the source tree this binary was built from.
std::string data_dir(const char* argv0) {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("TAXOPT_DATA_DIR")) return env;
  std::error_code ec;
  const fs::path exe = fs::canonical("/proc/self/exe", ec);
  const fs::path installed =
      (ec ? fs::path(argv0) : exe).parent_path() / ".." / "share" / "taxopt" / "data";
  if (fs::exists(installed / "demo", ec)) return installed.string();
  return TAXOPT_SOURCE_DATA_DIR;
}

int run_generate(const GenerateArgs& g) {
  if (g.out_cls.empty() && g.out_mesh.empty())
    return error("generate: give --out-cls and/or --out-mesh", 2);
  if (g.surface != "sine" && g.surface != "plane" && g.surface != "bump" && g.surface != "saddle") {
    return error("generate: --surface must be sine, plane, bump or saddle", 2);
  }
  // The outputs checked as the main job's are: not one file twice, nowhere they cannot be
  // written (a FIFO, a read-only file, a device).
  if (!g.out_cls.empty() && !g.out_mesh.empty() && taxopt::same_file(g.out_cls, g.out_mesh)) {
    return error("generate: --out-cls and --out-mesh name the same file " + g.out_cls, 2);
  }
  for (const auto& [opt, path] : {std::make_pair(std::string("--out-cls"), g.out_cls),
                                  std::make_pair(std::string("--out-mesh"), g.out_mesh)}) {
    if (path.empty()) continue;
    if (const std::string why = taxopt::writable_output_problem(path); !why.empty()) {
      return error("generate: " + opt + " " + path + ": cannot write there: " + why, 2);
    }
  }
  // Each option within what a part and a machine are (and NaN never): a bound with a reason,
  // checked before anything is allocated (issue 35).
  struct Bound {
    const char* name;
    double value, lo, hi;
    bool lo_open;
    const char* why;
  };
  const Bound bounds[] = {
      {"--height", g.height_mm, 0.0, 500.0, true, "mm: a part on a machine table"},
      {"--wavelength", g.wavelength_mm, 0.0, 2000.0, true, "mm"},
      {"--width", g.width_mm, 0.0, 2000.0, true, "mm: a machine's travel"},
      {"--length", g.length_mm, 0.0, 2000.0, true, "mm: a machine's travel"},
      {"--mesh-step", g.mesh_step_mm, 0.05, 50.0, false, "mm"},
      {"--feed", g.feed_mm_per_min, 0.01, 1e6, false, "mm/min"},
      {"--spindle", g.spindle_rpm, 0.0, 1e6, false, "rpm"},
      {"--tool-radius", g.raster.tool_radius_mm, 0.0, 100.0, true, "mm"},
      {"--scallop", g.raster.scallop_mm, 1e-4, 10.0, false, "mm"},
      {"--chord-error", g.raster.chord_error_mm, 1e-4, 10.0, false, "mm"},
      {"--tilt", g.raster.tilt_deg, -89.0, 89.0, false, "deg: the tool stays above the surface"},
      {"--yaw", g.raster.yaw_deg, -360.0, 360.0, false, "deg"},
  };
  for (const Bound& b : bounds) {
    const bool ok = (b.lo_open ? b.value > b.lo : b.value >= b.lo) && b.value <= b.hi;
    if (!ok) {
      std::ostringstream os;
      os << "generate: " << b.name << " must be within " << (b.lo_open ? "(" : "[") << b.lo << ", "
         << b.hi << "] " << b.why;
      return error(os.str(), 2);
    }
  }
  // Memory before allocating: the mesh's cells and the raster's points.
  const double reach = 2.0 * 4.0 * g.raster.tool_radius_mm;
  const double cells_budget = ((g.width_mm + reach) / g.mesh_step_mm + 1.0) *
                              ((g.length_mm + reach) / g.mesh_step_mm + 1.0);
  const double passes =
      g.width_mm / std::max(std::sqrt(8.0 * g.raster.tool_radius_mm * g.raster.scallop_mm), 1e-9);
  const double per_pass =
      g.length_mm / std::min(g.raster.max_step_mm,
                             std::sqrt(8.0 * g.raster.tool_radius_mm * g.raster.chord_error_mm));
  if (cells_budget > 5e6 || passes * per_pass > 5e6) {
    return error(
        "generate: more than 2e7 mesh cells or CL points (a budget of about 2 GB); "
        "coarsen --mesh-step, --scallop or --chord-error, or shrink --width/--length",
        2);
  }
  taxopt::SineSurfaced sine;
  sine.height_mm = g.height_mm;
  sine.wavelength_mm = g.wavelength_mm;
  sine.x1_mm = g.width_mm;
  sine.y1_mm = g.length_mm;
  taxopt::Planed plane;
  plane.u_size_mm = g.width_mm;
  plane.v_size_mm = g.length_mm;
  std::vector<taxopt::GeneratedPoint> pts;
  taxopt::TriangleMesh mesh;
  // The mesh extends beyond the path by the tool's reach so that a tool at the path's edge
  // still sees the part around it.
  const double margin = 4.0 * g.raster.tool_radius_mm;
  const auto cells = [&](double size) {
    return std::max(1, static_cast<int>(std::ceil(size / g.mesh_step_mm)));
  };
  try {
    // The raster over a surface on x, y, and its mesh over the domain grown by the margin.
    const auto raster_and_mesh = [&](const auto& surface) {
      pts = taxopt::generate_raster(surface, g.raster);
      auto big = surface;
      big.x0_mm -= margin, big.x1_mm += margin, big.y0_mm -= margin, big.y1_mm += margin;
      mesh = taxopt::tessellate(big, cells(big.x1_mm - big.x0_mm), cells(big.y1_mm - big.y0_mm));
    };
    if (g.surface == "sine") {
      raster_and_mesh(sine);
    } else if (g.surface == "bump" || g.surface == "saddle") {
      // Centred on the path's rectangle: the bump's sigma a quarter of --wavelength, the
      // saddle's half-widths the rectangle's; both --height high.
      const auto heightfield = [&](auto field) {
        raster_and_mesh(taxopt::HeightfieldSurface<double, decltype(field)>{
            {0.0, g.width_mm, 0.0, g.length_mm}, field});
      };
      if (g.surface == "bump") {
        heightfield(taxopt::BumpField<double>{g.height_mm, g.wavelength_mm / 4.0, g.width_mm / 2.0,
                                              g.length_mm / 2.0});
      } else {
        heightfield(taxopt::SaddleField<double>{g.height_mm, g.width_mm / 2.0, g.length_mm / 2.0,
                                                g.width_mm / 2.0, g.length_mm / 2.0});
      }
    } else {
      pts = taxopt::generate_raster(plane, g.raster);
      taxopt::Planed big = plane;
      big.origin = taxopt::Vec3d(-margin, -margin, 0.0);
      big.u_size_mm += 2 * margin, big.v_size_mm += 2 * margin;
      mesh = taxopt::tessellate(big, cells(big.u_size_mm), cells(big.v_size_mm));
    }
  } catch (const std::invalid_argument& e) {
    return error(std::string("generate: ") + e.what(), 2);
  }
  taxopt::Operationd op;
  op.name = g.surface == "sine" ? "SINE_FINISH" : "PLANE_FINISH";
  op.tool = taxopt::Tool::ball_end_mill(2 * g.raster.tool_radius_mm, 5 * g.raster.tool_radius_mm);
  op.tool.name =
      "BALL_MILL_D" + std::to_string(static_cast<int>(std::lround(2 * g.raster.tool_radius_mm)));
  op.tool.number = 1;
  op.spindle_rpm = g.spindle_rpm;
  std::size_t gouging = 0;
  for (const auto& p : pts) {
    taxopt::CLPointd c;
    c.tip_mm = p.tip_mm;
    c.axis = p.axis;
    c.motion = p.rapid ? taxopt::Motion::Rapid : taxopt::Motion::Feed;
    c.feed_mm_per_min = p.rapid ? 0.0 : g.feed_mm_per_min;
    op.points.push_back(c);
    gouging += p.gouges ? 1 : 0;
  }
  if (gouging) {
    return error(
        "generate: " + std::to_string(gouging) +
            " contact points have a concave radius below the tool radius: the ball "
            "would gouge (eq. 19); use a longer wavelength, a lower height or a smaller tool",
        2);
  }
  taxopt::OutputTransaction tx;
  if (!g.out_cls.empty()) tx.stage(g.out_cls, taxopt::format_new_cl({op}));
  if (!g.out_mesh.empty())
    tx.stage(g.out_mesh, taxopt::format_stl_binary(mesh, "taxopt generate " + g.surface));
  tx.commit();
  return 0;
}

}  // namespace

/// The command line as typed, each argument quoted where a shell would need it.
std::string quoted_command_line(int argc, char** argv) {
  std::string out;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool plain = !arg.empty() && arg.find_first_not_of(
                                           "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                           "0123456789-_./=:,+@%") == std::string::npos;
    if (i) out += ' ';
    if (plain) {
      out += arg;
    } else {
      out += '\'';
      for (char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
      out += '\'';
    }
  }
  return out;
}

/// Now, UTC, ISO 8601.
std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

int main(int argc, char** argv) {
  // A closed stdout (taxopt ... | head) is an error to write to, not a signal that kills the
  // run after its outputs were written (exit 141, issue 35).
  std::signal(SIGPIPE, SIG_IGN);
  // An interrupted run leaves no temporary file beside its outputs.
  taxopt::OutputTransaction::remove_pending_on_signals();
  const std::string command_line = quoted_command_line(argc, argv);
  const std::string started_utc = utc_now();
  Args a;
  CLI::App app{
      "taxopt: tool-axis optimisation for 5-axis ball-end finishing on A/C machines.\n"
      "Reads a cutter-location file, plans the machine's A/C axes and writes G-code.",
      "taxopt"};
  app.set_version_flag("--version", std::string("taxopt ") + taxopt::kVersion);
  app.add_option("--in", a.in, "cutter-location file (APT / NX CLSF)")
      ->check(CLI::ExistingFile)
      ->group("Input");
  app.add_option("--gcode", a.gcode, "G-code to write")->group("Outputs");
  app.add_option("--machine", a.machine, "machine file (TOML); default: generic A/C table-table")
      ->check(CLI::ExistingFile)
      ->group("Machine");
  app.add_option("--method", a.method, "none | paper | global (default paper)")
      ->check(CLI::IsMember({"none", "paper", "global"}))
      ->group("Method");
  app.add_option("--objective", a.objective,
                 "--method global: sum-squares (sum of squared rotary accelerations, default) | "
                 "peak (the largest one) | time (the cycle scheduled at the machine's limits)")
      ->check(CLI::IsMember({"sum-squares", "peak", "time"}))
      ->group("Method");
  app.add_option("--jerk-weight", a.jerk_weight,
                 "--method global: weight of the squared rotary jerk against the squared "
                 "acceleration, s^2 (default 0)")
      ->group("Method");
  app.add_option("--feed", a.feed_mm_per_min,
                 "feed for the metrics, mm/min (overrides FEDRAT; the feed written when the "
                 "file has none; default 1000)")
      ->group("Machine");
  app.add_option("--spindle-rpm", a.spindle_rpm,
                 "spindle speed of operations whose CL file has no SPINDL, rpm (before the "
                 "machine file's [defaults] spindle_rpm; none of them: exit 2)")
      ->group("Machine");
  app.add_option("--tool-number", a.tool_number,
                 "tool number of operations whose CL file calls no tool (LOADTL), 1 to 99999 "
                 "(before the machine file's [defaults] tool_number; none of them: exit 2)")
      ->group("Machine");
  app.add_option("--report", a.report, "JSON report to write")->group("Outputs");
  app.add_option("--points-csv", a.points_csv, "per-point CSV to write")->group("Outputs");
  app.add_option("--out-cls", a.out_cls, "optimised toolpath as a CL file")->group("Outputs");
  app.add_option("--html", a.html,
                 "one self-contained HTML page: the part, the tool axes before and after, where "
                 "every check fired, the rotary plots with the machine's limits")
      ->group("Outputs");
  app.add_option("--units", a.units, "units of the CL file: in | mm (default: from the file)")
      ->group("Input");
  app.add_option("--units-out", a.units_out, "units of the G-code: in | mm (default: as input)")
      ->group("Outputs");
  app.add_option("--dialect", a.dialect,
                 "G-code dialect, overriding the machine file's gcode.dialect: linuxcnc | fanuc "
                 "| siemens | heidenhain | haas")
      ->check(CLI::IsMember({"linuxcnc", "fanuc", "siemens", "heidenhain", "haas"}))
      ->group("Machine");
  app.add_option("--arc-direction", a.arc_direction,
                 "sense of CIRCLE arcs about their axis: auto (the CAM system's, checked against "
                 "the moves beside each arc) | cw | ccw")
      ->check(CLI::IsMember({"auto", "cw", "ccw"}))
      ->group("Input");
  app.add_option("--msys", a.msys,
                 "NX MSYS frames: ignore (default: post the coordinates as written, as NX's "
                 "own posts do) | apply (the coordinates are absolute: move them into the MCS)")
      ->check(CLI::IsMember({"apply", "ignore"}))
      ->group("Input");
  app.add_option("--skip-record", a.skip_records,
                 "skip every CL record with this major word (repeatable): a word taxopt does "
                 "not know, or one docs/cl-files.md marks skippable")
      ->group("Input");
  app.add_option("--tool-radius", a.tool_radius,
                 "ball radius, CL file units (default: TLDATA/CUTTER)")
      ->group("Tool");
  app.add_option("--part", a.part, "part mesh (STL, OBJ, OFF, PLY) in the CL file's coordinates")
      ->check(CLI::ExistingFile)
      ->group("Input");
  app.add_option(
         "--contact-tolerance", a.contact_tolerance,
         "largest | |C - Pc| - R | of a contact point, mm (default max(0.05, the mesh's chordal "
         "error + the CL file's INTOL/OUTTOL/TOLER band))")
      ->group("Input");
  app.add_option("--threads", a.threads, "worker threads, 1 to 1024 (default: all cores)")
      ->group("Diagnostics");
  app.add_flag("--feed-schedule", a.feed_schedule,
               "write per block the fastest feed the machine's limits allow (never above the "
               "programmed feed)")
      ->group("Machine");
  app.add_flag("--force", a.force, "write the G-code even when verification fails (exit 1)")
      ->group("Outputs");
  app.add_flag("-q,--quiet", a.quiet, "only errors and NOT CHECKED safety warnings on stderr")
      ->group("Diagnostics");
  app.add_flag("-v", a.verbose, "more on stderr")->group("Diagnostics");
  app.add_option("--shank-radius", a.shank_radius,
                 "shank radius, CL file units (default: the ball radius)")
      ->group("Tool");
  app.add_option("--flute-length", a.flute_length,
                 "flute length from the tip, CL file units (default: TLDATA/CUTTER)")
      ->group("Tool");
  app.add_option("--holder-radius", a.holder_radius,
                 "holder radius, CL file units (default: the machine file's [holder], else none)")
      ->group("Tool");
  app.add_option("--shank-clearance", a.shank_clearance_mm,
                 "distance the shank (past the flutes) keeps from the part in every check, mm "
                 "(default: the machine file's [checks], else 0.5)")
      ->group("Tool");
  app.add_option("--holder-clearance", a.holder_clearance_mm,
                 "distance the holder keeps from the part in every check, mm (default: the "
                 "machine file's [checks], else 1)")
      ->group("Tool");
  app.add_option("--part-tolerance", a.part_tolerance,
                 "how far the flutes may reach into the part mesh (its chordal error) without a "
                 "collision, mm (default: the contact tolerance)")
      ->group("Input");
  app.add_option("--holder-length", a.holder_length, "holder length, CL file units (default 40 mm)")
      ->group("Tool");
  app.add_option("--gauge-length", a.gauge_length,
                 "tip to holder face, CL file units (default: max(flute length, 10 diameters))")
      ->group("Tool");
  app.add_option("--grid", a.grid,
                 "C-space cell size, deg: spacing of the key-axis candidates and the global "
                 "method's finest (2)")
      ->group("Method");
  app.add_option("--max-deviation", a.max_deviation,
                 "largest angle between an output axis and its input axis, deg (30)")
      ->group("Method");
  app.add_option("--plots", a.plots,
                 "folder for SVG plots: A, C, omega and a against arc length, before and after; "
                 "C-space maps (with --part)")
      ->group("Outputs");

  GenerateArgs gen;
  auto* generate =
      app.add_subcommand("generate", "write a CL file and part mesh of a built-in surface");
  generate->add_option(
      "--surface", gen.surface,
      "sine (the paper's case) | plane | bump (a round bump, sigma = wavelength / 4) | saddle");
  generate->add_option("--out-cls", gen.out_cls, "CL file to write (NX CLSF, mm)");
  generate->add_option("--out-mesh", gen.out_mesh, "part mesh to write (binary STL, mm)");
  generate->add_option("--height", gen.height_mm, "sine amplitude, mm (10)");
  generate->add_option("--wavelength", gen.wavelength_mm, "sine wavelength along y, mm (40)");
  generate->add_option("--width", gen.width_mm, "extent along x (across the passes), mm (20)");
  generate->add_option("--length", gen.length_mm, "extent along y (the feed direction), mm (80)");
  generate->add_option("--tool-radius", gen.raster.tool_radius_mm, "ball radius, mm (3)");
  generate->add_option("--scallop", gen.raster.scallop_mm, "scallop height, mm (0.02)");
  generate->add_option("--chord-error", gen.raster.chord_error_mm, "chord error, mm (0.05)");
  generate->add_option("--tilt", gen.raster.tilt_deg, "tilt, deg (5)");
  generate->add_option("--yaw", gen.raster.yaw_deg, "yaw, deg (0)");
  generate->add_option("--feed", gen.feed_mm_per_min, "feed, mm/min (250)");
  generate->add_option("--spindle", gen.spindle_rpm, "spindle speed, rpm (3000)");
  generate->add_option("--mesh-step", gen.mesh_step_mm, "mesh grid spacing, mm (0.5)");
  std::string ini_in, machine_out;
  auto* machine_cmd = app.add_subcommand(
      "machine", "make a machine file from a LinuxCNC configuration (xyzac-trt-kins)");
  machine_cmd->add_option("--from-linuxcnc-ini", ini_in, "the configuration's INI file")
      ->required()
      ->check(CLI::ExistingFile);
  machine_cmd->add_option("--out", machine_out, "machine file to write (default: stdout)");
  std::string demo_out = "taxopt-demo";
  auto* demo = app.add_subcommand("demo", "run the bundled sine-surface case from data/");
  demo->add_option("--out", demo_out, "output folder (taxopt-demo)");

  // What each option takes, in words a user knows (not the parser's types).
  const std::map<std::string, std::string> takes = {{"--in", "FILE"},
                                                    {"--gcode", "FILE"},
                                                    {"--machine", "FILE"},
                                                    {"--method", "none|paper|global"},
                                                    {"--objective", "sum-squares|peak|time"},
                                                    {"--jerk-weight", "S^2"},
                                                    {"--feed", "MM/MIN"},
                                                    {"--report", "FILE"},
                                                    {"--points-csv", "FILE"},
                                                    {"--out-cls", "FILE"},
                                                    {"--units", "in|mm"},
                                                    {"--units-out", "in|mm"},
                                                    {"--arc-direction", "auto|cw|ccw"},
                                                    {"--msys", "ignore|apply"},
                                                    {"--dialect", "NAME"},
                                                    {"--skip-record", "WORD"},
                                                    {"--tool-radius", "LENGTH"},
                                                    {"--part", "FILE"},
                                                    {"--contact-tolerance", "MM"},
                                                    {"--threads", "N"},
                                                    {"--shank-radius", "LENGTH"},
                                                    {"--flute-length", "LENGTH"},
                                                    {"--holder-radius", "LENGTH"},
                                                    {"--shank-clearance", "MM"},
                                                    {"--holder-clearance", "MM"},
                                                    {"--part-tolerance", "MM"},
                                                    {"--holder-length", "LENGTH"},
                                                    {"--gauge-length", "LENGTH"},
                                                    {"--grid", "DEG"},
                                                    {"--max-deviation", "DEG"},
                                                    {"--plots", "FOLDER"},
                                                    {"--html", "FILE"}};
  for (CLI::Option* o : app.get_options()) {
    for (const auto& name : o->get_lnames()) {
      if (const auto t = takes.find("--" + name); t != takes.end()) o->option_text(t->second);
    }
  }
  // The global options may follow a subcommand too ("taxopt demo -q").
  generate->fallthrough();
  machine_cmd->fallthrough();
  demo->fallthrough();
  app.footer(
      "Exit codes: 0 written and verified; 1 verification failed or limits exceeded (nothing "
      "written\nwithout --force); 2 bad input or options (file, line and what was expected on "
      "stderr).\n\nExamples:\n"
      "  taxopt demo --out demo                       the bundled sine case, all outputs\n"
      "  taxopt --in path.cls --part part.stl --machine data/machines/paper-ac.toml \\\n"
      "         --gcode out.nc --report report.json   optimise, check against the part, post\n"
      "  taxopt machine --from-linuxcnc-ini my.ini --out my.toml\n"
      "Documentation: docs/cli.md (options, machine file, report), docs/gcode-dialects.md.");
  if (argc == 1) {
    std::cerr << "taxopt: nothing to do: give --in FILE --gcode FILE, or a subcommand (demo, "
                 "generate, machine)\nRun 'taxopt --help' for the options.\n";
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "taxopt: error: " << e.what() << "\nRun with --help for the options.\n";
    return 2;
  }

  if (app.count("--threads") && (a.threads < 1 || a.threads > 1024)) {
    return error("--threads must be a whole number from 1 to 1024", 2);
  }
  if (*generate) {
    try {
      return run_generate(gen);
    } catch (const taxopt::InputError& e) {
      return error(e.what(), 2);
    }
  }
  if (*machine_cmd) {
    try {
      const taxopt::ImportedMachine m = taxopt::machine_from_linuxcnc_ini(ini_in);
      for (const auto& note : m.assumptions) std::cerr << "taxopt: note: " << note << "\n";
      if (machine_out.empty()) {
        std::cout << m.toml;
        return 0;
      }
      if (const std::string why = taxopt::writable_output_problem(machine_out); !why.empty()) {
        return error("--out " + machine_out + ": " + why, 2);
      }
      taxopt::OutputTransaction out;
      out.stage(machine_out, m.toml);
      out.commit();
      return 0;
    } catch (const taxopt::InputError& e) {
      return error(e.what(), 2);
    }
  }
  if (*demo) {
    // The demo is the main job with the bundled files: the sine part's CL file on the
    // paper's machine (A limited to [-110, 30] deg).
    const std::string data = data_dir(argv[0]);
    if (!std::filesystem::exists(data + "/demo/sine.cls")) {
      return error(data + "/demo/sine.cls: demo data not found (set TAXOPT_DATA_DIR)", 2);
    }
    std::error_code ec;
    std::filesystem::create_directories(demo_out, ec);
    if (ec) return error(demo_out + ": cannot create folder: " + ec.message(), 2);
    a.in = data + "/demo/sine.cls";
    a.machine = data + "/machines/paper-ac.toml";
    a.part = data + "/demo/sine.stl";
    // A 15 mm stick-out (the flute length): with a longer tool the paper's input axes lean
    // the shank into the opposite flank of the sine (data/README.md); moving them clear is
    // the optimiser's work, not --method none's.
    if (!a.gauge_length) a.gauge_length = 15.0;
    a.gcode = demo_out + "/demo.nc";
    a.report = demo_out + "/report.json";
    a.points_csv = demo_out + "/points.csv";
    a.html = demo_out + "/demo.html";
    a.plots = demo_out + "/plots";
  }

  try {
    if (a.in.empty()) return error("--in is required", 2);
    if (a.gcode.empty() && a.out_cls.empty() && a.report.empty() && a.html.empty()) {
      return error("nothing to write: give --gcode, --out-cls, --report or --html", 2);
    }
    std::map<std::string, std::string> outputs;
    for (const auto& [opt, path] :
         std::map<std::string, std::string>{{"--gcode", a.gcode},
                                            {"--report", a.report},
                                            {"--points-csv", a.points_csv},
                                            {"--html", a.html},
                                            {"--out-cls", a.out_cls}}) {
      if (path.empty()) continue;
      // No output may replace an input (the CL file, the part, the machine file).
      for (const auto& [in_opt, in_path] : std::map<std::string, std::string>{
               {"--in", a.in}, {"--part", a.part}, {"--machine", a.machine}}) {
        if (!in_path.empty() && taxopt::same_file(path, in_path)) {
          return error(opt + " " + path + " is the " +
                           (in_opt == "--in" ? std::string("input") : in_opt) + " file",
                       2);
        }
      }
      // Nor may it lie in the plots folder (whose SVGs are written after it) or be that folder.
      if (!a.plots.empty()) {
        std::error_code ec;
        const auto dir =
            std::filesystem::weakly_canonical(std::filesystem::absolute(a.plots, ec), ec);
        const auto file =
            std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec);
        if (file == dir || file.parent_path() == dir) {
          return error(opt + " " + path + " lies in the --plots folder " + a.plots, 2);
        }
      }
      for (const auto& [other_opt, other] : outputs) {
        if (taxopt::same_file(path, other)) {
          return error(opt + " and " + other_opt + " name the same file " + path, 2);
        }
      }
      // Checked before any work: a run of minutes must not end in "cannot write".
      const std::string why = taxopt::writable_output_problem(path);
      if (!why.empty()) return error(opt + " " + path + ": cannot write there: " + why, 2);
      outputs[opt] = path;
    }
    if (!a.plots.empty()) {
      std::error_code ec;
      const auto plots_dir = std::filesystem::absolute(a.plots, ec);
      if (std::filesystem::exists(plots_dir, ec) && !std::filesystem::is_directory(plots_dir, ec)) {
        return error("--plots " + a.plots + " is a file, not a folder", 2);
      }
    }

    // The method's numbers, before any file is read (the library refuses them too, naming the
    // JobOptions field).
    if (a.jerk_weight && !(*a.jerk_weight >= 0.0 && std::isfinite(*a.jerk_weight))) {
      return error("--jerk-weight must be a number >= 0 (s^2)", 2);
    }
    if (a.max_deviation && !(*a.max_deviation >= 0.0 && *a.max_deviation <= 90.0)) {
      return error("--max-deviation must be within [0, 90] deg", 2);
    }
    if (a.grid && !(*a.grid >= 0.1 && *a.grid <= 10.0)) {
      return error("--grid must be within [0.1, 10] deg", 2);
    }
    if (a.feed_mm_per_min && !(*a.feed_mm_per_min >= 0.01 && *a.feed_mm_per_min <= 1e6))
      return error("--feed must be within [0.01, 1e6] mm/min", 2);
    if (a.spindle_rpm && !(*a.spindle_rpm >= 1.0 && *a.spindle_rpm <= 2e5))
      return error("--spindle-rpm must be within [1, 200000] rpm", 2);
    if (a.tool_number && !(*a.tool_number >= 1 && *a.tool_number <= 99999))
      return error("--tool-number must be a whole number from 1 to 99999", 2);
    taxopt::Machine machine =
        a.machine.empty() ? taxopt::default_machine() : taxopt::read_machine_file(a.machine);
    if (!a.dialect.empty() && a.dialect != taxopt::to_string(machine.gcode.dialect)) {
      // --dialect overrides the machine file's gcode.dialect, under the same rules: a program
      // template written for the file's dialect is not another's, and the decimals must fit.
      const taxopt::ProgramTemplate& t = machine.gcode.program;
      // A work offset is a dialect's word too (Sinumerik G505 is out of LinuxCNC's range).
      const bool own_work_offset = !t.work_offset.empty() && t.work_offset != "none";
      if (!t.header.empty() || !t.footer.empty() || !t.tool_change.empty() || !t.tcp_on.empty() ||
          !t.tcp_off.empty() || own_work_offset) {
        return error("--dialect " + a.dialect + ": the machine file's program template " +
                         "(header, footer, tool_change, tcp_on, tcp_off, work_offset) is written "
                         "for the " +
                         taxopt::to_string(machine.gcode.dialect) +
                         " dialect; change gcode.dialect in the file instead",
                     2);
      }
      for (const auto d : {taxopt::GcodeDialect::LinuxCNC, taxopt::GcodeDialect::Fanuc,
                           taxopt::GcodeDialect::Siemens, taxopt::GcodeDialect::Heidenhain,
                           taxopt::GcodeDialect::Haas}) {
        if (a.dialect == taxopt::to_string(d)) machine.gcode.dialect = d;
      }
      if (machine.gcode.decimals > taxopt::max_decimals(machine.gcode.dialect) ||
          machine.gcode.feed_decimals > taxopt::max_feed_decimals(machine.gcode.dialect)) {
        return error("--dialect " + a.dialect + ": the machine file's gcode.decimals or " +
                         "feed_decimals are more than the " + a.dialect + " dialect takes",
                     2);
      }
      if (machine.gcode.dialect == taxopt::GcodeDialect::Heidenhain &&
          machine.gcode.feed_mode == taxopt::FeedMode::InverseTime) {
        return error(
            "--dialect heidenhain: the machine's gcode.feed_mode is inverse-time, which "
            "the heidenhain dialect does not write (its ISO mode has no G93)",
            2);
      }
    }
    taxopt::ClReadOptions read_options;
    read_options.units = parse_unit(a.units, "--units");
    read_options.arc_direction = a.arc_direction == "cw"    ? taxopt::ArcDirection::Clockwise
                                 : a.arc_direction == "ccw" ? taxopt::ArcDirection::CounterClockwise
                                                            : taxopt::ArcDirection::Auto;
    read_options.apply_msys = a.msys == "apply";
    for (std::string w : a.skip_records) {
      for (auto& ch : w) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      read_options.skip_records.insert(w);
    }
    // The page's libraries are read before any work: a run must not end in "cannot embed".
    std::optional<taxopt::HtmlAssets> html_assets;
    if (!a.html.empty()) {
      const char* dir = std::getenv("TAXOPT_JAVASCRIPT_DIR");
      html_assets = taxopt::load_html_assets(dir && *dir ? dir : taxopt::kDefaultJavascriptDir);
    }
    taxopt::Toolpath toolpath = taxopt::read_cl_file(a.in, read_options);

    if (a.tool_radius && !(*a.tool_radius > 0.0)) {
      return error("--tool-radius must be positive", 2);
    }
    // Plots: five SVG files an operation (and C-space maps); 20,000 operations wrote 100,000
    // files, 468 MB (issue 35). A page of plots beyond a few hundred operations helps no one.
    constexpr std::size_t kMostPlottedOperations = 200;
    if (!a.plots.empty() && toolpath.operations.size() > kMostPlottedOperations) {
      return error("--plots: the CL file has " + std::to_string(toolpath.operations.size()) +
                       " operations; plots are written for at most " +
                       std::to_string(kMostPlottedOperations) +
                       " (about 5 SVG files each): split the file, or leave out --plots",
                   2);
    }
    // The part is in the CL file's units and coordinates (docs/cli.md).
    std::optional<taxopt::Part> part;
    if (!a.part.empty()) {
      std::string frame_note;
      std::optional<double> radius_mm;
      if (a.tool_radius) radius_mm = *a.tool_radius * taxopt::mm_per_unit(toolpath.units);
      part.emplace(taxopt::part_mesh_for(toolpath, taxopt::read_mesh_file(a.part), toolpath.units,
                                         &frame_note, radius_mm));
      if (!frame_note.empty() && !a.quiet) std::cerr << "taxopt: note: " << frame_note << "\n";
    }
    taxopt::JobOptions options;
    // The job's own arena: --threads workers, else all cores.
    options.threads = a.threads > 0 ? static_cast<std::size_t>(a.threads) : 0;
    if (part) options.part = &*part;
    options.count_free_cells = !a.points_csv.empty();
    options.cspace_maps = !a.plots.empty();
    options.feed_schedule = a.feed_schedule;
    ProgressPrinter printer(!a.quiet && isatty(STDERR_FILENO), !a.quiet && a.verbose > 0);
    if (!a.quiet) {
      options.progress = [&printer](const std::string& stage, std::size_t done, std::size_t total) {
        printer(stage, done, total);
      };
    }
    if (!a.quiet && a.verbose > 0) {
      options.log = [](const std::string& line) {
        std::fprintf(stderr, "taxopt: %s\n", line.c_str());
      };
    }
    {
      // Tool dimensions are in the CL file's units; none larger than a metre.
      const double u = taxopt::mm_per_unit(toolpath.units);
      for (const auto& [name, v] : {std::make_pair("--tool-radius", a.tool_radius),
                                    std::make_pair("--shank-radius", a.shank_radius),
                                    std::make_pair("--flute-length", a.flute_length),
                                    std::make_pair("--holder-radius", a.holder_radius),
                                    std::make_pair("--holder-length", a.holder_length),
                                    std::make_pair("--gauge-length", a.gauge_length)}) {
        if (v && !(*v > 0.0 && *v * u <= 1000.0)) {
          return error(std::string(name) + " must be within (0, 1000] mm (in the CL file's " +
                           taxopt::to_string(toolpath.units) + ")",
                       2);
        }
      }
      options.tool =
          taxopt::tool_overrides({toolpath.units, a.tool_radius, a.shank_radius, a.flute_length,
                                  a.holder_radius, a.holder_length, a.gauge_length});
      // The machine file's holder and clearances apply where these name none (the library's
      // resolved_options).
    }
    if (a.contact_tolerance) {
      // Beyond a millimetre a contact is no contact: the gouge and flute checks would be off.
      if (!(*a.contact_tolerance > 0.0 && *a.contact_tolerance <= 1.0)) {
        return error("--contact-tolerance must be within (0, 1] mm", 2);
      }
      options.contact.tolerance_mm = *a.contact_tolerance;
    }
    options.method = a.method == "none"    ? taxopt::Method::None
                     : a.method == "paper" ? taxopt::Method::Paper
                                           : taxopt::Method::Global;
    options.global.objective = a.objective == "peak"   ? taxopt::GlobalObjective::Peak
                               : a.objective == "time" ? taxopt::GlobalObjective::Time
                                                       : taxopt::GlobalObjective::SumSquares;
    if (a.jerk_weight) options.global.jerk_weight_s2 = *a.jerk_weight;
    if (a.grid) options.paper.grid_deg = *a.grid;
    options.max_deviation_deg = a.max_deviation;
    // Clearances a machine keeps (50 mm is more than any holder's), and a part tolerance that
    // is still one (1 mm): larger values turn the checks off or make them hang.
    for (const auto& [name, v, most] :
         {std::make_tuple("--shank-clearance", a.shank_clearance_mm, 50.0),
          std::make_tuple("--holder-clearance", a.holder_clearance_mm, 50.0),
          std::make_tuple("--part-tolerance", a.part_tolerance, 1.0)}) {
      if (v && !(*v >= 0.0 && *v <= most)) {
        std::ostringstream os;
        os << name << " must be within [0, " << most << "] mm";
        return error(os.str(), 2);
      }
    }
    options.shank_clearance_mm = a.shank_clearance_mm;
    options.holder_clearance_mm = a.holder_clearance_mm;
    options.part_tolerance_mm = a.part_tolerance;
    options.feed_mm_per_min = a.feed_mm_per_min;
    options.spindle_rpm = a.spindle_rpm;
    options.tool_number = a.tool_number;
    options.units_out = parse_unit(a.units_out, "--units-out");
    const taxopt::JobResult result = taxopt::run_job(toolpath, machine, options);

    // Errors first (the first 10; -v all of them), then how the file was read, then warnings.
    const std::size_t shown = a.verbose > 0 ? result.problems.size() : 10;
    for (std::size_t i = 0; i < result.problems.size() && i < shown; ++i) {
      std::cerr << "taxopt: error: " << result.problems[i] << "\n";
    }
    if (result.problems.size() > shown) {
      std::cerr << "taxopt: error: ... and " << result.problems.size() - shown
                << " more (-v lists them all)\n";
    }
    // What was not checked first (even with -q: -q silences progress and notes, never a
    // safety warning), then how the file was read, then the other warnings.
    for (const auto& w : result.safety_warnings) {
      std::cerr << "taxopt: warning: NOT CHECKED: " << w << "\n";
    }
    if (!a.quiet) {
      for (const auto& n : toolpath.notices) std::cerr << "taxopt: note: " << n << "\n";
      for (const auto& w : result.warnings) std::cerr << "taxopt: warning: " << w << "\n";
      if (a.verbose > 0) {
        // Each stage's own time over all operations (the report's timings_s per operation).
        double t[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        for (const auto& r : result.operations) {
          t[0] += r.time_contacts_s;
          t[1] += r.time_cspace_s;
          t[2] += r.time_optimise_s;
          t[3] += r.time_post_s;
          t[4] += r.time_verify_s;
        }
        std::fprintf(stderr,
                     "taxopt: stage times: contacts %.2f s, cspace %.2f s, optimise %.2f s, "
                     "post %.2f s, verify %.2f s\n",
                     t[0], t[1], t[2], t[3], t[4]);
        for (const auto& [word, count] : toolpath.skipped_records) {
          std::cerr << "taxopt: note: " << count << " " << word
                    << " record(s) skipped (no motion), kept for --out-cls\n";
        }
      }
      // Records skipped by --skip-record are said even with -q: the user decided, the
      // program lacks them.
      for (const auto& [word, count] : toolpath.skipped_by_option) {
        std::cerr << "taxopt: note: " << count << " " << word
                  << " record(s) skipped as asked (--skip-record " << word << ")\n";
      }
    }
    if (!result.ok() && !a.force) {
      std::cerr << "taxopt: no output written (--force writes it anyway)\n";
      return 1;
    }
    if (!a.gcode.empty() && result.gcode.text.find_first_of("\n") == std::string::npos) {
      return error("no G-code to write: no point of the program could be posted" +
                       (result.problems.empty() ? std::string() : " (" + result.problems[0] + ")"),
                   1);
    }
    taxopt::OutputTransaction tx;
    if (!a.gcode.empty()) tx.stage(a.gcode, result.gcode.text);
    if (!a.out_cls.empty()) tx.stage(a.out_cls, result.out_cls);
    if (!a.report.empty()) {
      taxopt::RunInfo run;
      run.command_line = command_line;
      run.started_utc = started_utc;
      if (!a.machine.empty()) {
        run.machine_file = a.machine;
        std::ifstream m(a.machine, std::ios::binary);
        std::ostringstream bytes;
        bytes << m.rdbuf();
        run.machine_sha256 = taxopt::sha256_hex(bytes.str());
      }
      run.part_file = a.part;
      tx.stage(a.report, taxopt::report_json(result, toolpath, machine, options, run));
    }
    if (!a.points_csv.empty()) tx.stage(a.points_csv, taxopt::points_csv(result));
    if (!a.html.empty()) {
      taxopt::RunInfo run;
      run.command_line = command_line;
      run.started_utc = started_utc;
      run.machine_file = a.machine;
      run.part_file = a.part;
      tx.stage(a.html, taxopt::html_page(result, toolpath, machine, options, run,
                                         part ? &part->mesh() : nullptr, *html_assets));
    }
    if (!a.plots.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(a.plots, ec);
      if (ec) return error(a.plots + ": cannot create folder: " + ec.message(), 2);
      for (const auto& [name, svg] : taxopt::job_plots(result)) tx.stage(a.plots + "/" + name, svg);
    }
    tx.commit();
    if (!a.quiet) print_summary(result);
    if (*demo && !a.quiet) {
      // What it wrote, and what to look at first.
      std::printf(
          "\ntaxopt demo wrote %s/: demo.nc (the G-code), report.json, points.csv, plots/ "
          "and demo.html.\nOpen %s/demo.html first: the part, the tool axes before and "
          "after, and the rotary axes' plots.\n",
          demo_out.c_str(), demo_out.c_str());
    }
    return result.ok() ? 0 : 1;
  } catch (const taxopt::InputError& e) {
    return error(e.what(), 2);
  } catch (const std::bad_alloc&) {
    // Not a failed verification (exit 1): the input is larger than this machine's memory.
    return error(
        "out of memory: the part, the CL file or an option's resolution needs more "
        "memory than this machine gives (docs/cli.md \"Bounds\"); nothing written",
        2);
  } catch (const std::exception& e) {
    return error(std::string("internal error: ") + e.what(), 1);
  }
}
