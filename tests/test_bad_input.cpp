// Silent holes of hostile input, each a regression test: every case exits non-zero with a clear
// message (file, line or face, what was expected), or gives the same G-code as the good input.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/types.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt::test;
using taxopt::Vec3d;

namespace {

const char* kInchCl =
    "UNITS/INCHES\nTOOL PATH/T,TOOL,BALL\nTLDATA/MILL,0.25,0.125,1.0,0,0\nRAPID\n"
    "GOTO/0,0,1,0,0,1\nFEDRAT/IPM,10\nGOTO/0,0,0\nGOTO/1,0,0\nGOTO/2,0.5,0\nEND-OF-PATH\n";

/// A binary STL of one or more triangles, its header count set to `count`.
std::string stl_with_count(const taxopt::TriangleMesh& mesh, std::uint32_t count) {
  std::string bytes = taxopt::format_stl_binary(mesh);
  std::memcpy(&bytes[80], &count, 4);
  return bytes;
}

taxopt::TriangleMesh plane(int n) {
  taxopt::TriangleMesh m;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) m.vertices.emplace_back(10.0 * i - 50, 10.0 * j - 50, -1.0);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.push_back({a, c, b});
      m.faces.push_back({b, c, d});
    }
  }
  return m;
}

bool leftover_temps(const std::string& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().filename().string().find(".taxopt-") != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("bad input: a UTF-8 byte-order mark changes nothing: same units, names, G-code",
          "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kInchCl);
  write_file(t.path("b.cls"), std::string("\xEF\xBB\xBF") + kInchCl);
  const auto a = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") +
                            " --gcode " + t.path("a.nc") + " --method none -q");
  const auto b = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("b.cls") +
                            " --gcode " + t.path("b.nc") + " --method none -q");
  REQUIRE(a.code == 0);
  REQUIRE(b.code == 0);
  std::string ga = read_file(t.path("a.nc")), gb = read_file(t.path("b.nc"));
  // The header names the source file; everything after it is the same.
  ga = ga.substr(ga.find("(machine"));
  gb = gb.substr(gb.find("(machine"));
  CHECK(ga == gb);
  CHECK_THAT(gb, Catch::Contains("G20"));
  CHECK_THAT(gb, Catch::Contains("(operation T)"));
  // UTF-16 is refused by name.
  write_file(t.path("u.cls"), std::string("\xFF\xFEG\0O\0", 6));
  const auto u = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("u.cls") +
                            " --gcode " + t.path("u.nc"));
  CHECK(u.code == 2);
  CHECK_THAT(u.err, Catch::Contains("UTF-16"));
}

TEST_CASE("bad input: a line that is no record is an error with its line, not a skip",
          "[cli][bad-input]") {
  TempDir t;
  std::string text = kInchCl;
  text.replace(0, 1, "\xC3\x9C");  // "ÜNITS/INCHES"
  write_file(t.path("a.cls"), text);
  const auto r = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.nc"));
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: " + t.path("a.cls") + ":1: not a CL record"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
}

TEST_CASE("bad input: a binary STL whose header count disagrees with its size is refused",
          "[cli][bad-input]") {
  TempDir t;
  const auto mesh = plane(4);  // 32 triangles
  write_file(t.path("a.cls"), kInchCl);
  for (const std::uint32_t count : {20u, 40u}) {
    INFO(count);
    write_file(t.path("p.stl"), stl_with_count(mesh, count));
    const auto r = run_taxopt("--in " + t.path("a.cls") + " --part " + t.path("p.stl") +
                              " --gcode " + t.path("o.nc") + " --method none");
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("header says " + std::to_string(count) + " triangles"));
    CHECK_THAT(r.err, Catch::Contains("the file has " + std::to_string(84 + 50 * 32) + " bytes"));
    CHECK_FALSE(file_exists(t.path("o.nc")));
  }
  // A binary STL whose header begins with "solid" is still binary (told by its size).
  std::string bytes = taxopt::format_stl_binary(mesh);
  bytes.replace(0, 5, "solid");
  write_file(t.path("s.stl"), bytes);
  CHECK(taxopt::read_mesh_file(t.path("s.stl")).faces.size() == 32);
}

TEST_CASE("bad input: a NaN or infinite vertex in a binary STL names its face",
          "[cli][bad-input]") {
  TempDir t;
  std::string bytes = taxopt::format_stl_binary(plane(4));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&bytes[84 + 50 * 6 + 12 + 12 + 4], &nan, 4);  // face 7, vertex 2, y
  write_file(t.path("p.stl"), bytes);
  write_file(t.path("a.cls"), kInchCl);
  const auto r = run_taxopt("--in " + t.path("a.cls") + " --part " + t.path("p.stl") + " --gcode " +
                            t.path("o.nc") + " --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("face 7 has a vertex that is not finite"));
}

TEST_CASE("bad input: outputs that alias each other or cannot be written are refused first",
          "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kInchCl);
  // The same file spelled two ways.
  const auto r = run("cd " + t.dir() + " && " + std::string(TAXOPT_EXE) +
                     " --in a.cls --gcode same.out --report ./same.out --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--report and --gcode name the same file"));
  CHECK_FALSE(file_exists(t.path("same.out")));
  // A folder that is not there, a folder that is a file: refused before any work.
  const auto m = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("nowhere/o.nc"));
  CHECK(m.code == 2);
  CHECK_THAT(m.err, Catch::Contains("--gcode " + t.path("nowhere/o.nc") + ": cannot write there"));
  const auto f = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("a.cls/o.nc"));
  CHECK(f.code == 2);
  CHECK_THAT(f.err, Catch::Contains("is not a folder"));
}

