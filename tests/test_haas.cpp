// A B/C table-table machine (the Haas UMC-750) beside the A/C: the kinematics' properties for
// both tilt axes, and taxopt's output for a real NX 5-axis file against what the production NX
// post for that machine wrote for the same operation; rs274 reads the same program written for
// a LinuxCNC B/C machine.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <regex>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// X Y Z B C of every position of a Fanuc-style program from its first block matching
/// `start` until a G53 or G49 block after positions were seen: words modal, comments removed.
struct Position {
  double x, y, z, b, c;
};
std::vector<Position> positions(const std::string& text, const std::string& start) {
  std::vector<Position> out;
  Position p{0, 0, 0, 0, 0};
  bool on = false;
  std::istringstream in(text);
  std::string line;
  const std::regex comment("\\(.*?\\)"), word("([XYZBC])(-?[0-9]*\\.?[0-9]*)");
  while (std::getline(in, line)) {
    line = std::regex_replace(line, comment, "");
    if (line.find(start) != std::string::npos) on = true;
    if (!on) continue;
    if (line.find("G53") != std::string::npos || line.find("G49") != std::string::npos) {
      if (!out.empty()) break;
      continue;
    }
    bool moves = false;
    for (std::sregex_iterator it(line.begin(), line.end(), word), end; it != end; ++it) {
      const double v = std::stod((*it)[2].str());
      switch ((*it)[1].str()[0]) {
        case 'X': p.x = v, moves = true; break;
        case 'Y': p.y = v, moves = true; break;
        case 'Z': p.z = v, moves = true; break;
        case 'B': p.b = v; break;
        case 'C': p.c = v; break;
      }
    }
    if (moves) out.push_back(p);
  }
  return out;
}

MachineKinematicsd machine_with(TiltAxis tilt) {
  MachineKinematicsd m = default_machine_kinematics();
  m.tilt_about = tilt;
  m.tilt_axis_point_mm = tilt == TiltAxis::X ? Vec3d(0.0, 12.5, -80.0) : Vec3d(7.5, 0.0, -60.0);
  m.c_axis_point_mm = Vec3d(4.0, -3.0, 0.0);
  return m;
}

}  // namespace

TEST_CASE(
    "table-table kinematics, A/C and B/C: both inverse branches give the axis back, the "
    "spindle is the machine's +Z, and B/C is A/C turned a quarter about C",
    "[kinematics][bc]") {
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (TiltAxis tilt : {TiltAxis::X, TiltAxis::Y}) {
    const MachineKinematicsd m = machine_with(tilt);
    INFO("tilt axis " << m.tilt_letter());
    int checked = 0;
    for (int trial = 0; trial < 500; ++trial) {
      const Vec3d v = Vec3d(u(rng), u(rng), u(rng)).normalized();
      if (!v.allFinite()) continue;
      const auto both = m.inverse(v);
      CHECK(both[0].tilt_rad >= 0.0);
      CHECK(both[1].tilt_rad <= 0.0);
      for (const Posed& p : both) {
        CHECK((m.forward(p) - v).norm() < 1e-12);
        // The tool axis, carried into the machine's frame with the part, is the spindle: +Z.
        const Vec3d q(u(rng) * 50.0, u(rng) * 50.0, u(rng) * 50.0);
        const Vec3d spindle = m.to_machine_mm(q + v, p) - m.to_machine_mm(q, p);
        CHECK((spindle - Vec3d::UnitZ()).norm() < 1e-12);
        // Machine mode round trip.
        CHECK((m.from_machine_mm(m.to_machine_mm(q, p), p) - q).norm() < 1e-9);
      }
      // The mirror pose (-T, C + 180 deg) is the same axis.
      const Posed mirror{-both[0].tilt_rad, both[0].c_rad + Constants<double>::pi()};
      CHECK((m.forward(mirror) - v).norm() < 1e-12);
      ++checked;
    }
    CHECK(checked > 400);
    // The pole: every C gives the same axis, and the inverse puts A (or B) = 0.
    const auto pole = m.inverse(Vec3d::UnitZ());
    CHECK(pole[0].tilt_rad == 0.0);
    CHECK(m.at_pole(m.forward(Posed{0.0, 1.234})));
  }
  // B/C at (t, c) is A/C at (t, c + 90 deg).
  const MachineKinematicsd ac = machine_with(TiltAxis::X), bc = machine_with(TiltAxis::Y);
  for (int trial = 0; trial < 100; ++trial) {
    const Posed p{u(rng) * 2.0, u(rng) * 3.0};
    CHECK((bc.forward(p) - ac.forward(Posed{p.tilt_rad, p.c_rad + Constants<double>::pi() / 2}))
              .norm() < 1e-12);
  }
}

