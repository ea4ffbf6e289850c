// The program as a machinist checks it (a machinist's review, tests/test_program.cpp): a tool
// called and the spindle turning before the first feed move, the coolant the CL file asks for, no
// table turned below the retract without a part model, the approach from the retract XY first and
// then down, the rotary axes home at the end; in every dialect, on every real CL file, and through
// rs274.
#include <catch2/catch.hpp>
#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include "pipeline/stages.hpp"
#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// The real CL files (tests/data/real/reference.tsv's first column).
std::vector<std::string> real_files() {
  std::istringstream table(read_file(real_data("reference.tsv")));
  std::string row;
  std::getline(table, row);  // header
  std::vector<std::string> out;
  while (std::getline(table, row)) {
    std::istringstream fields(row);
    std::string f;
    fields >> f;
    if (!f.empty()) out.push_back(f);
  }
  return out;
}

/// What a machinist checks, counted over the moves read back (independently of taxopt's own
/// check_program: a breach of each kind, by the same rules written again here).
struct Breaches {
  int no_tool = 0, spindle_off = 0, index = 0, diagonal = 0, retracts = 0;
  /// First moves after a retract that do not position X and Y (a lone Z from wherever the
  /// table's turn left the tip).
  int partial = 0;
  bool home_at_end = false;
};
Breaches breaches_of(const std::vector<GcodeMove>& moves, double threshold_deg) {
  Breaches b;
  const GcodeMove* prev = nullptr;
  bool after_retract = false, xy_given = false, first_linear = false;
  double x = 0.0, y = 0.0;
  for (const GcodeMove& m : moves) {
    if (!m.retract && m.tool <= 0) ++b.no_tool;
    if (!m.rapid && !m.spindle_on) ++b.spindle_off;
    if (prev && m.rapid && !m.positioning && !prev->positioning &&
        std::max(std::abs(m.tilt_deg - prev->tilt_deg), std::abs(m.c_deg - prev->c_deg)) >
            threshold_deg + 1e-9) {
      ++b.index;
    }
    if (!m.retract && first_linear && (m.given & 7u)) {
      first_linear = false;
      if ((m.given & 3u) != 3u) ++b.partial;
    }
    if (m.retract) {
      ++b.retracts;
      after_retract = true;
      xy_given = false;
      first_linear = true;
    } else if (after_retract && (m.given & 0x1fu) == 0x7u && m.positioning && !xy_given) {
      // the complete positioning: X, Y and Z (not the angles) over the way down
      xy_given = true;
      x = m.xyz_mm.x();
      y = m.xyz_mm.y();
    } else if (after_retract && (m.given & 4u) && !(m.given & 3u) && !xy_given &&
               !(prev && (m.tilt_deg != prev->tilt_deg || m.c_deg != prev->c_deg))) {
      // straight down to the clearance height
    } else if (after_retract && (m.given & 4u)) {
      // Straight down from the XY move, or along the tool axis (A/C: i = sin A sin C,
      // j = -sin A cos C, k = cos A), as CAM links an approach.
      const double a = m.tilt_deg * M_PI / 180.0, c = m.c_deg * M_PI / 180.0;
      const Vec3d axis(std::sin(a) * std::sin(c), -std::sin(a) * std::cos(c), std::cos(a));
      const Vec3d d = prev ? Vec3d(m.xyz_mm - prev->xyz_mm) : Vec3d::Zero();
      const bool along = d.norm() > 1e-9 && std::abs(d.normalized().dot(axis)) > std::cos(1e-3);
      if (!xy_given || ((m.xyz_mm.x() != x || m.xyz_mm.y() != y) && !along)) ++b.diagonal;
      after_retract = false;
    } else if (after_retract && (m.given & 3u)) {
      xy_given = true;
      x = m.xyz_mm.x();
      y = m.xyz_mm.y();
    }
    prev = &m;
  }
  b.home_at_end = !moves.empty() && moves.back().tilt_deg == 0.0 &&
                  std::fmod(moves.back().c_deg, 360.0) == 0.0;  // a continuous C: any whole turn
  return b;
}

const char* const kDialects[] = {"linuxcnc", "fanuc", "siemens", "heidenhain", "haas"};

GcodeDialect dialect_of(const std::string& name) {
  if (name == "fanuc") return GcodeDialect::Fanuc;
  if (name == "siemens") return GcodeDialect::Siemens;
  if (name == "heidenhain") return GcodeDialect::Heidenhain;
  if (name == "haas") return GcodeDialect::Haas;
  return GcodeDialect::LinuxCNC;
}

}  // namespace