TEST_CASE("bad input: a coordinate beyond any machine is refused at its CL line",
          "[cli][bad-input]") {
  TempDir t;
  std::string text = kInchCl;
  text.replace(text.find("GOTO/1,0,0"), 10, "GOTO/1e308,0,0");
  write_file(t.path("a.cls"), text);
  const auto r = run_taxopt("--in " + t.path("a.cls") + " --gcode " + t.path("o.nc"));
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains(t.path("a.cls") + ":8: GOTO: point"));
  CHECK_THAT(r.err, Catch::Contains("beyond +-1e6 mm"));
}

TEST_CASE("bad input: the machine's linear travel is checked, errors come first and few",
          "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kInchCl);
  write_file(t.path("m.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n"
             "[axes.C]\ncontinuous = true\n[axes.X]\nmin_mm = -10\nmax_mm = 30\n"
             "[setup]\nwork_offset_mm = [0, 0, 0]\n");
  const auto r =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                 t.path("m.toml") + " --gcode " + t.path("o.nc") + " --method none");
  CHECK(r.code == 1);
  // X reaches 2 in = 50.8 mm at line 9.
  CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: " + t.path("a.cls") +
                                      ":9: operation T: X would be 50.8 mm"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  write_file(t.path("bad.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n"
             "[axes.C]\ncontinuous = true\n[axes.Y]\nmin_mm = 10\n");
  const auto b = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") +
                            " --machine " + t.path("bad.toml") + " --gcode " + t.path("o.nc"));
  CHECK(b.code == 2);
  CHECK_THAT(b.err, Catch::Contains("axes.Y needs min_mm and max_mm"));
  // Many operations out of range: ten lines and a count, not one line each.
  std::string many;
  for (int k = 0; k < 30; ++k) {
    many += "TOOL PATH/T" + std::to_string(k) +
            ",TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nGOTO/0,0,1,0,0.8,0.6\nGOTO/100,0,1\nEND-OF-PATH\n";
  }
  write_file(t.path("many.cls"), many);
  const auto n =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("many.cls") + " --machine " +
                 t.path("m.toml") + " --gcode " + t.path("o.nc") + " --method none");
  CHECK(n.code == 1);
  std::size_t lines = 0;
  for (std::size_t p = n.err.find("taxopt: error:"); p != std::string::npos;
       p = n.err.find("taxopt: error:", p + 1))
    ++lines;
  CHECK(lines == 11);
  // 30 points, and the program's approach moves out of X's travel too (one finding for all,
  // after the points').
  CHECK_THAT(n.err, Catch::Contains("... and 21 more (-v lists them all)"));
}

