// The command line as scripts see it: exit codes, the error line, atomic outputs.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cctype>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "support.hpp"
#include "support/digest.hpp"
#include "taxopt/core/types.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt::test;
using taxopt::Vec3d;

namespace {

const char* kSmallCl =
    "TOOL PATH/T,TOOL,BALL\nTLDATA/MILL,6.0,3.0,20.0,0,0\nRAPID\nGOTO/0,0,10,0,0,1\n"
    "FEDRAT/MMPM,250\nGOTO/0,0,0,0,-0.3281,0.9447\nGOTO/1,0,0,0,-0.6063,0.7952\n"
    "GOTO/2,0,0\nEND-OF-PATH\n";

}  // namespace

TEST_CASE("cli: --version and --help exit 0", "[cli]") {
  const auto v = run_taxopt("--version");
  CHECK(v.code == 0);
  CHECK_THAT(v.out, Catch::Contains("taxopt 0."));
  const auto h = run_taxopt("--help");
  CHECK(h.code == 0);
  CHECK_THAT(h.out, Catch::Contains("--gcode"));
}

TEST_CASE("cli: bad usage exits 2 with one error line", "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  for (const std::string& args :
       {std::string("--bogus"), std::string("--gcode x.nc"), "--in " + t.path("a.cls"),
        "--in " + t.path("a.cls") + " --gcode " + t.path("o.nc") + " --method fast",
        "--in " + t.path("a.cls") + " --gcode " + t.path("o.nc") + " --method none --feed -3",
        "--in " + t.path("missing.cls") + " --gcode " + t.path("o.nc")}) {
    INFO(args);
    const auto r = run_taxopt(args);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: "));
    CHECK_FALSE(file_exists(t.path("o.nc")));
  }
}

TEST_CASE("cli: a malformed CL file names file and line, exits 2, writes nothing",
          "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("bad.cls"), "GOTO/0,0,0\nGOTO/1,2..0,3\n");
  write_file(t.path("out.nc"), "good old program\n");
  const auto r = run_taxopt("--in " + t.path("bad.cls") + " --gcode " + t.path("out.nc") +
                            " --report " + t.path("r.json") + " --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: " + t.path("bad.cls") + ":2: "));
  CHECK(read_file(t.path("out.nc")) == "good old program\n");
  CHECK_FALSE(file_exists(t.path("r.json")));
  // No temporary file is left behind either.
  CHECK(run("ls -A " + t.dir() + " | grep -c taxopt-").out == "0\n");
}

TEST_CASE("cli: an output path equal to the input is refused", "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  const auto r =
      run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.dir() + "/./a.cls --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("is the input file"));
  CHECK(read_file(t.path("a.cls")) == kSmallCl);
}

TEST_CASE("cli: an unwritable output exits 2 and leaves the others unwritten", "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  const auto r = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.nc") +
                            " --report /nonexistent-dir/r.json --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("/nonexistent-dir/r.json"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
}

TEST_CASE("cli: axes out of the machine's range exit 1 and write nothing without --force",
          "[cli]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  write_file(t.path("m.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -10\nmax_deg = 10\n"
             "[axes.C]\ncontinuous = true\n");
  const std::string base = "--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") +
                           " --machine " + t.path("m.toml") + " --gcode " + t.path("o.nc") +
                           " --method none";
  const auto r = run_taxopt(base);
  CHECK(r.code == 1);
  CHECK_THAT(r.err,
             Catch::Contains(t.path("a.cls") + ":6: operation T: no pose within the axis ranges"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
}

TEST_CASE("cli: bad optimiser options are refused clearly", "[cli]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  for (const char* bad : {"--method global --objective fastest", "--method global --jerk-weight -1",
                          "--method best"}) {
    const auto r = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.nc") + " " + bad);
    INFO(bad);
    CHECK(r.code == 2);
    CHECK(!file_exists(t.path("o.nc")));
  }
  for (const char* bad : {"--grid 0", "--grid 20", "--max-deviation -1", "--max-deviation 95"}) {
    const auto b = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.nc") + " " + bad);
    CHECK(b.code == 2);
    CHECK_THAT(b.err, Catch::Contains(std::string(bad).substr(0, std::string(bad).find(' '))));
  }
  const auto p = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.nc") +
                            " --method none --part x.stl");
  CHECK(p.code == 2);
  CHECK_THAT(p.err, Catch::Contains("--part"));
}

