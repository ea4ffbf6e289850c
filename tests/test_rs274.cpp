#include <algorithm>
// Integration with LinuxCNC's real interpreter: every file taxopt writes must run through
// `rs274 -g`, and its canonical moves must put the tool where the CL file says.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "support.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

int trials() {
  const char* env = std::getenv("TAXOPT_PROPERTY_TRIALS");
  return env ? std::max(1, std::atoi(env)) : 2;
}

struct Checked {
  double max_tip_mm = 0.0;
  double max_axis_deg = 0.0;
  double max_c_step_feed_deg = 0.0;
  /// Machine mode: the blocks rs274 ran between two CL points (linearisation), and the
  /// largest distance of their tips from the straight line between those points.
  std::size_t between = 0;
  double max_between_mm = 0.0;
  std::vector<CanonMove> moves;
};

/// Runs rs274 on `ngc` and compares its moves one by one with the generated CL points; in
/// machine mode a move that is no CL point must lie on the way between two (linearisation).
Checked check_against(const std::string& ngc, const GeneratedCl& g, const Machine& m,
                      double unit_mm) {
  Checked out;
  const RunResult r = run_rs274(ngc, out.moves);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const bool machine = m.gcode.mode == GcodeMode::Machine;
  if (!machine) REQUIRE(out.moves.size() == g.tips_mm.size());
  std::size_t i = 0;  // the next CL point
  double last_c = 0.0;
  for (const CanonMove& cm : out.moves) {
    const Posed pose{deg_to_rad(cm.a), deg_to_rad(cm.c)};
    const Vec3d xyz = Vec3d(cm.x, cm.y, cm.z) * unit_mm;
    const Vec3d tip = machine ? m.rotary.from_machine_mm(xyz, pose) : xyz;
    // In machine mode compare in the machine's own coordinates, as the convention defines them.
    const double off = i >= g.tips_mm.size() ? 1e9
                       : machine ? (xyz - m.rotary.to_machine_mm(g.tips_mm[i], pose)).norm()
                                 : (tip - g.tips_mm[i]).norm();
    if (machine && off > 0.002 && i > 0 && i < g.tips_mm.size()) {
      const Vec3d a = g.tips_mm[i - 1], b = g.tips_mm[i];
      const double w = std::clamp((tip - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      out.max_between_mm = std::max(out.max_between_mm, (tip - (a + w * (b - a))).norm());
      ++out.between;
      REQUIRE(cm.feed == !g.rapid[i]);  // a rapid's blocks between are rapids
      continue;
    }
    REQUIRE(i < g.tips_mm.size());
    // On LinuxCNC in tcp mode a rapid may be written at a joint-safe feed (docs/gcode-dialects.md):
    // the approach's last leg along a tilted tool axis (an operation's first point, or the
    // point after an index move), which its planner would run with the spindle's Z past its
    // limit.
    const bool joint_safe_rapid =
        g.rapid[i] && cm.feed && m.gcode.dialect == GcodeDialect::LinuxCNC && !machine;
    INFO("point " << i << " of " << g.tips_mm.size());
    REQUIRE((cm.feed == !g.rapid[i] || joint_safe_rapid));
    out.max_tip_mm = std::max(out.max_tip_mm, off);
    out.max_axis_deg =
        std::max(out.max_axis_deg, rad_to_deg(angle_between(m.rotary.forward(pose), g.axes[i])));
    if (i > 0 && cm.feed) {
      out.max_c_step_feed_deg = std::max(out.max_c_step_feed_deg, std::abs(cm.c - last_c));
    }
    last_c = cm.c;
    ++i;
  }
  REQUIRE(i == g.tips_mm.size());
  return out;
}

}  // namespace

TEST_CASE("rs274: --method none on unseen heightfields puts every tip and axis in place",
          "[rs274][integration]") {
  REQUIRE(have_rs274());
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> tilt(0.0, 15.0), yoff(-3.0, 3.0);
  for (int t = 0; t < trials(); ++t) {
    for (const Heightfield& hf : random_heightfields(rng)) {
      INFO(hf.name << " trial " << t);
      TempDir dir;
      const double y = 25.0 + yoff(rng);
      const GeneratedCl g = raster_cl(hf, 3.0, tilt(rng), 4, 0.5, y - 4.0, y + 4.0, 0.0, 50.0);
      write_file(dir.path("in.cls"), g.text);
      const RunResult r = run_taxopt("--in " + dir.path("in.cls") + " --gcode " +
                                     dir.path("out.ngc") + " --method none -q");
      INFO(r.err);
      REQUIRE(r.code == 0);
      const Checked c = check_against(dir.path("out.ngc"), g, default_machine(), 1.0);
      CHECK(c.max_tip_mm <= 0.002);
      CHECK(c.max_axis_deg <= 0.01);
      CHECK(c.max_c_step_feed_deg <= 90.0);
    }
  }
}

TEST_CASE("rs274: machine mode with pivot offsets and inverse time follows the CLI.md convention",
          "[rs274][integration]") {
  REQUIRE(have_rs274());
  std::mt19937 rng(77);
  for (int sense : {1, -1}) {
    for (const char* feed_mode : {"units-per-minute", "inverse-time"}) {
      INFO("sense " << sense << " " << feed_mode);
      TempDir dir;
      const std::string toml = std::string(
                                   "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
                                   "max_deg = 120\nsense = ") +
                               std::to_string(sense) +
                               "\n[axes.C]\ncontinuous = true\nsense = " + std::to_string(sense) +
                               "\n[pivot]\na_axis_y = 12.5\na_axis_z = -80.0\nc_axis_x = 7.0\n"
                               "c_axis_y = -4.0\n[gcode]\nmode = \"machine\"\nfeed_mode = \"" +
                               feed_mode + "\"\n";
      write_file(dir.path("m.toml"), toml);
      const Machine m = read_machine_file(dir.path("m.toml"));
      const auto hfs = random_heightfields(rng);
      const GeneratedCl g = raster_cl(hfs[1], 3.0, 10.0, 3, 0.5, 20.0, 30.0, 5.0, 45.0);
      write_file(dir.path("in.cls"), g.text);
      const RunResult r =
          run_taxopt("--in " + dir.path("in.cls") + " --machine " + dir.path("m.toml") +
                     " --gcode " + dir.path("out.ngc") + " --method none -q");
      INFO(r.err);
      REQUIRE(r.code == 0);
      const Checked c = check_against(dir.path("out.ngc"), g, m, 1.0);
      CHECK(c.max_tip_mm <= 0.002);
      CHECK(c.max_axis_deg <= 0.01);
      // The pivot 80 mm below the table: joint-linear moves would bow the tip off the
      // path; the blocks between keep it within the linearisation tolerance (0.01 mm).
      INFO(c.between << " blocks between the points");
      CHECK(c.between > 0);
      CHECK(c.max_between_mm <= 0.01 + 0.002);
    }
  }
}

TEST_CASE("rs274: sense -1 writes mirrored A and C for the same tool axes",
          "[rs274][integration]") {
  REQUIRE(have_rs274());
  std::mt19937 rng(5);
  const auto hfs = random_heightfields(rng);
  const GeneratedCl g = raster_cl(hfs[0], 3.0, 5.0, 2, 0.5, 10.0, 40.0, 0.0, 50.0);
  TempDir dir;
  write_file(dir.path("in.cls"), g.text);
  std::vector<CanonMove> plus, minus;
  REQUIRE(run_taxopt("--in " + dir.path("in.cls") + " --gcode " + dir.path("p.ngc") +
                     " --method none -q")
              .code == 0);
  REQUIRE(run_taxopt("--in " + dir.path("in.cls") + " --gcode " + dir.path("m.ngc") +
                     " --method none -q --feed-schedule --machine " +
                     std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml")
              .code == 0);
  REQUIRE(run_rs274(dir.path("p.ngc"), plus).code == 0);
  Rs274Options sample;  // the preset is LinuxCNC's sample configuration: run with its INI
  sample.ini = std::string(TAXOPT_SOURCE_DIR) + "/tests/data/linuxcnc/xyzac-trt/xyzac-trt.ini";
  sample.stub_switchkins = true;
  REQUIRE(run_rs274(dir.path("m.ngc"), minus, sample).code == 0);
  REQUIRE(plus.size() == minus.size());
  const Machine mm =
      read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml");
  for (std::size_t i = 0; i < plus.size(); ++i) {
    CHECK(minus[i].a == Approx(-plus[i].a).margin(1e-4));
    CHECK(minus[i].c == Approx(-plus[i].c).margin(1e-4));
    const Vec3d v = mm.rotary.forward({deg_to_rad(minus[i].a), deg_to_rad(minus[i].c)});
    CHECK(rad_to_deg(angle_between(v, g.axes[i])) <= 0.01);
  }
}

TEST_CASE("rs274: every real CL file posts to G-code rs274 accepts, move for move",
          "[rs274][integration]") {
  REQUIRE(have_rs274());
  // What each file means, read by scripts/cl_reference.py (no code shared with the reader):
  // its motion records, CIRCLE records, and the length of its path with every arc run in the
  // sense of the straight moves beside it.
  std::istringstream table(read_file(real_data("reference.tsv")));
  std::string row;
  std::getline(table, row);  // header
  int files = 0;
  while (std::getline(table, row)) {
    std::istringstream fields(row);
    std::string f;
    int motion_records = 0, circles = 0;
    double path_mm = 0.0;
    fields >> f >> motion_records >> circles >> path_mm;
    INFO(f);
    ++files;
    const Toolpath tp = taxopt::test::read_real(f);
    CHECK(tp.reading.motion_records == motion_records);
    CHECK(tp.reading.arcs == circles);
    TempDir dir;
    const RunResult r =
        run_taxopt("--in " + taxopt::test::real_path(f, dir.dir()) + taxopt::test::real_flags(f) +
                   " --gcode " + dir.path("o.ngc") + " --method none -q");
    INFO(r.err);
    REQUIRE(r.code == 0);
    std::vector<CanonMove> moves;
    const RunResult rs = run_rs274(dir.path("o.ngc"), moves);
    INFO(rs.out.substr(rs.out.size() > 400 ? rs.out.size() - 400 : 0));
    REQUIRE(rs.code == 0);
    std::vector<GcodeMove> ours;
    for (const GcodeMove& g : read_gcode_moves(read_file(dir.path("o.ngc")), "o.ngc")) {
      if (!g.positioning) ours.push_back(g);
    }
    REQUIRE(moves.size() == ours.size());
    for (std::size_t i = 0; i < ours.size(); ++i) {
      REQUIRE(moves[i].a == Approx(ours[i].tilt_deg).margin(1e-4));
      REQUIRE(moves[i].c == Approx(ours[i].c_deg).margin(1e-4));
    }
    // The whole path as rs274 moves the tip (TCP mode), from the first point on.
    std::size_t arcs = 0;
    const double rs274_mm = path_length(moves, &arcs) * mm_per_unit(tp.units);
    // Arcs kept as arcs where their plane and axes allow (never more blocks than CIRCLEs need
    // at 180 deg each; none without a CIRCLE).
    if (circles == 0) CHECK(arcs == 0);
    INFO("G2/G3 blocks: " << arcs << " for " << circles << " CIRCLE records");
    CHECK(rs274_mm == Approx(path_mm).epsilon(0.002));
  }
  CHECK(files == 8);
}

TEST_CASE("rs274: inch output of a millimetre file", "[rs274][integration]") {
  REQUIRE(have_rs274());
  std::mt19937 rng(11);
  const auto hfs = random_heightfields(rng);
  const GeneratedCl g = raster_cl(hfs[2], 3.0, 0.0, 2, 0.5, 10.0, 20.0, 20.0, 50.0);
  TempDir dir;
  write_file(dir.path("in.cls"), g.text);
  const RunResult r = run_taxopt("--in " + dir.path("in.cls") + " --gcode " + dir.path("o.ngc") +
                                 " --units-out in --method none -q");
  REQUIRE(r.code == 0);
  CHECK_THAT(read_file(dir.path("o.ngc")), Catch::Contains("G20"));
  // 4 decimals of an inch: each coordinate within 0.00005 in.
  const Checked c = check_against(dir.path("o.ngc"), g, default_machine(), 25.4);
  CHECK(c.max_tip_mm <= std::sqrt(3.0) * 0.00005 * 25.4 + 1e-9);
  CHECK(c.max_axis_deg <= 0.01);
}

TEST_CASE("rs274: taxopt demo writes G-code rs274 accepts, with the paper's C flips counted",
          "[rs274][integration][slow]") {
  REQUIRE(have_rs274());
  TempDir dir;
  const RunResult r = run_taxopt("demo --out " + dir.path("demo"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.out, Catch::Contains("SINE_FINISH"));
  for (const char* plot :
       {"op1-angles-a.svg", "op1-angles-c.svg", "op1-omega.svg", "op1-accel.svg"}) {
    CHECK(file_exists(dir.path("demo/plots/") + plot));
  }
  std::vector<CanonMove> moves;
  REQUIRE(run_rs274(dir.path("demo/demo.nc"), moves).code == 0);
  CHECK(moves.size() > 1000);
  CHECK(file_exists(dir.path("demo/report.json")));
  CHECK(file_exists(dir.path("demo/points.csv")));
  // A is limited to [-110, 30] deg: the input axes crossing the vertical need C flips (paper
  // fig. 21); the optimised axes lean less and the flips, and their peaks, go.
  const auto report = nlohmann::json::parse(read_file(dir.path("demo/report.json")));
  const auto& op = report["operations"].at(0);
  CHECK(report["method"] == "paper");
  CHECK(op["before"]["c_jumps"].get<int>() > 0);
  CHECK(op["after"]["c_jumps"].get<int>() < op["before"]["c_jumps"].get<int>());
  CHECK(op["after"]["max_omega_deg_s"].get<double>() <
        (1.0 - 0.109) * op["before"]["max_omega_deg_s"].get<double>());
  CHECK(op["after"]["max_accel_deg_s2"].get<double>() <
        (1.0 - 0.248) * op["before"]["max_accel_deg_s2"].get<double>());
  CHECK(op["after"]["colliding_points"] == 0);
  CHECK(op["max_axis_change_deg"].get<double>() <= 30.0 + 1e-6);
}

TEST_CASE(
    "rs274: CIRCLE arcs are written as G2/G3 in XY, XZ and YZ, helical and in turns, and "
    "rs274 moves them the length the file means",
    "[rs274][integration][arcs]") {
  REQUIRE(have_rs274());
  // NX (clockwise about (i,j,k)), every arc tangent to the moves beside it: a quarter in XY,
  // a half in XZ, a quarter in YZ, a helix of TIMES,2 (a half turn plus one more: 540 deg)
  // falling 4 mm.
  const std::string cl =
      "TOOL PATH/ARCS,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nFEDRAT/MMPM,600\n"
      "GOTO/0,10,0,0,0,1\nGOTO/10,10,0\nCIRCLE/10,0,0,0,0,1,10\nGOTO/20,0,0\n"          // XY
      "GOTO/20,-10,0\nCIRCLE/30,-10,0,0,-1,0,10\nGOTO/40,-10,0\n"                       // XZ
      "GOTO/40,-10,-5\nGOTO/40,-20,-5\nCIRCLE/40,-20,-15,-1,0,0,10\nGOTO/40,-30,-15\n"  // YZ
      "GOTO/40,-30,-25\nGOTO/70,-30,-25\nGOTO/60,-30,-25\n"
      "CIRCLE/60,-20,-25,0,0,1,10,TIMES,2\nGOTO/60,-10,-29\nGOTO/70,-10,-29\nEND-OF-PATH\n";
  // The path the file means, by hand.
  const double quarter = M_PI / 2 * 10;
  const double expect_mm = 10 + quarter + 10 + 2 * quarter + 5 + 10 + quarter + 10 + 30 + 10 +
                           std::hypot(6 * quarter, 4.0) + 10;
  TempDir dir;
  write_file(dir.path("a.cls"), cl);
  for (const char* dialect : {"linuxcnc", "fanuc", "siemens", "heidenhain"}) {
    INFO(dialect);
    write_file(dir.path("m.toml"),
               "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
               "max_deg = 120\n[axes.C]\ncontinuous = true\n[gcode]\n"
               "dialect = \"" +
                   std::string(dialect) + "\"\n");
    const RunResult r =
        run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + dir.path("a.cls") + " --machine " +
                   dir.path("m.toml") + " --gcode " + dir.path("o.nc") + " --method none -q");
    INFO(r.err);
    REQUIRE(r.code == 0);  // the read-back verification passed, arcs included
    const std::string g = read_file(dir.path("o.nc"));
    if (std::string(dialect) == "heidenhain") {
      CHECK(g.find("G02") == std::string::npos);  // chords: I J K are not written there
      CHECK(g.find("G03") == std::string::npos);
      continue;
    }
    // Clockwise about +Z is G2 in G17; clockwise about -Y and about -X are counter-clockwise
    // about +Y and +X: G3 in G18 and G19; the helix: G2 in G17, in 3 blocks of 180 deg.
    CHECK_THAT(g, Catch::Contains("G17 G2 X20"));
    CHECK_THAT(g, Catch::Contains("G18 G3 X40"));
    CHECK_THAT(g, Catch::Contains("G19 G3 X40"));
    if (std::string(dialect) != "linuxcnc") continue;
    std::vector<CanonMove> moves;
    const RunResult rs = run_rs274(dir.path("o.nc"), moves);
    REQUIRE(rs.code == 0);
    std::size_t arcs = 0;
    const double path = path_length(moves, &arcs);
    CHECK(arcs == 1 + 1 + 1 + 3);
    CHECK(path == Approx(expect_mm).epsilon(1e-5));
    // The feed is the programmed one on every arc block.
    for (const auto& m : moves) {
      if (m.arc) CHECK(m.feed_rate == Approx(600.0));
    }
  }
  // Inverse time (G93) or a tilted plane in TCP mode: chords; the path is the same.
  write_file(dir.path("g93.toml"),
             "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
             "max_deg = 120\n[axes.C]\ncontinuous = true\n[gcode]\n"
             "feed_mode = \"inverse-time\"\n");
  const RunResult r93 =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + dir.path("a.cls") + " --machine " +
                 dir.path("g93.toml") + " --gcode " + dir.path("o93.nc") + " --method none -q");
  REQUIRE(r93.code == 0);
  CHECK(read_file(dir.path("o93.nc")).find(" G2 ") == std::string::npos);
  std::vector<CanonMove> moves;
  REQUIRE(run_rs274(dir.path("o93.nc"), moves).code == 0);
  const double path = path_length(moves);
  CHECK(path == Approx(expect_mm).epsilon(1e-4));
}

TEST_CASE("rs274: a 3+2 arc in a tilted plane is G17 in machine mode, chords in TCP mode",
          "[rs274][integration][arcs]") {
  REQUIRE(have_rs274());
  // Tool axis tilted 30 deg about X; the arc lies in the plane normal to it (NX, clockwise).
  const double s = std::sin(deg_to_rad(30.0)), c = std::cos(deg_to_rad(30.0));
  const auto p = [&](double x, double y) {  // a point of the tilted plane through the origin
    return std::to_string(x) + "," + std::to_string(y * c) + "," + std::to_string(y * s);
  };
  const std::string axis = "0," + std::to_string(-s) + "," + std::to_string(c);
  const std::string cl =
      "TOOL PATH/TILT,TOOL,BALL\nTLDATA/MILL,6,3,20,0,0\nFEDRAT/MMPM,600\n"
      "GOTO/" +
      p(0, 10) + "," + axis + "\nGOTO/" + p(10, 10) + "\nCIRCLE/" + p(10, 0) + "," + axis +
      ",10\nGOTO/" + p(20, 0) + "\nGOTO/" + p(20, -10) + "\nEND-OF-PATH\n";
  TempDir dir;
  write_file(dir.path("a.cls"), cl);
  for (const char* mode : {"tcp", "machine"}) {
    INFO(mode);
    write_file(dir.path("m.toml"),
               "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -120\n"
               "max_deg = 120\n[axes.C]\ncontinuous = true\n[pivot]\na_axis_y = 0\n"
               "a_axis_z = 0\nc_axis_x = 0\nc_axis_y = 0\n[gcode]\nmode = \"" +
                   std::string(mode) + "\"\n");
    const RunResult r =
        run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + dir.path("a.cls") + " --machine " +
                   dir.path("m.toml") + " --gcode " + dir.path("o.nc") + " --method none -q");
    INFO(r.err);
    REQUIRE(r.code == 0);
    std::vector<CanonMove> moves;
    REQUIRE(run_rs274(dir.path("o.nc"), moves).code == 0);
    std::size_t arcs = 0;
    path_length(moves, &arcs);
    CHECK(arcs == (std::string(mode) == "machine" ? 1u : 0u));
  }
}