TEST_CASE("bad input: --force never writes an empty program", "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("a.cls"), kInchCl);
  write_file(t.path("m.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = 50\nmax_deg = 60\n"
             "[axes.C]\ncontinuous = true\n[gcode]\nend_pose = \"none\"\n");
  const auto r =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + t.path("a.cls") + " --machine " +
                 t.path("m.toml") + " --gcode " + t.path("o.nc") + " --method none --force");
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("no G-code to write"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
}

TEST_CASE("bad input: a signal during the run or the write leaves no temporary file",
          "[cli][bad-input][signals][slow]") {
  // A run long enough to be cut at many moments: the demo part, the paper method.
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  write_file(t.path("o.nc"), "previous good program\n");
  const std::string cmd = std::string(TAXOPT_EXE) + " --in " + d + "demo/sine.cls --machine " + d +
                          "machines/paper-ac.toml --method paper --gcode " + t.path("o.nc") +
                          " --report " + t.path("r.json") + " --points-csv " + t.path("p.csv") +
                          " --out-cls " + t.path("o.cls") + " -q";
  // How long a whole run takes (the shorter of two: a first run on a busy machine can take
  // several times as long, and signals timed from it would all come after the end), then
  // signals spread over it (and past its write).
  double whole_s = 1e9;
  for (int k = 0; k < 2; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    REQUIRE(run(cmd).code == 0);
    whole_s = std::min(
        whole_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  write_file(t.path("o.nc"), "previous good program\n");
  // Spread over the run, and dense over its last fifth, where the outputs are written; SIGINT
  // and SIGTERM in turn.
  std::vector<double> moments;
  for (int k = 1; k <= 4; ++k) moments.push_back(whole_s * k / 5.0);
  for (int k = 0; k < 10; ++k) moments.push_back(whole_s * (0.8 + 0.025 * k));
  int interrupted = 0;
  for (std::size_t m = 0; m < moments.size(); ++m) {
    const double at_s = moments[m];
    const char* sig = m % 2 ? "TERM" : "INT";
    const auto r = run("timeout -s " + std::string(sig) + " " + std::to_string(at_s) + " " + cmd);
    INFO(sig << " at " << at_s << " s, exit " << r.code);
    CHECK_FALSE(leftover_temps(t.dir()));
    // Either the run finished (a whole new program) or the old one is intact.
    const std::string g = read_file(t.path("o.nc"));
    CHECK((g == "previous good program\n" || g.find("M30") != std::string::npos ||
           g.find("M2") != std::string::npos));
    if (r.code == 124) ++interrupted;
    write_file(t.path("o.nc"), "previous good program\n");
  }
  CHECK(interrupted > 0);
}

TEST_CASE(
    "safe by default: without a part no real file's axis turns more than 1 deg, and "
    "the user is told nothing was checked",
    "[cli][safety][slow]") {
  TempDir t;
  for (const char* f :
       {"mech491-variable-axis-ballmill.cls", "mech491-project2-multiop.cls",
        "peening-catia-multax.aptsource", "amorim-tilt-support1.apt", "amorim-interface-glue.apt",
        "amorim-wall-holes.apt", "creopost-profilfraesen.ncl"}) {
    for (const char* method : {"paper", "global"}) {
      INFO(f << " --method " << method);
      // mech491-project2-multiop.cls turns its tool over within a pass: the paper method threw
      // "slerp: opposite axes" on it before.
      const auto r = run_taxopt("--in " + taxopt::test::real_path(f, t.dir()) +
                                taxopt::test::real_flags(f) + " --gcode " + t.path("o.nc") +
                                " --report " + t.path("r.json") + " --method " + method);
      REQUIRE(r.code == 0);
      CHECK_THAT(r.err, Catch::StartsWith("taxopt: warning: NOT CHECKED: no part (--part)"));
      const auto j = nlohmann::json::parse(read_file(t.path("r.json")));
      CHECK(j["collision_checked"] == false);
      for (const auto& op : j["operations"]) {
        CHECK(op["max_axis_change_deg"].get<double>() <= 1.0 + 1e-9);
        CHECK(op["after"]["colliding_points"].is_null());
      }
    }
  }
  // --max-deviation widens the cone, and the warning says it is unchecked.
  const auto w = run_taxopt("--in " + real_data("mech491-variable-axis-ballmill.cls") +
                            taxopt::test::real_flags("mech491-variable-axis-ballmill.cls") +
                            " --gcode " + t.path("o.nc") + " --max-deviation 10");
  CHECK(w.code == 0);
  CHECK_THAT(w.err, Catch::Contains("within 10 deg of its input as --max-deviation asks, "
                                    "unchecked"));
  CHECK_THAT(w.out, Catch::Contains("unchecked"));
}

TEST_CASE(
    "safe by default: flutes that touch the surface they cut within the part tolerance "
    "are no collision -- deeper they are",
    "[cli][safety][collision]") {
  // A plane z = 0; a ball of R = 3 with its axis lying flat (+X), its centre 0.02 mm lower than
  // touching: the flute cylinder reaches 0.02 mm into the part, as a concave fillet's faceting
  // makes real flutes do.
  TempDir t;
  taxopt::TriangleMesh mesh;
  mesh.vertices = {Vec3d(-100, -100, 0), Vec3d(100, -100, 0), Vec3d(100, 100, 0),
                   Vec3d(-100, 100, 0)};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  write_file(t.path("p.stl"), taxopt::format_stl_binary(mesh));
  std::string cl = "TOOL PATH/FLAT,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nFEDRAT/MMPM,500\n";
  for (int k = 0; k <= 10; ++k) {
    cl += "GOTO/-3," + std::to_string(2.0 * k) + ",2.98,1,0,0\n";
  }
  cl += "END-OF-PATH\n";
  write_file(t.path("f.cls"), cl);
  // A necked shank (radius 2, 2.5 with its clearance) stays clear of the plane.
  const std::string base = "--in " + t.path("f.cls") + " --part " + t.path("p.stl") +
                           " --method none --machine " + std::string(TAXOPT_SOURCE_DIR) +
                           "/data/machines/paper-ac.toml --gcode " + t.path("o.nc") +
                           " --tool-number 1 --spindle-rpm 6000";
  // Default part tolerance (the contact tolerance, 0.05 mm and more): no collision.
  const auto ok = run_taxopt(base + " --shank-radius 2 --report " + t.path("r.json"));
  INFO(ok.err);
  CHECK(ok.code == 0);
  // A part tolerance below the 0.02 mm: the flutes are judged as hitting.
  const auto hit = run_taxopt(base + " --shank-radius 2 --part-tolerance 0.01");
  CHECK(hit.code == 1);
  CHECK_THAT(hit.err, Catch::Contains("11 CL points where the flutes reach into the part deeper "
                                      "than the part tolerance 0.01 mm (as given; a gouge"));
  CHECK_THAT(hit.err, !Catch::Contains("CL points where the tool hits the part"));
  // A shank 2.9 mm wide lying 2.98 mm above the plane clears it by 0.08 mm: free without a
  // clearance, a collision with the default 0.5 mm. It never cuts, so it gets no tolerance.
  const auto shank = run_taxopt(base + " --shank-radius 2.9");
  CHECK(shank.code == 1);
  CHECK_THAT(shank.err, Catch::Contains("11 CL points where the tool hits the part (the shank"));
  const auto shank_free = run_taxopt(base + " --shank-radius 2.9 --shank-clearance 0");
  CHECK(shank_free.code == 0);
}

TEST_CASE(
    "safe by default: the machine file's usual holder and clearances apply where the "
    "command line gives none",
    "[cli][safety][slow]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  write_file(t.path("m.toml"), read_file(d + "machines/paper-ac.toml") +
                                   "\n[checks]\nshank_clearance_mm = 0.2\nholder_clearance_mm = "
                                   "3\n[holder]\nradius_mm = 12\nlength_mm = 50\n"
                                   "gauge_length_mm = 15\n");
  const std::string base = "--in " + d + "demo/sine.cls --part " + d + "demo/sine.stl --machine " +
                           t.path("m.toml") + " --method none --report " + t.path("r.json");
  const auto r = run_taxopt(base + " --force");
  const auto j = nlohmann::json::parse(read_file(t.path("r.json")));
  CHECK(j["clearances_mm"]["shank"] == 0.2);
  CHECK(j["clearances_mm"]["holder"] == 3.0);
  CHECK(j["clearances_mm"]["holder_modelled"] == true);
  CHECK_THAT(r.err, !Catch::Contains("no holder model"));
  // The command line wins.
  run_taxopt(base + " --holder-clearance 0.5 --force");
  CHECK(nlohmann::json::parse(read_file(t.path("r.json")))["clearances_mm"]["holder"] == 0.5);
}

TEST_CASE(
    "hostile input, round 3: numbers outside their bounds are exit 2 naming the option or the "
    "line, before any output",
    "[cli][bad-input][hostile]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  const std::string base =
      "--in " + d + "sine.cls --part " + d + "sine.stl --method none -q --gcode " + t.path("o.nc");
  const struct {
    const char* args;
    const char* says;
  } cases[] = {
      {"--contact-tolerance inf", "--contact-tolerance must be within (0, 1] mm"},
      {"--contact-tolerance 1e300", "--contact-tolerance must be within (0, 1] mm"},
      {"--contact-tolerance 2", "--contact-tolerance must be within (0, 1] mm"},
      {"--part-tolerance 5", "--part-tolerance must be within [0, 1] mm"},
      {"--shank-clearance inf", "--shank-clearance must be within [0, 50] mm"},
      {"--holder-clearance 1e300", "--holder-clearance must be within [0, 50] mm"},
      {"--grid 1e-8", "--grid must be within [0.1, 10] deg"},
      {"--feed 1e-300", "--feed must be within [0.01, 1e6] mm/min"},
      {"--shank-radius inf", "--shank-radius must be within (0, 1000] mm"},
      {"--gauge-length 1e300", "--gauge-length must be within (0, 1000] mm"},
      {"--holder-radius 1e30", "--holder-radius must be within (0, 1000] mm"},
  };
  for (const auto& c : cases) {
    INFO(c.args);
    const RunResult r = run_taxopt(base + " " + c.args);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains(c.says));
    CHECK_FALSE(file_exists(t.path("o.nc")));
  }
  // A feed no program writes.
  write_file(t.path("f.cls"), "FEDRAT/MMPM,1e-300\nGOTO/0,0,0\nGOTO/1,0,0\n");
  const RunResult f = run_taxopt("--in " + t.path("f.cls") + " -q --gcode " + t.path("o.nc"));
  CHECK(f.code == 2);
  CHECK_THAT(f.err, Catch::Contains(t.path("f.cls") + ":1: FEDRAT: a feed of 1e-300 mm/min"));
}

TEST_CASE("hostile input, round 3: no output replaces an input, a device or a read-only file",
          "[cli][bad-input][hostile]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  write_file(t.path("p.stl"), read_file(d + "demo/sine.stl"));
  write_file(t.path("m.toml"), read_file(d + "machines/paper-ac.toml"));
  const std::string part = read_file(t.path("p.stl")), machine = read_file(t.path("m.toml"));
  const std::string base = "--in " + d + "demo/sine.cls --part " + t.path("p.stl") + " --machine " +
                           t.path("m.toml") + " --gauge-length 15 -q ";
  const struct {
    std::string args;
    const char* says;
  } cases[] = {
      {"--gcode " + t.path("o.nc") + " --report " + t.path("p.stl"), "is the --part file"},
      {"--gcode " + t.path("o.nc") + " --points-csv " + t.path("m.toml"), "is the --machine file"},
      {"--gcode " + t.path("pl/o.nc") + " --plots " + t.path("pl"), "lies in the --plots folder"},
      {"--gcode " + t.path("o.nc") + " --plots " + t.path("o.nc"), "lies in the --plots folder"},
      {"--gcode /dev/null", "is not a regular file"},
  };
  for (const auto& c : cases) {
    INFO(c.args);
    const RunResult r = run_taxopt(base + c.args);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains(c.says));
  }
  CHECK(read_file(t.path("p.stl")) == part);
  CHECK(read_file(t.path("m.toml")) == machine);
  CHECK_FALSE(file_exists(t.path("o.nc")));
  CHECK_FALSE(file_exists(t.path("pl")));
  // A read-only program stays as it was.
  write_file(t.path("ro.nc"), "(keep)\n");
  std::filesystem::permissions(t.path("ro.nc"), std::filesystem::perms::owner_read);
  const RunResult ro = run_taxopt(base + "--gcode " + t.path("ro.nc"));
  CHECK(ro.code == 2);
  CHECK_THAT(ro.err, Catch::Contains("is read-only"));
  CHECK(read_file(t.path("ro.nc")) == "(keep)\n");
}

