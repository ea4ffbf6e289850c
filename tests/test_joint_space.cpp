// Between the cuts, in joint space (issue 61): a turn of the rotary axes alone with TCP on keeps
// the tip put in the table's frame, so the joints swing round it; where LinuxCNC (which plans
// a TCP block in the program's axes) would drive a joint past its velocity limit at the
// rapid's rate, the writer turns the table at the joints' rate, and a joint velocity past its
// limit that is left is a problem (exit 1), not a warning.
#include <catch2/catch.hpp>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "support.hpp"

using namespace taxopt::test;

namespace {

/// The CL file `in` with every GOTO's X moved by `dx_mm` (the part away from the C axis).
std::string shifted_cl(const std::string& in, double dx_mm) {
  std::istringstream text(in);
  std::ostringstream out;
  out << std::setprecision(12);
  for (std::string l; std::getline(text, l);) {
    if (l.rfind("GOTO/", 0) == 0) {
      const std::size_t comma = l.find(',');
      const double x = std::stod(l.substr(5, comma - 5));
      l = "GOTO/" +
          [&] {
            std::ostringstream v;
            v << std::setprecision(12) << x + dx_mm;
            return v.str();
          }() +
          l.substr(comma);
    }
    out << l << "\n";
  }
  return out.str();
}

/// The program's lines.
std::vector<std::string> program_lines(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST_CASE(
    "joints: with TCP on and no kinematics switch the table turns home round the tip at the "
    "joints' rate where a rapid would drive a joint past its velocity limit",
    "[program][tcp][joints]") {
  TempDir t;
  REQUIRE(run_taxopt("generate --width 3 --length 20 --out-cls " + t.path("g.cls") +
                     " --out-mesh " + t.path("g.stl"))
              .code == 0);
  const std::string args =
      " --method none -q --report " + t.path("r.json") + " --gcode " + t.path("o.ngc");
  // In place (the part on C): the turn home is the rapid it always was.
  RunResult r = run_taxopt("--in " + t.path("g.cls") + args);
  INFO(r.err);
  REQUIRE(r.code == 0);
  std::vector<std::string> lines = program_lines(read_file(t.path("o.ngc")));
  REQUIRE(lines.size() > 3);
  CHECK(lines[lines.size() - 2] == "G0 A0.0000 C0.0000");
  // 900 mm off C (a fixture at the table's edge, as real set-ups are): a rapid turn of A round
  // the tip would swing joint Z at hundreds of mm/s past its limit.
  write_file(t.path("far.cls"), shifted_cl(read_file(t.path("g.cls")), 900.0));
  r = run_taxopt("--in " + t.path("far.cls") + args);
  INFO(r.err);
  REQUIRE(r.code == 0);
  lines = program_lines(read_file(t.path("o.ngc")));
  const std::string& turn = lines[lines.size() - 2];
  INFO(turn);
  CHECK(std::regex_match(turn, std::regex(R"(G1 A0\.0000 C0\.0000 F[0-9.]+)")));
  CHECK(lines[lines.size() - 3].find("joint-safe rapid") != std::string::npos);
  const auto report = nlohmann::json::parse(read_file(t.path("r.json")));
  const auto& peaks = report["gcode"]["tcp_joint_peaks"];
  REQUIRE(peaks.is_object());
  const auto& limits = report["axis_limits"];
  for (const char* joint : {"X", "Y", "Z", "A", "C"}) {
    INFO(joint);
    const double v = peaks[joint]["velocity_per_s"].get<double>();
    const auto& axis = limits[joint];
    const double limit = (axis.contains("max_velocity_mm_s") ? axis["max_velocity_mm_s"]
                                                             : axis["max_velocity_deg_s"])
                             .get<double>();
    CHECK(v <= 1.001 * limit);
  }
  // The turn itself moves the joints (its line is the peak of some joint) within them.
  bool turn_peaks = false;
  for (const char* joint : {"X", "Y", "Z"}) {
    turn_peaks |= peaks[joint]["velocity_line"].get<int>() == static_cast<int>(lines.size() - 1);
  }
  CHECK(turn_peaks);
  for (const auto& f : report["findings"]) CHECK(f["code"] != "dynamic_limit_exceeded");
}
