// Forms real CAM systems write that a reader meets (issue 62), each reproduced in a file of our
// own: Pro/CLfile's GOTO of several points (its full circle as three arcs), its 4-axis MULTAX
// file, NX's MSYS with Z pointing down, a tool 0 with a length register, CATIA's turning files.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"

using namespace taxopt;
using taxopt::test::read_file;
using taxopt::test::run_taxopt;
using taxopt::test::TempDir;
using taxopt::test::write_file;

namespace {

/// Creo's full circle (gg.ncl's form, our numbers): a CIRCLE about (10, 0, -1), radius 5,
/// axis +Z, then one GOTO whose further points stand on lines of their own, no `$`: from
/// (5, 0) round to 300, 60 and back to 180 deg.
std::string creo_circle() {
  return "$$*          Pro/CLfile  Version 18.0 - 9731\n"
         "UNITS / MM\n"
         "LOADTL / 4\n"
         "SPINDL / RPM, 2000.000000,  CLW\n"
         "RAPID \n"
         "GOTO / 5.0000, 0.0000, 10.0000\n"
         "FEDRAT / 100.000000,  MMPM\n"
         "GOTO / 5.0000, 0.0000, -1.0000\n"
         "CIRCLE / 10.0000, 0.0000, -1.0000,  $\n"
         "0.0000, 0.0000, 1.0000,  5.0000\n"
         "GOTO / 12.5000, -4.3301, -1.0000\n"
         "       12.5000, 4.3301, -1.0000\n"
         "       5.0000, 0.0000, -1.0000\n"
         "RAPID \n"
         "GOTO / 5.0000, 0.0000, 10.0000\n"
         "FINI \n";
}

double angle_about(const Vec3d& p, const Vec3d& centre) {
  return std::atan2(p.y() - centre.y(), p.x() - centre.x());
}

}  // namespace

TEST_CASE("cl Pro/CLfile: a GOTO's points on lines of their own, after a CIRCLE each an arc on it",
          "[io][cl][creo]") {
  const Toolpath tp = parse_cl(creo_circle(), "gg.ncl");
  REQUIRE(tp.operations.size() == 1);
  const Operationd& op = tp.operations[0];
  CHECK(op.arcs.size() == 3);
  // From the plunge's end to the circle's close: every point on the circle, counter-clockwise
  // (Creo's sense) all the way round, once.
  const Vec3d centre(10.0, 0.0, -1.0);
  std::size_t first = 0;
  while (first < op.points.size() && op.points[first].tip_mm.z() > -0.5) ++first;
  REQUIRE(first < op.points.size());
  double turned = 0.0;
  std::size_t on_circle = 0;
  for (std::size_t i = first; i < op.points.size() && op.points[i].tip_mm.z() < -0.5; ++i) {
    CHECK(std::abs((op.points[i].tip_mm - centre).norm() - 5.0) < 1e-3);
    if (i > first) {
      const double step = std::remainder(
          angle_about(op.points[i].tip_mm, centre) - angle_about(op.points[i - 1].tip_mm, centre),
          2.0 * M_PI);
      CHECK(step > 0.0);
      turned += step;
    }
    ++on_circle;
  }
  CHECK(on_circle > 12);
  CHECK(turned == Approx(2.0 * M_PI).margin(1e-3));
  // Written back unchanged, the file is the same bytes.
  CHECK(format_cl(tp, tp.operations) == creo_circle());
}

TEST_CASE("cl Pro/CLfile: continuation points with no CIRCLE are straight moves, in order",
          "[io][cl][creo]") {
  const Toolpath tp = parse_cl(
      "$$*          Pro/CLfile  Vers 1.0\nFEDRAT / 100, MMPM\nSPINDL / RPM, 2000, CLW\n"
      "GOTO / 0, 0, 0\n  1, 0, 0\n  1, 2, 0\n  $$ a comment between\n  1, 2, 3\n"
      "GOTO / 4, 2, 3\n",
      "p.ncl");
  const auto& pts = tp.operations.at(0).points;
  REQUIRE(pts.size() == 5);
  CHECK((pts[1].tip_mm - Vec3d(1, 0, 0)).norm() < 1e-12);
  CHECK((pts[2].tip_mm - Vec3d(1, 2, 0)).norm() < 1e-12);
  CHECK((pts[3].tip_mm - Vec3d(1, 2, 3)).norm() < 1e-12);
  CHECK(tp.operations[0].arcs.empty());
  // Only after a GOTO: a line of numbers after another record is no record.
  CHECK_THAT(test::input_error_of(
                 [] { parse_cl("GOTO / 0, 0, 0\nFEDRAT / 100, MMPM\n  1, 0, 0\n", "q.ncl"); }),
             Catch::Contains("q.ncl:3: not a CL record"));
  // Nor a line of two numbers, or of words.
  CHECK_THAT(test::input_error_of([] { parse_cl("GOTO / 0, 0, 0\n  1, 0\n", "q.ncl"); }),
             Catch::Contains("q.ncl:2: not a CL record"));
}