TEST_CASE("cli: report, CSV and CL file carry the contract's names", "[cli]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  const auto r =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --gcode " +
                 t.path("o.nc") + " --report " + t.path("r.json") + " --points-csv " +
                 t.path("p.csv") + " --out-cls " + t.path("o.cls") + " --method none -q");
  REQUIRE(r.code == 0);
  CHECK(r.out.empty());
  const auto j = nlohmann::json::parse(read_file(t.path("r.json")));
  CHECK(j["method"] == "none");
  CHECK(j["taxopt_version"].is_string());
  const auto& op = j["operations"].at(0);
  CHECK(op["name"] == "T");
  CHECK(op["points"] == 4);
  CHECK(op["feed_mm_min"] == 250.0);
  for (const char* side : {"before", "after"}) {
    for (const char* key : {"max_omega_deg_s", "max_accel_deg_s2", "rms_accel_deg_s2",
                            "rms_omega_deg_s", "c_jumps", "colliding_points"}) {
      CHECK(op[side].contains(key));
    }
    // Each rotary axis on its own; no share without the machine file's limits.
    for (const char* axis : {"A", "C"}) {
      for (const char* key : {"max_omega_deg_s", "max_accel_deg_s2", "rms_accel_deg_s2"}) {
        CHECK(op[side]["axes"][axis].contains(key));
      }
      CHECK(op[side]["axes"][axis]["accel_share"].is_null());
    }
  }
  CHECK(op.contains("worst_axis"));
  CHECK(op["max_axis_change_deg"] == 0.0);
  CHECK(op["verification"]["within_axis_limits"] == true);
  CHECK(op["verification"]["roundtrip_max_mm"].get<double>() < 1e-4);
  CHECK(op["verification"]["collision_free"].is_null());
  for (const char* key : {"contacts", "cspace", "optimise", "post", "verify"}) {
    CHECK(op["timings_s"][key].get<double>() >= 0.0);
  }
  CHECK_FALSE(op.contains("kept_input_points"));  // no optimiser
  // Before and after agree with --method none; the paper's first axis gives its omega.
  CHECK(op["before"]["max_omega_deg_s"] == op["after"]["max_omega_deg_s"]);
  // With an optimiser the report says how many points kept their input axes, and why.
  REQUIRE(run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --gcode " +
                     t.path("o.nc") + " --report " + t.path("r.json") + " --method paper -q")
              .code == 0);
  const auto kept =
      nlohmann::json::parse(read_file(t.path("r.json")))["operations"].at(0)["kept_input_points"];
  std::size_t by_reason = 0;
  for (const char* why : {"collision", "peak_rate", "no_gain", "no_free_axis", "method_choice"}) {
    by_reason += kept["by_reason"][why].get<std::size_t>();
  }
  CHECK(kept["total"].get<std::size_t>() == by_reason);
  for (const char* key : {"join_points", "whole_passes", "stretches"}) CHECK(kept.contains(key));
  const std::string csv = read_file(t.path("p.csv"));
  CHECK_THAT(
      csv, Catch::StartsWith(
               "op,index,arc_mm,tip_x,tip_y,tip_z,axis_i,axis_j,axis_k,cc_x,cc_y,cc_z,n_x,n_y,n_z,"
               "tilt_deg,yaw_deg,A_deg,C_deg,omega_deg_s,accel_deg_s2,free_cells,feed_mm_min,cl_"
               "line,findings,gap_mm,surface,normal_uncertainty_deg,omega_tilt_deg_s,"
               "omega_C_deg_s,accel_tilt_deg_s2,accel_C_deg_s2,tilt_after_deg,"
               "cutting_diameter_before_mm,cutting_diameter_mm\n"));
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 5);
  CHECK(read_file(t.path("o.cls")) == kSmallCl);
}

TEST_CASE("cli: the same input gives the same bytes at 1 and 2 threads", "[cli]") {
  TempDir t;
  const std::string in = real_data("mech491-variable-axis-ballmill.cls");
  const auto a =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + in + " --gcode " + t.path("1.nc") +
                 " --points-csv " + t.path("1.csv") + " --method none --threads 1 -q");
  const auto b =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + in + " --gcode " + t.path("2.nc") +
                 " --points-csv " + t.path("2.csv") + " --method none --threads 2 -q");
  REQUIRE(a.code == 0);
  REQUIRE(b.code == 0);
  CHECK(read_file(t.path("1.nc")) == read_file(t.path("2.nc")));
  CHECK(read_file(t.path("1.csv")) == read_file(t.path("2.csv")));
}

