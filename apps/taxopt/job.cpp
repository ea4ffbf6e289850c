// The main job on the command line: the options checked and turned into the library's inputs,
// the job run, its messages printed and its outputs written in one transaction.
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <iostream>
#include <map>
#include <sstream>
#include <tuple>

#include "cli.hpp"
#include "support/digest.hpp"
#include "support/html_page.hpp"
#include "support/plots.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/atomic_file.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/io/mesh_file.hpp"

namespace taxopt::cli {
namespace {

/// An option refused: its message and exit code (cli.md), printed by run_main_job.
struct Refused {
  std::string what;
  int code;
};
[[noreturn]] void refuse(const std::string& what, int code = 2) { throw Refused{what, code}; }

/// The input option (--in, --part, --machine) whose file `path` is, else nullopt.
std::optional<std::pair<std::string, std::string>> input_at(const Args& a,
                                                            const std::string& path) {
  for (const auto& [opt, in_path] : std::map<std::string, std::string>{
           {"--in", a.in}, {"--part", a.part}, {"--machine", a.machine}}) {
    if (!in_path.empty() && same_file(path, in_path)) return std::make_pair(opt, in_path);
  }
  return std::nullopt;
}

/// The outputs: given, none of them an input or another output, none in the plots folder, each
/// writable, checked before any work (a run of minutes must not end in "cannot write").
void check_outputs(const Args& a) {
  if (a.in.empty()) refuse("--in is required");
  if (a.gcode.empty() && a.out_cls.empty() && a.report.empty() && a.html.empty()) {
    refuse("nothing to write: give --gcode, --out-cls, --report or --html");
  }
  std::map<std::string, std::string> outputs;
  for (const auto& [opt, path] : std::map<std::string, std::string>{{"--gcode", a.gcode},
                                                                    {"--report", a.report},
                                                                    {"--points-csv", a.points_csv},
                                                                    {"--html", a.html},
                                                                    {"--out-cls", a.out_cls}}) {
    if (path.empty()) continue;
    // No output may replace an input (the CL file, the part, the machine file).
    if (const auto in = input_at(a, path)) {
      refuse(opt + " " + path + " is the " +
             (in->first == "--in" ? std::string("input") : in->first) + " file");
    }
    // Nor may it lie in the plots folder (whose SVGs are written after it) or be that folder.
    if (!a.plots.empty()) {
      std::error_code ec;
      const auto dir =
          std::filesystem::weakly_canonical(std::filesystem::absolute(a.plots, ec), ec);
      const auto file = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec);
      if (file == dir || file.parent_path() == dir) {
        refuse(opt + " " + path + " lies in the --plots folder " + a.plots);
      }
    }
    for (const auto& [other_opt, other] : outputs) {
      if (same_file(path, other)) {
        refuse(opt + " and " + other_opt + " name the same file " + path);
      }
    }
    // Checked before any work: a run of minutes must not end in "cannot write".
    const std::string why = writable_output_problem(path);
    if (!why.empty()) refuse(opt + " " + path + ": cannot write there: " + why);
    outputs[opt] = path;
  }
  if (!a.plots.empty()) {
    std::error_code ec;
    const auto plots_dir = std::filesystem::absolute(a.plots, ec);
    if (std::filesystem::exists(plots_dir, ec) && !std::filesystem::is_directory(plots_dir, ec)) {
      refuse("--plots " + a.plots + " is a file, not a folder");
    }
  }
}

/// The library's option fields as this command line names them: its messages then name the
/// flag to give (taxopt/core/option_names.hpp).
const OptionNames& cli_option_names() {
  static const OptionNames names = {
      {"JobOptions::part", "--part"},
      {"JobOptions::max_deviation_deg", "--max-deviation"},
      {"JobOptions::min_tilt_deg", "--min-tilt"},
      {"JobOptions::work_offset_mm", "--work-offset"},
      {"JobOptions::paper.grid_deg", "--grid"},
      {"JobOptions::global.jerk_weight_s2", "--jerk-weight"},
      {"JobOptions::feed_mm_per_min", "--feed"},
      {"JobOptions::feed_schedule", "--feed-schedule"},
      {"JobOptions::contact.tolerance_mm", "--contact-tolerance"},
      {"JobOptions::part_tolerance_mm", "--part-tolerance"},
      {"JobOptions::shank_clearance_mm", "--shank-clearance"},
      {"JobOptions::holder_clearance_mm", "--holder-clearance"},
      {"JobOptions::tool.ball_radius_mm", "--tool-radius"},
      {"JobOptions::tool.shank_radius_mm", "--shank-radius"},
      {"JobOptions::tool.flute_length_mm", "--flute-length"},
      {"JobOptions::tool.holder_radius_mm", "--holder-radius"},
      {"JobOptions::tool.holder_length_mm", "--holder-length"},
      {"JobOptions::tool.gauge_length_mm", "--gauge-length"},
      {"JobOptions::spindle_rpm", "--spindle-rpm"},
      {"JobOptions::tool_number", "--tool-number"},
      {"JobOptions::threads", "--threads"},
      {"ClReadOptions::skip_records", "--skip-record"},
      {"ClReadOptions::arc_direction", "--arc-direction"},
      {"ClReadOptions::units", "--units"},
      {"ClReadOptions::apply_msys", "--msys apply"},
      {"part_mesh_for::mesh_units", "--part-units"},
      // The machine's fields as its file names them.
      {"Machine::default_tool_number", "tool_number in the machine file's [defaults]"},
      {"Machine::default_spindle_rpm", "spindle_rpm in the machine file's [defaults]"},
      {"Machine::work_offset_mm", "the machine file's [setup] work_offset_mm"},
      {"Machine::gcode.program.retract", "the machine file's gcode.safe_retract"},
      {"Machine::gcode.program.coolant", "the machine file's gcode.coolant"},
      {"Machine::gcode.program.linearise_tolerance_mm",
       "the machine file's gcode.linearise_tolerance_mm"},
  };
  return names;
}

/// The machine: its file (else the built-in one), with --dialect over its gcode.dialect.
Machine machine_of(const Args& a) {
  Machine machine = a.machine.empty() ? default_machine() : read_machine_file(a.machine);
  if (!a.dialect.empty() && a.dialect != to_string(machine.gcode.dialect)) {
    // --dialect overrides the machine file's gcode.dialect, under the same rules: a program
    // template written for the file's dialect is not another's, and the decimals must fit.
    const ProgramTemplate& t = machine.gcode.program;
    // A work offset is a dialect's word too (Sinumerik G505 is out of LinuxCNC's range).
    const bool own_work_offset = !t.work_offset.empty() && t.work_offset != "none";
    if (!t.header.empty() || !t.footer.empty() || !t.tool_change.empty() || !t.tcp_on.empty() ||
        !t.tcp_off.empty() || own_work_offset) {
      refuse("--dialect " + a.dialect + ": the machine file's program template " +
             "(header, footer, tool_change, tcp_on, tcp_off, work_offset) is written "
             "for the " +
             to_string(machine.gcode.dialect) +
             " dialect; change gcode.dialect in the file instead");
    }
    for (const GcodeDialect d : gcode_dialects()) {
      if (a.dialect == to_string(d)) machine.gcode.dialect = d;
    }
    if (machine.gcode.decimals > max_decimals(machine.gcode.dialect) ||
        machine.gcode.feed_decimals > max_feed_decimals(machine.gcode.dialect)) {
      refuse("--dialect " + a.dialect + ": the machine file's gcode.decimals or " +
             "feed_decimals are more than the " + a.dialect + " dialect takes");
    }
    if (!has_inverse_time(machine.gcode.dialect) &&
        machine.gcode.feed_mode == FeedMode::InverseTime) {
      refuse("--dialect " + a.dialect + ": the machine's gcode.feed_mode is inverse-time, which " +
             "the " + a.dialect + " dialect does not write (its ISO mode has no G93)");
    }
  }
  return machine;
}

ClReadOptions read_options_of(const Args& a) {
  ClReadOptions read_options;
  read_options.option_names = cli_option_names();
  read_options.units = parse_unit(a.units, "--units");
  read_options.arc_direction = a.arc_direction == "cw"    ? ArcDirection::Clockwise
                               : a.arc_direction == "ccw" ? ArcDirection::CounterClockwise
                                                          : ArcDirection::Auto;
  read_options.apply_msys = a.msys == "apply";
  for (std::string w : a.skip_records) {
    for (auto& ch : w) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    read_options.skip_records.insert(w);
  }
  return read_options;
}

/// The part mesh file read (`--part`), on a thread of its own beside the CL file's reading
/// unless the run has one thread: its error, if any, comes where it always did, after the CL
/// file's (get()).
std::future<TriangleMesh> mesh_file_of(const Args& a) {
  const auto how = a.threads == 1 ? std::launch::deferred : std::launch::async;
  return std::async(
      how, [path = a.part] { return path.empty() ? TriangleMesh{} : read_mesh_file(path); });
}

/// The part mesh in the CL file's units and coordinates, with its frame note; its build's
/// progress to `progress`.
std::optional<Part> part_of(
    const Args& a, const Toolpath& toolpath, std::future<TriangleMesh>& mesh_file,
    const std::function<void(const std::string&, std::size_t, std::size_t)>& progress) {
  std::optional<Part> part;
  if (!a.part.empty()) {
    std::string frame_note;
    std::optional<double> radius_mm;
    if (a.tool_radius) radius_mm = *a.tool_radius * mm_per_unit(toolpath.units);
    const MeshFrame frame = a.part_frame == "mcs"        ? MeshFrame::Mcs
                            : a.part_frame == "absolute" ? MeshFrame::Absolute
                                                         : MeshFrame::Auto;
    part.emplace(part_mesh_for(toolpath, mesh_file.get(),
                               parse_unit(a.part_units, "--part-units").value_or(toolpath.units),
                               frame, &frame_note, radius_mm),
                 StopSource(), progress);
    if (!frame_note.empty() && !a.quiet) std::cerr << "taxopt: note: " << frame_note << "\n";
  }
  return part;
}

/// The job's options from the command line (the tool's dimensions come with the CL file's
/// units: tool_dimensions_of). The library checks every value (check_options), naming the flag.
JobOptions job_options_of(const Args& a) {
  JobOptions options;
  options.option_names = cli_option_names();
  // The job's own arena: --threads workers, else all cores.
  options.threads = a.threads > 0 ? static_cast<std::size_t>(a.threads) : 0;
  options.count_free_cells = !a.points_csv.empty();
  options.cspace_maps = !a.plots.empty();
  options.feed_schedule = a.feed_schedule;
  if (a.contact_tolerance) {
    // The library's 0 means "the default"; on the command line that is leaving it out (a 0
    // given silently meant the default, issue 63.12).
    if (*a.contact_tolerance == 0.0) {
      refuse("--contact-tolerance must be within (0, 1] mm, got 0 (leave it out for the default)");
    }
    options.contact.tolerance_mm = *a.contact_tolerance;
  }
  options.method = a.method == "none"    ? Method::None
                   : a.method == "paper" ? Method::Paper
                                         : Method::Global;
  options.global.objective = a.objective == "peak"   ? GlobalObjective::Peak
                             : a.objective == "time" ? GlobalObjective::Time
                                                     : GlobalObjective::SumSquares;
  if (a.jerk_weight) options.global.jerk_weight_s2 = *a.jerk_weight;
  if (a.grid) options.paper.grid_deg = *a.grid;
  options.max_deviation_deg = a.max_deviation;
  options.min_tilt_deg = a.min_tilt;
  if (a.work_offset.size() == 3) {
    options.work_offset_mm = Vec3d(a.work_offset[0], a.work_offset[1], a.work_offset[2]);
  }
  options.shank_clearance_mm = a.shank_clearance_mm;
  options.holder_clearance_mm = a.holder_clearance_mm;
  options.part_tolerance_mm = a.part_tolerance;
  options.feed_mm_per_min = a.feed_mm_per_min;
  options.spindle_rpm = a.spindle_rpm;
  options.tool_number = a.tool_number;
  options.units_out = parse_unit(a.units_out, "--units-out");
  return options;
}

/// The tool's dimensions (--tool-radius ...), given in the CL file's units, in mm.
ToolOverrides tool_dimensions_of(const Args& a, const Toolpath& toolpath) {
  return tool_overrides({toolpath.units, a.tool_radius, a.shank_radius, a.flute_length,
                         a.holder_radius, a.holder_length, a.gauge_length});
}

/// The report's and page's account of the run.
RunInfo run_info(const Args& a, const Invocation& how, bool digest) {
  RunInfo run;
  run.command_line = how.command_line;
  run.started_utc = how.started_utc;
  run.machine_file = a.machine;
  if (digest && !a.machine.empty()) {
    std::ifstream m(a.machine, std::ios::binary);
    std::ostringstream bytes;
    bytes << m.rdbuf();
    run.machine_sha256 = sha256_hex(bytes.str());
  }
  run.part_file = a.part;
  return run;
}

/// The folders `dir` needs made, deepest first (none when it exists).
std::vector<std::string> folders_to_make(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  std::error_code ec;
  for (fs::path p = fs::absolute(dir, ec).lexically_normal(); !p.empty() && !fs::exists(p, ec);
       p = p.parent_path()) {
    if (p.has_filename()) out.push_back(p.string());
    if (p == p.parent_path()) break;
  }
  return out;
}

/// Removes the folders a failed run made, deepest first, each only if empty.
void remove_made_folders(const std::vector<std::string>& made) {
  std::error_code ec;
  for (const std::string& d : made) std::filesystem::remove(d, ec);
}

/// Stages the plots in the --plots folder (made here, the folders it made in `made`), after
/// checking each plot's path as an output's: never an input, a link (renaming over it would
/// replace the link), a folder or a read-only file.
void stage_plots(const Args& a, const JobResult& result, OutputTransaction& tx,
                 std::vector<std::string>& made) {
  if (a.plots.empty()) return;
  const std::vector<std::pair<std::string, std::string>> plots = job_plots(result);
  for (const auto& [name, svg] : plots) {
    // A plot's name may be an input's that lies in the folder: never written over it.
    const std::string path = a.plots + "/" + name;
    if (const auto in = input_at(a, path)) {
      refuse("--plots " + a.plots + ": its plot " + name + " would replace the " + in->first +
             " file " + in->second + "; give the plots a folder of their own");
    }
    std::error_code ec;
    if (std::filesystem::exists(std::filesystem::symlink_status(path, ec))) {
      if (const std::string why = writable_output_problem(path); !why.empty()) {
        refuse("--plots " + a.plots + ": its plot " + path + " " + why);
      }
    }
  }
  made = folders_to_make(a.plots);
  std::error_code ec;
  std::filesystem::create_directories(a.plots, ec);
  if (ec) refuse(a.plots + ": cannot create folder: " + ec.message());
  for (const auto& [name, svg] : plots) tx.stage(a.plots + "/" + name, svg);
}

/// Every output of the run in one transaction (all or none), then the summary.
void write_outputs(const Args& a, const Invocation& how, const Toolpath& toolpath,
                   const Machine& machine, const JobOptions& options, const JobResult& result,
                   const std::optional<Part>& part, const std::optional<HtmlAssets>& html_assets) {
  OutputTransaction tx;
  if (!a.gcode.empty()) tx.stage(a.gcode, result.gcode.text);
  if (!a.out_cls.empty()) tx.stage(a.out_cls, result.out_cls);
  if (!a.report.empty()) {
    tx.stage(a.report, report_json(result, toolpath, machine, options, run_info(a, how, true)));
  }
  if (!a.points_csv.empty()) tx.stage(a.points_csv, points_csv(result));
  if (!a.html.empty()) {
    tx.stage(a.html, html_page(result, toolpath, machine, options, run_info(a, how, false),
                               part ? &part->mesh() : nullptr, *html_assets));
  }
  std::vector<std::string> made;
  try {
    stage_plots(a, result, tx, made);
    tx.commit();
  } catch (...) {
    // Every output as it was: the plots' folders this run made go too (a full disk left an
    // empty --plots folder behind), whether a plot's write or the commit failed.
    tx.abort();
    remove_made_folders(made);
    throw;
  }
  if (!a.quiet) print_summary(result);
  if (how.demo && !a.quiet) {
    // What it wrote, and what to look at first.
    std::printf(
        "\ntaxopt demo wrote %s/: demo.nc (the G-code), report.json, points.csv, plots/ "
        "and demo.html.\nOpen %s/demo.html first: the part, the tool axes before and "
        "after, and the rotary axes' plots.\n",
        how.demo_out.c_str(), how.demo_out.c_str());
  }
}

}  // namespace