TEST_CASE(
    "rs274: with LinuxCNC's sample xyzac-trt configuration and a 50 mm tool, every TCP move "
    "runs with the tool length offset on and the TCP kinematics switched in",
    "[rs274][integration]") {
  REQUIRE(have_rs274());
  std::mt19937 rng(31);
  const auto hfs = random_heightfields(rng);
  const GeneratedCl g = raster_cl(hfs[1], 3.0, 8.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0);
  TempDir dir;
  write_file(dir.path("in.cls"), g.text);
  const std::string preset =
      std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml";
  const RunResult r = run_taxopt("--in " + dir.path("in.cls") + " --gcode " + dir.path("o.ngc") +
                                 " --method none -q --feed-schedule --machine " + preset);
  INFO(r.err);
  REQUIRE(r.code == 0);
  Rs274Options opt;
  opt.ini = std::string(TAXOPT_SOURCE_DIR) + "/tests/data/linuxcnc/xyzac-trt/xyzac-trt.ini";
  opt.stub_switchkins = true;
  opt.tool_length = 50.0;
  std::vector<CanonMove> points, all;
  const RunResult rs = run_rs274(dir.path("o.ngc"), points, opt, &all);
  INFO(rs.out.substr(rs.out.size() > 600 ? rs.out.size() - 600 : 0));
  REQUIRE(rs.code == 0);
  REQUIRE(points.size() == g.tips_mm.size());  // the sample INI ran the whole program
  for (const CanonMove& m : points) {
    CHECK(m.tool_length == Approx(50.0));
    CHECK(m.kins == 1);
  }
  // The safe retracts run in identity kinematics with no tool length: the spindle goes to
  // the top of Z's travel (its MAX_LIMIT, 120 mm) before the first and after the last move.
  // The set-up switches the TCP kinematics off (M429) whatever the controller started in.
  REQUIRE(all.size() > points.size());
  CHECK(all.front().z == Approx(120.0));
  CHECK(all.front().kins == 0);
  CHECK(all.front().tool_length == 0.0);
  CHECK(all.back().z == Approx(120.0));
  CHECK(all.back().kins == 0);
  CHECK(all.back().tool_length == 0.0);
}