TEST_CASE("cli: generate reproduces the bundled demo files byte for byte", "[cli][generator]") {
  TempDir t;
  const auto r =
      run_taxopt("generate --out-cls " + t.path("s.cls") + " --out-mesh " + t.path("s.stl"));
  REQUIRE(r.code == 0);
  CHECK(read_file(t.path("s.cls")) ==
        read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls"));
  CHECK(read_file(t.path("s.stl")) ==
        read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.stl"));
}

TEST_CASE("cli: generate refuses impossible settings with exit 2", "[cli][generator][bad-input]") {
  TempDir t;
  for (const std::string& bad :
       {std::string("--scallop 0"), std::string("--tool-radius -1"), std::string("--surface torus"),
        std::string("--height 1 --wavelength 4"),
        // A surface the ball cannot follow, refused before its raster is made (it asked for
        // 5.7 GB of points, then std::bad_alloc).
        std::string("--wavelength 0.0001"), std::string("--wavelength 0.001"),
        std::string("--surface bump --wavelength 0.0001")}) {
    INFO(bad);
    const auto r = run_taxopt("generate --out-cls " + t.path("s.cls") + " " + bad);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: "));
    CHECK_FALSE(file_exists(t.path("s.cls")));
  }
}

TEST_CASE("cli: an input path whose shank hits the part exits 1, names the lines, writes nothing",
          "[cli][collision][slow]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  // The tool's exact bodies first (no clearances): 60 points.
  const std::string base = "--in " + d + "demo/sine.cls --part " + d + "demo/sine.stl --machine " +
                           d + "machines/paper-ac.toml --method none --gauge-length 18 --gcode " +
                           t.path("o.nc") + " --report " + t.path("r.json") +
                           " --shank-clearance 0 --holder-clearance 0";
  write_file(t.path("o.nc"), "previous good program\n");
  const auto r = run_taxopt(base);
  CHECK(r.code == 1);
  CHECK_THAT(r.err,
             Catch::Contains("sine.cls:23: operation SINE_FINISH: 60 CL points where the tool"));
  CHECK(read_file(t.path("o.nc")) == "previous good program\n");
  CHECK_FALSE(file_exists(t.path("r.json")));
  // --force writes it anyway, still exits 1, and the report says what was wrong.
  const auto f = run_taxopt(base + " --force");
  CHECK(f.code == 1);
  const auto j = nlohmann::json::parse(read_file(t.path("r.json")));
  CHECK(j["ok"] == false);
  CHECK(j["operations"][0]["after"]["colliding_points"] == 60);
  CHECK(j["operations"][0]["verification"]["collision_free"] == false);
  // The default clearances (shank 0.5 mm) judge more points, never fewer.
  const auto m = run_taxopt(base.substr(0, base.find(" --shank-clearance")) + " --force -q");
  CHECK(m.code == 1);
  CHECK(nlohmann::json::parse(
            read_file(t.path("r.json")))["operations"][0]["after"]["colliding_points"]
            .get<int>() > 60);
  // With the demo's 15 mm stub tool the path is clear, clearances included.
  const auto ok =
      run_taxopt("--in " + d + "demo/sine.cls --part " + d + "demo/sine.stl --machine " + d +
                 "machines/paper-ac.toml --method none --gauge-length 15 --report " +
                 t.path("r2.json") + " -q");
  CHECK(ok.code == 0);
  const auto j2 = nlohmann::json::parse(read_file(t.path("r2.json")));
  CHECK(j2["operations"][0]["after"]["colliding_points"] == 0);
  CHECK(j2["operations"][0]["verification"]["collision_free"] == true);
}

TEST_CASE("cli: with a part, 1 and 2 threads give the same bytes", "[cli][collision][slow]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  for (int n : {1, 2}) {
    const auto r = run_taxopt("--in " + d + "sine.cls --part " + d +
                              "sine.stl --method none --gauge-length 15 --threads " +
                              std::to_string(n) + " --gcode " + t.path(std::to_string(n) + ".nc") +
                              " --points-csv " + t.path(std::to_string(n) + ".csv") +
                              " -q --grid 6");  // free_cells too, on a coarse grid (ASan time)
    REQUIRE(r.code == 0);
  }
  CHECK(read_file(t.path("1.nc")) == read_file(t.path("2.nc")));
  CHECK(read_file(t.path("1.csv")) == read_file(t.path("2.csv")));
}

TEST_CASE("cli: --method global gives the same bytes on 1 and 2 threads", "[cli][global]") {
  TempDir t;
  // A small sine case with its part: two passes, so that the passes run in parallel.
  const auto g = run_taxopt(
      "generate --surface sine --width 4 --length 30 --tilt 10 --yaw 10 "
      "--scallop 0.5 --out-cls " +
      t.path("s.cls") + " --out-mesh " + t.path("s.stl"));
  REQUIRE(g.code == 0);
  for (int n : {1, 2}) {
    const auto r = run_taxopt("--in " + t.path("s.cls") + " --part " + t.path("s.stl") +
                              " --method global --gauge-length 15 --threads " + std::to_string(n) +
                              " --gcode " + t.path(std::to_string(n) + ".nc") + " --report " +
                              t.path(std::to_string(n) + ".json") + " -q");
    INFO(r.err);
    REQUIRE(r.code == 0);
  }
  CHECK(read_file(t.path("1.nc")) == read_file(t.path("2.nc")));
  const auto rep = nlohmann::json::parse(read_file(t.path("1.json")));
  CHECK(rep["method"] == "global");
}

namespace {

/// OFF text of an axis-aligned box.
std::string box_off(const Vec3d& lo, const Vec3d& hi) {
  std::string s = "OFF\n8 12 0\n";
  for (int k = 0; k < 8; ++k) {
    s += std::to_string((k & 1) ? hi.x() : lo.x()) + " " +
         std::to_string((k & 2) ? hi.y() : lo.y()) + " " +
         std::to_string((k & 4) ? hi.z() : lo.z()) + "\n";
  }
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f)
    s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
         "\n";
  return s;
}

}  // namespace

TEST_CASE("cli: a move that sweeps the shank through the part between two free poses exits 1",
          "[cli][collision]") {
  TempDir t;
  // A floor (z = 0, finely split) and a thin pin standing at x = 0 from z = 8 up: the tool
  // touches the floor at x = -10 and x = +10, both poses free; the move between them sweeps
  // the shank through the pin.
  std::string floor_off = "OFF\n";
  const int n = 40;
  floor_off += std::to_string((n + 1) * (n + 1)) + " " + std::to_string(2 * n * n) + " 0\n";
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j)
      floor_off += std::to_string(-40.0 + 2.0 * i) + " " + std::to_string(-40.0 + 2.0 * j) + " 0\n";
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j;
      floor_off += "3 " + std::to_string(a) + " " + std::to_string(a + n + 1) + " " +
                   std::to_string(a + n + 2) + "\n";
      floor_off += "3 " + std::to_string(a) + " " + std::to_string(a + n + 2) + " " +
                   std::to_string(a + 1) + "\n";
    }
  }
  write_file(t.path("floor.off"), floor_off);
  // Two OFF files cannot be merged by the CLI: write one mesh with both (pin vertices after
  // the floor's).
  std::string pin = box_off(Vec3d(-0.5, -0.5, 8.0), Vec3d(0.5, 0.5, 50.0));
  std::istringstream pin_in(pin);
  std::string line;
  std::getline(pin_in, line);  // OFF
  std::getline(pin_in, line);  // counts
  std::vector<std::string> pin_v, pin_f;
  for (int k = 0; k < 8; ++k) {
    std::getline(pin_in, line);
    pin_v.push_back(line);
  }
  const int base = (n + 1) * (n + 1);
  for (int k = 0; k < 12; ++k) {
    int c, a, b, d;
    pin_in >> c >> a >> b >> d;
    pin_f.push_back("3 " + std::to_string(a + base) + " " + std::to_string(b + base) + " " +
                    std::to_string(d + base));
  }
  std::string both =
      "OFF\n" + std::to_string(base + 8) + " " + std::to_string(2 * n * n + 12) + " 0\n";
  std::istringstream fl(floor_off);
  std::getline(fl, line);
  std::getline(fl, line);
  std::string rest((std::istreambuf_iterator<char>(fl)), std::istreambuf_iterator<char>());
  const std::size_t split = [&] {
    std::size_t at = 0;
    for (int k = 0; k < base; ++k) at = rest.find('\n', at) + 1;
    return at;
  }();
  both += rest.substr(0, split);
  for (const auto& v : pin_v) both += v + "\n";
  both += rest.substr(split);
  for (const auto& f : pin_f) both += f + "\n";
  write_file(t.path("part.off"), both);
  write_file(
      t.path("a.cls"),
      "TLDATA/MILL,6,3,20,0,0\nFEDRAT/MMPM,500\nGOTO/-10,0,0,0,0,1\nGOTO/10,0,0\nGOTO/10,10,0\n");
  const auto r =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --part " +
                 t.path("part.off") + " --method none --gauge-length 30 --gcode " + t.path("o.nc"));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains(
                        "a.cls:4: operation 1: 1 moves where the tool hits the part "
                        "between CL points as the machine moves it, first from line 3 to line 4"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  // A short tool stays below the pin: clear.
  CHECK(run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --part " +
                   t.path("part.off") +
                   " --method none --flute-length 6 --gauge-length 7 --gcode " + t.path("o.nc") +
                   " -q")
            .code == 0);
}