TEST_CASE(
    "cl Pro/CLfile 4-axis MULTAX: four-digit axes and a FROM continued by $ post on A/C "
    "and B/C, the rotary axes where the file's axes point",
    "[io][cl][creo][cli]") {
  // 4x_conv.ncl's form (usnistgov/engineering-design-models, our numbers): tool axes in the YZ
  // plane written to four digits (length 1 +- 5e-5), TLAXIS and MULTAX/OFF after the last move.
  std::ostringstream cl;
  cl << "$$*          Pro/CLfile  Vers 1.0\nPARTNO CORE_WORK\nMACHIN / MILL, M0001\n"
        "UNITS / INCHES\nLOADTL / 3\n$$-> CUTTER / 0.500000\nMULTAX / ON\n"
        "SPINDL / RPM, 2000.000000,  CLW\nFROM / 0.0000, 0.0000, 3.7750,  $\n"
        "0.0000, -0.7675, 0.6410\nRAPID \nGOTO / 1.0000, 1.0000, 3.0000,  $\n"
        "0.0000, -0.7675, 0.6410\nFEDRAT / 30.000000,  IPM\n";
  // The leans as written (the rapids' too: the descent runs on the first axis), deg.
  const auto lean_deg = [](double j, double k) {
    return std::atan2(std::abs(j), k) * 180.0 / M_PI;
  };
  std::vector<double> tilt_deg = {lean_deg(-0.7675, 0.6410), lean_deg(0.2588, 0.9659)};
  for (int k = 0; k <= 12; ++k) {
    const double t = (-50.0 + 5.0 * k) * M_PI / 180.0;  // the tool leaning about X
    const double j = std::round(std::sin(t) * 1e4) / 1e4, kk = std::round(std::cos(t) * 1e4) / 1e4;
    char buf[160];
    std::snprintf(buf, sizeof buf, "GOTO / 1.0000, %.4f, %.4f,  $\n0.0000, %.4f, %.4f\n",
                  1.0 + 0.1 * k, 1.0 + 0.02 * k, j, kk);
    cl << buf;
    tilt_deg.push_back(lean_deg(j, kk));
  }
  cl << "RAPID \nGOTO / 1.0000, 3.0000, 3.7750,  $\n0.0000, 0.2588, 0.9659\n"
        "TLAXIS / 0.0000, 0.0000, 1.0000\nMULTAX / OFF\nSPINDL / OFF\n$$-> END / \nFINI \n";
  TempDir t;
  write_file(t.path("4x.ncl"), cl.str());
  for (const auto& [machine, letter] :
       {std::pair<std::string, char>{"", 'A'}, {"haas-umc750.toml", 'B'}}) {
    INFO(machine);
    const std::string m = machine.empty() ? ""
                                          : " --machine " + std::string(TAXOPT_SOURCE_DIR) +
                                                "/data/machines/" + machine;
    const auto r =
        run_taxopt("--in " + t.path("4x.ncl") + " --gcode " + t.path("o.nc") + m + " -q");
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::string text = read_file(t.path("o.nc"));
    const auto moves = read_gcode_moves(
        text, "o.nc", machine.empty() ? GcodeDialect::LinuxCNC : GcodeDialect::Haas, {}, letter);
    // Each feed move's tilt is the file's lean (the axis as written, 4 digits), within the
    // words' rounding.
    std::size_t feeds = 0;
    for (const GcodeMove& mv : moves) {
      if (mv.rapid || mv.positioning || mv.feed <= 0.0) continue;
      const double lean = std::abs(mv.tilt_deg);
      double nearest = 1e9;
      for (double want : tilt_deg) nearest = std::min(nearest, std::abs(lean - want));
      CHECK(nearest < 0.01);
      ++feeds;
    }
    CHECK(feeds >= 13);
  }
}