TEST_CASE("machine: the shipped LinuxCNC preset is LinuxCNC's sample xyzac-trt configuration",
          "[cli][machine]") {
  TempDir dir;
  const std::string ini =
      std::string(TAXOPT_SOURCE_DIR) + "/tests/data/linuxcnc/xyzac-trt/xyzac-trt.ini";
  const RunResult r =
      run_taxopt("machine --from-linuxcnc-ini " + ini + " --out " + dir.path("m.toml"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const Machine imported = read_machine_file(dir.path("m.toml"));
  const Machine preset =
      read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-xyzac-trt.toml");
  // The sample's HAL: y-offset 20, z-offset 10, rot points 0; its [AXIS_*] limits.
  CHECK(imported.rotary.tilt_axis_point_mm.isApprox(Vec3d(0, 20, 10)));
  CHECK(imported.rotary.c_axis_point_mm.norm() == 0.0);
  CHECK(rad_to_deg(imported.rotary.tilt.min_rad) == Approx(-100));
  CHECK(rad_to_deg(imported.rotary.tilt.max_rad) == Approx(50));
  CHECK(imported.rotary.tilt.sense == -1);
  CHECK(imported.rotary.c.sense == -1);
  CHECK(imported.limits[static_cast<std::size_t>(Joint::Tilt)].max_velocity_per_s == 30.0);
  CHECK(imported.linear_range[1].min_mm == -100.0);
  CHECK(imported.gcode.program.tcp_on == std::vector<std::string>{"M428"});
  CHECK(imported.gcode.program.retract_z_mm == 120.0);
  // The preset says the same.
  CHECK(preset.rotary.tilt_axis_point_mm == imported.rotary.tilt_axis_point_mm);
  CHECK(preset.rotary.c_axis_point_mm == imported.rotary.c_axis_point_mm);
  CHECK(preset.rotary.tilt.min_rad == imported.rotary.tilt.min_rad);
  CHECK(preset.rotary.tilt.max_rad == imported.rotary.tilt.max_rad);
  CHECK(preset.rotary.c.min_rad == imported.rotary.c.min_rad);
  CHECK(preset.rotary.c.max_rad == imported.rotary.c.max_rad);
  for (std::size_t j = 0; j < kJointCount; ++j) {
    CHECK(preset.limits[j].max_velocity_per_s == imported.limits[j].max_velocity_per_s);
    CHECK(preset.limits[j].max_accel_per_s2 == imported.limits[j].max_accel_per_s2);
  }
  for (std::size_t q = 0; q < 3; ++q) {
    CHECK(preset.linear_range[q].min_mm == imported.linear_range[q].min_mm);
    CHECK(preset.linear_range[q].max_mm == imported.linear_range[q].max_mm);
  }
  CHECK(preset.gcode.program.tcp_on == imported.gcode.program.tcp_on);
  CHECK(preset.gcode.program.tcp_off == imported.gcode.program.tcp_off);
  CHECK(preset.gcode.program.retract_z_mm == imported.gcode.program.retract_z_mm);
  // The sample's joints have their axes' accelerations: no joint limit of their own. With an
  // axis below its joint (the remedy of tcp_joint_limit), the joint's is read too.
  for (std::size_t j = 0; j < kJointCount; ++j) CHECK(imported.joint_max_accel_per_s2[j] == 0.0);
  std::filesystem::copy(std::filesystem::path(ini).parent_path(), dir.path("low"),
                        std::filesystem::copy_options::recursive);
  std::string low = read_file(ini);
  const std::size_t y = low.find("[AXIS_Y]");
  REQUIRE(y != std::string::npos);
  const std::size_t acc = low.find("MAX_ACCELERATION =  300", y);
  REQUIRE(acc != std::string::npos);
  low.replace(acc, 23, "MAX_ACCELERATION = 212.5");
  write_file(dir.path("low/xyzac-trt.ini"), low);
  const RunResult lowered =
      run_taxopt("machine --from-linuxcnc-ini " + dir.path("low/xyzac-trt.ini") + " --out " +
                 dir.path("low.toml"));
  INFO(lowered.err);
  REQUIRE(lowered.code == 0);
  const Machine l = read_machine_file(dir.path("low.toml"));
  CHECK(l.limits[1].max_accel_per_s2 == 212.5);
  CHECK(l.joint_max_accel_per_s2[1] == 300.0);
  CHECK(l.joint_max_accel_per_s2[0] == 0.0);
  CHECK(joint_accel_limit(l, effective_limits(l), 1) == 300.0);
  // ANGULAR_UNITS (issue 63.9): the rotary axes' numbers in grad (by name, and as units per
  // degree), converted; an unknown unit refused naming its line.
  for (const std::string unit : {"grad", "1.111111"}) {
    INFO(unit);
    std::string text = read_file(ini);
    text.replace(text.find("ANGULAR_UNITS = deg"), 19, "ANGULAR_UNITS = " + unit);
    write_file(dir.path("low/xyzac-trt.ini"), text);
    const RunResult g = run_taxopt("machine --from-linuxcnc-ini " + dir.path("low/xyzac-trt.ini") +
                                   " --out " + dir.path("g.toml"));
    INFO(g.err);
    REQUIRE(g.code == 0);
    const Machine m = read_machine_file(dir.path("g.toml"));
    CHECK(rad_to_deg(m.rotary.tilt.min_rad) == Approx(-90.0));
    CHECK(rad_to_deg(m.rotary.tilt.max_rad) == Approx(45.0));
    CHECK(m.limits[static_cast<std::size_t>(Joint::Tilt)].max_velocity_per_s == Approx(27.0));
  }
  {
    std::string text = read_file(ini);
    text.replace(text.find("ANGULAR_UNITS = deg"), 19, "ANGULAR_UNITS = turns");
    write_file(dir.path("low/xyzac-trt.ini"), text);
    const RunResult g = run_taxopt("machine --from-linuxcnc-ini " + dir.path("low/xyzac-trt.ini"));
    CHECK(g.code == 2);
    CHECK_THAT(g.err, Catch::Contains("xyzac-trt.ini:85") && Catch::Contains("ANGULAR_UNITS"));
  }
  // Another kinematics is refused by name and line.
  write_file(dir.path("other.ini"), "[KINS]\nKINEMATICS = genhexkins\n");
  const RunResult other = run_taxopt("machine --from-linuxcnc-ini " + dir.path("other.ini"));
  CHECK(other.code == 2);
  CHECK_THAT(other.err, Catch::Contains("other.ini:2") && Catch::Contains("xyzbc-trt-kins") &&
                            Catch::Contains("5axiskins"));
}

TEST_CASE(
    "machine: LinuxCNC's sample xyzbc-trt configuration imports as the B/C sample preset, "
    "B's range its joint's",
    "[cli][machine][bc]") {
  TempDir dir;
  const std::string ini =
      std::string(TAXOPT_SOURCE_DIR) + "/tests/data/linuxcnc/xyzbc-trt/xyzbc-trt.ini";
  const RunResult r =
      run_taxopt("machine --from-linuxcnc-ini " + ini + " --out " + dir.path("m.toml"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const Machine imported = read_machine_file(dir.path("m.toml"));
  const Machine preset = read_machine_file(std::string(TAXOPT_SOURCE_DIR) +
                                           "/data/machines/linuxcnc-xyzbc-trt-sample.toml");
  CHECK(imported.rotary.tilt_about == TiltAxis::Y);
  // trtfuncs.c: joints = Rot(Y, B)(Rot(Z, C)(p - rot) - d) + d + rot, d = (x-offset 0 z-offset)
  // with the sample's x-offset -20, z-offset -15: the B axis through (-20, 0, -15).
  CHECK(imported.rotary.tilt_axis_point_mm.isApprox(Vec3d(-20, 0, -15)));
  CHECK(imported.rotary.tilt.sense == -1);
  CHECK(imported.rotary.c.sense == -1);
  // [AXIS_B] gives +-36000, joint 3 (B in COORDINATES = XYZBC) -100 .. 50.
  CHECK(rad_to_deg(imported.rotary.tilt.min_rad) == Approx(-100));
  CHECK(rad_to_deg(imported.rotary.tilt.max_rad) == Approx(50));
  CHECK(imported.gcode.program.tcp_on == std::vector<std::string>{"M428"});
  // The machine-mode convention reproduces trtfuncs.c's inverse kinematics (written out here
  // from its formula) at a few poses.
  for (const double b_deg : {-70.0, -10.0, 35.0}) {
    for (const double c_deg : {-120.0, 0.0, 77.0}) {
      const Vec3d p(12.0, -7.0, 4.0);
      const double b = deg_to_rad(b_deg), c = deg_to_rad(c_deg), dx = -20.0, dz = -15.0;
      const Vec3d lcnc(std::cos(c) * std::cos(b) * p.x() - std::sin(c) * std::cos(b) * p.y() +
                           std::sin(b) * p.z() - std::cos(b) * dx - std::sin(b) * dz + dx,
                       std::sin(c) * p.x() + std::cos(c) * p.y(),
                       -std::cos(c) * std::sin(b) * p.x() + std::sin(c) * std::sin(b) * p.y() +
                           std::cos(b) * p.z() + std::sin(b) * dx - std::cos(b) * dz + dz);
      // Written B and C are the machine's values: the pose holds them (sense on the axes).
      const Vec3d ours = imported.rotary.to_machine_mm(p, Posed{b, c});
      CHECK((ours - lcnc).norm() < 1e-9);
    }
  }
  CHECK(preset.rotary.tilt_axis_point_mm == imported.rotary.tilt_axis_point_mm);
  CHECK(preset.rotary.tilt.min_rad == imported.rotary.tilt.min_rad);
  CHECK(preset.rotary.tilt.max_rad == imported.rotary.tilt.max_rad);
  CHECK(preset.rotary.tilt.sense == imported.rotary.tilt.sense);
  CHECK(preset.rotary.c.sense == imported.rotary.c.sense);
  for (std::size_t j = 0; j < kJointCount; ++j) {
    CHECK(preset.limits[j].max_velocity_per_s == imported.limits[j].max_velocity_per_s);
    CHECK(preset.limits[j].max_accel_per_s2 == imported.limits[j].max_accel_per_s2);
  }
}

TEST_CASE(
    "rs274: the demo in machine mode with its part: linearisation keeps the tip on the path, "
    "no move between points hits the part",
    "[rs274][integration][slow]") {
  REQUIRE(have_rs274());
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  TempDir dir;
  const std::string machine = read_file(d + "machines/paper-ac.toml");
  // The paper's machine has its rotary axes through the origin: said explicitly.
  const std::string pivot = "[pivot]\na_axis_y = 0\na_axis_z = 0\nc_axis_x = 0\nc_axis_y = 0\n";
  write_file(dir.path("m.toml"), machine + "mode = \"machine\"\n" + pivot);
  write_file(dir.path("m0.toml"),
             machine + "mode = \"machine\"\nlinearise_tolerance_mm = 0\n" + pivot);
  const std::string args = "--in " + d + "demo/sine.cls --part " + d +
                           "demo/sine.stl --gauge-length 15 -q --report " + dir.path("r.json");
  const RunResult r =
      run_taxopt(args + " --machine " + dir.path("m.toml") + " --gcode " + dir.path("o.ngc"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto rep = nlohmann::json::parse(read_file(dir.path("r.json")));
  const std::size_t blocks = rep["gcode"]["linearised_blocks"];
  CHECK(blocks > 0);
  for (const auto& op : rep["operations"]) {
    CHECK(op["verification"]["colliding_moves"] == 0);
    CHECK(op["verification"]["collision_free"] == true);
    CHECK(op["verification"]["tool_length_active"] == true);
  }
  // rs274 runs every block: the points and the blocks between them.
  std::vector<CanonMove> moves;
  REQUIRE(run_rs274(dir.path("o.ngc"), moves).code == 0);
  std::size_t points = 0;
  for (const auto& op : rep["operations"]) points += op["points"].get<std::size_t>();
  CHECK(moves.size() <= points + blocks);
  CHECK(moves.size() + 10 >= points + blocks);  // points that repeat the last block are not written
  // The input's axes (C flips through the pole): linearised, no move hits the part; without
  // linearisation the joints' straight lines swing the tool into it.
  const RunResult lin = run_taxopt(args + " --method none --machine " + dir.path("m.toml") +
                                   " --gcode " + dir.path("n.ngc"));
  INFO(lin.err);
  CHECK(lin.code == 0);
  const RunResult bare = run_taxopt(args + " --method none --machine " + dir.path("m0.toml") +
                                    " --gcode " + dir.path("o0.ngc"));
  CHECK(bare.code == 1);
  CHECK_THAT(bare.err, Catch::Contains("between CL points"));
}
