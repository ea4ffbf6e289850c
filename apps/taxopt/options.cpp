// taxopt's options, subcommands and help (cli.md is the contract: keep the names).
#include <map>
#include <regex>
#include <set>

#include "cli.hpp"
#include "taxopt/core/version.hpp"

namespace taxopt::cli {
namespace {

// Each group's options in the order --help lists them; the groups in the order they first
// appear (Input, Outputs, Machine, Method, Tool, Diagnostics), as define_command_line calls
// them.

void add_input_options(CLI::App& app, Args& a) {
  app.add_option("--in", a.in, "cutter-location file (APT / NX CLSF)")
      ->check(CLI::ExistingFile)
      ->group("Input");
  app.add_option("--units", a.units, "units of the CL file: in | mm (default: from the file)")
      ->group("Input");
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
  app.add_option("--part", a.part, "part mesh (STL, OBJ, OFF, PLY) in the CL file's coordinates")
      ->check(CLI::ExistingFile)
      ->group("Input");
  app.add_option("--part-units", a.part_units,
                 "units of the part mesh: in | mm (default: the CL file's)")
      ->group("Input");
  app.add_option("--part-frame", a.part_frame,
                 "where the CL file names an NX MSYS: the part mesh is in that MCS (mcs) or in "
                 "absolute coordinates (absolute); default auto: where the ball touches it")
      ->check(CLI::IsMember({"auto", "mcs", "absolute"}))
      ->group("Input");
  app.add_option(
         "--contact-tolerance", a.contact_tolerance,
         "largest | |C - Pc| - R | of a contact point, mm (default max(0.05, the mesh's chordal "
         "error + the CL file's INTOL/OUTTOL/TOLER band))")
      ->group("Input");
  app.add_option("--part-tolerance", a.part_tolerance,
                 "how far the flutes may reach into the part mesh (its chordal error) without a "
                 "collision, mm (default: the contact tolerance)")
      ->group("Input");
}

void add_outputs_options(CLI::App& app, Args& a) {
  app.add_option("--gcode", a.gcode, "G-code to write")->group("Outputs");
  app.add_option("--report", a.report, "JSON report to write")->group("Outputs");
  app.add_option("--points-csv", a.points_csv, "per-point CSV to write")->group("Outputs");
  app.add_option("--out-cls", a.out_cls, "optimised toolpath as a CL file")->group("Outputs");
  app.add_option("--html", a.html,
                 "one self-contained HTML page: the part, the tool axes before and after, where "
                 "every check fired, the rotary plots with the machine's limits")
      ->group("Outputs");
  app.add_option("--units-out", a.units_out, "units of the G-code: in | mm (default: as input)")
      ->group("Outputs");
  app.add_flag("--force", a.force, "write the G-code even when verification fails (exit 1)")
      ->group("Outputs");
  app.add_option("--plots", a.plots,
                 "folder for SVG plots: A, C, omega and a against arc length, before and after; "
                 "C-space maps (with --part)")
      ->group("Outputs");
}

void add_machine_options(CLI::App& app, Args& a) {
  app.add_option("--machine", a.machine, "machine file (TOML); default: generic A/C table-table")
      ->check(CLI::ExistingFile)
      ->group("Machine");
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
  std::vector<std::string> dialects;
  std::string dialect_list;
  for (const GcodeDialect d : gcode_dialects()) {
    dialect_list += (dialects.empty() ? "" : " | ") + std::string(to_string(d));
    dialects.emplace_back(to_string(d));
  }
  app.add_option("--dialect", a.dialect,
                 "G-code dialect, overriding the machine file's gcode.dialect: " + dialect_list)
      ->check(CLI::IsMember(dialects))
      ->group("Machine");
  app.add_flag("--feed-schedule", a.feed_schedule,
               "write per block the fastest feed the machine's limits allow (never above the "
               "programmed feed)")
      ->group("Machine");
}

void add_method_options(CLI::App& app, Args& a) {
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
  app.add_option("--grid", a.grid,
                 "C-space cell size, deg: spacing of the key-axis candidates and the global "
                 "method's finest (2)")
      ->group("Method");
  app.add_option("--max-deviation", a.max_deviation,
                 "largest angle between an output axis and its input axis, deg (30)")
      ->group("Method");
  app.add_option("--min-tilt", a.min_tilt,
                 "least angle between an output axis and the surface normal at a contact, held "
                 "where the input's own angle there is not less, deg (default: the input's least "
                 "over the operation, rounded down to 0.1, at most 10, held from 1; 0: none held)")
      ->group("Method");
}

void add_tool_options(CLI::App& app, Args& a) {
  app.add_option("--tool-radius", a.tool_radius,
                 "ball radius, CL file units (default: TLDATA/CUTTER)")
      ->group("Tool");
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
  app.add_option("--holder-length", a.holder_length, "holder length, CL file units (default 40 mm)")
      ->group("Tool");
  app.add_option("--gauge-length", a.gauge_length,
                 "tip to holder face, CL file units (default: max(flute length, 10 diameters))")
      ->group("Tool");
  app.add_option("--work-offset", a.work_offset,
                 "where the program's zero sits in machine coordinates with the rotary axes at "
                 "home (the work offset, G54's X,Y,Z), mm: the travel check holds every block to "
                 "the machine's travel with it (default: the machine file's [setup], else only "
                 "the program's span is checked)")
      ->delimiter(',')
      ->expected(3)
      ->group("Tool");
}

void add_diagnostics_options(CLI::App& app, Args& a) {
  app.add_option("--threads", a.threads, "worker threads, 1 to 1024 (default: all cores)")
      ->group("Diagnostics");
  app.add_flag("-q,--quiet", a.quiet, "only errors and NOT CHECKED safety warnings on stderr")
      ->group("Diagnostics");
  app.add_flag("-v", a.verbose, "more on stderr")->group("Diagnostics");
}

void add_subcommands(CLI::App& app, Commands& c) {
  c.generate_cmd =
      app.add_subcommand("generate", "write a CL file and part mesh of a built-in surface");
  c.generate_cmd->add_option(
      "--surface", c.generate.surface,
      "sine (the paper's case) | plane | bump (a round bump, sigma = wavelength / 4) | saddle");
  c.generate_cmd->add_option("--out-cls", c.generate.out_cls, "CL file to write (NX CLSF, mm)");
  c.generate_cmd->add_option("--out-mesh", c.generate.out_mesh,
                             "part mesh to write (binary STL, mm)");
  c.generate_cmd->add_option("--height", c.generate.height_mm, "sine amplitude, mm (10)");
  c.generate_cmd->add_option("--wavelength", c.generate.wavelength_mm,
                             "sine wavelength along y, mm (40)");
  c.generate_cmd->add_option("--width", c.generate.width_mm,
                             "extent along x (across the passes), mm (20)");
  c.generate_cmd->add_option("--length", c.generate.length_mm,
                             "extent along y (the feed direction), mm (80)");
  c.generate_cmd->add_option("--tool-radius", c.generate.raster.tool_radius_mm,
                             "ball radius, mm (3)");
  c.generate_cmd->add_option("--scallop", c.generate.raster.scallop_mm,
                             "scallop height, mm (0.02)");
  c.generate_cmd->add_option("--chord-error", c.generate.raster.chord_error_mm,
                             "chord error, mm (0.05)");
  c.generate_cmd->add_option("--tilt", c.generate.raster.tilt_deg, "tilt, deg (5)");
  c.generate_cmd->add_option("--yaw", c.generate.raster.yaw_deg, "yaw, deg (0)");
  c.generate_cmd->add_option("--feed", c.generate.feed_mm_per_min, "feed, mm/min (250)");
  c.generate_cmd->add_option("--spindle", c.generate.spindle_rpm, "spindle speed, rpm (3000)");
  c.generate_cmd->add_option("--mesh-step", c.generate.mesh_step_mm, "mesh grid spacing, mm (0.5)");
  c.machine_cmd = app.add_subcommand(
      "machine", "make a machine file from a LinuxCNC configuration (xyzac-trt-kins)");
  c.machine_cmd->add_option("--from-linuxcnc-ini", c.ini_in, "the configuration's INI file")
      ->required()
      ->check(CLI::ExistingFile);
  c.machine_cmd->add_option("--out", c.machine_out, "machine file to write (default: stdout)");
  c.demo_cmd = app.add_subcommand("demo", "run the bundled sine-surface case from data/");
  c.demo_cmd->add_option("--out", c.demo_out, "output folder (taxopt-demo)");
}

/// What each option takes, in words a user knows (not the parser's types).
void name_option_values(CLI::App& app) {
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
                                                    {"--part-units", "in|mm"},
                                                    {"--part-frame", "auto|mcs|absolute"},
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
                                                    {"--min-tilt", "DEG"},
                                                    {"--work-offset", "X,Y,Z"},
                                                    {"--plots", "FOLDER"},
                                                    {"--html", "FILE"}};
  for (CLI::Option* o : app.get_options()) {
    for (const auto& name : o->get_lnames()) {
      if (const auto t = takes.find("--" + name); t != takes.end()) o->option_text(t->second);
    }
  }
}

}  // namespace