TEST_CASE(
    "cl NX MSYS with Z pointing down: the unreachable axis's error names --msys apply, "
    "with which the file posts",
    "[io][cl][msys][cli]") {
  // ust_a.cls's form (HumMan/CLSFProcessor, our numbers): the MCS's x along +Y and y along +X,
  // so its z points down, and every axis written (0, 0, -1): straight up in that frame.
  std::ostringstream cl;
  cl << "TOOL PATH/VARIABLE_CONTOUR,TOOL,BALL6\nTLDATA/MILL,6.0000,3.0000,40.0000,0.0000,0.0000\n"
        "MSYS/10.0,20.0,100.0,0.0000000,1.0000000,0.0000000,1.0000000,0.0000000,0.0000000\n"
        "LOAD/TOOL,2,ADJUST,2\nSPINDL/RPM,8000,CLW\nRAPID\n"
        "GOTO/0.0000,22.0000,-40.0000,0.0000000,0.0000000,-1.0000000\nFEDRAT/MMPM,250.0000\n";
  for (int k = 0; k <= 10; ++k) cl << "GOTO/" << k << ".0000,22.0000,-20.0000\n";
  cl << "RAPID\nGOTO/10.0000,22.0000,-40.0000\nEND-OF-PATH\n";
  TempDir t;
  write_file(t.path("ust.cls"), cl.str());
  const std::string args = "--in " + t.path("ust.cls") + " --gcode " + t.path("o.nc") + " -q";
  const auto as_written = run_taxopt(args);
  CHECK(as_written.code == 1);
  CHECK_THAT(as_written.err, Catch::Contains("ust.cls:7:") && Catch::Contains("--msys apply") &&
                                 Catch::Contains("line 3"));
  const auto applied = run_taxopt(args + " --msys apply");
  INFO(applied.err);
  CHECK(applied.code == 0);
  // A file whose axes no frame makes reachable says nothing of the option.
  const std::string flat =
      test::replaced_once(cl.str(), "0.0000000,1.0000000,0.0000000,1.0000000,0.0000000,0.0000000",
                          "1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000");
  write_file(t.path("flat.cls"), flat);
  const auto no_frame = run_taxopt("--in " + t.path("flat.cls") + " --gcode " + t.path("o.nc"));
  CHECK(no_frame.code == 1);
  for (const std::string& line : test::lines_of(no_frame.err)) {
    if (line.rfind("taxopt: error:", 0) == 0) CHECK_THAT(line, !Catch::Contains("--msys apply"));
  }
}

TEST_CASE("cl tool 0 with a length register names the tool, turning files name turning",
          "[io][cl][bad-input]") {
  // NX's LOAD/TOOL,0,ADJUST,1 (userFour/MECH491-postprocessor's Zig_Zag): tool 0 is no tool.
  const std::string zero = test::input_error_of(
      [] { parse_cl("TOOL PATH/F,TOOL,T\nLOAD/TOOL,0,ADJUST,1\nGOTO/0,0,0\n", "z.cls"); });
  CHECK_THAT(zero, Catch::Contains("z.cls:2: ") && Catch::Contains("tool 0 is no tool number") &&
                       !Catch::Contains("its own register in the CAM"));
  // CATIA V5 turning (karlo-c277/CATIAV5-Post-Processor-): the tool's TURN, or a TURRET after
  // an ICAM PPFUN no reader knows, name turning wherever they stand.
  const std::string catia = "$$     CATIA APT VERSION 1.0\n$$*CATIA0\nPARTNO P\n";
  CHECK_THAT(test::input_error_of([&] {
               parse_cl(catia +
                            "CUTTER/    0.800000\nTOOLNO/1,TURN,1,0,3,    0.400000,$\n"
                            "    0.000000,    0.000000,    0.100000,MMPR\nLOADTL/1,1,1\n"
                            "GOTO  /   17.00000,    0.00000,    2.00000\n",
                        "d1.aptsource");
             }),
             Catch::Contains("d1.aptsource:5: TOOLNO/1,TURN,...: a turning file"));
  CHECK_THAT(test::input_error_of([&] {
               parse_cl(catia +
                            "PPFUN/15,1318046,OFF\nTURRET/1,OSETNO,1,SETOOL,0,0,0\n"
                            "GOTO  /   17.00000,    0.00000,    2.00000\n",
                        "d3.aptsource");
             }),
             Catch::Contains("d3.aptsource:5: TURRET/1,...: a turning file"));
  CHECK_THAT(test::input_error_of([&] { parse_cl("MACHIN/LATHE,1\nGOTO/0,0,0\n", "m.cls"); }),
             Catch::Contains("m.cls:1: MACHIN/LATHE,...: a turning file"));
}