TEST_CASE("cli: axis velocity and acceleration beyond the machine file's limits exit 1",
          "[cli][verification]") {
  TempDir t;
  write_file(t.path("a.cls"),
             "FEDRAT/MMPM,600\nGOTO/0,0,0,0,0,1\nGOTO/1,0,0,0,-0.1736482,0.9848078\n"
             "GOTO/2,0,0,0,-0.3420201,0.9396926\nGOTO/3,0,0,0,-0.3420201,0.9396926\n");
  const std::string m =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\nmax_deg = 120\n";
  // 10 deg per mm at 10 mm/s: A turns at 100 deg/s.
  write_file(t.path("slow.toml"), m + "max_velocity_deg_s = 50.0\n[axes.C]\ncontinuous = true\n");
  auto r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                      t.path("slow.toml") + " --method none --gcode " + t.path("o.nc"));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("axis A velocity 100.0"));
  CHECK_THAT(r.err, Catch::Contains("the machine allows 50.0"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  write_file(t.path("stiff.toml"), m + "max_accel_deg_s2 = 500.0\n[axes.C]\ncontinuous = true\n");
  r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                 t.path("stiff.toml") + " --method none --gcode " + t.path("o.nc"));
  CHECK(r.code == 1);
  // From rest to 100 deg/s within half the first move (0.1 s): 2000 deg/s^2.
  CHECK_THAT(r.err, Catch::Contains("axis A acceleration 2000.0"));
  CHECK_THAT(r.err, Catch::Contains("--feed-schedule writes feeds within the machine's limits"));
  // With --feed-schedule the same machine gets feeds it can hold: A within 50 deg/s.
  r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                 t.path("slow.toml") + " --method none --feed-schedule --gcode " + t.path("o.nc") +
                 " --report " + t.path("r.json"));
  INFO(r.err);
  CHECK(r.code == 0);
  const auto j = nlohmann::json::parse(read_file(t.path("r.json")));
  const auto& after = j["operations"][0]["after"];
  CHECK(after["limiting_axis"] == "A");
  CHECK(after["feed_limited_fraction"].get<double>() > 0.5);
  CHECK(after["min_feed_mm_min"].get<double>() <= 300.0 + 1e-6);  // 50 of 100 deg/s: half of 600
  // 10 deg at 50 deg/s twice, then 1 mm at the programmed 10 mm/s.
  CHECK(after["cycle_time_s"].get<double>() == Approx(0.2 + 0.2 + 0.1).epsilon(1e-3));
  // The table's turns with the tool up, from home and back, on their own.
  CHECK(after["table_turn_s"].get<double>() > 0.0);
  CHECK(j["operations"][0]["feed_schedule_written"] == true);
  // The G-code's F words say the same: 300 mm/min on the two turning moves, 600 after.
  const std::string nc = read_file(t.path("o.nc"));
  CHECK_THAT(nc, Catch::Contains("F299.99"));
  CHECK_THAT(nc, Catch::Contains("F600.000"));
  // A jerk limit is checked and reported, not scheduled: a warning, still exit 0.
  write_file(t.path("jerky.toml"), m + "max_velocity_deg_s = 50.0\nmax_jerk_deg_s3 = 1.0\n"
                                       "[axes.C]\ncontinuous = true\n");
  r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                 t.path("jerky.toml") + " --method none --feed-schedule --gcode " + t.path("o.nc") +
                 " -v --points-csv " + t.path("p.csv"));
  CHECK(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("axis A jerk"));
  CHECK_THAT(r.err, Catch::Contains("not jerk"));
  // The CSV's feed_mm_min: empty for the first point, then the scheduled feeds.
  std::istringstream csv(read_file(t.path("p.csv")));
  std::string line;
  std::vector<std::string> feeds;
  std::getline(csv, line);
  const auto fields = [](const std::string& row) {
    std::vector<std::string> out(1);
    for (char c : row) {
      if (c == ',') {
        out.emplace_back();
      } else {
        out.back().push_back(c);
      }
    }
    return out;
  };
  const std::vector<std::string> header = fields(line);
  const auto column = static_cast<std::size_t>(
      std::find(header.begin(), header.end(), "feed_mm_min") - header.begin());
  REQUIRE(column < header.size());
  while (std::getline(csv, line)) feeds.push_back(fields(line).at(column));
  REQUIRE(feeds.size() == 4);
  CHECK(feeds[0].empty());
  CHECK(std::stod(feeds[1]) == Approx(300.0).epsilon(1e-4));
  CHECK(std::stod(feeds[2]) == Approx(300.0).epsilon(1e-4));
  CHECK(std::stod(feeds[3]) == Approx(600.0).epsilon(1e-4));
  write_file(
      t.path("fast.toml"),
      m + "max_velocity_deg_s = 150.0\nmax_accel_deg_s2 = 2500.0\n[axes.C]\ncontinuous = true\n");
  CHECK(run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                   t.path("fast.toml") + " --method none --gcode " + t.path("o.nc") + " -q")
            .code == 0);
}

