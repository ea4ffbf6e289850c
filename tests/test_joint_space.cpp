// Between the cuts, in joint space (issue 61): a turn of the rotary axes alone with TCP on keeps
// the tip put in the table's frame, so the joints swing round it; where LinuxCNC (which plans
// a TCP block in the program's axes) would drive a joint past its velocity limit at the
// rapid's rate, the writer turns the table at the joints' rate, and a joint velocity past its
// limit that is left is a problem (exit 1), not a warning.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "support.hpp"

using namespace taxopt;
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
  REQUIRE(generate_small_sine(t) == 0);
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

TEST_CASE(
    "travel: the work offset places the program in machine coordinates, and without one the "
    "program's span alone is held to the travel, and the run says so naming the option",
    "[program][travel]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/machines/";
  // A real file on LinuxCNC's bridge-mill sample (Z travel [-500, 100] mm): its clearance
  // plane stands over 200 mm above the program's zero.
  const std::string f = "amorim-tilt-support1.apt";
  const std::string base =
      "--in " + real_path(f, t.dir()) + real_flags(f) +
      " --spindle-rpm 1000 --tool-number 1 --machine " + d +
      "linuxcnc-5axis-bridgemill.toml --method none --feed-schedule --report " + t.path("r.json") +
      " --gcode " + t.path("o.ngc");
  // No offset: the span fits, the program posts, and the run names what it did not check.
  RunResult r = run_taxopt(base);
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto report = nlohmann::json::parse(read_file(t.path("r.json")));
  bool noted = false;
  for (const auto& finding : report["findings"]) {
    if (finding["code"] != "no_work_offset") continue;
    noted = true;
    CHECK(finding["severity"] == "safety");
    CHECK_THAT(finding["message"].get<std::string>(), Catch::Contains("--work-offset"));
  }
  CHECK(noted);
  CHECK(read_file(t.path("o.ngc")).find("NOT CHECKED: no work offset") != std::string::npos);
  // The offset of LinuxCNC's simulation (G54 at zero): Z leaves the travel, exit 1 naming it.
  r = run_taxopt(base + " --work-offset 0,0,0");
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("outside the machine's travel"));
  CHECK_THAT(r.err, Catch::Contains("work offset Z 0 mm"));
  // The part clamped 300 mm below the machine's zero: every block within the travel.
  r = run_taxopt(base + " --work-offset 0,0,-300");
  INFO(r.err);
  CHECK(r.code == 0);
  report = nlohmann::json::parse(read_file(t.path("r.json")));
  for (const auto& finding : report["findings"]) CHECK(finding["code"] != "no_work_offset");
  // The machine file's [setup] says the same as the option.
  std::string toml = read_file(d + "linuxcnc-5axis-bridgemill.toml");
  write_file(t.path("m.toml"), toml + "\n[setup]\nwork_offset_mm = [0.0, 0.0, -300.0]\n");
  r = run_taxopt(replaced_once(base, d + "linuxcnc-5axis-bridgemill.toml", t.path("m.toml")));
  INFO(r.err);
  CHECK(r.code == 0);
  write_file(t.path("bad.toml"), toml + "\n[setup]\nwork_offset_mm = [0.0, -300.0]\n");
  r = run_taxopt(replaced_once(base, d + "linuxcnc-5axis-bridgemill.toml", t.path("bad.toml")));
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("setup.work_offset_mm must be [x, y, z]"));
  // A program longer than the travel: no offset fits it, said without one.
  const std::string big = t.path("big.cls");
  REQUIRE(run_taxopt("generate --surface plane --width 2 --length 1200 --mesh-step 5 --out-cls " +
                     big + " --out-mesh " + t.path("big.stl"))
              .code == 0);
  r = run_taxopt("--in " + big + " --machine " + d +
                 "linuxcnc-5axis-bridgemill.toml --method none -q --gcode " + t.path("b.ngc"));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("no work offset fits the program"));
}