namespace {

/// Two straight moves and a counter-clockwise arc between them about (0, 0, 0), radius 10,
/// from `from_deg` through `sweep_deg`; each move meets the arc `kink_deg` off the clockwise
/// tangent (a boss's outline met by a pocket's passes) or, with `lead` true, along the
/// counter-clockwise one (a lead-in).
std::string arc_between(double from_deg, double sweep_deg, double kink_deg, bool lead) {
  const double d = M_PI / 180.0;
  const auto at = [&](double deg) {
    return Vec3d(10 * std::cos(deg * d), 10 * std::sin(deg * d), 0);
  };
  const auto ccw_tangent = [&](double deg) {
    return Vec3d(-std::sin(deg * d), std::cos(deg * d), 0);
  };
  const auto turned = [&](const Vec3d& v, double deg) {
    return Vec3d(std::cos(deg * d) * v.x() - std::sin(deg * d) * v.y(),
                 std::sin(deg * d) * v.x() + std::cos(deg * d) * v.y(), 0);
  };
  const Vec3d s = at(from_deg), e = at(from_deg + sweep_deg);
  const Vec3d in = lead ? ccw_tangent(from_deg) : turned(-ccw_tangent(from_deg), kink_deg);
  const Vec3d out = lead ? ccw_tangent(from_deg + sweep_deg)
                         : turned(-ccw_tangent(from_deg + sweep_deg), -kink_deg);
  const Vec3d before = s - 8.0 * in, after = e + 8.0 * out;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "GOTO / %.6f, %.6f, 0\nGOTO / %.6f, %.6f, 0\nCIRCLE / 0, 0, 0, 0, 0, 1, 10\n"
                "GOTO / %.6f, %.6f, 0\nGOTO / %.6f, %.6f, 0\n",
                before.x(), before.y(), s.x(), s.y(), e.x(), e.y(), after.x(), after.y());
  return buf;
}

}  // namespace

TEST_CASE(
    "cl arcs: a corner is no evidence of an arc's sense, and an option against arcs "
    "tangent at both ends names each",
    "[io][cl][arcs]") {
  // SOLIDWORKS CAM's boss outline (Teste-Metrologia.apt's form, our numbers): short arcs whose
  // straight moves meet them 12.6 deg off the clockwise tangent. They decide nothing: the
  // documented counter-clockwise sense holds and each arc is the short one.
  const std::string header = "$$*          Pro/CLfile  Version 18.0\nFEDRAT / 100, MMPM\n";
  const Toolpath boss =
      parse_cl(header + arc_between(90, 65, 12.6, false) + arc_between(200, 65, 12.6, false) +
                   arc_between(300, 40, 25.0, false),
               "boss.ncl");
  CHECK(boss.reading.arcs == 3);
  CHECK(boss.reading.arcs_decidable == 0);
  CHECK(boss.reading.arc_convention == ArcDirection::CounterClockwise);
  double swept = 0.0;
  for (const ArcRun& run : boss.operations.at(0).arcs) swept += run.sweep_rad;
  CHECK(swept * 180.0 / M_PI == Approx(65 + 65 + 40).margin(1e-3));
  // A lead-in tangent at both ends only counter-clockwise: --arc-direction cw is applied as
  // asked, and the notice names its line.
  ClReadOptions cw;
  cw.arc_direction = ArcDirection::Clockwise;
  const Toolpath lead = parse_cl(
      header + arc_between(90, 45, 0, true) + arc_between(200, 65, 12.6, false), "l.ncl", cw);
  std::string notices;
  for (const std::string& n : lead.notices) notices += n + "\n";
  CHECK_THAT(notices,
             Catch::Contains("1 of them are tangent at both ends only counter-clockwise") &&
                 Catch::Contains("lines 5;"));
  CHECK(lead.operations.at(0).arcs.at(0).sweep_rad * 180.0 / M_PI == Approx(315).margin(1e-3));
}