TEST_CASE("hostile input, round 3: generate refuses NaN, infinite and out-of-budget options",
          "[cli][bad-input][hostile][generate]") {
  TempDir t;
  const std::string out = " --out-cls " + t.path("g.cls") + " --out-mesh " + t.path("g.stl");
  for (const char* o :
       {"--tilt nan", "--tilt inf", "--yaw nan", "--tilt 1e300", "--spindle -1", "--mesh-step 1e-4",
        "--mesh-step 0.01", "--width 1e9", "--length 1e12", "--scallop 1e-12", "--tool-radius inf",
        "--width 2000 --length 2000 --mesh-step 0.05"}) {
    INFO(o);
    const RunResult r = run_taxopt(std::string("generate ") + o + out);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: generate: "));
    CHECK_FALSE(file_exists(t.path("g.cls")));
    CHECK_FALSE(file_exists(t.path("g.stl")));
  }
}

TEST_CASE(
    "hostile input, round 3: machine lengths and C ranges beyond a machine, a 10 MB token, a "
    "closed stdout",
    "[cli][bad-input][hostile]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  const std::string ac =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\nmax_deg = 120\n";
  const struct {
    std::string toml;
    const char* says;
  } machines[] = {
      {ac + "[axes.C]\ncontinuous = true\n[pivot]\na_axis_y = 1e300\n[gcode]\nmode = \"machine\"\n",
       "pivot.a_axis_y must be within [-1e4, 1e4] mm"},
      {ac + "[axes.C]\nmin_deg = -1e9\nmax_deg = 1e9\n", "range must lie within [-1e5, 1e5] deg"},
      {ac + "[axes.C]\ncontinuous = true\n[gcode]\nretract_z_mm = 1e300\n",
       "gcode.retract_z_mm must be within [-1e4, 1e4] mm"},
  };
  for (const auto& m : machines) {
    INFO(m.toml);
    write_file(t.path("m.toml"), m.toml);
    const RunResult r = run_taxopt("--in " + d + "demo/sine.cls --machine " + t.path("m.toml") +
                                   " -q --gcode " + t.path("o.nc"));
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains(m.says));
  }
  // A 10 MB token is not echoed back.
  write_file(t.path("big.cls"), "GOTO/0,0,0\nCUTCOM/" + std::string(10000000, 'X') + "\n");
  const RunResult big = run_taxopt("--in " + t.path("big.cls") + " -q --gcode " + t.path("o.nc"));
  CHECK(big.code == 2);
  CHECK(big.err.size() < 1000);
  // A closed stdout: the run ends as it would, not by SIGPIPE (exit 141).
  const RunResult piped =
      run("(" + std::string(TAXOPT_EXE) + " --in " + d + "demo/sine.cls --gcode " + t.path("p.nc") +
          " 2>/dev/null; echo $? > " + t.path("code") + ") | true");
  CHECK(piped.code == 0);
  CHECK(read_file(t.path("code")) == "0\n");
  CHECK(file_exists(t.path("p.nc")));
}