TEST_CASE("machine file: bc-table-table takes [axes.B] and the B pivot, refuses an A axis",
          "[machine][bc][bad-input]") {
  const Machine m = parse_machine_toml(
      "kinematics = \"bc-table-table\"\n[axes.B]\nmin_deg = -35\nmax_deg = 120\n"
      "max_velocity_deg_s = 100\n[axes.C]\ncontinuous = true\n[pivot]\nb_axis_x = 1.5\n"
      "b_axis_z = -40\nc_axis_x = 2\nc_axis_y = 3\n[gcode]\ndialect = \"haas\"\n",
      "m.toml");
  CHECK(m.rotary.tilt_about == TiltAxis::Y);
  CHECK(m.rotary.tilt_letter() == 'B');
  CHECK(m.rotary.tilt.min_rad == Approx(deg_to_rad(-35.0)));
  CHECK(m.rotary.tilt_axis_point_mm.x() == 1.5);
  CHECK(m.rotary.tilt_axis_point_mm.z() == -40.0);
  CHECK(m.limits[static_cast<std::size_t>(Joint::Tilt)].max_velocity_per_s == 100.0);
  CHECK(m.gcode.dialect == GcodeDialect::Haas);
  CHECK_THROWS_AS(parse_machine_toml("kinematics = \"bc-table-table\"\n[axes.A]\nmin_deg = -35\n"
                                     "max_deg = 120\n[axes.C]\ncontinuous = true\n",
                                     "m.toml"),
                  InputError);
  CHECK_THROWS_AS(parse_machine_toml("kinematics = \"bc-table-table\"\n[axes.B]\nmin_deg = -35\n"
                                     "max_deg = 120\n[axes.C]\ncontinuous = true\n[pivot]\n"
                                     "a_axis_y = 1\n",
                                     "m.toml"),
                  InputError);
  CHECK_THROWS_WITH(parse_machine_toml("kinematics = \"xyz-head\"\n", "m.toml"),
                    Catch::Contains("bc-table-table"));
}