TEST_CASE(
    "program: every real CL file, in every dialect, calls its tool and starts its spindle "
    "before it feeds, indexes up at the retract, comes down XY first, ends home and says what "
    "was not checked -- rs274 runs no feed move with the spindle off",
    "[program][real][rs274][integration][slow]") {
  REQUIRE(have_rs274());
  int programs = 0, index_retracts = 0;
  for (const std::string& f : real_files()) {
    for (const char* dialect : kDialects) {
      INFO(f << " --dialect " << dialect);
      TempDir dir;
      const RunResult r =
          run_taxopt("--in " + real_path(f, dir.dir()) + real_flags(f) + " --dialect " + dialect +
                     " --gcode " + dir.path("o.nc") + " --method none -q");
      INFO(r.err);
      if (r.code == 2 &&
          r.err.find("DELAY: taxopt writes a dwell for LinuxCNC") != std::string::npos) {
        // A dwell of the file in a dialect whose dwell words taxopt does not write: refused.
        CHECK(std::string(dialect) != "linuxcnc");
        CHECK(std::string(dialect) != "fanuc");
        continue;
      }
      REQUIRE(r.code == 0);
      ++programs;
      const std::string text = read_file(dir.path("o.nc"));
      // No part: the program says so before its first block.
      CHECK(text.substr(0, 1500).find("NOT CHECKED: no part") != std::string::npos);
      // SOLIDWORKS CAM's INSERT prose: a comment of the dialect, in its operation.
      if (f.rfind("amorim-", 0) == 0) {
        const std::string d = dialect;
        const bool semicolon = d == "siemens" || d == "heidenhain";
        const std::size_t at = text.find(semicolon ? "; Stock Size X" : "(Stock Size X");
        CHECK(at != std::string::npos);
        CHECK(at > text.find("operation "));  // in its operation, not the header
      }
      const std::vector<GcodeMove> moves =
          read_gcode_moves(text, "o.nc", dialect_of(dialect), {}, 'A');
      const Breaches b = breaches_of(moves, 1.0);
      CHECK(b.no_tool == 0);
      CHECK(b.spindle_off == 0);
      CHECK(b.index == 0);
      CHECK(b.diagonal == 0);
      CHECK(b.partial == 0);
      CHECK(b.home_at_end);
      std::size_t operations = 0;
      for (std::size_t at = text.find("operation "); at != std::string::npos;
           at = text.find("operation ", at + 1)) {
        ++operations;
      }
      // One retract before each operation and one at the end; more are index moves.
      if (std::string(dialect) == "linuxcnc") {
        index_retracts += b.retracts - static_cast<int>(operations) - 1;
        std::vector<CanonMove> points, all;
        const RunResult rs = run_rs274(dir.path("o.nc"), points, {}, &all);
        INFO(rs.err);
        REQUIRE(rs.code == 0);
        int feeds = 0, off = 0, toolless = 0;
        for (const CanonMove& m : all) {
          if (!m.feed) continue;
          ++feeds;
          off += m.spindle_on ? 0 : 1;
          toolless += m.tool > 0 ? 0 : 1;
        }
        CHECK(feeds > 0);
        CHECK(off == 0);
        CHECK(toolless == 0);
      }
    }
  }
  CHECK(programs >= 8 * 3);
  // amorim-wall-holes turns its table by 90 deg inside an operation (CL lines 2112-2119).
  CHECK(index_retracts >= 1);
}

TEST_CASE(
    "program: a 90 deg index inside an operation goes up, turns, comes down XY first -- "
    "index_threshold_deg above it keeps the turn in the air",
    "[program][cli]") {
  TempDir t;
  write_file(t.path("a.cls"),
             "TOOL PATH/IDX,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nLOADTL/2\nSPINDL/RPM,5000,CLW\n"
             "RAPID\nGOTO/0,0,10,0,0,1\nFEDRAT/MMPM,500\nGOTO/0,0,0\nGOTO/10,0,0\n"
             "RAPID\nGOTO/10,0,10\nRAPID\nGOTO/20,-10,0,0,-1,0\nFEDRAT/MMPM,500\nGOTO/30,-10,0\n"
             "END-OF-PATH\n");
  const auto r = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.ngc") +
                            " --method none -q --max-deviation 0");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string text = read_file(t.path("o.ngc"));
  const auto moves = read_gcode_moves(text, "o.ngc");
  const Breaches b = breaches_of(moves, 1.0);
  CHECK(b.retracts == 3);  // the start, the index, the end
  CHECK(b.index == 0);
  CHECK(b.diagonal == 0);
  CHECK(b.partial == 0);
  CHECK(text.find("T2 M6") != std::string::npos);
  CHECK(text.find("S5000 M3") != std::string::npos);
  // The turn is made with the tool up: the turning block follows a retract and holds A and C
  // only.
  const std::size_t idx = text.find("G53 G0 Z", text.find("G53 G0 Z") + 1);
  REQUIRE(idx != std::string::npos);
  const std::size_t turn = text.find('\n', idx) + 1;
  const std::string turn_block = text.substr(turn, text.find('\n', turn) - turn);
  CHECK(turn_block == "G0 A90.0000 C0.0000");
  // The rapid's 90 deg stays in the air with a threshold above it: the check then fails it,
  // since nothing verifies the move without a part.
  write_file(t.path("m.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\nmax_deg = 120\n"
             "[axes.C]\ncontinuous = true\n[gcode]\nindex_threshold_deg = 120\n");
  const auto wide = run_taxopt("--in " + t.path("a.cls") + " --machine " + t.path("m.toml") +
                               " --gcode " + t.path("w.ngc") + " --method none -q");
  CHECK(wide.code == 0);
  const Breaches bw = breaches_of(read_gcode_moves(read_file(t.path("w.ngc")), "w.ngc"), 1.0);
  CHECK(bw.retracts == 2);
  CHECK(bw.index == 1);
}

