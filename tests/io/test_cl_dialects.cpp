// What each CAM system's motion records mean (docs/cl-files.md): arc sense per dialect and its
// self-check, NX splines, MSYS frames, feed words, drilling cycles, refused motion words.
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"

using namespace taxopt;
using taxopt::test::read_file;
using taxopt::test::real_data;

namespace {

/// Length of an operation's polyline, mm.
double path_mm(const Operationd& op) {
  double l = 0.0;
  for (std::size_t i = 1; i < op.points.size(); ++i) {
    l += (op.points[i].tip_mm - op.points[i - 1].tip_mm).norm();
  }
  return l;
}

/// A straight move along +X into (10,10), a quarter arc about (10,0) to (20,0) and a move
/// down -Y: the arc runs clockwise seen from +Z. `axis_z` is the k of the CIRCLE's axis.
std::string quarter(const std::string& header, int axis_z, double dx = 0.0) {
  std::ostringstream os;
  os << header << "GOTO/" << dx << ",10,0\nGOTO/" << 10 + dx << ",10,0\nCIRCLE/" << 10 + dx
     << ",0,0,0,0," << axis_z << ",10\nGOTO/" << 20 + dx << ",0,0\nGOTO/" << 20 + dx << ",-10,0\n";
  return os.str();
}

bool throws_with(const std::function<void()>& f, const std::string& text) {
  try {
    f();
  } catch (const InputError& e) {
    INFO(e.what());
    return std::string(e.what()).find(text) != std::string::npos;
  }
  return false;
}

}  // namespace

TEST_CASE(
    "cl arcs: NX and Makino run CIRCLE clockwise about (i,j,k), APT systems counter-clockwise",
    "[io][cl][arcs]") {
  const double quarter_mm = 10.0 + 0.5 * M_PI * 10.0 + 10.0;
  // NX: axis +Z, clockwise: the quarter the straight moves join without a reversal.
  const Toolpath nx = parse_cl(quarter("TOOL PATH/OP,TOOL,T\n", 1), "nx.cls");
  CHECK(nx.reading.dialect == ClDialect::SiemensNx);
  CHECK(nx.reading.arc_convention == ArcDirection::Clockwise);
  CHECK(path_mm(nx.operations[0]) == Approx(quarter_mm).epsilon(1e-4));
  CHECK(nx.reading.arcs == 1);
  CHECK(nx.reading.arcs_decidable == 1);
  CHECK(nx.reading.arcs_contradicting == 0);
  CHECK(nx.notices.empty());
  // Makino FF declares itself on line 1 (steptools/STEPNode examples/data/Plane_2.cldata).
  const Toolpath makino = parse_cl(quarter("PPRINT/APTCL-SPEC,MAKINO-FF,1\n", 1), "m.cl");
  CHECK(makino.reading.dialect == ClDialect::MakinoFfcam);
  CHECK(makino.reading.dialect_evidence == "line 1: Makino FF's PPRINT/APTCL-SPEC,MAKINO-FF");
  CHECK(path_mm(makino.operations[0]) == Approx(quarter_mm).epsilon(1e-4));
  // Creo writes the same arc about -Z (counter-clockwise about it).
  const Toolpath creo = parse_cl(quarter("$$* Pro/CLfile Version 8.0\n", -1), "c.ncl");
  CHECK(creo.reading.dialect == ClDialect::Creo);
  CHECK(path_mm(creo.operations[0]) == Approx(quarter_mm).epsilon(1e-4));
  // Every chord point lies on the arc, between its ends, within the chordal tolerance.
  for (const auto& p : nx.operations[0].points) {
    if (p.line != 3) continue;
    CHECK((p.tip_mm - Vec3d(10, 0, 0)).norm() == Approx(10.0).margin(1e-9));
    CHECK(p.tip_mm.x() >= 10.0);
    CHECK(p.tip_mm.y() >= 0.0);
  }
}