TEST_CASE(
    "hostile input, round 3: the LinuxCNC importer refuses garbage pins, offsets beyond a "
    "machine and files that are no configuration, and quotes nothing it reads",
    "[cli][bad-input][hostile][machine]") {
  TempDir t;
  const std::string sample =
      read_file(std::string(TAXOPT_SOURCE_DIR) + "/tests/data/linuxcnc/xyzac-trt/xyzac-trt.ini");
  const auto with = [&](const std::string& from, const std::string& to) {
    return taxopt::test::replaced_once(sample, from, to);
  };
  const struct {
    std::string ini;
    const char* says;
  } cases[] = {
      {with("setp xyzac-trt-kins.y-rot-point 0", "setp xyzac-trt-kins.y-rot-point abc"),
       "y-rot-point = abc is not a number"},
      {with("setp xyzac-trt-kins.y-rot-point 0", "setp xyzac-trt-kins.y-rot-point nan"),
       "y-rot-point = nan is not a number"},
      {with("sets :y-offset     20", "sets :y-offset     1e300"), "lies beyond 1e4 mm"},
  };
  for (const auto& c : cases) {
    INFO(c.says);
    write_file(t.path("x.ini"), c.ini);
    const RunResult r =
        run_taxopt("machine --from-linuxcnc-ini " + t.path("x.ini") + " --out " + t.path("m.toml"));
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains(c.says));
    CHECK_FALSE(file_exists(t.path("m.toml")));
  }
  // A name with a quote and a newline becomes a plain TOML string; the file reads back.
  const std::string odd = t.path("my\"mill\nx.ini");
  write_file(odd, sample);
  const RunResult named =
      run_taxopt("machine --from-linuxcnc-ini '" + odd + "' --out " + t.path("n.toml"));
  INFO(named.err);
  REQUIRE(named.code == 0);
  const taxopt::Machine m = taxopt::read_machine_file(t.path("n.toml"));
  CHECK(m.name == "my_mill_x");
  // A HAL file named past the system's NAME_MAX (a fuzzed INI: filesystem_error went through
  // the importer and ended the process): not read, and said.
  write_file(t.path("long.ini"),
             with("[HAL]\n", "[HAL]\nHALFILE = " + std::string(300, 'h') + ".hal\n"));
  const RunResult long_name = run_taxopt("machine --from-linuxcnc-ini " + t.path("long.ini") +
                                         " --out " + t.path("l.toml"));
  INFO(long_name.err);
  CHECK(long_name.code == 0);
  CHECK_THAT(long_name.err, Catch::Contains("not read (not a .hal file here)"));
  // A FIFO is no configuration file: refused, not waited on.
  REQUIRE(run("mkfifo " + t.path("f.ini")).code == 0);
  const RunResult fifo = run_taxopt("machine --from-linuxcnc-ini " + t.path("f.ini"));
  CHECK(fifo.code == 2);
  CHECK_THAT(fifo.err, Catch::Contains("not a regular file"));
}