TEST_CASE(
    "program: the spindle speed and tool come from the CL file, else the command line, else "
    "the machine file's [defaults] -- with none of them exit 2 naming them",
    "[program][cli][bad-input]") {
  TempDir t;
  const std::string body =
      "TOOL PATH/T,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nRAPID\nGOTO/0,0,10,0,0,1\n"
      "FEDRAT/MMPM,250\nGOTO/0,0,0\nGOTO/5,0,0\nEND-OF-PATH\n";
  write_file(t.path("bare.cls"), body);
  write_file(t.path("full.cls"), "LOADTL/4\nSPINDL/RPM,7000,CCLW\n" + body);
  write_file(t.path("m.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\nmax_deg = 120\n"
             "[axes.C]\ncontinuous = true\n[defaults]\nspindle_rpm = 9000\ntool_number = 6\n");
  const std::string out = " --gcode " + t.path("o.ngc") + " --method none -q";
  const auto none = run_taxopt("--in " + t.path("bare.cls") + out);
  CHECK(none.code == 2);
  CHECK_THAT(none.err, Catch::Contains("bare.cls:4: operation T: the CL file calls no tool"));
  CHECK_THAT(none.err, Catch::Contains("give --tool-number, or tool_number in the machine file"));
  CHECK_FALSE(file_exists(t.path("o.ngc")));
  const auto no_speed = run_taxopt("--in " + t.path("bare.cls") + " --tool-number 3" + out);
  CHECK(no_speed.code == 2);
  CHECK_THAT(no_speed.err, Catch::Contains("bare.cls:6: operation T: feed moves without a "
                                           "spindle speed"));
  CHECK_THAT(no_speed.err, Catch::Contains("give --spindle-rpm, or spindle_rpm in the machine"));
  // The command line.
  const auto cli =
      run_taxopt("--in " + t.path("bare.cls") + " --tool-number 3 --spindle-rpm 4500" + out);
  REQUIRE(cli.code == 0);
  std::string text = read_file(t.path("o.ngc"));
  CHECK(text.find("T3 M6") != std::string::npos);
  CHECK(text.find("S4500 M3") != std::string::npos);
  // The machine file's [defaults]; the command line before them.
  const std::string machine = " --machine " + t.path("m.toml");
  REQUIRE(run_taxopt("--in " + t.path("bare.cls") + machine + out).code == 0);
  text = read_file(t.path("o.ngc"));
  CHECK(text.find("T6 M6") != std::string::npos);
  CHECK(text.find("S9000 M3") != std::string::npos);
  REQUIRE(run_taxopt("--in " + t.path("bare.cls") + machine + " --spindle-rpm 4500" + out).code ==
          0);
  CHECK(read_file(t.path("o.ngc")).find("S4500 M3") != std::string::npos);
  // The CL file before both.
  REQUIRE(run_taxopt("--in " + t.path("full.cls") + machine + " --spindle-rpm 4500" + out).code ==
          0);
  text = read_file(t.path("o.ngc"));
  CHECK(text.find("T4 M6") != std::string::npos);
  CHECK(text.find("S7000 M4") != std::string::npos);
  // Hostile values.
  for (const char* bad :
       {"--spindle-rpm 0", "--spindle-rpm -5", "--spindle-rpm nan", "--spindle-rpm 1e9",
        "--tool-number 0", "--tool-number 1.5", "--tool-number abc", "--tool-number 100000"}) {
    INFO(bad);
    const auto b = run_taxopt("--in " + t.path("bare.cls") + " " + bad + out);
    CHECK(b.code == 2);
  }
}

TEST_CASE("program: check_program finds each breach a machinist looks for in a program read back",
          "[program]") {
  const Toolpath tp = parse_cl(
      "TOOL PATH/T,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nLOADTL/1\nSPINDL/RPM,6000,CLW\n"
      "COOLNT/FLOOD\nRAPID\nGOTO/0,0,10,0,0,1\nFEDRAT/MMPM,250\nGOTO/0,0,0\nGOTO/5,0,0\n"
      "GOTO/10,0,0\nRAPID\nGOTO/10,0,10\nRAPID\nGOTO/12,0,10\nEND-OF-PATH\n",
      "t.cls");
  const Machine machine = default_machine();
  JobOptions given;
  given.method = Method::None;
  const auto findings_of = [&](const std::function<void(pipeline::Written&)>& tamper) {
    JobResult res;
    pipeline::Run run = pipeline::validate(tp, machine, given, res);
    std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
    pipeline::plan_operations(run, ops, res);
    std::optional<std::vector<PostedOperation>> posted = pipeline::post_operations(run, ops, res);
    REQUIRE(posted);
    pipeline::Written w = pipeline::write_program(run, ops, *posted, res);
    tamper(w);
    JobResult checked;
    pipeline::check_program(run, *posted, w, checked);
    std::vector<FindingCode> codes;
    for (const Finding& f : checked.findings) {
      codes.push_back(f.code);
      CHECK(f.severity == Severity::Problem);
      CHECK_THAT(f.message, Catch::Contains("operation T: G-code line "));
    }
    return codes;
  };
  using V = std::vector<FindingCode>;
  CHECK(findings_of([](pipeline::Written&) {}).empty());
  const auto first_feed = [](pipeline::Written& w) -> GcodeMove& {
    for (GcodeMove& m : w.moves) {
      if (!m.rapid) return m;
    }
    throw std::logic_error("no feed move");
  };
  CHECK(findings_of([&](pipeline::Written& w) { first_feed(w).spindle_on = false; }) ==
        V{FindingCode::SpindleOff});
  CHECK(findings_of([&](pipeline::Written& w) { first_feed(w).tool = 0; }) ==
        V{FindingCode::NoToolCalled});
  CHECK(findings_of([&](pipeline::Written& w) { w.point_moves[0][0] = &first_feed(w); }) ==
        V{});  // the first point's move starts with flood: no breach
  CHECK(findings_of([&](pipeline::Written& w) {
          for (GcodeMove& m : w.moves) m.coolant = 0;
        }) == V{FindingCode::CoolantMismatch});
  // The last rapid (10,0,10) -> (12,0,10) turned by 5 deg below the retract.
  CHECK(findings_of([&](pipeline::Written& w) {
          for (std::size_t i = w.moves.size(); i-- > 0;) {
            if (!w.moves[i].positioning) {
              w.moves[i].c_deg += 5.0;
              break;
            }
          }
        }) == V{FindingCode::IndexWithoutRetract});
  // The positioning block moved off the point's X: the way down is diagonal.
  CHECK(findings_of([&](pipeline::Written& w) {
          for (GcodeMove& m : w.moves) {
            if (m.given == 7u && m.positioning) {
              m.xyz_mm.x() += 1.0;
              break;
            }
          }
        }) == V{FindingCode::DiagonalApproach});
  CHECK(findings_of([&](pipeline::Written& w) { w.moves.back().c_deg = 5.0; }) ==
        V{FindingCode::EndPoseNotHome});
  // A continuous C is home at any whole turn.
  CHECK(findings_of([&](pipeline::Written& w) { w.moves.back().c_deg = 720.0; }).empty());
}

TEST_CASE(
    "program: Fanuc keeps G2/G3 under G43.4 only where neither rotary axis has moved since "
    "G43.4 came on (FANUC 30i-A TCP manual, alarm PS5421) -- LinuxCNC keeps the arc",
    "[program][arcs][cli]") {
  TempDir t;
  const std::string head =
      "TOOL PATH/ARC,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nLOADTL/1\nSPINDL/RPM,6000,CLW\n"
      "FEDRAT/MMPM,600\n";
  const std::string arc = "CIRCLE/10,0,0,0,0,1,10\nGOTO/20,0,0\nGOTO/20,-10,0\nEND-OF-PATH\n";
  // A10 from the start: the table does not move under TCP before the arc.
  write_file(t.path("still.cls"),
             head + "GOTO/0,10,0,0,-0.1736482,0.9848078\nGOTO/10,10,0\n" + arc);
  // A0 at the start, A10 by a feed move under TCP, then the same arc.
  write_file(t.path("turned.cls"),
             head + "GOTO/0,10,0,0,0,1\nGOTO/10,10,0,0,-0.1736482,0.9848078\n" + arc);
  const auto post = [&](const std::string& cls, const std::string& dialect) {
    const auto r = run_taxopt("--in " + t.path(cls) + " --dialect " + dialect +
                              " --method none -q --gcode " + t.path("o.nc"));
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::string text = read_file(t.path("o.nc"));
    return text.find(" G2 ") != std::string::npos || text.find(" G3 ") != std::string::npos;
  };
  CHECK(post("still.cls", "fanuc"));
  CHECK_FALSE(post("turned.cls", "fanuc"));
  CHECK_FALSE(post("turned.cls", "haas"));
  CHECK(post("turned.cls", "linuxcnc"));
  CHECK(post("turned.cls", "siemens"));
}

TEST_CASE(
    "program: LinuxCNC programs bound the controller's blending (G64 P Q0 from "
    "blend_tolerance_mm, G61 at 0), and rs274 sets that motion mode",
    "[program][rs274][cli]") {
  REQUIRE(have_rs274());
  TempDir t;
  write_file(t.path("a.cls"),
             "TOOL PATH/T,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nLOADTL/1\nSPINDL/RPM,6000,CLW\n"
             "FEDRAT/MMPM,500\nGOTO/0,0,5,0,0,1\nGOTO/10,0,0\nGOTO/10,10,0\nEND-OF-PATH\n");
  const std::string head =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
      "max_deg = 120\n[axes.C]\ncontinuous = true\n[gcode]\n";
  for (const auto& [key, block, canon] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"", "G64 P0.0100 Q0", "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.010000)"},
           {"blend_tolerance_mm = 0.05\n", "G64 P0.0500 Q0",
            "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.050000)"},
           {"blend_tolerance_mm = 0\n", "G61", "SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)"}}) {
    INFO(key);
    write_file(t.path("m.toml"), head + key);
    const auto r = run_taxopt("--in " + t.path("a.cls") + " --machine " + t.path("m.toml") +
                              " --method none -q --gcode " + t.path("o.ngc"));
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::string text = read_file(t.path("o.ngc"));
    CHECK(text.find("\n" + block + "\n") != std::string::npos);
    std::vector<CanonMove> moves;
    const RunResult rs = run_rs274(t.path("o.ngc"), moves);
    REQUIRE(rs.code == 0);
    CHECK_THAT(rs.out, Catch::Contains(canon));
    if (block != "G61") CHECK_THAT(rs.out, Catch::Contains("SET_NAIVECAM_TOLERANCE(0.0000)"));
  }
  write_file(t.path("m.toml"), head + "blend_tolerance_mm = 2\n");
  const auto bad = run_taxopt("--in " + t.path("a.cls") + " --machine " + t.path("m.toml") +
                              " --method none -q --gcode " + t.path("o.ngc"));
  CHECK(bad.code == 2);
  CHECK_THAT(bad.err, Catch::Contains("gcode.blend_tolerance_mm must be within [0, 1] mm"));
}