TEST_CASE(
    "cl arcs: free text names no CAM system -- the convention of arcs no move decides comes from "
    "a system's own structure, is said with it, and two systems of opposite senses are refused",
    "[io][cl][arcs][hostile]") {
  // A 90 deg counter-clockwise arc (APT's sense) between vertical moves: nothing decides it.
  const std::string arc =
      "GOTO/20,0,5\nGOTO/20,0,0\nCIRCLE/10,0,0,0,0,1,10\nGOTO/10,10,0\nGOTO/10,10,5\n";
  const double ninety = 10.0 + 0.5 * M_PI * 10.0;
  for (const char* header :
       {"PPRINT/POST FOR MAKINO D500\n", "$$ Makino FFCAM\n", "PARTNO/CATIA and CREO part\n",
        "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\n"}) {
    INFO(header);
    const Toolpath tp = parse_cl(std::string(header) + arc, "g.apt");
    CHECK(tp.reading.dialect == ClDialect::Generic);
    CHECK(tp.reading.dialect_evidence.empty());
    CHECK(path_mm(tp.operations[0]) == Approx(ninety).epsilon(1e-4));  // not 270 deg
  }
  // NX's own structure: its clockwise convention, said with the record that named it.
  const Toolpath nx = parse_cl("TOOL PATH/OP,TOOL,T\n" + arc, "nx.cls");
  CHECK(nx.reading.dialect_evidence == "line 1: NX CLSF's TOOL PATH record");
  CHECK(path_mm(nx.operations[0]) == Approx(10.0 + 1.5 * M_PI * 10.0).epsilon(1e-4));
  REQUIRE(nx.notices.size() == 1);
  CHECK_THAT(nx.notices[0], Catch::Contains("1 of 1 arcs have no neighbouring moves that decide "
                                            "their sense; they run clockwise") &&
                                Catch::Contains("line 1: NX CLSF's TOOL PATH record"));
  // NX and Creo (clockwise and counter-clockwise) in one file: refused, both named.
  CHECK(throws_with(
      [&] { parse_cl("$$* Pro/CLfile Version 8.0\nTOOL PATH/OP,TOOL,T\n" + arc, "x.ncl"); },
      "x.ncl:5: CIRCLE: the file shows two CAM systems whose arcs run in opposite senses (line 1: "
      "Creo's header ($$* Pro/CLfile); line 2: NX CLSF's TOOL PATH record)"));
  ClReadOptions o;
  o.arc_direction = ArcDirection::CounterClockwise;
  CHECK_NOTHROW(parse_cl("$$* Pro/CLfile Version 8.0\nTOOL PATH/OP,TOOL,T\n" + arc, "x.ncl", o));
}

TEST_CASE("cl arcs: when most arcs run against the CAM system's sense the reader stops",
          "[io][cl][arcs]") {
  // An NX file whose arcs are written counter-clockwise: exit 2 naming the line and the option.
  CHECK(throws_with([] { parse_cl(quarter("TOOL PATH/OP,TOOL,T\n", -1), "nx.cls"); },
                    "nx.cls:4: CIRCLE: 1 of 1 decidable arcs (lines 4) run against the clockwise"));
  CHECK(throws_with([] { parse_cl(quarter("TOOL PATH/OP,TOOL,T\n", -1), "nx.cls"); },
                    "ClReadOptions::arc_direction cw|ccw"));
  // The option applies one sense to every arc, as given, with a note.
  ClReadOptions o;
  o.arc_direction = ArcDirection::CounterClockwise;
  const Toolpath forced = parse_cl(quarter("TOOL PATH/OP,TOOL,T\n", -1), "nx.cls", o);
  CHECK(forced.reading.arc_convention_source == "option");
  CHECK(forced.notices.empty());
  CHECK(path_mm(forced.operations[0]) == Approx(20.0 + 0.5 * M_PI * 10.0).epsilon(1e-4));
  // Against the tangents: applied as asked, and said.
  o.arc_direction = ArcDirection::Clockwise;
  const Toolpath long_way = parse_cl(quarter("TOOL PATH/OP,TOOL,T\n", -1), "nx.cls", o);
  CHECK(path_mm(long_way.operations[0]) == Approx(20.0 + 1.5 * M_PI * 10.0).epsilon(1e-4));
  CHECK(long_way.notices.size() == 1);
}