TEST_CASE("hostile input, round 3: a FIFO or /dev/zero as the CL or machine file is refused",
          "[cli][bad-input][hostile][files]") {
  TempDir t;
  REQUIRE(run("mkfifo " + t.path("in.cls") + " " + t.path("m.toml")).code == 0);
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls";
  const std::vector<std::string> cases = {"--in " + t.path("in.cls"), "--in /dev/zero",
                                          "--in " + d + " --machine " + t.path("m.toml"),
                                          "--in " + d + " --machine /dev/zero"};
  for (const std::string& args : cases) {
    INFO(args);
    const RunResult r = run_taxopt(args + " -q --gcode " + t.path("o.nc"));
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("not a regular file"));
  }
}

TEST_CASE(
    "hostile input, round 3: a mill that is no ball end, with a part, has its shank and holder "
    "checked: the collisions the ball-end run refuses are refused for it too",
    "[cli][bad-input][collision][slow]") {
  TempDir t;
  const std::string demo = read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls");
  const std::string part = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.stl";
  REQUIRE(demo.find("TLDATA/MILL,6.0000,3.0000,15.0000") != std::string::npos);
  // The ball-end tool, its axes kept: the shank comes within its clearance at 330 points.
  const auto ball =
      run_taxopt("--in " + std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls --part " + part +
                 " --method none -q --gcode " + t.path("b.nc"));
  CHECK(ball.code == 1);
  CHECK_THAT(ball.err, Catch::Contains("330 CL points where the tool hits the part"));
  for (const char* corner : {"1.0000", "2.9990", "0.0000"}) {
    INFO("corner radius " << corner);
    std::string cl = demo;
    cl.replace(cl.find("TLDATA/MILL,6.0000,3.0000"), 25,
               std::string("TLDATA/MILL,6.0000,") + corner);
    write_file(t.path("c.cls"), cl);
    const auto r = run_taxopt("--in " + t.path("c.cls") + " --part " + part + " -q --gcode " +
                              t.path("c.nc") + " --report " + t.path("c.json"));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("CL points where the shank of the (not ball-end) tool hits "
                                      "the part within its clearance"));
    CHECK_FALSE(file_exists(t.path("c.nc")));
    // Flutes long enough to reach past the part: free.
    std::string longer = cl;
    longer.replace(longer.find(",15.0000,"), 9, ",40.0000,");
    write_file(t.path("l.cls"), longer);
    const auto l = run_taxopt("--in " + t.path("l.cls") + " --part " + part + " -q --gcode " +
                              t.path("l.nc") + " --report " + t.path("l.json"));
    INFO(l.err);
    CHECK(l.code == 0);
    const auto j = nlohmann::json::parse(read_file(t.path("l.json")));
    CHECK(j["operations"][0]["after"]["colliding_points"] == 0);
  }
}

TEST_CASE(
    "hostile input, round 3: out of memory (ulimit -v) with a 46 MB part is exit 2 naming "
    "memory, nothing written, no crash",
    "[cli][bad-input][hostile][memory]") {
#if defined(TAXOPT_SANITIZE) || defined(TAXOPT_TSAN)
  WARN("skipped under a sanitizer: it reserves more address space than the limit");
  return;
#else
  TempDir t;
  REQUIRE(run_taxopt("generate --mesh-step 0.1 --out-cls " + t.path("m.cls") + " --out-mesh " +
                     t.path("m.stl"))
              .code == 0);
  // FCL's model of this part fails to allocate under the limit: it printed "BVH Error! Out of
  // memory" and the next query segfaulted (tests/test_bad_input.cpp).
  const RunResult r =
      run("ulimit -v 600000; " + std::string(TAXOPT_EXE) + " --in " + t.path("m.cls") + " --part " +
          t.path("m.stl") + " --method none -q --gcode " + t.path("o.nc"));
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("taxopt: error: out of memory"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(t.dir())) {
    (void)e;
    ++files;
  }
  CHECK(files == 2);  // the CL file and the mesh: no temporary file left
#endif
}

TEST_CASE(
    "hostile input, round 3: --plots for more than 200 operations is refused before "
    "anything is written",
    "[cli][bad-input][hostile]") {
  TempDir t;
  std::string cl = "LOADTL/1\nSPINDL/RPM,3000,CLW\nFEDRAT/MMPM,500\n";
  for (int k = 0; k < 201; ++k) {
    cl += "TOOL PATH/OP" + std::to_string(k) + ",TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\n" +
          "GOTO/0,0,10,0,0,1\nGOTO/" + std::to_string(k + 1) + ",0,10\nEND-OF-PATH\n";
  }
  write_file(t.path("many.cls"), cl);
  const RunResult r = run_taxopt("--in " + t.path("many.cls") + " --plots " + t.path("p") +
                                 " --gcode " + t.path("o.nc") + " -q");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--plots: the CL file has 201 operations"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  CHECK_FALSE(std::filesystem::exists(t.path("p")));
  // Without --plots the same file posts.
  CHECK(run_taxopt("--in " + t.path("many.cls") + " --gcode " + t.path("o.nc") + " -q").code == 0);
}