std::optional<LengthUnit> parse_unit(const std::string& s, const char* option) {
  if (s.empty()) return std::nullopt;
  if (s == "mm") return LengthUnit::Millimetre;
  if (s == "in") return LengthUnit::Inch;
  throw InputError(std::string(option) + " expects 'in' or 'mm', got '" + s + "'");
}

int run_main_job(Args& a, const Invocation& how) {
  try {
    check_outputs(a);
    // Every option's value checked before any file is read (the library's rules and words).
    JobOptions options = job_options_of(a);
    check_options(options);
    const Machine machine = machine_of(a);
    const ClReadOptions read_options = read_options_of(a);
    // The page's libraries are read before any work: a run must not end in "cannot embed".
    std::optional<HtmlAssets> html_assets;
    if (!a.html.empty()) {
      const char* dir = std::getenv("TAXOPT_JAVASCRIPT_DIR");
      html_assets = load_html_assets(dir && *dir ? dir : kDefaultJavascriptDir);
    }
    std::future<TriangleMesh> mesh_file = mesh_file_of(a);
    const Toolpath toolpath = read_cl_file(a.in, read_options);
    // Plots: five SVG files an operation (and C-space maps); 20,000 operations wrote 100,000
    // files, 468 MB. A page of plots beyond a few hundred operations helps no one.
    constexpr std::size_t kMostPlottedOperations = 200;
    if (!a.plots.empty() && toolpath.operations.size() > kMostPlottedOperations) {
      refuse("--plots: the CL file has " + std::to_string(toolpath.operations.size()) +
             " operations; plots are written for at most " +
             std::to_string(kMostPlottedOperations) +
             " (about 5 SVG files each): split the file, or leave out --plots");
    }
    ProgressPrinter printer(!a.quiet && isatty(STDERR_FILENO), !a.quiet && a.verbose > 0);
    if (!a.quiet) {
      options.progress = [&printer](const std::string& stage, std::size_t done, std::size_t total) {
        printer(stage, done, total);
      };
    }
    const std::optional<Part> part = part_of(a, toolpath, mesh_file, options.progress);
    // The tool's dimensions, known now in the CL file's units: run_job checks them first.
    options.tool = tool_dimensions_of(a, toolpath);
    if (part) options.part = &*part;
    if (!a.quiet && a.verbose > 0) {
      options.log = [](const std::string& line) {
        std::fprintf(stderr, "taxopt: %s\n", line.c_str());
      };
    }
    const JobResult result = run_job(toolpath, machine, options);
    print_messages(result, toolpath, a);
    if (!result.ok() && !a.force) {
      std::cerr << "taxopt: no output written (--force writes it anyway)\n";
      return 1;
    }
    if (!a.gcode.empty() && result.gcode.text.find_first_of("\n") == std::string::npos) {
      refuse("no G-code to write: no point of the program could be posted" +
                 (result.problems.empty() ? std::string() : " (" + result.problems[0] + ")"),
             1);
    }
    write_outputs(a, how, toolpath, machine, options, result, part, html_assets);
    return result.ok() ? 0 : 1;
  } catch (const Refused& r) {
    return error(r.what, r.code);
  } catch (const InputError& e) {
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

}  // namespace taxopt::cli