TEST_CASE("cl arcs: a minority arc against the sense runs its tangents' way, with a note",
          "[io][cl][arcs]") {
  // Three NX arcs written clockwise, one (line 14) written the APT way.
  const std::string text = "TOOL PATH/OP,TOOL,T\n" + quarter("", 1) + quarter("", 1, 100) +
                           quarter("", -1, 200) + quarter("", 1, 300);
  const Toolpath tp = parse_cl(text, "nx.cls");
  CHECK(tp.reading.arcs == 4);
  CHECK(tp.reading.arcs_contradicting == 1);
  CHECK(tp.reading.arcs_reversed == 1);
  REQUIRE(tp.reading.reversed_arc_lines.size() == 1);
  CHECK(tp.reading.reversed_arc_lines[0] == 14);
  REQUIRE(tp.notices.size() == 1);
  CHECK_THAT(tp.notices[0], Catch::Contains("nx.cls:14"));
  // Every arc is a quarter: no reversal anywhere.
  double l = 0.0;
  for (const auto& op : tp.operations) l += path_mm(op);
  CHECK(l == Approx(4 * (20.0 + 0.5 * M_PI * 10.0) + 3 * std::hypot(80.0, 20.0)).epsilon(1e-4));
}

TEST_CASE("cl arcs: an unknown CAM system's sense is what its arcs show, or the reader stops",
          "[io][cl][arcs]") {
  const Toolpath cw = parse_cl(quarter("", 1) + quarter("", 1, 100) + quarter("", 1, 200), "g.apt");
  CHECK(cw.reading.dialect == ClDialect::Generic);
  CHECK(cw.reading.arc_convention == ArcDirection::Clockwise);
  CHECK(cw.reading.arc_convention_source == "tangents");
  CHECK(cw.notices.size() == 1);
  // Half one way, half the other: nothing to go by.
  CHECK(throws_with([] { parse_cl(quarter("", 1) + quarter("", -1, 100), "g.apt"); },
                    "arcs disagree"));
}

TEST_CASE("cl arcs: the real files' arcs read in their CAM system's sense", "[io][cl][arcs]") {
  struct Expect {
    const char* file;
    ClDialect dialect;
    ArcDirection sense;
    int arcs, reversed;
  };
  for (const Expect& e : {Expect{"mech491-project2-multiop.cls", ClDialect::SiemensNx,
                                 ArcDirection::Clockwise, 146, 0},
                          Expect{"amorim-interface-glue.apt", ClDialect::SolidworksCam,
                                 ArcDirection::CounterClockwise, 50, 0},
                          // 20 keyhole arcs of 270 deg whose axis is written flipped.
                          Expect{"amorim-wall-holes.apt", ClDialect::SolidworksCam,
                                 ArcDirection::CounterClockwise, 336, 20},
                          Expect{"creopost-profilfraesen.ncl", ClDialect::Creo,
                                 ArcDirection::CounterClockwise, 20, 0},
                          Expect{"peening-catia-multax.aptsource", ClDialect::Catia,
                                 ArcDirection::CounterClockwise, 0, 0},
                          // No arc: the report still names the CAM system's sense.
                          Expect{"mech491-variable-axis-ballmill.cls", ClDialect::SiemensNx,
                                 ArcDirection::Clockwise, 0, 0},
                          Expect{"amorim-tilt-support1.apt", ClDialect::SolidworksCam,
                                 ArcDirection::CounterClockwise, 0, 0}}) {
    INFO(e.file);
    const Toolpath tp = taxopt::test::read_real(e.file);
    CHECK(tp.reading.dialect == e.dialect);
    CHECK(tp.reading.arcs == e.arcs);
    CHECK(tp.reading.arcs_reversed == e.reversed);
    CHECK(tp.reading.arc_convention == e.sense);
    CHECK(tp.reading.arcs_contradicting == e.reversed);
  }
}

namespace {

/// Rational B-spline point by the Cox-de Boor basis (independent of the reader's de Boor).
Vec3d nurbs_point(const std::vector<double>& U, const std::vector<Vec3d>& P,
                  const std::vector<double>& w, int p, double t) {
  const std::function<double(int, int)> N = [&](int i, int k) -> double {
    if (k == 0) {
      const bool last = t == U.back() && U[static_cast<std::size_t>(i + 1)] == U.back() &&
                        U[static_cast<std::size_t>(i)] < U.back();
      return (U[static_cast<std::size_t>(i)] <= t && t < U[static_cast<std::size_t>(i + 1)]) || last
                 ? 1.0
                 : 0.0;
    }
    double v = 0.0;
    const double d1 = U[static_cast<std::size_t>(i + k)] - U[static_cast<std::size_t>(i)];
    const double d2 = U[static_cast<std::size_t>(i + k + 1)] - U[static_cast<std::size_t>(i + 1)];
    if (d1 > 0) v += (t - U[static_cast<std::size_t>(i)]) / d1 * N(i, k - 1);
    if (d2 > 0) v += (U[static_cast<std::size_t>(i + k + 1)] - t) / d2 * N(i + 1, k - 1);
    return v;
  };
  Vec3d num = Vec3d::Zero();
  double den = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const double b = N(static_cast<int>(i), p) * w[i];
    num += b * P[i];
    den += b;
  }
  return num / den;
}