TEST_CASE("cli: --points-csv counts the free C-space cells of each contact (closed form, plane)",
          "[cli][cspace]") {
  // A plane z = 0 far wider than the tool, vertical input axes. At --grid 3 the window of 30
  // deg holds the cells of tilt 1.5, 4.5, ..., 28.5 deg (10 rows of 120 yaw cells): all free
  // without a holder; with a holder of radius 40 from 17 mm above the ball centre (gauge 20)
  // the rim reaches the plane where 17 cos a - 40 sin a = -3, so only rows below that tilt.
  Heightfield hf;
  hf.name = "plane";
  hf.z = [](double, double) { return 0.0; };
  hf.normal = [](double, double) { return taxopt::Vec3d::UnitZ(); };
  TempDir t;
  write_file(t.path("in.cls"), raster_cl(hf, 3.0, 0.0, 1, 2.0, 0.0, 0.0, 0.0, 20.0).text);
  write_file(t.path("plane.stl"),
             taxopt::format_stl_binary(heightfield_mesh(hf, 20.0, -150.0, 170.0, -150.0, 150.0)));
  // With a holder clearance h the judged holder is 40 + h wide and its face h lower.
  const auto free_rows = [](double h) {
    double lo = 0.0, hi = 1.5;
    for (int i = 0; i < 100; ++i) {
      const double mid = 0.5 * (lo + hi);
      ((17.0 - h) * std::cos(mid) - (40.0 + h) * std::sin(mid) + 3.0 > 0 ? lo : hi) = mid;
    }
    int rows = 0;
    for (double a = 1.5; a < 30.0; a += 3.0) rows += taxopt::deg_to_rad(a) < lo ? 1 : 0;
    return rows;
  };
  const int rows_free = free_rows(0.0), rows_free_h4 = free_rows(4.0);
  REQUIRE(rows_free > 0);
  REQUIRE(rows_free < 10);
  REQUIRE(rows_free_h4 < rows_free);
  const std::string holder =
      "--holder-radius 40 --holder-length 20 --flute-length 15 "
      "--gauge-length 20 ";
  for (const auto& [args, expected] : {std::pair<std::string, int>{"", 1200},
                                       {holder + "--holder-clearance 0", 120 * rows_free},
                                       {holder + "--holder-clearance 4", 120 * rows_free_h4}}) {
    INFO(args);
    const RunResult r = run_taxopt("--in " + t.path("in.cls") + " --part " + t.path("plane.stl") +
                                   " --method none --grid 3 -q --report " + t.path("r.json") +
                                   " --points-csv " + t.path("p.csv") + " " + args);
    INFO(r.err);
    REQUIRE(r.code == 0);
    std::istringstream csv(read_file(t.path("p.csv")));
    std::string line;
    std::getline(csv, line);
    int touching = 0;
    while (std::getline(csv, line)) {
      // free_cells is the 22nd column (feed_mm_min follows it).
      std::vector<std::string> fields;
      std::istringstream row(line);
      for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
      fields.resize(23);
      const std::string last = fields[21];
      const bool has_contact = line.find(",,,,,,,,") == std::string::npos;
      if (!has_contact) {
        CHECK(last.empty());
        continue;
      }
      ++touching;
      CHECK(std::stoi(last) == expected);
    }
    CHECK(touching == 11);
    // The raster's time is its own, apart from the contacts' and the verification's.
    const auto timings =
        nlohmann::json::parse(read_file(t.path("r.json")))["operations"].at(0)["timings_s"];
    CHECK(timings["cspace"].get<double>() > 0.0);
    CHECK(timings["contacts"].get<double>() > 0.0);
    CHECK(timings["verify"].get<double>() > 0.0);
  }
}

TEST_CASE("cli: the machine file's dialect picks the controller's program format", "[cli][gcode]") {
  TempDir t;
  write_file(t.path("a.cls"), kSmallCl);
  const std::pair<const char*, const char*> dialects[] = {
      {"fanuc", "G43.4 H"}, {"siemens", "TRAORI"}, {"heidenhain", "M128 *"}};
  for (const auto& [dialect, tcp_word] : dialects) {
    INFO(dialect);
    write_file(t.path("m.toml"), std::string("kinematics = \"ac-table-table\"\n[axes.A]\n"
                                             "min_deg = -120\nmax_deg = 120\n[axes.C]\n"
                                             "continuous = true\n[gcode]\ndialect = \"") +
                                     dialect + "\"\n");
    const auto r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") +
                              " --machine " + t.path("m.toml") +
                              " --method none --feed-schedule --gcode " + t.path("o.nc") + " -q");
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK_THAT(read_file(t.path("o.nc")), Catch::Contains(tcp_word));
  }
}