TEST_CASE(
    "program: the first table turn goes to the winding nearest home, whatever method, on "
    "LinuxCNC's sample (C within +-36000 deg)",
    "[program][cli][global][slow]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  for (const char* method : {"paper", "global"}) {
    INFO(method);
    const auto r =
        run_taxopt("--in " + d + "demo/sine.cls --part " + d + "demo/sine.stl --machine " + d +
                   "machines/linuxcnc-xyzac-trt.toml --method " + method +
                   " --feed-schedule -q --gcode " + t.path("o.ngc"));
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::string text = read_file(t.path("o.ngc"));
    const std::size_t at = text.find("\nG0 A");
    REQUIRE(at != std::string::npos);
    const std::size_t c = text.find(" C", at + 1);
    const double c_deg = std::stod(text.substr(c + 2, 20));
    // Before: the global method's first turn went to C-720, two turns (24 s) from home.
    CHECK(std::abs(c_deg) <= 180.0);
  }
}

TEST_CASE(
    "program: every block's end stays within the machine's travel, the spindle's: NX's "
    "variable-axis file on LinuxCNC's sample machine leaves Z's at its approach with a 50 mm "
    "tool (where LinuxCNC's controller stopped), exit 1 naming that line",
    "[program][travel]") {
  TempDir dir;
  const std::string cls = real_data("mech491-variable-axis-ballmill.cls");
  const std::string machine =
      std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml";
  // The sample's simulation starts with G54 at zero: the work offset the controller ran with.
  const std::string args = "--in " + cls + " --machine " + machine +
                           " --spindle-rpm 1000 --tool-number 1 --method none --feed-schedule -q "
                           "--work-offset 0,0,0 --gcode " +
                           dir.path("o.ngc");
  // 50 mm in the file's inches.
  const RunResult r = run_taxopt(args + " --gauge-length 1.9685");
  INFO(r.err);
  CHECK(r.code == 1);
  CHECK_FALSE(file_exists(dir.path("o.ngc")));
  const std::size_t at = r.err.find("takes the spindle to Z ");
  REQUIRE(at != std::string::npos);
  CHECK(std::stod(r.err.substr(at + 23)) > 120.0);
  // The line named is the positioning at the approach height (X, Y and Z), the first block
  // with TCP on.
  const std::size_t l = r.err.find("G-code line ");
  REQUIRE(l != std::string::npos);
  const int line = std::stoi(r.err.substr(l + 12));
  // Written anyway, the program says what failed in comments at its top; the line named is
  // the program's as written, those comments counted (they were not: the named line was off
  // by their number).
  const RunResult forced = run_taxopt(args + " --gauge-length 1.9685 --force");
  const std::vector<std::string> lines = lines_of(read_file(dir.path("o.ngc")));
  std::size_t marks = 0;
  for (const std::string& s : lines) {
    if (s.rfind("(NOT VERIFIED", 0) == 0 || s.rfind("(FAILED", 0) == 0) ++marks;
  }
  CHECK(marks > 0);
  CHECK(forced.err.find("G-code line " + std::to_string(line) + " ") != std::string::npos);
  const std::size_t n = static_cast<std::size_t>(line);
  REQUIRE(n <= lines.size());
  // A rapid, or the joint-safe feed block in its place after its comment.
  CHECK((lines[n - 1].rfind("G0 X", 0) == 0 || lines[n - 1].rfind("G1 X", 0) == 0));
  CHECK(lines[n - 1].find(" Y") != std::string::npos);
  CHECK(lines[n - 1].find(" Z") != std::string::npos);
  CHECK((lines[n - 2] == "M428" ||
         (lines[n - 2].find("joint-safe") != std::string::npos && lines[n - 3] == "M428")));
  // With the tip as the spindle (no tool length given) that block stays within the travel:
  // what the tool's length adds is what breaks it.
  const RunResult tip = run_taxopt(args);
  CHECK(tip.err.find("G-code line " + std::to_string(line) + " ") == std::string::npos);
}