/// Distance from q to the curve, by dense sampling and a golden-section polish.
double distance_to_curve(const std::function<Vec3d(double)>& c, const Vec3d& q) {
  double best_t = 0.0, best = 1e300;
  for (int k = 0; k <= 2000; ++k) {
    const double t = k / 2000.0, d = (c(t) - q).norm();
    if (d < best) best = d, best_t = t;
  }
  double lo = std::max(0.0, best_t - 1e-3), hi = std::min(1.0, best_t + 1e-3);
  for (int it = 0; it < 60; ++it) {
    const double a = lo + (hi - lo) * 0.382, b = lo + (hi - lo) * 0.618;
    if ((c(a) - q).norm() < (c(b) - q).norm()) {
      hi = b;
    } else {
      lo = a;
    }
  }
  return std::min(best, (c(0.5 * (lo + hi)) - q).norm());
}

}  // namespace

TEST_CASE("cl splines: NX NURBS become points on the curve, chords within the tolerance",
          "[io][cl][nurbs]") {
  // A rational quadratic quarter circle (weights 1, sqrt(2)/2, 1): exact on the circle.
  {
    const Toolpath tp = parse_cl(
        "TOOL PATH/OP,TOOL,T\nGOTO/10,0,0\nNURBS/\nKNOT/1.0\nCNTRL/10,10,0,0.70710678118654752\n"
        "CNTRL/0,10,0\nGOTO/0,20,0\n",
        "arc.cls");
    const auto& pts = tp.operations[0].points;
    CHECK(tp.reading.splines == 1);
    CHECK(tp.reading.spline_points == static_cast<int>(pts.size()) - 2);
    REQUIRE(pts.size() > 20);
    for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
      CHECK(pts[i].tip_mm.norm() == Approx(10.0).margin(1e-9));
      CHECK(pts[i].line == 3);
      const double chord = (pts[i].tip_mm - pts[i - 1].tip_mm).norm();
      CHECK(10.0 - std::sqrt(100.0 - chord * chord / 4) <= 0.001 + 1e-12);
    }
    CHECK((pts[pts.size() - 2].tip_mm - Vec3d(0, 10, 0)).norm() < 1e-12);
  }
  // A cubic with two spans (KNOT/0.4,1: degree 5 - 2 + 1 = ... 4 CNTRL + start, 2 knots: 3).
  {
    const std::vector<Vec3d> P = {Vec3d(0, 0, 0), Vec3d(10, 20, 0), Vec3d(30, -15, 5),
                                  Vec3d(45, 10, 0), Vec3d(60, 0, 2)};
    const std::vector<double> w = {1, 1, 2, 1, 1};
    std::ostringstream os;
    os.precision(17);
    os << "TOOL PATH/OP,TOOL,T\nGOTO/0,0,0\nNURBS/\nKNOT/0.4,1\n";
    for (std::size_t i = 1; i < P.size(); ++i) {
      os << "CNTRL/" << P[i].x() << "," << P[i].y() << "," << P[i].z() << "," << w[i] << "\n";
    }
    const Toolpath tp = parse_cl(os.str(), "cubic.cls");
    const std::vector<double> U = {0, 0, 0, 0, 0.4, 1, 1, 1, 1};
    const auto curve = [&](double t) { return nurbs_point(U, P, w, 3, t); };
    const auto& pts = tp.operations[0].points;
    REQUIRE(pts.size() > 10);
    double worst_point = 0.0, worst_chord = 0.0;
    for (std::size_t i = 1; i < pts.size(); ++i) {
      worst_point = std::max(worst_point, distance_to_curve(curve, pts[i].tip_mm));
      // The curve strays from each chord by at most the tolerance: the chord's points at
      // quarters are within it of the curve.
      for (double f : {0.25, 0.5, 0.75}) {
        const Vec3d q = pts[i - 1].tip_mm + f * (pts[i].tip_mm - pts[i - 1].tip_mm);
        worst_chord = std::max(worst_chord, distance_to_curve(curve, q));
      }
    }
    CHECK(worst_point < 1e-6);
    CHECK(worst_chord <= 0.001 + 1e-6);
    CHECK((pts.back().tip_mm - P.back()).norm() < 1e-9);
  }
}