TEST_CASE("cli: generate names the operation after its surface", "[cli]") {
  TempDir t;
  for (const std::string surface : {"sine", "plane", "bump", "saddle"}) {
    REQUIRE(run_taxopt("generate --surface " + surface + " --mesh-step 2 " + "--out-cls " +
                       t.path(surface + ".cls"))
                .code == 0);
    std::string name = surface + "_FINISH";
    for (char& ch : name) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    const taxopt::Toolpath tp = taxopt::read_cl_file(t.path(surface + ".cls"));
    REQUIRE(tp.operations.size() == 1);
    CHECK(tp.operations[0].name == name);
  }
}

TEST_CASE("cli: -v tells each long stage's time, -q says nothing", "[cli]") {
  TempDir t;
  // A small generated plane: every stage runs, quickly even under the sanitizers.
  REQUIRE(run_taxopt("generate --surface plane --width 4 --length 12 --out-cls " + t.path("p.cls") +
                     " --out-mesh " + t.path("p.stl"))
              .code == 0);
  const std::string args =
      "--in " + t.path("p.cls") + " --part " + t.path("p.stl") + " --gcode " + t.path("o.nc");
  auto r = run_taxopt(args + " -v");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* stage : {"contact recovery", "optimisation", "verification"}) {
    CHECK_THAT(r.err, Catch::Contains(std::string("taxopt: ") + stage + ": "));
  }
  // And each stage's own time, split as in the report.
  const auto at = r.err.find("taxopt: stage times: ");
  REQUIRE(at != std::string::npos);
  CHECK_THAT(r.err.substr(at, r.err.find('\n', at) - at),
             Catch::Matches("taxopt: stage times: contacts [0-9.]+ s, cspace [0-9.]+ s, optimise "
                            "[0-9.]+ s, post [0-9.]+ s, verify [0-9.]+ s"));
  // Not a terminal: no bar.
  CHECK(r.err.find('\r') == std::string::npos);
  r = run_taxopt(args + " -q");
  REQUIRE(r.code == 0);
  // -q silences progress, notes and the summary, never what was not checked.
  std::istringstream err_lines(r.err);
  for (std::string l; std::getline(err_lines, l);) {
    CHECK_THAT(l, Catch::StartsWith("taxopt: warning: NOT CHECKED: "));
  }
  CHECK(r.out.empty());
}

