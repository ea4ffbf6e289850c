// The part's chordal error and the default contact tolerance built on it: the largest sagitta
// of the mesh's tessellated curves (not a percentile, not a designed crease), plus the band the
// CL file says its path keeps about the surface (INTOL / OUTTOL / TOLER). Checked on an
// extruded CAD-style profile whose sagittas are known in closed form, with balls placed on the
// analytic (designed) surface, as a CAM system places them.
#include <catch2/catch.hpp>
#include <cmath>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

constexpr double kDeg = M_PI / 180.0;

/// A step part across y: a ramp falling 20 deg to a floor (a designed 20 deg crease, its faces
/// 20 mm wide), a concave fillet of radius 10 mm up to a wall in `coarse` strips, a top, a
/// convex fillet of radius 2 mm in 40 strips, the right side, the bottom; 50 rows along y.
struct StepPart {
  static constexpr double kFilletR = 10.0, kSmallR = 2.0;
  int coarse = 5;
  TriangleMesh mesh() const {
    std::vector<Eigen::Vector2d> p;  // (x, z)
    p.emplace_back(-40.0, 20.0 * std::tan(20.0 * kDeg));
    p.emplace_back(-20.0, 0.0);
    for (int k = 0; k <= coarse; ++k) {  // centre (0, 10), from the floor up to the wall
      const double t = 0.5 * M_PI * k / coarse;
      p.emplace_back(kFilletR * std::sin(t), kFilletR - kFilletR * std::cos(t));
    }
    p.emplace_back(10.0, 20.0);
    for (int k = 0; k <= 40; ++k) {  // centre (23, 18)
      const double t = 0.5 * M_PI * k / 40;
      p.emplace_back(23.0 + kSmallR * std::sin(t), 18.0 + kSmallR * std::cos(t));
    }
    p.emplace_back(25.0, -10.0);
    p.emplace_back(-40.0, -10.0);
    return extruded_profile(p, -25.0, 25.0, 50);
  }
  /// The sagitta of the concave fillet's chords: r (1 - cos(half a strip's angle)).
  double fillet_sagitta_mm() const { return kFilletR * (1.0 - std::cos(0.25 * M_PI / coarse)); }
  /// Tip of a ball of radius R (axis +Z) whose sphere touches the designed fillet at angle t
  /// (0 at the floor, pi/2 at the wall), sunk `depth_mm` further into it.
  static Vec3d tip_on_fillet(double t, double y, double R, double depth_mm = 0.0) {
    const double d = kFilletR - R + depth_mm;  // centre's distance from the fillet's axis
    return Vec3d(d * std::sin(t), y, kFilletR - d * std::cos(t)) - R * Vec3d::UnitZ();
  }
};

std::string cl_on_fillet(const std::vector<double>& t_deg, double depth_mm,
                         const std::string& tolerance_records) {
  std::ostringstream os;
  os.precision(12);
  os << "UNITS/MM\nLOADTL/1\nSPINDL/8000\nCUTTER/6.0,3.0\n" << tolerance_records << "FEDRAT/1000\n";
  for (std::size_t i = 0; i < t_deg.size(); ++i) {
    const Vec3d tip = StepPart::tip_on_fillet(t_deg[i] * kDeg, -20.0 + 0.4 * static_cast<double>(i),
                                              3.0, depth_mm);
    os << "GOTO/" << tip.x() << "," << tip.y() << "," << tip.z() << ",0,0,1\n";
  }
  os << "FINI\n";
  return os.str();
}

}  // namespace

TEST_CASE(
    "chordal error: the largest sagitta of the part's tessellated curves, not a percentile and "
    "not a designed crease",
    "[geometry][contact][cad]") {
  for (int coarse : {3, 5, 9}) {
    const StepPart step{coarse};
    const Part part(step.mesh());
    INFO("concave fillet in " << coarse << " strips");
    // The concave fillet's chords are the mesh's largest departure from the designed part:
    // 200 of its edges against 1,950 of the small fillet's (a 99th percentile would be the
    // small fillet's) and 50 of the 20 deg crease's (whose formula would give 0.875 mm).
    CHECK(part.chordal_error_mm() == Approx(step.fillet_sagitta_mm()).epsilon(1e-9));
    CHECK(contact_tolerance_mm(part, {}) ==
          Approx(std::max(kContactToleranceFloorMm, step.fillet_sagitta_mm())).epsilon(1e-9));
  }
  // Flat faces with sharp and 20 deg edges only: no curve, no chordal error.
  std::vector<Eigen::Vector2d> p = {{-40.0, 20.0 * std::tan(20.0 * kDeg)},
                                    {-20.0, 0.0},
                                    {10.0, 0.0},
                                    {10.0, -10.0},
                                    {-40.0, -10.0}};
  CHECK(Part(extruded_profile(p, -25.0, 25.0, 10)).chordal_error_mm() == 0.0);
}