TEST_CASE("cl splines: a NURBS layout taxopt does not know stops the reader", "[io][cl][nurbs]") {
  const std::string head = "TOOL PATH/OP,TOOL,T\nGOTO/0,0,0\n";
  CHECK(throws_with(
      [&] { parse_cl(head + "NURBS/\nKNOT/0.5,0.6,1\nCNTRL/1,1,1\nGOTO/2,2,2\n", "n"); },
      "n:3: NURBS at line 3"));
  CHECK(throws_with([&] { parse_cl(head + "NURBS/ORDER,4\nKNOT/1\nCNTRL/1,1,1\n", "n"); },
                    "n:3: NURBS/ORDER,4"));
  CHECK(throws_with([&] { parse_cl(head + "CNTRL/1,1,1\n", "n"); }, "n:3: CNTRL outside"));
  CHECK(throws_with(
      [&] {
        parse_cl(head + "NURBS/\nKNOT/0.7,0.5,1\nCNTRL/1,1,1\nCNTRL/2,1,1\nCNTRL/3,1,1\n", "n");
      },
      "knots must rise"));
  CHECK(throws_with([&] { parse_cl(head + "NURBS/\nKNOT/1\nCNTRL/1,1,1,0\nCNTRL/2,1,1\n", "n"); },
                    "n:5: CNTRL: weight must be positive"));
  // A control point beyond any machine's reach (a fuzzed file's 1.1e43 made the spans'
  // bisection run 28 s): refused with its line, as a GOTO would be.
  CHECK(throws_with(
      [&] {
        parse_cl(head + "NURBS/\nKNOT/0.5,1\nCNTRL/1,1,0\nCNTRL/2,1.1e43,0\nCNTRL/3,1,0\n", "n");
      },
      "n:6: CNTRL: point"));
}

TEST_CASE("cl MSYS: a real file moved by a known MSYS reads as the original", "[io][cl][msys]") {
  // mech491-variable-axis-ballmill.cls (MSYS at (3,3,0), unrotated) rewritten in a frame
  // rotated 90 deg about X and 30 deg about Z and moved: every GOTO and its MSYS move with it.
  const std::string text = read_file(real_data("mech491-variable-axis-ballmill.cls"));
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(deg_to_rad(30.0), Vec3d::UnitZ()) *
                             Eigen::AngleAxisd(deg_to_rad(180.0), Vec3d::UnitX()))
                                .toRotationMatrix();
  const Vec3d o(12.5, -4.0, 7.25);  // inches
  std::istringstream in(text);
  std::ostringstream out;
  out.precision(12);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> v;
    const std::size_t slash = line.find('/');
    if (line.rfind("GOTO/", 0) == 0 || line.rfind("MSYS/", 0) == 0) {
      std::istringstream fields(line.substr(slash + 1));
      std::string f;
      while (std::getline(fields, f, ',')) v.push_back(std::stod(f));
    }
    if (line.rfind("GOTO/", 0) == 0) {
      const Vec3d p = R * Vec3d(v[0], v[1], v[2]) + o;
      out << "GOTO/" << p.x() << "," << p.y() << "," << p.z();
      if (v.size() == 6) {
        const Vec3d a = R * Vec3d(v[3], v[4], v[5]);
        out << "," << a.x() << "," << a.y() << "," << a.z();
      }
      out << "\n";
    } else if (line.rfind("MSYS/", 0) == 0) {
      const Vec3d p = R * Vec3d(v[0], v[1], v[2]) + o, x = R * Vec3d(v[3], v[4], v[5]),
                  y = R * Vec3d(v[6], v[7], v[8]);
      out << "MSYS/" << p.x() << "," << p.y() << "," << p.z() << "," << x.x() << "," << x.y() << ","
          << x.z() << "," << y.x() << "," << y.y() << "," << y.z() << "\n";
    } else {
      out << line << "\n";
    }
  }
  // --msys apply: both files' coordinates are taken as absolute and moved into their MCS.
  ClReadOptions apply;
  apply.apply_msys = true;
  const Toolpath original = parse_cl(text, "o.cls", apply);
  const Toolpath moved = parse_cl(out.str(), "m.cls", apply);
  // In the file's own frame every tool axis now points down (k < 0)...
  CHECK(moved.reading.msys_applied == 1);
  REQUIRE(moved.operations.size() == 1);
  const auto& a = original.operations[0].points;
  const auto& b = moved.operations[0].points;
  REQUIRE(a.size() == b.size());
  // ...and in the MCS, where taxopt posts, the points are the original's.
  for (std::size_t i = 0; i < a.size(); ++i) {
    REQUIRE((a[i].tip_mm - b[i].tip_mm).norm() < 1e-6);
    REQUIRE((a[i].axis - b[i].axis).norm() < 1e-9);
  }
  // --out-cls writes a changed point back in the file's frame.
  auto ops = moved.operations;
  ops[0].points[5].tip_mm += Vec3d(0.0, 0.0, 2.54);
  const Toolpath again = parse_cl(format_cl(moved, ops), "again.cls", apply);
  CHECK((again.operations[0].points[5].tip_mm - ops[0].points[5].tip_mm).norm() < 1e-5);
}