TEST_CASE(
    "program: LinuxCNC with TCP on, the joints where its planner accelerates at the axes' limits "
    "are in the report, and a joint past its limit is a warning naming the line",
    "[program][tcp][slow]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  REQUIRE(generate_small_sine(t) == 0);
  const std::string common = "--in " + t.path("g.cls") + " --part " + t.path("g.stl") +
                             " --gauge-length 50 --method paper --feed-schedule -q --report " +
                             t.path("r.json") + " --gcode " + t.path("o.ngc") + " --machine ";
  // The preset (tcp): where LinuxCNC accelerates the program's axes at their limits (a rapid
  // down to a pass that tilts A, a chain's end while A turns), a joint such as Z = f(Y, Z, A)
  // passes its 300 mm/s^2 (the controller test runs this program on LinuxCNC and holds the
  // measured peaks to these predictions).
  auto r = run_taxopt(common + d + "machines/linuxcnc-xyzac-trt.toml");
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto report = nlohmann::json::parse(read_file(t.path("r.json")));
  const auto& peaks = report["gcode"]["tcp_joint_peaks"];
  REQUIRE(peaks.is_object());
  std::vector<std::string> lines;
  {
    std::istringstream text(read_file(t.path("o.ngc")));
    for (std::string l; std::getline(text, l);) lines.push_back(l);
  }
  bool warned = false;
  for (const auto& f : report["findings"]) {
    if (f["code"] != "tcp_joint_limit") continue;
    warned = true;
    // About a block of the program: its G-code line, no CL line.
    CHECK(f["line"].is_null());
    CHECK(f["gcode_line"].get<int>() > 0);
    CHECK_THAT(f["message"].get<std::string>(),
               Catch::Contains("G-code line " + std::to_string(f["gcode_line"].get<int>())));
  }
  bool over = false;
  for (const char* joint : {"X", "Y", "Z", "A", "C"}) {
    INFO(joint);
    const auto& p = peaks[joint];
    const int line = p["accel_line"].get<int>();
    if (line == 0) continue;
    // The line is a motion block: a rapid, a feed block that starts or ends a chain.
    const std::string block = lines.at(static_cast<std::size_t>(line - 1));
    CHECK((block.rfind("G0 ", 0) == 0 || block.rfind("G1 ", 0) == 0));
    const double limit = 300.0;  // the preset's every axis: mm/s^2 and deg/s^2
    over |= p["accel_per_s2"].get<double>() > 1.001 * limit;
  }
  CHECK(over == warned);
  CHECK(over);  // a joint past 300 (the controller test measures the same program on LinuxCNC)
  CHECK(warned);
  // The remedy the warning gives: the axes' accelerations at a share of theirs, the joints'
  // left at 300. Posted again for the machine so configured, no joint passes its limit (the
  // program is scheduled anew at the lower limits: within the warning's 0.1 %).
  const auto& share = report["gcode"]["tcp_axis_accel_scale"];
  REQUIRE(share.is_number());
  const double s = share.get<double>();
  // 0.855: the program's first positioning (X, Y and Z at once with A at -20.6 deg, from the
  // start the model takes) drives joint Z at 351 mm/s^2; the blocks of the cut at most 302.
  CHECK(s > 0.8);
  CHECK(s < 1.0);
  const std::string preset = read_file(d + "machines/linuxcnc-xyzac-trt.toml");
  const auto scaled = [&](double axis_share, double joint_mm_s2) {
    std::string m = preset;
    for (const std::string unit : {"mm", "deg"}) {
      const std::string key = "max_accel_" + unit + "_s2 = 300.0";
      std::ostringstream with;
      with << "max_accel_" << unit << "_s2 = " << std::setprecision(10) << 300.0 * axis_share
           << "\njoint_max_accel_" << unit << "_s2 = " << joint_mm_s2;
      for (std::size_t at = m.find(key); at != std::string::npos; at = m.find(key, at + 1)) {
        m.replace(at, key.size(), with.str());
      }
    }
    return m;
  };
  write_file(t.path("s.toml"), scaled(s, 300.0));
  REQUIRE(count_of(read_file(t.path("s.toml")), "joint_max_accel_") == 5);
  r = run_taxopt(common + t.path("s.toml"));
  REQUIRE(r.code == 0);
  auto remedied = nlohmann::json::parse(read_file(t.path("r.json")));
  for (const auto& f : remedied["findings"]) CHECK(f["code"] != "tcp_joint_limit");
  CHECK(remedied["gcode"]["tcp_axis_accel_scale"].is_null());
  for (const char* joint : {"X", "Y", "Z", "A", "C"}) {
    INFO(joint);
    CHECK(remedied["gcode"]["tcp_joint_peaks"][joint]["accel_per_s2"].get<double>() <=
          1.001 * 300.0);
  }
  // Joints stronger than the axes (the same axes, joints 2 % above the highest joint peak):
  // the same peaks, within them.
  double highest = 0.0;
  for (const char* joint : {"X", "Y", "Z", "A", "C"}) {
    highest = std::max(highest, peaks[joint]["accel_per_s2"].get<double>());
  }
  write_file(t.path("j.toml"), scaled(1.0, std::ceil(1.02 * highest)));
  r = run_taxopt(common + t.path("j.toml"));
  REQUIRE(r.code == 0);
  remedied = nlohmann::json::parse(read_file(t.path("r.json")));
  for (const auto& f : remedied["findings"]) CHECK(f["code"] != "tcp_joint_limit");
  for (const char* joint : {"X", "Y", "Z", "A", "C"}) {
    INFO(joint);
    CHECK(remedied["gcode"]["tcp_joint_peaks"][joint]["accel_per_s2"] ==
          peaks[joint]["accel_per_s2"]);
  }
  // A share the bisection would have to go below 0.05 for (joints far weaker than the axes):
  // 0, and the warning says no share does.
  write_file(t.path("w.toml"), scaled(1.0, 5.0));
  r = run_taxopt(common + t.path("w.toml"));
  REQUIRE(r.code == 0);
  remedied = nlohmann::json::parse(read_file(t.path("r.json")));
  CHECK(remedied["gcode"]["tcp_axis_accel_scale"].get<double>() == 0.0);
  bool none = false;
  for (const auto& f : remedied["findings"]) {
    none |= f["code"] == "tcp_joint_limit" &&
            f["message"].get<std::string>().find("no share of the [AXIS_*]") != std::string::npos;
  }
  CHECK(none);
  // Machine mode: LinuxCNC plans the joints themselves; nothing to predict.
  std::string toml = preset;
  toml.replace(toml.find("mode = \"tcp\""), 12, "mode = \"machine\"");
  write_file(t.path("m.toml"), toml);
  r = run_taxopt(common + t.path("m.toml"));
  REQUIRE(r.code == 0);
  report = nlohmann::json::parse(read_file(t.path("r.json")));
  CHECK(report["gcode"]["tcp_joint_peaks"].is_null());
}