TEST_CASE("cli: the report's clearance bound of shank and holder matches the closed form",
          "[cli][verification]") {
  TempDir t;
  // The generator's plane, axes 5 deg off the normal, R = 3; with 5 mm flutes the shank starts
  // 2 mm above the ball centre. Grown by d in radius and at both ends, its lowest rim point is
  // 3 + (2 - d) cos a - (3 + d) sin a above the plane: zero at d* = (3 + 2 cos a - 3 sin a) /
  // (cos a + sin a), the bound the report gives (the true distance, 3 + 2 cos a - 3 sin a, is
  // at most sqrt 2 times it).
  REQUIRE(run_taxopt("generate --surface plane --width 6 --length 20 --out-cls " + t.path("p.cls") +
                     " --out-mesh " + t.path("p.stl"))
              .code == 0);
  const double a = taxopt::deg_to_rad(5.0);
  const double bound = (3.0 + 2.0 * std::cos(a) - 3.0 * std::sin(a)) / (std::cos(a) + std::sin(a));
  auto r = run_taxopt("--in " + t.path("p.cls") + " --part " + t.path("p.stl") +
                      " --method none --flute-length 5 --gcode " + t.path("p.nc") + " --report " +
                      t.path("r.json") + " -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto v = nlohmann::json::parse(read_file(t.path("r.json")))["operations"][0]["verification"];
  CHECK(v["min_clearance_mm"].get<double>() == Approx(bound).margin(0.006));
  CHECK(v["min_clearance_mm"].get<double>() <= 3.0 + 2.0 * std::cos(a) - 3.0 * std::sin(a));
  // Far from the part (default 15 mm flutes): the 10 mm cap.
  r = run_taxopt("--in " + t.path("p.cls") + " --part " + t.path("p.stl") +
                 " --method none --gcode " + t.path("p.nc") + " --report " + t.path("r.json") +
                 " -q");
  REQUIRE(r.code == 0);
  v = nlohmann::json::parse(read_file(t.path("r.json")))["operations"][0]["verification"];
  CHECK(v["min_clearance_mm"].get<double>() == 10.0);
  // Without a part nothing is measured.
  r = run_taxopt("--in " + t.path("p.cls") + " --method none --gcode " + t.path("p.nc") +
                 " --report " + t.path("r.json") + " -q");
  REQUIRE(r.code == 0);
  CHECK(nlohmann::json::parse(
            read_file(t.path("r.json")))["operations"][0]["verification"]["min_clearance_mm"]
            .is_null());
}

TEST_CASE("cli: the report can be reproduced from itself, its numbers tidy", "[cli][slow]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  // Global options after the subcommand, as a user types them.
  const RunResult r = run_taxopt("demo --out " + t.path("demo") + " -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  // Only the NOT CHECKED safety warnings (-q never silences them): here the holder.
  CHECK(r.err.find("taxopt: note:") == std::string::npos);
  CHECK(r.err.find("NOT CHECKED: no holder model") != std::string::npos);
  const std::string text = read_file(t.path("demo/report.json"));
  const auto rep = nlohmann::json::parse(text);
  const auto& run = rep["run"];
  CHECK_THAT(run["command_line"].get<std::string>(),
             Catch::EndsWith("demo --out " + t.path("demo") + " -q"));
  CHECK(run["machine_file"] == d + "machines/paper-ac.toml");
  CHECK(run["machine_file_sha256"] == taxopt::sha256_hex(read_file(d + "machines/paper-ac.toml")));
  CHECK(run["part_file"] == d + "demo/sine.stl");
  const std::string when = run["started_utc"];
  CHECK(when.size() == 20);
  CHECK(when[10] == 'T');
  CHECK(when.back() == 'Z');
  CHECK(rep["options"]["method"] == "paper");
  CHECK(rep["options"]["gcode"]["dialect"] == "linuxcnc");
  // The tool as the checks model it: the demo's 15 mm gauge length is visible.
  const auto& tool = rep["operations"][0]["tool"];
  CHECK(tool["diameter_mm"] == 6.0);
  CHECK(tool["model"]["bodies"].back()["to_mm"].get<double>() == Approx(15.0 - 3.0));
  // A null comes with its reason; no number carries float noise.
  const auto& v = rep["operations"][0]["verification"];
  CHECK(v["min_clearance_mm"].is_null());
  CHECK(v["null_reasons"].contains("min_clearance_mm"));
  CHECK(rep["operations"][0]["max_axis_change_deg"] == 30.0);
  CHECK(text.find("0000000000") == std::string::npos);
  CHECK(text.find("9999999999") == std::string::npos);
  // The CSV has no negative zero.
  const std::string csv = read_file(t.path("demo/points.csv"));
  for (const char* neg : {",-0.000000,", ",-0.000000000,", ",-0.0000,"}) {
    CHECK(csv.find(neg) == std::string::npos);
  }
}

TEST_CASE("cli: help in groups with units, exit codes and examples -- a bare call says what to do",
          "[cli]") {
  const RunResult help = run_taxopt("--help");
  CHECK(help.code == 0);
  for (const char* group : {"Input:", "Tool:", "Machine:", "Method:", "Outputs:", "Diagnostics:"}) {
    CHECK_THAT(help.out, Catch::Contains(group));
  }
  CHECK_THAT(help.out, Catch::Contains("--gauge-length LENGTH") &&
                           Catch::Contains("--max-deviation DEG") &&
                           Catch::Contains("Exit codes:") && Catch::Contains("Examples:"));
  CHECK(help.out.find("INT:INT") == std::string::npos);
  CHECK(help.out.find("TEXT:{") == std::string::npos);
  const RunResult bare = run_taxopt("");
  CHECK(bare.code == 2);
  CHECK_THAT(bare.err, Catch::Contains("--help"));
  const RunResult threads = run_taxopt("--threads 0 --in x");
  CHECK(threads.code == 2);
  // SHA-256 of the report's machine digest: FIPS 180-4's test vectors.
  CHECK(taxopt::sha256_hex("abc") ==
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(taxopt::sha256_hex("") ==
        "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(taxopt::sha256_hex(std::string(1000000, 'a')) ==
        "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST_CASE(
    "cli: a point refused for a shank hit names the body, its distance from the part and the "
    "flute length that clears it, and that length does",
    "[cli][collision][refusal]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  const std::string base = "--in " + d + "sine.cls --part " + d + "sine.stl --method none -q " +
                           "--gauge-length 30 --gcode " + t.path("o.nc");
  const RunResult r = run_taxopt(base + " --flute-length 4");
  REQUIRE(r.code == 1);
  const std::regex first(
      "sine\\.cls:([0-9]+): operation SINE_FINISH: [0-9]+ CL points where the "
      "tool hits the part[^\\n]*; at line ([0-9]+) the shank comes "
      "([0-9.]+) mm from the part \\(its clearance 0\\.500 mm\\); flutes of "
      "([0-9.]+) mm from the tip \\(--flute-length\\) would clear it here");
  std::smatch m;
  INFO(r.err);
  REQUIRE(std::regex_search(r.err, m, first));
  CHECK(m[1].str() == m[2].str());
  const double distance = std::stod(m[3].str()), flutes = std::stod(m[4].str());
  CHECK(distance >= 0.0);
  CHECK(distance < 0.5);
  // With those flutes that line is clear.
  const RunResult again = run_taxopt(base + " --flute-length " + std::to_string(flutes + 0.02));
  INFO(again.err);
  const std::regex line(
      "sine\\.cls:([0-9]+): operation SINE_FINISH: [0-9]+ CL points where the "
      "tool hits the part");
  std::smatch m2;
  if (std::regex_search(again.err, m2, line)) CHECK(m2[1].str() != m[1].str());
}

TEST_CASE(
    "cli: a program says in its first lines what was not checked, and a --force program that "
    "its verification failed",
    "[cli][safety]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  // No part: the program's header says so.
  RunResult r = run_taxopt("--in " + d + "sine.cls --gcode " + t.path("a.ngc") + " -q");
  REQUIRE(r.code == 0);
  const auto head = [](const std::string& text) {
    std::istringstream in(text);
    std::string out, l;
    for (int i = 0; i < 12 && std::getline(in, l); ++i) out += l + "\n";
    return out;
  };
  CHECK_THAT(head(read_file(t.path("a.ngc"))), Catch::Contains("(NOT CHECKED: no part"));
  CHECK(read_file(t.path("a.ngc")).find("NOT VERIFIED") == std::string::npos);
  // A failed verification written with --force: named in the header; rs274 still reads it.
  r = run_taxopt("--in " + d + "sine.cls --part " + d + "sine.stl --method none -q " +
                 "--gauge-length 30 --flute-length 4 --force --gcode " + t.path("f.ngc"));
  REQUIRE(r.code == 1);
  const std::string forced = read_file(t.path("f.ngc"));
  CHECK_THAT(head(forced), Catch::Contains("(NOT VERIFIED: the verification failed ["));
  CHECK_THAT(forced, Catch::Contains("(FAILED: "));
  if (have_rs274()) {
    std::vector<CanonMove> moves;
    CHECK(run_rs274(t.path("f.ngc"), moves).code == 0);
  }
}

TEST_CASE("cli: --dialect overrides the machine file's dialect under the same rules",
          "[cli][gcode]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  RunResult r = run_taxopt("--in " + d + "sine.cls --dialect fanuc -q --gcode " + t.path("f.nc"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK_THAT(read_file(t.path("f.nc")), Catch::Contains("G43.4"));
  r = run_taxopt("--in " + d + "sine.cls --dialect sinumerik -q --gcode " + t.path("s.nc"));
  CHECK(r.code == 2);
  // A template written for the file's dialect is not another dialect's.
  write_file(t.path("m.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
             "max_deg = 120\n[axes.C]\ncontinuous = true\n[gcode]\n"
             "dialect = \"linuxcnc\"\nheader = [\"G80\"]\n");
  r = run_taxopt("--in " + d + "sine.cls --machine " + t.path("m.toml") +
                 " --dialect heidenhain -q --gcode " + t.path("h.nc"));
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("program template"));
  CHECK_FALSE(file_exists(t.path("h.nc")));
}

TEST_CASE("cli: every operation's first feed block carries its F", "[cli][gcode]") {
  TempDir t;
  const RunResult r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " +
                                 real_data("mech491-project2-multiop.cls") + " --method none -q " +
                                 "--gcode " + t.path("o.ngc"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::vector<std::string> lines = lines_of(read_file(t.path("o.ngc")));
  int operations = 0;
  for (std::size_t at = line_of(lines, "(operation "); at != std::string::npos;
       at = line_of(lines, "(operation ", at + 1)) {
    ++operations;
    const std::size_t next = line_of(lines, "(operation ", at + 1);
    for (std::size_t i = at; i < std::min(next, lines.size()); ++i) {
      if (lines[i].rfind("G1 ", 0) == 0 || lines[i].find(" G1 ") != std::string::npos) {
        INFO(lines[i]);
        CHECK(lines[i].find(" F") != std::string::npos);
        break;
      }
    }
  }
  CHECK(operations == 15);
}

TEST_CASE("cli: a longer cycle is said above its threshold, naming what grew",
          "[cli][feed][slow]") {
  TempDir t;
  REQUIRE(run_taxopt("generate --surface sine --height 10 --tilt 15 --yaw 10 --out-cls " +
                     t.path("s.cls") + " --out-mesh " + t.path("s.stl"))
              .code == 0);
  const RunResult r =
      run_taxopt("--in " + t.path("s.cls") + " --part " + t.path("s.stl") +
                 " --method paper -q --gcode " + t.path("s.nc") + " --report " + t.path("s.json"));
  REQUIRE(r.code == 0);
  const auto rep = nlohmann::json::parse(read_file(t.path("s.json")));
  const auto& op = rep["operations"][0];
  const double before = op["before"]["cycle_time_s"], after = op["after"]["cycle_time_s"];
  bool said = false;
  for (const auto& f : rep["findings"]) {
    if (f["code"] != "longer_cycle") continue;
    said = true;
    const std::string m = f["message"];
    // What grew, with its times: here the rapids, by the table's turns between passes.
    CHECK_THAT(m, Catch::Contains("rapids ") && Catch::Contains(" -> "));
  }
  CHECK(said == (after - before > std::max(0.01, 1e-3 * before)));
}

TEST_CASE("cli: the LinuxCNC preset turns the tool length on before the TCP kinematics",
          "[cli][gcode][linuxcnc][slow]") {
  // LinuxCNC's motion controller jumps its joints when M428 switches to the TCP kinematics with
  // the table tilted and G43 follows (measured on LinuxCNC's motion controller, tests/controller):
  // G43 first.
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  const RunResult r =
      run_taxopt("--in " + d + "demo/sine.cls --machine " + d +
                 "machines/linuxcnc-xyzac-trt.toml --feed-schedule -q --gcode " + t.path("o.ngc"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::vector<std::string> lines = lines_of(read_file(t.path("o.ngc")));
  const std::size_t g43 = line_of(lines, "G43 H"), m428 = line_of(lines, "M428");
  REQUIRE(g43 != std::string::npos);
  REQUIRE(m428 != std::string::npos);
  CHECK(g43 < m428);
}

TEST_CASE("cli: records skipped by --skip-record are said on stderr even with -q", "[cli][cl]") {
  TempDir t;
  write_file(t.path("s.cls"),
             "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nFROBNICATE/3\nRAPID\n"
             "GOTO/0,0,5\nFROBNICATE/4\nGOTO/50,0,5\n");
  for (const char* quiet : {"", " -q"}) {
    INFO("quiet: '" << quiet << "'");
    const auto r = run_taxopt("--in " + t.path("s.cls") +
                              " --skip-record FROBNICATE --spindle-rpm 5000 --tool-number 1 "
                              "--method none --gcode " +
                              t.path("s.nc") + quiet);
    REQUIRE(r.code == 0);
    CHECK_THAT(r.err, Catch::Contains(
                          "taxopt: note: 2 FROBNICATE record(s) skipped as asked (--skip-record "
                          "FROBNICATE)"));
  }
}

TEST_CASE(
    "cli: where the input axis lies outside the machine's rotary range, no_free_axis says so "
    "with the range, not only the cone",
    "[cli][machine]") {
  TempDir t;
  write_file(t.path("a.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = 30\nmax_deg = 60\n[axes.C]\n"
             "continuous = true\n[gcode]\nend_pose = \"none\"\n");
  const auto r =
      run_taxopt("--in " + std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls --machine " +
                 t.path("a.toml") + " -q --gcode " + t.path("a.nc"));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("the input axis itself is out of the machine's reach: it "
                                    "needs A 5 or -5 deg, and A runs over [30, 60] deg"));
  CHECK_FALSE(file_exists(t.path("a.nc")));
}