TEST_CASE("cl feeds: FEDRAT with PERMIN, PERREV and the value first or last", "[io][cl]") {
  const auto feed = [](const std::string& units, const std::string& fedrat) {
    const Toolpath tp = parse_cl(units + "SPINDL/1000,RPM,CLW\n" + fedrat + "\nGOTO/1,2,3\n", "f");
    return tp.operations.at(0).points.at(0).feed_mm_per_min;
  };
  CHECK(feed("UNITS/INCHES\n", "FEDRAT/PERMIN,20") == Approx(20 * 25.4));
  CHECK(feed("UNITS/INCHES\n", "FEDRAT/20,PERMIN") == Approx(20 * 25.4));
  CHECK(feed("UNITS/MM\n", "FEDRAT/PERMIN,250") == Approx(250));
  CHECK(feed("UNITS/MM\n", "FEDRAT/0.05,PERREV") == Approx(50));
  CHECK(feed("UNITS/INCHES\n", "FEDRAT/MMPM,300") == Approx(300));
  CHECK(feed("", "FEDRAT/IPM,10") == Approx(254));
  CHECK(feed("", "FEDRAT/400") == Approx(400));
  CHECK(throws_with([&] { feed("", "FEDRAT/PERSEC,4"); }, "f:2: FEDRAT: expected a feed"));
}

TEST_CASE(
    "cl feeds: a feed per revolution is the spindle's -- it follows every SPINDL, waits for the "
    "first, and a feed move with none in force is refused naming both lines",
    "[io][cl][hostile]") {
  const auto feeds = [](const std::string& text) {
    std::vector<double> out;
    const Toolpath tp = parse_cl(text, "r.cls");  // alive while its points are walked
    for (const CLPointd& p : tp.operations.at(0).points) {
      if (p.motion == Motion::Feed) out.push_back(p.feed_mm_per_min);
    }
    return out;
  };
  // 0.1 mm/rev at 3000 rpm is 300 mm/min, at 6000 rpm 600 (it kept 300).
  CHECK(feeds("SPINDL/RPM,3000,CLW\nRAPID\nGOTO/0,0,10\nFEDRAT/0.1,MMPR\nGOTO/0,0,0\nGOTO/10,0,0\n"
              "SPINDL/RPM,6000,CLW\nGOTO/20,0,0\n") == std::vector<double>{300, 300, 600});
  // Given before the spindle speed: 300 from the SPINDL on (it was the 1000 mm/min default).
  CHECK(feeds("FEDRAT/0.1,MMPR\nSPINDL/RPM,3000,CLW\nGOTO/0,0,10\nGOTO/0,0,0\n") ==
        std::vector<double>{300, 300});
  // Inches per revolution; a feed per minute after it no longer follows the spindle. (Feed
  // words in both units say nothing of the coordinates' unit: the file states it.)
  CHECK(feeds("UNITS/MM\nSPINDL/RPM,1000\nFEDRAT/IPR,0.004\nGOTO/0,0,1\nFEDRAT/MMPM,250\n"
              "SPINDL/2000\nGOTO/1,0,1\n") == std::vector<double>{0.004 * 25.4 * 1000, 250});
  const std::string off = test::input_error_of([&] {
    parse_cl("FEDRAT/0.1,MMPR\nSPINDL/RPM,3000,CLW\nGOTO/0,0,10\nSPINDL/OFF\nGOTO/0,0,0\n",
             "r.cls");
  });
  CHECK_THAT(off, Catch::Contains("r.cls:5: a feed move at a feed per revolution (FEDRAT, line 1) "
                                  "with no spindle speed in force"));
  CHECK_THAT(test::input_error_of(
                 [&] { parse_cl("FEDRAT/0.1,MMPR\nGOTO/0,0,10\nGOTO/0,0,0\n", "r.cls"); }),
             Catch::Contains("r.cls:2: a feed move at a feed per revolution"));
}