TEST_CASE(
    "program: operations that keep the tool, the spindle speed and the coolant run on without "
    "M5 / M9 and a restart between them, in every dialect, and a tool change stops the spindle",
    "[program][real]") {
  const std::string f = "mech491-project2-multiop.cls";  // 15 operations, 3 tools
  for (const char* dialect : kDialects) {
    INFO(dialect);
    TempDir dir;
    const RunResult r =
        run_taxopt("--in " + real_path(f, dir.dir()) + real_flags(f) + " --dialect " + dialect +
                   " --gcode " + dir.path("o.nc") + " --method none -q");
    INFO(r.err);
    REQUIRE(r.code == 0);
    std::istringstream text(read_file(dir.path("o.nc")));
    std::string last_s;  // the last spindle start written
    bool stopped = false, changed_tool = false;
    int pointless = 0, stops = 0, changes = 0;
    for (std::string l; std::getline(text, l);) {
      const std::size_t s = l.find('S');
      const bool start = s != std::string::npos && s + 1 < l.size() &&
                         std::isdigit(static_cast<unsigned char>(l[s + 1])) &&
                         (l.find("M3") != std::string::npos || l.find("M4") != std::string::npos);
      // A tool change: a T word (T1 M6, Heidenhain's T2 G17, a TNC's TOOL CALL).
      if (std::regex_search(l, std::regex(R"((^|\s)T=?\d)")) ||
          l.find("TOOL CALL") != std::string::npos) {
        changed_tool = true;
        ++changes;
      }
      if (std::regex_search(l, std::regex(R"((^|\s)M0?5(\s|$))"))) {
        stopped = true;
        ++stops;
      }
      if (start) {
        const std::string words = l.substr(s);
        if (stopped && !changed_tool && words == last_s) ++pointless;
        last_s = words;
        stopped = changed_tool = false;
      }
    }
    CHECK(pointless == 0);
    CHECK(stops >= 1);
    CHECK(stops <= changes + 1);
  }
}