/// Every number an option takes written as a decimal (issue 63.12: CLI11 reads "--feed 0x100"
/// as 256, "0b11" as 3): the options whose value is a length, an angle, a rate or a count.
void decimal_numbers_only(CLI::App& app) {
  static const std::set<std::string> kNumeric = {"MM",     "LENGTH", "DEG",   "N",
                                                 "MM/MIN", "S^2",    "X,Y,Z", "RPM",
                                                 "FLOAT",  "INT",    "UINT",  "NUMBER"};
  // inf and nan pass to the bounds, which name the range the option takes.
  static const std::regex kDecimal(
      R"(\s*[+-]?((\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|inf|infinity|nan)\s*)", std::regex::icase);
  const CLI::Validator decimal(
      [](std::string& v) -> std::string {
        return std::regex_match(v, kDecimal) ? std::string() : "a decimal number, got " + v;
      },
      "");
  for (CLI::Option* o : app.get_options()) {
    if (o->get_type_size() == 0) continue;  // a flag
    if (kNumeric.count(o->get_option_text()) || kNumeric.count(o->get_type_name())) {
      o->check(decimal);
    }
  }
}

void define_command_line(CLI::App& app, Args& a, Commands& c) {
  app.set_version_flag("--version", std::string("taxopt ") + kVersion);
  add_input_options(app, a);
  add_outputs_options(app, a);
  add_machine_options(app, a);
  add_method_options(app, a);
  add_tool_options(app, a);
  add_diagnostics_options(app, a);
  add_subcommands(app, c);
  name_option_values(app);
  decimal_numbers_only(app);
  decimal_numbers_only(*c.generate_cmd);
  // The global options may follow a subcommand too ("taxopt demo -q").
  c.generate_cmd->fallthrough();
  c.machine_cmd->fallthrough();
  c.demo_cmd->fallthrough();
  app.footer(
      "Exit codes: 0 written and verified; 1 verification failed or limits exceeded (nothing "
      "written\nwithout --force); 2 bad input or options (file, line and what was expected on "
      "stderr).\n\nExamples:\n"
      "  taxopt demo --out demo                       the bundled sine case, all outputs\n"
      "  taxopt --in path.cls --part part.stl --machine data/machines/paper-ac.toml \\\n"
      "         --gcode out.nc --report report.json   optimise, check against the part, post\n"
      "  taxopt machine --from-linuxcnc-ini my.ini --out my.toml\n"
      "Documentation: docs/cli.md (options, machine file, report), docs/gcode-dialects.md.");
}

}  // namespace taxopt::cli