TEST_CASE(
    "cl units: a file's first UNITS after its first motion is refused (the moves before it were "
    "read in its units without a word) unless --units says them",
    "[io][cl][hostile]") {
  const std::string text =
      "FEDRAT/MMPM,500\nRAPID\nGOTO/0,0,5\nGOTO/50,0,5\nUNITS/INCHES\n"
      "GOTO/60,0,5\n";
  CHECK(throws_with(
      [&] { parse_cl(text, "u.cls"); },
      "u.cls:5: UNITS/INCHES comes after the first motion (line 3): whether the "
      "moves before it are in inches too is not known; give ClReadOptions::units in|mm"));
  ClReadOptions o;
  o.units = LengthUnit::Inch;
  CHECK(parse_cl(text, "u.cls", o).operations.at(0).points.at(1).tip_mm.x() == Approx(50 * 25.4));
  // Before the motion it is the file's units, as always.
  CHECK_NOTHROW(parse_cl("UNITS/INCHES\n" + text.substr(0, text.find("UNITS")), "u.cls"));
}

TEST_CASE(
    "cl units: numbers in the other unit than the file says are refused by their feed per "
    "revolution, naming both readings -- --units reads the whole file in its unit, feed words too",
    "[io][cl][hostile]") {
  // Creo's layout: UNITS / INCHES over millimetre numbers (a D6 cutter, 1193.66 at 7958 rpm).
  const std::string creo =
      "UNITS / INCHES\nCUTTER / 6.000000\nSPINDL / RPM, 7958.000000, CLW\n"
      "FEDRAT / 1193.660000, IPM\nGOTO / 0.0, 0.0, 5.0\nGOTO / 40.0, 0.0, 5.0\n"
      "GOTO / 40.0, 30.0, 5.0\n";
  CHECK(throws_with([&] { parse_cl(creo, "c.ncl"); },
                    "its feed, 30319 mm/min at 7958 rpm, is 3.81 mm a revolution, no milling "
                    "feed; read as millimetres it would be 0.15 mm"));
  CHECK(throws_with([&] { parse_cl(creo, "c.ncl"); },
                    "ClReadOptions::units mm reads the whole file so"));
  ClReadOptions mm;
  mm.units = LengthUnit::Millimetre;
  const Toolpath read = parse_cl(creo, "c.ncl", mm);
  CHECK(read.operations.at(0).points.at(1).feed_mm_per_min == Approx(1193.66));
  CHECK(read.operations.at(0).points.at(1).tip_mm.x() == Approx(40.0));
  // Fusion's: an inch file whose FEDRAT says MMPM over inches per minute, 30000 rpm.
  const std::string fusion =
      "UNITS/INCHES\nSPINDL/RPM, 30000, CLW\nFEDRAT/35., MMPM\n"
      "GOTO/0,0,0.2\nGOTO/1,0,0.2\nGOTO/1,1,0.2\n";
  CHECK(throws_with([&] { parse_cl(fusion, "f.apt"); }, "read as inches it would be 0.02963 mm"));
  ClReadOptions in;
  in.units = LengthUnit::Inch;
  CHECK(parse_cl(fusion, "f.apt", in).operations.at(0).points.at(1).feed_mm_per_min ==
        Approx(35 * 25.4));
  // A plausible feed in either reading is left as the file says.
  CHECK_NOTHROW(
      parse_cl("UNITS/MM\nSPINDL/RPM, 8000\nFEDRAT/MMPM,800\nGOTO/0,0,5\n"
               "GOTO/50,0,5\n",
               "ok.cls"));
}