TEST_CASE(
    "program: the end parks X Y where the machine file says, in machine coordinates, after the "
    "retract and the rotaries' home, in every dialect and unit, and rs274 runs it there",
    "[program][real]") {
  const std::string f = "mech491-project2-multiop.cls";
  // The file is in inches: --units-out mm writes mm.
  const std::map<std::string, std::string> want = {{"linuxcnc", "G53 G0 X10.0000 Y-20.0000"},
                                                   {"fanuc", "G53 G0 X10.0000 Y-20.0000"},
                                                   {"haas", "G53 G0 X10.0000 Y-20.0000"},
                                                   {"siemens", "G0 SUPA X10.0000 Y-20.0000"},
                                                   {"heidenhain", "G00 X10.0000 Y-20.0000 M91"}};
  for (const char* dialect : kDialects) {
    for (const char* units : {"mm", "in"}) {
      INFO(dialect << " " << units);
      TempDir dir;
      write_file(dir.path("m.toml"),
                 std::string("kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
                             "max_deg = 120\n[axes.C]\ncontinuous = true\n[gcode]\ndialect = \"") +
                     dialect + "\"\nend_park_xy_mm = [10, -20]\n");
      const RunResult r =
          run_taxopt("--in " + real_path(f, dir.dir()) + real_flags(f) + " --machine " +
                     dir.path("m.toml") + " --units-out " + units + " --gcode " + dir.path("o.nc") +
                     " --report " + dir.path("r.json") + " --method none -q");
      INFO(r.err);
      REQUIRE(r.code == 0);
      const std::string text = read_file(dir.path("o.nc"));
      const std::vector<std::string> lines = lines_of(text);
      std::string park = want.at(dialect);
      if (std::string(units) == "in") {
        park = std::regex_replace(park, std::regex("X10.0000 Y-20.0000"), "X0.3937 Y-0.7874");
      }
      // The park is the program's last motion block: after the last retract and the home.
      std::size_t at = lines.size();
      for (std::size_t i = 0; i < lines.size(); ++i) {
        if (lines[i].find(park) != std::string::npos) at = i;
      }
      REQUIRE(at < lines.size());
      CHECK(count_of(text, park) == 1);
      const std::map<std::string, GcodeDialect> dialects = {
          {"linuxcnc", GcodeDialect::LinuxCNC},
          {"fanuc", GcodeDialect::Fanuc},
          {"haas", GcodeDialect::Haas},
          {"siemens", GcodeDialect::Siemens},
          {"heidenhain", GcodeDialect::Heidenhain}};
      const std::vector<GcodeMove> moves = read_gcode_moves(text, "o.nc", dialects.at(dialect));
      REQUIRE(!moves.empty());
      CHECK(moves.back().line == static_cast<int>(at) + 1);
      CHECK(moves.back().retract);
      CHECK(moves.back().given == 3u);  // X and Y
      CHECK(moves[moves.size() - 2].tilt_deg == 0.0);
      CHECK(std::fmod(moves[moves.size() - 2].c_deg, 360.0) == 0.0);  // C home at a whole turn
      if (std::string(dialect) == "linuxcnc" && have_rs274()) {
        std::vector<CanonMove> pts, all;
        const RunResult rs = run_rs274(dir.path("o.nc"), pts, {}, &all);
        INFO(rs.out);
        CHECK(rs.code == 0);
        REQUIRE(!all.empty());
        // rs274 standalone has every offset at 0: machine X Y are the program's.
        const double s = std::string(units) == "mm" ? 1.0 : 1.0 / 25.4;
        CHECK(all.back().x == Approx(10.0 * s).margin(1e-4));
        CHECK(all.back().y == Approx(-20.0 * s).margin(1e-4));
        // The program's time counts the park: the same program without it is shorter.
        write_file(dir.path("n.toml"), std::regex_replace(read_file(dir.path("m.toml")),
                                                          std::regex("end_park_xy_mm.*\n"), ""));
        REQUIRE(run_taxopt("--in " + real_path(f, dir.dir()) + real_flags(f) + " --machine " +
                           dir.path("n.toml") + " --units-out " + units + " --gcode " +
                           dir.path("n.nc") + " --report " + dir.path("n.json") +
                           " --method none -q")
                    .code == 0);
        const auto time_of = [&](const char* name) {
          const nlohmann::json j = nlohmann::json::parse(read_file(dir.path(name)));
          return j["gcode"]["time_s"].get<double>();
        };
        CHECK(time_of("r.json") > time_of("n.json") + 0.01);
      }
    }
  }
  // Outside the travel, or without the retract that lifts the tool first: refused.
  const std::string head =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n";
  const auto refusal = [](const std::string& toml) {
    return input_error_of([&] { (void)parse_machine_toml(toml, "m.toml"); });
  };
  CHECK_THAT(
      refusal(head + "[axes.X]\nmin_mm = -300\nmax_mm = 0\n[gcode]\nend_park_xy_mm = [10, 0]\n"),
      Catch::Contains("gcode.end_park_xy_mm's X lies outside the machine's travel"));
  CHECK_THAT(refusal(head + "[gcode]\nsafe_retract = \"none\"\nend_park_xy_mm = [0, 0]\n"),
             Catch::Contains("needs the safe retract"));
  for (const char* bad : {"[0]", "[0, 1, 2]", "[\"a\", 0]", "[nan, 0]", "0"}) {
    INFO(bad);
    CHECK_THAT(refusal(head + "[gcode]\nend_park_xy_mm = " + bad + "\n"),
               Catch::Contains("gcode.end_park_xy_mm"));
  }
}