TEST_CASE(
    "hostile input, round 4: a program whose rounding moves the tips past a finishing tolerance "
    "(decimals = 0), or whose feed rounds to F0, is no verified program -- exit 1 naming why",
    "[hostile][gcode]") {
  TempDir dir;
  const std::string machine =
      read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/generic-ac-trt.toml");
  REQUIRE(machine.find("decimals = 4") != std::string::npos);
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string m = machine;
    m.replace(m.find(from), from.size(), to);
    return m;
  };
  write_file(dir.path("coarse.toml"), with("decimals = 4", "decimals = 0"));
  write_file(dir.path("in.cls"),
             "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nLOADTL/1\nSPINDL/3000\nFEDRAT/MMPM,500\n"
             "GOTO/0,3.555,8.4996\nGOTO/10,3.555,8.4996\n");
  RunResult r = run_taxopt("--in " + dir.path("in.cls") + " --machine " + dir.path("coarse.toml") +
                           " --method none -q --gcode " + dir.path("o.nc"));
  INFO(r.err);
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("gcode.decimals = 0"));
  CHECK_FALSE(file_exists(dir.path("o.nc")));
  // A feed of 0.01 mm/min written with no decimals: F0.
  write_file(dir.path("f.toml"), with("decimals = 4", "decimals = 4\nfeed_decimals = 0"));
  write_file(dir.path("slow.cls"),
             "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nLOADTL/1\nSPINDL/3000\nFEDRAT/MMPM,0.01\n"
             "GOTO/0,0,5\nGOTO/10,0,5\n");
  r = run_taxopt("--in " + dir.path("slow.cls") + " --machine " + dir.path("f.toml") +
                 " --method none -q --gcode " + dir.path("s.nc"));
  INFO(r.err);
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("F0"));
}

TEST_CASE(
    "hostile input, round 4: outputs that are symbolic links are refused, not replaced, and "
    "generate checks its outputs as the main job does",
    "[hostile][outputs]") {
  TempDir dir;
  write_file(dir.path("target.nc"), "keep\n");
  std::filesystem::create_symlink(dir.path("target.nc"), dir.path("link.nc"));
  RunResult r = run_taxopt("--in " + std::string(TAXOPT_SOURCE_DIR) +
                           "/data/demo/sine.cls --method none -q --gcode " + dir.path("link.nc"));
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("symbolic link"));
  CHECK(std::filesystem::is_symlink(dir.path("link.nc")));
  CHECK(read_file(dir.path("target.nc")) == "keep\n");
  // generate: one file named twice, a link, a read-only file.
  r = run_taxopt("generate --out-cls " + dir.path("x") + " --out-mesh " + dir.path("./x"));
  CHECK(r.code == 2);
  CHECK_FALSE(file_exists(dir.path("x")));
  r = run_taxopt("generate --out-cls " + dir.path("link.nc"));
  CHECK(r.code == 2);
  CHECK(read_file(dir.path("target.nc")) == "keep\n");
}

TEST_CASE(
    "hostile input, round 4: --dialect over a machine file whose work offset is another "
    "dialect's word is refused before any work",
    "[hostile][gcode]") {
  TempDir dir;
  std::string m = read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/generic-ac-trt.toml");
  const std::string from = "dialect = \"linuxcnc\"";
  REQUIRE(m.find(from) != std::string::npos);
  m.replace(m.find(from), from.size(), "dialect = \"siemens\"\nwork_offset = \"G505\"");
  write_file(dir.path("s.toml"), m);
  const std::string common = "--in " + std::string(TAXOPT_SOURCE_DIR) +
                             "/data/demo/sine.cls --method none -q --machine " +
                             dir.path("s.toml") + " --gcode " + dir.path("o.nc");
  RunResult r = run_taxopt(common);
  INFO(r.err);
  CHECK(r.code == 0);  // G505 is Sinumerik's
  r = run_taxopt(common + " --dialect linuxcnc");
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("work_offset"));
}