TEST_CASE("cl cycles: a drilling cycle's holes become their moves", "[io][cl]") {
  const Toolpath tp = parse_cl(
      "UNIT/MM\nFEDRAT/500,MMPM\nGOTO/0,0,50\nCYCLE/INIT\n"
      "CYCLE/DEEP2,FEDTO,10.,1STPECK,5.,SUBPECK,2.,MMPM,100.,RAPTO,3.,RTRCTO,20.\n"
      "GOTO/10,0,0\nCYCLE/OFF\nGOTO/0,0,50\n",
      "c.apt");
  const auto& pts = tp.operations[0].points;
  CHECK(tp.reading.cycle_holes == 1);
  std::vector<double> z;
  for (const auto& p : pts) z.push_back(p.tip_mm.z());
  // In at 20, down to 3, pecks to -5, -7, -9, -10 with returns to 3 and rapids back down to
  // 0.254 mm above the depth reached (LinuxCNC's G83), out at 20.
  const double c = 0.254;
  const std::vector<double> expect = {50,     20, 3, -5,     3,   -5 + c, -7, 3,
                                      -7 + c, -9, 3, -9 + c, -10, 20,     50};
  REQUIRE(z.size() == expect.size());
  for (std::size_t i = 0; i < z.size(); ++i) CHECK(z[i] == Approx(expect[i]));
  CHECK(pts[3].motion == Motion::Feed);
  CHECK(pts[3].feed_mm_per_min == Approx(100));
  CHECK(pts[4].motion == Motion::Rapid);
  CHECK(throws_with([] { parse_cl("GOTO/0,0,0\nCYCLE/DRILL,10,IPM,5,0.1\n", "c"); },
                    "positional form"));
  CHECK(throws_with([] { parse_cl("GOTO/0,0,0\nCYCLE/THREAD,FEDTO,3\n", "c"); },
                    "CYCLE/THREAD: drilling cycle not interpreted"));
}

TEST_CASE("cl motion words: GODLTA and GOHOME move -- words taxopt cannot interpret stop it",
          "[io][cl]") {
  const Toolpath tp =
      parse_cl("FROM/0,0,100\nGOTO/10,0,5\nGODLTA/0,0,-5\nGODLTA/20\nGOHOME\n", "m.apt");
  const auto& pts = tp.operations[0].points;
  REQUIRE(pts.size() == 5);
  CHECK((pts[2].tip_mm - Vec3d(10, 0, 0)).norm() < 1e-12);
  CHECK((pts[3].tip_mm - Vec3d(10, 0, 20)).norm() < 1e-12);
  CHECK((pts[4].tip_mm - Vec3d(0, 0, 100)).norm() < 1e-12);
  CHECK(pts[4].motion == Motion::Rapid);
  CHECK(tp.reading.motion_records == 5);
  for (const char* word : {"DEFSUB/1", "CALL/1", "COPY/1,INDEX,2", "LOOP/START,15",
                           "ROTATE/ZAXIS,90", "INDEX/3", "ROTABL/90"}) {
    INFO(word);
    CHECK(throws_with(
        [&] { parse_cl(std::string("GOTO/0,0,0\n") + word + "\nGOTO/1,0,0\n", "w.cls"); },
        "w.cls:2: "));
  }
  // MULTAX/OFF: 3-axis from there on, the axis +Z.
  const Toolpath off = parse_cl("GOTO/0,0,0,0,1,0\nMULTAX/OFF\nGOTO/1,0,0\n", "o.apt");
  CHECK((off.operations[0].points[1].axis - Vec3d::UnitZ()).norm() < 1e-12);
  // A GOHOME with no FROM before it.
  CHECK(throws_with([] { parse_cl("GOTO/0,0,0\nGOHOME\n", "h"); }, "h:2: GOHOME: no FROM"));
}

TEST_CASE("cl text: a UTF-8 byte-order mark is read past and written back -- UTF-16 is refused",
          "[io][cl]") {
  const std::string plain = "UNITS/INCHES\nTOOL PATH/OP,TOOL,T\nGOTO/1,2,3\n";
  const Toolpath a = parse_cl(plain, "a");
  const Toolpath b = parse_cl("\xEF\xBB\xBF" + plain, "b");
  CHECK(b.units == LengthUnit::Inch);
  CHECK(b.operations.at(0).name == "OP");
  CHECK((b.operations[0].points[0].tip_mm - a.operations[0].points[0].tip_mm).norm() == 0.0);
  CHECK(format_cl(b, b.operations) == "\xEF\xBB\xBF" + plain);
  CHECK(throws_with([] { parse_cl(std::string("\xFF\xFEG\0O", 5), "u"); }, "UTF-16"));
}