TEST_CASE(
    "program: the writer's blocks of every real CL file, in every dialect and in machine mode, "
    "are the program's lines: each point's line a block leading to it, every motion read back "
    "a motion block (arcs, index moves, linearisation and joint-safe rapids among them)",
    "[program][real][gcode]") {
  std::size_t arcs = 0, index_moves = 0, linearised = 0, joint_safe = 0;
  for (const std::string& f : real_files()) {
    const Toolpath tp = read_real(f);
    for (const char* dialect : kDialects) {
      for (GcodeMode mode : {GcodeMode::Tcp, GcodeMode::Machine}) {
        INFO(f << " --dialect " << dialect << (mode == GcodeMode::Machine ? " machine mode" : ""));
        Machine machine = default_machine();
        machine.gcode.dialect = dialect_of(dialect);
        machine.gcode.mode = mode;
        JobOptions options;
        options.method = Method::None;
        options.spindle_rpm = 8000.0;
        options.tool_number = 3;
        JobResult r;
        try {
          r = run_job(tp, machine, options);
        } catch (const InputError& e) {
          // A dwell in a dialect whose dwell words taxopt does not write: refused.
          REQUIRE(std::string(e.what()).find("DELAY:") != std::string::npos);
          continue;
        }
        REQUIRE_FALSE(r.gcode.text.empty());
        check_blocks(r.gcode, machine.gcode.dialect, machine.rotary.tilt_letter());
        arcs += r.gcode.arcs_kept;
        index_moves += r.gcode.index_moves;
        linearised += r.gcode.linearised_blocks;
        joint_safe += r.gcode.joint_safe_rapids.size();
        // Each run of joint-safe rapids follows a comment saying what they are (a machinist's
        // rapid override does not govern them).
        const std::vector<std::string> lines = lines_of(r.gcode.text);
        const std::set<int> safe(r.gcode.joint_safe_rapids.begin(),
                                 r.gcode.joint_safe_rapids.end());
        for (int at : r.gcode.joint_safe_rapids) {
          int j = at - 1;  // 1-based line before it
          while (safe.count(j)) --j;
          REQUIRE(j >= 1);
          CHECK_THAT(lines[static_cast<std::size_t>(j - 1)],
                     Catch::Contains("joint-safe rapid: a feed block at the joints' rate"));
        }
      }
    }
  }
  CHECK(arcs > 0);
  CHECK(index_moves > 0);
  CHECK(linearised > 0);
  CHECK(joint_safe > 0);
}

TEST_CASE(
    "program: a reorientation in rapid steps is one index move that comes down at its last "
    "step (Creo wrote 11 steps: 8 index cycles) -- a stop between the steps splits it",
    "[program][rs274][integration]") {
  REQUIRE(have_rs274());
  // A pass along X, then the tool turned about X in 11 rapid steps of 6 deg on a 30 mm arc
  // above the pass's end (as Creo's GPOST file wrote its reorientation), then a pass at 66 deg.
  const auto goto_at = [](double x, double y, double z, double deg) {
    const double a = deg * std::acos(-1.0) / 180.0;
    std::ostringstream os;
    os << std::fixed << std::setprecision(6) << "GOTO/" << x << "," << y << "," << z << ",0,"
       << -std::sin(a) << "," << std::cos(a) << "\n";
    return os.str();
  };
  const auto file = [&](int stop_before_step) {
    std::string cl = "UNITS/MM\nLOADTL/4\nCUTTER/10,5\nSPINDL/8000,RPM,CLW\nFEDRAT/800,MMPM\n";
    cl += "RAPID\n" + goto_at(0, 0, 50, 0) + goto_at(0, 0, 5, 0) + goto_at(40, 0, 5, 0);
    for (int s = 1; s <= 11; ++s) {
      const double a = 6.0 * s * std::acos(-1.0) / 180.0;
      if (s == stop_before_step) cl += "STOP\n";
      cl += "RAPID\n" + goto_at(40, 30 * std::sin(a), 5 + 30 * std::cos(a), 6.0 * s);
    }
    return cl + goto_at(40, 10, 5, 66) + goto_at(0, 10, 5, 66) + "RAPID\n" +
           goto_at(0, 10, 60, 66) + "FINI\n";
  };
  const std::string machine = std::string(TAXOPT_SOURCE_DIR) + "/data/machines/generic-ac-trt.toml";
  for (const int stop : {0, 6}) {
    INFO("STOP before step " << stop);
    TempDir t;
    write_file(t.path("c.apt"), file(stop));
    const RunResult r = run_taxopt("--in " + t.path("c.apt") + " --machine " + machine +
                                   " --method none -q --gcode " + t.path("o.ngc") + " --report " +
                                   t.path("r.json"));
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto report = nlohmann::json::parse(read_file(t.path("r.json")));
    // One cycle for the whole reorientation; with the stop, one on each side of it (the stop
    // happens where the file puts it: at step 5, the tool down there).
    CHECK(report["gcode"]["index_moves"] == (stop ? 2 : 1));
    CHECK(report["gcode"]["index_passed_over_points"] == (stop ? 9 : 10));
    CHECK(report["ok"] == true);
    CHECK(report["problems"].empty());
    const std::string text = read_file(t.path("o.ngc"));
    std::size_t retracts = 0;
    for (std::size_t at = text.find("G53 G0 Z"); at != std::string::npos;
         at = text.find("G53 G0 Z", at + 1)) {
      ++retracts;
    }
    CHECK(retracts == (stop ? 4u : 3u));  // the operation's start, the index moves, the end
    // rs274 runs it; the tool comes down at the last step, tilted 66 deg, and the pass at 66
    // deg starts there.
    std::vector<CanonMove> points, all;
    REQUIRE(run_rs274(t.path("o.ngc"), points, {}, &all).code == 0);
    const double a66 = 66.0 * std::acos(-1.0) / 180.0;
    const Vec3d last_step(40, 30 * std::sin(a66), 5 + 30 * std::cos(a66));
    std::size_t at_last = all.size();
    for (std::size_t m = 0; m < all.size(); ++m) {
      if ((Vec3d(all[m].x, all[m].y, all[m].z) - last_step).norm() < 1e-3) at_last = m;
    }
    REQUIRE(at_last + 1 < all.size());
    CHECK(std::abs(all[at_last].a - 66.0) < 1e-6);
    const CanonMove& cut = all[at_last + 1];
    CHECK(cut.feed);
    CHECK((Vec3d(cut.x, cut.y, cut.z) - Vec3d(40, 10, 5)).norm() < 1e-3);
  }
}