TEST_CASE(
    "haas: on a real NX file, --method none writes the B and C of the production NX post "
    "for the Haas UMC-750, and its positions",
    "[bc][haas][real]") {
  TempDir dir;
  const std::string cls =
      std::string(TAXOPT_TEST_DATA) + "/real/mech491-variable-axis-ballmill.cls";
  const std::vector<Position> post = positions(
      read_file(std::string(TAXOPT_TEST_DATA) + "/real-post/mech491-variable-axis-haas-umc750.nc"),
      "N70 ");
  REQUIRE(post.size() == 348);  // one per GOTO
  // The post writes the GOTOs as they are in the listing (the MCS's own coordinates): so does
  // taxopt by default, though the file says MSYS/3,3,0,... (tests/data/real/SOURCES.md).
  const RunResult r = run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + cls + " --machine " +
                                 std::string(TAXOPT_SOURCE_DIR) +
                                 "/data/machines/haas-umc750.toml --method none "
                                 "--gcode " +
                                 dir.path("o.nc") + " -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string ours_text = read_file(dir.path("o.nc"));
  CHECK(ours_text.find("G234 H1") != std::string::npos);  // TCPC, with the tool's offset
  // Our own reader of the Haas dialect reads it (B is the tilt axis, A is refused).
  CHECK(read_gcode_moves(ours_text, "o.nc", GcodeDialect::Haas, {}, 'B').size() >= 348);
  CHECK_THROWS_AS(read_gcode_moves(ours_text, "o.nc", GcodeDialect::Haas, {}, 'A'), InputError);
  std::vector<Position> ours = positions(ours_text, "G234");
  // taxopt's first block after the retract is a complete positioning (X, Y and Z) at the
  // clearance height above the first point on its tool axis, then along the axis (as CAM
  // links an approach); the post's first block goes to the first point itself. The
  // positioning block is ours.
  REQUIRE(ours.size() == post.size() + 1);
  const double tilt_rad = std::abs(ours[1].b) * M_PI / 180.0;
  CHECK(std::hypot(ours[0].x - ours[1].x, ours[0].y - ours[1].y) ==
        Approx((ours[0].z - ours[1].z) * std::tan(tilt_rad)).margin(3e-4));
  CHECK(ours[0].z >= ours[1].z);
  ours.erase(ours.begin(), ours.begin() + 1);
  REQUIRE(ours.size() == post.size());
  double worst_b = 0.0, worst_c = 0.0, worst_xyz = 0.0;
  int branch = 0, moving = 0;
  for (std::size_t i = 0; i < post.size(); ++i) {
    worst_b = std::max(worst_b, std::abs(ours[i].b - post[i].b));
    // C as the post winds it, not modulo a turn (tests/test_program.cpp: half-turn ties turned the
    // post's way).
    worst_c = std::max(worst_c, std::abs(ours[i].c - post[i].c));
    worst_xyz = std::max({worst_xyz, std::abs(ours[i].x - post[i].x),
                          std::abs(ours[i].y - post[i].y), std::abs(ours[i].z - post[i].z)});
    branch += (ours[i].b > 0.0) != (post[i].b > 0.0);
    if (i > 0 && std::abs(post[i].c - post[i - 1].c) > 10.0) ++moving;
  }
  INFO("B within " << worst_b << ", C within " << worst_c << ", XYZ within " << worst_xyz
                   << ", branch differs at " << branch << " points");
  // The post writes 3 decimals of a degree, taxopt 4: half a unit of the third is the rounding.
  CHECK(worst_b <= 0.0006);
  CHECK(worst_c <= 0.0008);
  CHECK(worst_xyz <= 0.00011);
  CHECK(branch == 0);
  CHECK(moving > 10);  // the file does pass near the pole: C swings, and both agree
}

TEST_CASE(
    "haas: the B/C program written for LinuxCNC is read by rs274 with the same B and C, "
    "and every method runs on the B/C machine",
    "[bc][rs274][integration]") {
  REQUIRE(have_rs274());
  TempDir dir;
  const std::string cls =
      std::string(TAXOPT_TEST_DATA) + "/real/mech491-variable-axis-ballmill.cls";
  const std::string machines = std::string(TAXOPT_SOURCE_DIR) + "/data/machines/";
  const RunResult r =
      run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + cls + " --machine " + machines +
                 "linuxcnc-xyzbc-trt.toml --method none --gcode " + dir.path("o.ngc") + " -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  std::vector<CanonMove> moves;
  const RunResult rs = run_rs274(dir.path("o.ngc"), moves);
  INFO(rs.err);
  REQUIRE(rs.code == 0);
  const auto ours =
      read_gcode_moves(read_file(dir.path("o.ngc")), "o.ngc", GcodeDialect::LinuxCNC, {}, 'B');
  std::vector<GcodeMove> points;
  for (const GcodeMove& g : ours) {
    if (!g.positioning) points.push_back(g);
  }
  REQUIRE(moves.size() == points.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < moves.size(); ++i) {
    CHECK(moves[i].a == 0.0);  // no A axis on this machine: rs274's A stays put
    worst = std::max(
        {worst, std::abs(moves[i].b - points[i].tilt_deg), std::abs(moves[i].c - points[i].c_deg)});
  }
  CHECK(worst < 1e-4);
  // The optimisers, the schedule and the checks work on the B/C machine as on the A/C.
  for (const char* method : {"paper", "global", "global --objective time"}) {
    INFO(method);
    const RunResult m =
        run_taxopt("--tool-number 1 --spindle-rpm 6000 --in " + cls + " --machine " + machines +
                   "haas-umc750.toml --method " + method + " --max-deviation 5 --gcode " +
                   dir.path("m.nc") + " --report " + dir.path("m.json") + " -q");
    INFO(m.err);
    CHECK(m.code == 0);
    const std::string report = read_file(dir.path("m.json"));
    CHECK(report.find("\"B\"") != std::string::npos);  // the axis limits name B
    CHECK(report.find("\"kinematics\": \"bc-table-table\"") != std::string::npos);
  }
}