namespace {

/// An ASCII STL of axis-aligned boxes, each [x0, x1] x [y0, y1] x [z0, z1], faces outward.
std::string boxes_stl(const std::vector<std::array<double, 6>>& boxes) {
  std::ostringstream out;
  out << "solid boxes\n";
  for (const auto& b : boxes) {
    const auto p = [&](int i, int j, int k) {
      std::ostringstream v;
      v << "vertex " << b[static_cast<std::size_t>(i)] << " " << b[static_cast<std::size_t>(2 + j)]
        << " " << b[static_cast<std::size_t>(4 + k)] << "\n";
      return v.str();
    };
    // Each face as four corners (i j k: 0 low, 1 high), counter-clockwise seen from outside.
    const int quads[6][4][3] = {
        {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
        {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}};
    for (const auto& q : quads) {
      for (const int t : {1, 2}) {
        out << "facet normal 0 0 0\nouter loop\n"
            << p(q[0][0], q[0][1], q[0][2]) << p(q[t][0], q[t][1], q[t][2])
            << p(q[t + 1][0], q[t + 1][1], q[t + 1][2]) << "endloop\nendfacet\n";
      }
    }
  }
  out << "endsolid boxes\n";
  return out.str();
}

}  // namespace

TEST_CASE(
    "retracts: a retract in machine coordinates from a known pose is swept along machine Z "
    "until the tool clears the part, and with the work offset and the gauge length the blocks "
    "after it are swept too",
    "[program][collision]") {
  TempDir t;
  // A pass along X on a plate at Z 0; 20 mm of tool; an overhang 30 mm up over its end.
  write_file(t.path("p.cls"),
             "TOOL PATH/T,TOOL,BALL\nTLDATA/MILL,6.0000,3.0000,20.0000,0.0000,0.0000\n"
             "LOADTL/1\nSPINDL/RPM,8000,CLW\nFEDRAT/MMPM,500.0000\n"
             "GOTO/0.0,0.0,5.0,0.0,0.0,1.0\nGOTO/0.0,0.0,0.0\nGOTO/10.0,0.0,0.0\n"
             "GOTO/20.0,0.0,0.0\nGOTO/20.0,0.0,5.0\nEND-OF-PATH\n");
  const std::array<double, 6> plate = {-10, 30, -10, 10, -10, 0};
  write_file(t.path("over.stl"), boxes_stl({plate, {15, 30, -10, 10, 30, 40}}));
  write_file(t.path("side.stl"), boxes_stl({plate, {15, 30, 20, 30, 30, 40}}));
  const std::string args = "--in " + t.path("p.cls") +
                           " --method none --gauge-length 20 -q --gcode " + t.path("o.ngc") +
                           " --report " + t.path("r.json") + " --part ";
  // The end's G53 retract goes up into the overhang: exit 1 naming it.
  RunResult r = run_taxopt(args + t.path("over.stl"));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("(the retract, a rapid in machine coordinates)"));
  // The overhang beside the pass: the retract is swept and clear.
  r = run_taxopt(args + t.path("side.stl"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto report = nlohmann::json::parse(read_file(t.path("r.json")));
  const auto& v = report["operations"][0]["verification"];
  const long swept = v["blocks_swept"].get<long>(), unknown = v["blocks_not_checked"].get<long>();
  CHECK(v["colliding_blocks"] == 0);
  // Placed (the work offset and the gauge length given): only the blocks before the program
  // first states the tool's X Y Z stay unknown.
  r = run_taxopt(args + t.path("side.stl") + " --work-offset 0,0,-200");
  INFO(r.err);
  REQUIRE(r.code == 0);
  report = nlohmann::json::parse(read_file(t.path("r.json")));
  const auto& placed = report["operations"][0]["verification"];
  CHECK(placed["blocks_not_checked"].get<long>() < unknown);
  CHECK(placed["blocks_swept"].get<long>() > swept);
  CHECK(placed["blocks_not_checked"].get<long>() <= 2);
}

TEST_CASE(
    "joints: a continuous C wound by the cut turns home to the nearest whole turn, not back "
    "through every turn it made",
    "[program][joints]") {
  // A ring cut five and a third times round with the tool leaning 10 deg outward: C follows the
  // angle round, 1,920 deg by the last point.
  std::ostringstream cl;
  cl << "TOOL PATH/RING,TOOL,BALL6\nTLDATA/MILL,6.0000,3.0000,40.0000,0.0000,0.0000\n"
        "LOAD/TOOL,1\nSPINDL/RPM,8000,CLW\nRAPID\nGOTO/20.0,0.0,10.0,0.1736482,0.0,0.9848078\n"
        "FEDRAT/MMPM,1000\n";
  const double d = M_PI / 180.0;
  for (int k = 0; k <= 1920; k += 4) {
    const double a = k * d, s = std::sin(10 * d), c = std::cos(10 * d);
    char buf[160];
    std::snprintf(buf, sizeof buf, "GOTO/%.6f,%.6f,0.0,%.7f,%.7f,%.7f\n", 20 * std::cos(a),
                  20 * std::sin(a), s * std::cos(a), s * std::sin(a), c);
    cl << buf;
  }
  cl << "END-OF-PATH\n";
  TempDir t;
  write_file(t.path("ring.cls"), cl.str());
  const RunResult r =
      run_taxopt("--in " + t.path("ring.cls") + " --method none -q --gcode " + t.path("o.ngc"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto moves = read_gcode_moves(read_file(t.path("o.ngc")), "o.ngc");
  REQUIRE(moves.size() > 2);
  double wound = 0.0;
  for (const GcodeMove& m : moves) wound = std::max(wound, std::abs(m.c_deg));
  CHECK(wound > 1800.0);
  // The last block is home: A0 and a whole turn of C, at most half a turn from where C was.
  const GcodeMove& last = moves.back();
  CHECK(last.tilt_deg == 0.0);
  CHECK(std::fmod(last.c_deg, 360.0) == 0.0);
  CHECK(std::abs(last.c_deg - moves[moves.size() - 2].c_deg) <= 180.0);
}

TEST_CASE(
    "joints: the first positioning after the program's first retract names X, Y and Z, and on "
    "LinuxCNC with TCP its feed holds every joint within its velocity limit whichever way it "
    "goes from where the machine stood",
    "[program][tcp][joints]") {
  TempDir t;
  REQUIRE(generate_small_sine(t) == 0);
  // The preset: TCP switched on by M428, every axis and joint at 20 mm/s; the table tilted
  // about 20 deg before the positioning.
  const RunResult r =
      run_taxopt("--in " + t.path("g.cls") + " --part " + t.path("g.stl") + " --machine " +
                 std::string(TAXOPT_SOURCE_DIR) +
                 "/data/machines/linuxcnc-xyzac-trt.toml --gauge-length 50 -q --report " +
                 t.path("r.json") + " --gcode " + t.path("o.ngc"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::vector<std::string> lines = program_lines(read_file(t.path("o.ngc")));
  const auto on = std::find(lines.begin(), lines.end(), "M428");
  REQUIRE(on != lines.end());
  REQUIRE(on + 2 < lines.end());
  CHECK(on[1].find("joint-safe rapid") != std::string::npos);
  std::smatch m;
  const std::string& block = on[2];
  INFO(block);
  REQUIRE(
      std::regex_match(block, m, std::regex(R"(G1 X-?[0-9.]+ Y-?[0-9.]+ Z-?[0-9.]+ F([0-9.]+))")));
  // A feed of at most the joints' 20 mm/s: a table-table machine turns the tip's velocity,
  // no joint moves faster than the tip. At the rapid's rate the diagonal could drive joint Z
  // at 20 (|sin A| + |cos A|) mm/s, 25.6.
  const double f = std::stod(m[1]);
  CHECK(f <= 1200.0);
  CHECK(f > 1150.0);
  const auto report = nlohmann::json::parse(read_file(t.path("r.json")));
  for (const auto& finding : report["findings"]) {
    if (finding["code"] != "tcp_joint_limit") continue;
    CHECK_THAT(finding["message"].get<std::string>(),
               !Catch::Contains("mm/s against") && !Catch::Contains("deg/s against"));
  }
}

TEST_CASE(
    "joint space: a pivot given in machine coordinates lies at the pivot less the work offset "
    "in the workpiece, as the controller's G54 turns with the table",
    "[program][joints][setup]") {
  TempDir t;
  REQUIRE(generate_small_sine(t) == 0);
  // LinuxCNC's xyzac-trt sample in machine mode (the written words are the joints), its pivot
  // (A axis at Y 20, Z 10) in machine coordinates, the program's zero at X 5 Y -30 Z -40.
  const std::string sample =
      read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml");
  REQUIRE(sample.find("frame = \"machine\"") != std::string::npos);
  const auto variant = [&](const std::string& name, const std::string& frame, double a_y,
                           double a_z, double c_x, double c_y) {
    std::string text =
        std::regex_replace(sample, std::regex("mode = \"tcp\""), "mode = \"machine\"");
    text = std::regex_replace(text, std::regex("frame = \"machine\""), "frame = \"" + frame + "\"");
    text = std::regex_replace(text, std::regex("a_axis_y = [-0-9.]+"),
                              "a_axis_y = " + std::to_string(a_y));
    text = std::regex_replace(text, std::regex("a_axis_z = [-0-9.]+"),
                              "a_axis_z = " + std::to_string(a_z));
    text = std::regex_replace(text, std::regex("c_axis_x = [-0-9.]+"),
                              "c_axis_x = " + std::to_string(c_x));
    text = std::regex_replace(text, std::regex("c_axis_y = [-0-9.]+"),
                              "c_axis_y = " + std::to_string(c_y));
    write_file(t.path(name + ".toml"), text);
    const RunResult r = run_taxopt(
        "--in " + t.path("g.cls") + " --machine " + t.path(name + ".toml") +
        " --gauge-length 50 --work-offset 5,-30,-40 -q --force --gcode " + t.path(name + ".ngc"));
    INFO(r.err);
    REQUIRE(r.code <= 1);
    // The points' blocks: the header names the machine file, which differs.
    std::string out;
    for (const std::string& l : program_lines(read_file(t.path(name + ".ngc")))) {
      if (l.rfind("G1 ", 0) == 0) out += l + "\n";
    }
    REQUIRE(!out.empty());
    return out;
  };
  // In machine coordinates at (Y 20, Z 10) and (0, 0): in the workpiece's at the same less
  // the offset, (Y 50, Z 50) and (-5, 30).
  const std::string machine_frame = variant("m", "machine", 20.0, 10.0, 0.0, 0.0);
  CHECK(machine_frame == variant("w", "workpiece", 50.0, 50.0, -5.0, 30.0));
  // Taken as the workpiece's, the same numbers give other joints.
  CHECK(machine_frame != variant("u", "workpiece", 20.0, 10.0, 0.0, 0.0));
}
