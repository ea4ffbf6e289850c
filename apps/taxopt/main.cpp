// taxopt command line: option parsing and printing only (cli.md is the contract); the pieces
// are in cli.hpp: options.cpp, job.cpp (the main job), generate.cpp, print.cpp.
#include <csignal>
#include <ctime>
#include <filesystem>
#include <iostream>

#include "cli.hpp"
#include "support/linuxcnc_ini.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/atomic_file.hpp"

using namespace taxopt::cli;

namespace {

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

/// taxopt machine: a machine file from a LinuxCNC configuration.
int run_machine_import(const Commands& c) {
  try {
    const taxopt::ImportedMachine m = taxopt::machine_from_linuxcnc_ini(c.ini_in);
    for (const auto& note : m.assumptions) std::cerr << "taxopt: note: " << note << "\n";
    if (c.machine_out.empty()) {
      std::cout << m.toml;
      return 0;
    }
    // Never over the configuration it came from (an audit's --out X.ini replaced the INI).
    for (const std::string& f : m.files_read) {
      if (taxopt::same_file(c.machine_out, f)) {
        return error("--out " + c.machine_out + " is the configuration's own file " + f +
                         " (read to make the machine file): write the machine file elsewhere",
                     2);
      }
    }
    if (const std::string why = taxopt::writable_output_problem(c.machine_out); !why.empty()) {
      return error("--out " + c.machine_out + ": " + why, 2);
    }
    taxopt::OutputTransaction out;
    out.stage(c.machine_out, m.toml);
    out.commit();
    return 0;
  } catch (const taxopt::InputError& e) {
    return error(e.what(), 2);
  }
}

/// taxopt demo: the main job's arguments for the bundled files (the sine part's CL file on the
/// paper's machine, A limited to [-110, 30] deg); 0, else the exit code of a refusal.
int demo_arguments(const char* argv0, const Commands& c, Args& a) {
  const std::string data = data_dir(argv0);
  if (!std::filesystem::exists(data + "/demo/sine.cls")) {
    return error(data + "/demo/sine.cls: demo data not found (set TAXOPT_DATA_DIR)", 2);
  }
  std::error_code ec;
  std::filesystem::create_directories(c.demo_out, ec);
  if (ec) return error(c.demo_out + ": cannot create folder: " + ec.message(), 2);
  a.in = data + "/demo/sine.cls";
  a.machine = data + "/machines/paper-ac.toml";
  a.part = data + "/demo/sine.stl";
  // A 15 mm stick-out (the flute length): with a longer tool the paper's input axes lean
  // the shank into the opposite flank of the sine (data/README.md); moving them clear is
  // the optimiser's work, not --method none's.
  if (!a.gauge_length) a.gauge_length = 15.0;
  a.gcode = c.demo_out + "/demo.nc";
  a.report = c.demo_out + "/report.json";
  a.points_csv = c.demo_out + "/points.csv";
  a.html = c.demo_out + "/demo.html";
  a.plots = c.demo_out + "/plots";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // A closed stdout (taxopt ... | head) is an error to write to, not a signal that kills the
  // run after its outputs were written (exit 141).
  std::signal(SIGPIPE, SIG_IGN);
  // An interrupted run leaves no temporary file beside its outputs.
  taxopt::OutputTransaction::remove_pending_on_signals();
  Invocation how;
  how.command_line = quoted_command_line(argc, argv);
  how.started_utc = utc_now();
  Args a;
  Commands c;
  CLI::App app{
      "taxopt: tool-axis optimisation for 5-axis ball-end finishing on A/C machines.\n"
      "Reads a cutter-location file, plans the machine's A/C axes and writes G-code.",
      "taxopt"};
  define_command_line(app, a, c);
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
  if (*c.generate_cmd) {
    try {
      return run_generate(c.generate);
    } catch (const taxopt::InputError& e) {
      return error(e.what(), 2);
    }
  }
  if (*c.machine_cmd) return run_machine_import(c);
  if (*c.demo_cmd) {
    if (const int code = demo_arguments(argv[0], c, a)) return code;
  }
  how.demo = static_cast<bool>(*c.demo_cmd);
  how.demo_out = c.demo_out;
  return run_main_job(a, how);
}