TEST_CASE(
    "chordal error: balls on the designed fillet sink into its chords by up to the chordal "
    "error, and the default tolerance takes every one as touching",
    "[geometry][contact][cad]") {
  const StepPart step{5};  // 18 deg strips: 0.1231 mm, above the 0.05 mm floor
  const Part part(step.mesh());
  std::vector<double> t_deg;
  for (double t = 0.5; t < 90.0; t += 1.0) t_deg.push_back(t);
  const Toolpath tp = parse_cl(cl_on_fillet(t_deg, 0.0, ""), "f.cls");
  const Operationd& op = tp.operations.front();
  const auto contacts = recover_contacts(part, op, 3.0);
  double deepest = 0.0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    INFO("t " << t_deg[i] << " deg");
    // The chord under angle t lies r cos(9 deg) from the fillet's axis, square to its middle's
    // direction; the centre (r - R) from the axis at angle t.
    const double middle = 18.0 * (std::floor(t_deg[i] / 18.0) + 0.5);
    const double R = 3.0, r = StepPart::kFilletR;
    const double depth =
        R + (r - R) * std::cos((t_deg[i] - middle) * kDeg) - r * std::cos(9.0 * kDeg);
    CHECK(contacts[i].gap_mm == Approx(-depth).margin(1e-6));
    CHECK(contacts[i].state == ContactState::Touching);
    deepest = std::max(deepest, depth);
  }
  // The deepest is above the floor: a percentile or the floor alone would have refused them.
  CHECK(deepest > 0.12);
  CHECK(deepest <= part.chordal_error_mm());
}

TEST_CASE(
    "chordal error: the CL file's INTOL / OUTTOL / TOLER widen the default tolerance by their "
    "band, and a ball deeper than both is refused naming the two numbers and the option",
    "[geometry][contact][cad][io]") {
  const StepPart step{5};
  const Part part(step.mesh());
  const double chordal = step.fillet_sagitta_mm();
  const std::vector<double> t_deg = {9.0, 27.0, 45.0};  // the chords' middles
  JobOptions options;
  options.part = &part;
  options.method = Method::None;
  const auto refusal = [&](const std::string& text) {
    return input_error_of(
        [&] { (void)run_job(parse_cl(text, "f.cls"), default_machine(), options); });
  };
  // 0.03 mm deeper than the chords: refused without a band, and the message says why.
  const std::string no_band = refusal(cl_on_fillet(t_deg, 0.03, ""));
  CHECK_THAT(no_band, Catch::Contains("f.cls:6"));
  CHECK_THAT(no_band, Catch::Contains("the ball cuts 0.153"));
  CHECK_THAT(no_band, Catch::Contains("more than the contact tolerance 0.123"));
  CHECK_THAT(no_band, Catch::Contains("the mesh's chordal error 0.123"));
  CHECK_THAT(no_band, Catch::Contains("JobOptions::contact.tolerance_mm"));
  // The CAM's band: the part surface's (second) value, the larger of INTOL and OUTTOL.
  for (const std::string& records :
       {std::string("INTOL/0.1,0.04\n"), std::string("INTOL/0.01\nOUTTOL/0.04\n"),
        std::string("TOLER/0.04\n")}) {
    INFO(records);
    const Toolpath tp = parse_cl(cl_on_fillet(t_deg, 0.03, records), "f.cls");
    REQUIRE(tp.operations.front().cam_tolerance_mm);
    CHECK(*tp.operations.front().cam_tolerance_mm == Approx(0.04));
    CHECK(contact_tolerance_mm(part, {}, tp.operations.front().cam_tolerance_mm) ==
          Approx(chordal + 0.04));
    for (const ContactPoint& c : recover_contacts(part, tp.operations.front(), 3.0)) {
      CHECK(c.state == ContactState::Touching);
    }
  }
  // Beyond chordal error + band: refused, both numbers named.
  const std::string banded = refusal(cl_on_fillet(t_deg, 0.06, "INTOL/0.02\n"));
  CHECK_THAT(banded, Catch::Contains("the ball cuts 0.183"));
  CHECK_THAT(banded, Catch::Contains("more than the contact tolerance 0.143"));
  CHECK_THAT(banded, Catch::Contains("+ the CL file's tolerance (INTOL/OUTTOL/TOLER) 0.02 mm"));
  // Inch files: the band in inches.
  const Toolpath inch = parse_cl("UNITS/INCHES\nINTOL/0.001\nGOTO/0,0,0\nFINI\n", "i.cls");
  CHECK(*inch.operations.front().cam_tolerance_mm == Approx(0.0254));
  // A band given only after an operation's points does not reach back to them.
  const Toolpath later =
      parse_cl("UNITS/MM\nGOTO/0,0,0\nINTOL/0.02\nLOADTL/2\nGOTO/1,0,0\nFINI\n", "l.cls");
  REQUIRE(later.operations.size() == 2);
  CHECK_FALSE(later.operations[0].cam_tolerance_mm);
  CHECK(*later.operations[1].cam_tolerance_mm == Approx(0.02));
}

TEST_CASE("chordal error: hostile CAM tolerances are refused with their line",
          "[io][cl][hostile]") {
  for (const char* record : {"INTOL/-0.01", "INTOL/abc", "INTOL/", "OUTTOL/0.1,0.1,0.1,0.1,0.1",
                             "TOLER/2", "INTOL/nan", "OUTTOL/inf", "INTOL/0.05,1e300"}) {
    INFO(record);
    try {
      (void)parse_cl("UNITS/MM\n" + std::string(record) + "\nGOTO/0,0,0\nFINI\n", "h.cls");
      FAIL("accepted");
    } catch (const InputError& e) {
      CHECK_THAT(e.what(), Catch::Contains("h.cls:2"));
    }
  }
  // --skip-record drops a band taxopt would refuse.
  ClReadOptions skip;
  skip.skip_records = {"TOLER"};
  CHECK_FALSE(parse_cl("UNITS/MM\nTOLER/2\nGOTO/0,0,0\nFINI\n", "h.cls", skip)
                  .operations[0]
                  .cam_tolerance_mm);
}