TEST_CASE(
    "hostile input, round 4: a part and an operation with no tool geometry -- the user is "
    "told nothing of it was checked against the part",
    "[hostile][safety]") {
  TempDir dir;
  const std::string demo = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  // The demo's CL file without its tool record.
  std::istringstream in(read_file(demo + "sine.cls"));
  std::string text;
  for (std::string l; std::getline(in, l);) {
    if (l.rfind("TLDATA", 0) == 0 || l.rfind("CUTTER", 0) == 0) continue;
    text += l + "\n";
  }
  REQUIRE(text.size() > 1000);
  write_file(dir.path("notool.cls"), text);
  const RunResult r =
      run_taxopt("--in " + dir.path("notool.cls") + " --part " + demo + "sine.stl" +
                 " --method none --gcode " + dir.path("o.nc") + " --report " + dir.path("r.json"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("NOT CHECKED") && Catch::Contains("no tool geometry"));
  const auto report = nlohmann::json::parse(read_file(dir.path("r.json")));
  bool said = false;
  for (const auto& f : report["findings"]) {
    said = said || (f["code"] == "no_tool_model" && f["severity"] == "safety");
  }
  CHECK(said);
  CHECK_THAT(read_file(dir.path("o.nc")), Catch::Contains("no tool geometry"));
}

TEST_CASE(
    "safe by default: a program that turns no coolant on says so, unless the CL file or "
    "the machine file asks for some",
    "[hostile][safety][coolant]") {
  TempDir dir;
  const std::string machine =
      read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/generic-ac-trt.toml");
  REQUIRE(machine.find("coolant") == std::string::npos);
  write_file(dir.path("m.toml"), machine);
  const std::string body =
      "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nLOADTL/1\nSPINDL/3000\nFEDRAT/MMPM,500\n"
      "GOTO/0,0,5\nGOTO/10,0,5\n";
  const auto coolant_said = [&](const std::string& cl) {
    write_file(dir.path("in.cls"), cl);
    const RunResult r = run_taxopt("--in " + dir.path("in.cls") + " --machine " +
                                   dir.path("m.toml") + " --method none --gcode " +
                                   dir.path("o.nc") + " --report " + dir.path("r.json"));
    INFO(r.err);
    REQUIRE(r.code == 0);
    bool said = false;
    const auto report = nlohmann::json::parse(read_file(dir.path("r.json")));
    for (const auto& f : report["findings"]) said = said || f["code"] == "no_coolant";
    return said;
  };
  CHECK(coolant_said(body));
  CHECK_FALSE(coolant_said("COOLNT/ON\n" + body));
  CHECK_FALSE(coolant_said("COOLNT/OFF\n" + body));  // asked for none: no surprise
}

TEST_CASE(
    "bad input: no output replaces the files it was made from -- machine --out naming the "
    "configuration's INI or a HAL file it read, a plot named as an input in the plots folder",
    "[bad-input][cli][outputs]") {
  TempDir t;
  const std::string cfg = std::string(TAXOPT_TEST_DATA) + "/linuxcnc/xyzac-trt/";
  for (const char* f : {"xyzac-trt.ini", "switchkins_postgui.hal"}) {
    write_file(t.path(f), read_file(cfg + f));
  }
  for (const std::string& out :
       {t.path("xyzac-trt.ini"), t.path("switchkins_postgui.hal"), t.path("./xyzac-trt.ini")}) {
    INFO(out);
    const std::string before = read_file(t.path("xyzac-trt.ini"));
    const RunResult r =
        run_taxopt("machine --from-linuxcnc-ini " + t.path("xyzac-trt.ini") + " --out " + out);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("is the configuration's own file"));
    CHECK(read_file(t.path("xyzac-trt.ini")) == before);
  }
  // The CL file in the plots folder under a plot's name.
  const std::string in = t.path("plots/op1-feed.svg");
  std::filesystem::create_directories(t.path("plots"));
  write_file(in, read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls"));
  const std::string text = read_file(in);
  const RunResult r = run_taxopt("--in " + in + " --method none --plots " + t.path("plots") +
                                 " --report " + t.path("r.json") + " -q");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("its plot op1-feed.svg would replace the --in file"));
  CHECK(read_file(in) == text);
  CHECK_FALSE(file_exists(t.path("r.json")));
}

TEST_CASE(
    "bad input: an output the system cannot create is refused before any work, naming its "
    "option (a 300-character file name failed after the whole run)",
    "[bad-input][cli][outputs]") {
  TempDir t;
  const std::string name = t.path(std::string(300, 'x') + ".ngc");
  const RunResult r = run_taxopt("--in " + std::string(TAXOPT_SOURCE_DIR) +
                                 "/data/demo/sine.cls --method none -q --gcode " + name +
                                 " --report " + t.path("r.json"));
  CHECK(r.code == 2);
  CHECK_THAT(r.err,
             Catch::Contains("--gcode " + name + ": cannot write there: File name too long"));
  CHECK_FALSE(file_exists(t.path("r.json")));
  // The probe leaves nothing behind.
  std::size_t left = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(t.path(""))) ++left;
  CHECK(left == 0);
}

TEST_CASE(
    "bad input: a limited C that must unwind inside a feed move is a problem naming the CL line, "
    "part or no part (it turned 356 deg inside a G1, said only as a C jump)",
    "[bad-input][cli][machine]") {
  TempDir t;
  // A 30 deg tilted axis going twice round Z while the tip circles: C runs through 720 deg.
  std::ostringstream cl;
  cl << "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nRAPID\n";
  cl.precision(9);
  for (int i = 0; i <= 200; ++i) {
    const double c = taxopt::deg_to_rad(720.0 * i / 200.0), a = taxopt::deg_to_rad(30.0);
    cl << "GOTO/" << 10 * std::cos(c) << "," << 10 * std::sin(c) << ",0,"
       << std::sin(a) * std::sin(c) << "," << -std::sin(a) * std::cos(c) << "," << std::cos(a)
       << "\n";
  }
  write_file(t.path("rot.cls"), cl.str());
  const std::string machine =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\nmax_deg = 120\n[axes.C]\n";
  write_file(t.path("c200.toml"), machine + "min_deg = -200\nmax_deg = 200\n");
  write_file(t.path("cinf.toml"), machine + "continuous = true\n");
  const auto run = [&](const char* m) {
    return run_taxopt("--in " + t.path("rot.cls") + " --machine " + t.path(m) +
                      " --method none --spindle-rpm 5000 --tool-number 1 -q --gcode " +
                      t.path("o.nc") + " --report " + t.path("r.json") + " --force");
  };
  RunResult r = run("c200.toml");
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("feed move(s) where a rotary axis turns more than half a turn, "
                                    "the first 356.4 deg into CL line") &&
                        Catch::Contains("C's range [-200, 200] deg makes it unwind there"));
  CHECK_THAT(read_file(t.path("r.json")), Catch::Contains("\"turn_in_cut\""));
  // The same path on a C that turns for ever: no unwind, no finding.
  r = run("cinf.toml");
  CHECK(r.code == 0);
  CHECK_THAT(read_file(t.path("r.json")), !Catch::Contains("turn_in_cut"));
}
