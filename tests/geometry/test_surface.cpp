#include <catch2/catch.hpp>
#include <random>

#include "taxopt/geometry/bspline_surface.hpp"
#include "taxopt/geometry/raster_generator.hpp"
#include "taxopt/geometry/surface.hpp"

using namespace taxopt;

namespace {

/// Sphere of radius r seen from outside (normal outwards): u longitude, v colatitude.
struct Sphere {
  double r = 7.0;
  double u_min() const { return 0.0; }
  double u_max() const { return 6.0; }
  double v_min() const { return 0.3; }
  double v_max() const { return 2.8; }
  SurfaceJet<double> jet(double u, double v) const {
    const double cu = std::cos(u), su = std::sin(u), cv = std::cos(v), sv = std::sin(v);
    SurfaceJet<double> j;
    // Parametrised so that S_u x S_v points outwards.
    // (y mirrored so that the longitude runs clockwise and S_u x S_v points outwards)
    j.p = r * Vec3d(cu * sv, -su * sv, cv);
    j.su = r * Vec3d(-su * sv, -cu * sv, 0);
    j.sv = r * Vec3d(cu * cv, -su * cv, -sv);
    j.suu = r * Vec3d(-cu * sv, su * sv, 0);
    j.suv = r * Vec3d(-su * cv, -cu * cv, 0);
    j.svv = r * Vec3d(-cu * sv, su * sv, -cv);
    return j;
  }
};

/// Cylinder of radius r about z, seen from inside (normal towards the axis).
struct InsideCylinder {
  double r = 5.0;
  double u_min() const { return 0.0; }
  double u_max() const { return 6.0; }
  double v_min() const { return 0.0; }
  double v_max() const { return 10.0; }
  SurfaceJet<double> jet(double u, double v) const {
    SurfaceJet<double> j;
    // z runs downwards so that S_u x S_v points to the axis.
    j.p = Vec3d(r * std::cos(u), r * std::sin(u), -v);
    j.su = Vec3d(-r * std::sin(u), r * std::cos(u), 0);
    j.sv = Vec3d(0, 0, -1);
    j.suu = Vec3d(-r * std::cos(u), -r * std::sin(u), 0);
    j.suv = j.svv = Vec3d::Zero();
    return j;
  }
};

template <class Surface>
void check_derivatives(const Surface& s, std::mt19937& rng) {
  std::uniform_real_distribution<double> uu(s.u_min() + 0.01, s.u_max() - 0.01);
  std::uniform_real_distribution<double> vv(s.v_min() + 0.01, s.v_max() - 0.01);
  const double h = 1e-5;
  for (int k = 0; k < 100; ++k) {
    const double u = uu(rng), v = vv(rng);
    const auto j = s.jet(u, v);
    const auto ju0 = s.jet(u - h, v), ju1 = s.jet(u + h, v);
    const auto jv0 = s.jet(u, v - h), jv1 = s.jet(u, v + h);
    const double scale = 1.0 + j.p.norm();
    REQUIRE((j.su - (ju1.p - ju0.p) / (2 * h)).norm() < 1e-5 * scale);
    REQUIRE((j.sv - (jv1.p - jv0.p) / (2 * h)).norm() < 1e-5 * scale);
    REQUIRE((j.suu - (ju1.su - ju0.su) / (2 * h)).norm() < 1e-4 * scale);
    REQUIRE((j.suv - (jv1.su - jv0.su) / (2 * h)).norm() < 1e-4 * scale);
    REQUIRE((j.svv - (jv1.sv - jv0.sv) / (2 * h)).norm() < 1e-4 * scale);
  }
}

BSplineSurfaced wavy_bspline(std::mt19937& rng) {
  std::uniform_real_distribution<double> z(-3.0, 3.0);
  std::vector<Vec3d> ctrl;
  const int n = 7;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) ctrl.emplace_back(10.0 * i, 10.0 * j + 0.5 * i, z(rng));
  }
  return BSplineSurfaced(ctrl, n, n, 3);
}

}  // namespace

TEST_CASE("surfaces: derivatives match finite differences", "[geometry]") {
  std::mt19937 rng(12);
  check_derivatives(SineSurfaced{}, rng);
  check_derivatives(Sphere{}, rng);
  check_derivatives(InsideCylinder{}, rng);
  check_derivatives(wavy_bspline(rng), rng);
  Planed plane;
  plane.du = Vec3d(1, 1, 0).normalized();
  plane.dv = Vec3d(0, 0, 1);
  check_derivatives(plane, rng);
}

TEST_CASE("surfaces: B-spline interpolates its corners and reproduces a plane", "[geometry]") {
  std::vector<Vec3d> ctrl;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 6; ++j) ctrl.emplace_back(2.0 * i, 3.0 * j, 0.5 * i - 0.25 * j + 1.0);
  }
  const BSplineSurfaced b(ctrl, 5, 6, 3);
  CHECK((b.jet(0, 0).p - ctrl.front()).norm() < 1e-12);
  CHECK((b.jet(1, 1).p - ctrl.back()).norm() < 1e-12);
  // Control points on a plane give the plane: zero curvature, constant normal.
  const Vec3d n_plane = Vec3d(-0.5 / 2.0, 0.25 / 3.0, 1.0).normalized();
  for (double u : {0.1, 0.45, 0.9}) {
    for (double v : {0.05, 0.5, 0.77}) {
      const auto j = b.jet(u, v);
      CHECK((unit_normal(j) - n_plane).norm() < 1e-9);
      const auto pc = principal_curvatures(j);
      CHECK(std::abs(pc.k1) < 1e-9);
      CHECK(std::abs(pc.k2) < 1e-9);
    }
  }
}

TEST_CASE("surfaces: curvature of sphere and cylinder in closed form", "[geometry]") {
  const Sphere sphere;
  for (double u : {0.3, 2.0, 4.0}) {
    for (double v : {0.5, 1.5, 2.5}) {
      const auto pc = principal_curvatures(sphere.jet(u, v));
      // Convex seen from outside: both curvatures -1/r (bending away from the normal).
      CHECK(pc.k1 == Approx(-1.0 / sphere.r).margin(1e-12));
      CHECK(pc.k2 == Approx(-1.0 / sphere.r).margin(1e-12));
      CHECK((unit_normal(sphere.jet(u, v)) - sphere.jet(u, v).p / sphere.r).norm() < 1e-12);
    }
  }
  const InsideCylinder cyl;
  const auto j = cyl.jet(1.0, 4.0);
  const auto pc = principal_curvatures(j);
  // Inside of a cylinder: concave, k1 = +1/r around, k2 = 0 along the axis.
  CHECK(unit_normal(j).dot(Vec3d(-j.p.x(), -j.p.y(), 0.0)) > 0.0);
  CHECK(pc.k1 == Approx(1.0 / cyl.r).margin(1e-12));
  CHECK(pc.k2 == Approx(0.0).margin(1e-12));
  CHECK(std::abs(pc.d2.z()) == Approx(1.0).margin(1e-9));
  CHECK(normal_curvature(pc, Vec3d(0, 0, 1)) == Approx(0.0).margin(1e-12));
}

TEST_CASE("surfaces: the sine part's extremes are those documented in data/README.md",
          "[geometry]") {
  const SineSurfaced s;
  double max_tilt = 0.0, max_k = 0.0;
  for (int i = 0; i <= 8000; ++i) {
    const auto j = s.jet(5.0, 80.0 * i / 8000.0);
    max_tilt = std::max(max_tilt, rad_to_deg(std::acos(unit_normal(j).z())));
    max_k = std::max(max_k, principal_curvatures(j).k1);
  }
  CHECK(max_tilt ==
        Approx(rad_to_deg(std::atan(2 * Constants<double>::pi() * 10.0 / 40.0))).margin(1e-3));
  CHECK(1.0 / max_k ==
        Approx(1600.0 / (4 * Constants<double>::pi() * Constants<double>::pi() * 10.0))
            .epsilon(1e-4));
}

TEST_CASE("generator: side step, step length and tilt follow eq. 8-11", "[geometry][generator]") {
  RasterOptions o;
  const SineSurfaced s;
  const auto pts = generate_raster(s, o);
  // Passes: x advances by 2 sqrt(2 h R) (flat across), the last pass at the edge.
  std::vector<double> xs;
  for (const auto& p : pts) {
    if (!p.rapid && (xs.empty() || std::abs(p.cc_mm.x() - xs.back()) > 1e-9))
      xs.push_back(p.cc_mm.x());
  }
  const double side = 2.0 * std::sqrt(2.0 * o.scallop_mm * o.tool_radius_mm);
  REQUIRE(xs.size() == static_cast<std::size_t>(std::ceil(20.0 / side)) + 1);
  for (std::size_t i = 1; i + 1 < xs.size(); ++i) CHECK(xs[i] - xs[i - 1] == Approx(side));
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const auto& a = pts[i - 1];
    const auto& b = pts[i];
    if (a.rapid || b.rapid) continue;
    // Chord error of each step within the tolerance (circle of the local radius).
    const double chord = (b.cc_mm - a.cc_mm).norm();
    const double k = std::abs(principal_curvatures(s.jet(a.cc_mm.x(), a.cc_mm.y())).k1);
    if (k > 1e-9)
      CHECK(1.0 / k - std::sqrt(1.0 / (k * k) - chord * chord / 4.0) <= o.chord_error_mm * 1.05);
    CHECK(chord <= o.max_step_mm + 1e-9);
  }
  for (const auto& p : pts) {
    if (p.rapid) continue;
    // Ball centre and contact point (eq. 5) and the 5 deg tilt towards the feed (+y).
    CHECK((p.tip_mm + o.tool_radius_mm * p.axis - (p.cc_mm + o.tool_radius_mm * p.normal)).norm() <
          1e-9);
    CHECK(rad_to_deg(angle_between(p.axis, p.normal)) == Approx(5.0).margin(1e-9));
    CHECK(p.axis.x() == Approx(0.0).margin(1e-12));
    const Vec3d t = Vec3d(0, 1, 0) - Vec3d(0, 1, 0).dot(p.normal) * p.normal;
    CHECK((p.axis - p.normal).dot(t) > 0.0);
    CHECK_FALSE(p.gouges);
  }
}

TEST_CASE("generator: eq. 8 narrows, eq. 9 widens the side step on curved ground",
          "[geometry][generator]") {
  // Passes along v = y on a sine along x (u): curvature across the path.
  struct Across {
    double u_min() const { return 0.0; }
    double u_max() const { return 10.0; }
    double v_min() const { return 0.0; }
    double v_max() const { return 4.0; }
    SurfaceJet<double> jet(double u, double v) const {
      const double h = 2.0, w = 0.3;
      SurfaceJet<double> j;
      j.p = Vec3d(u, v, h * std::cos(w * u));
      j.su = Vec3d(1, 0, -h * w * std::sin(w * u));
      j.sv = Vec3d(0, 1, 0);
      j.suu = Vec3d(0, 0, -h * w * w * std::cos(w * u));
      j.suv = j.svv = Vec3d::Zero();
      return j;
    }
  };
  RasterOptions o;
  const auto pts = generate_raster(Across{}, o);
  const double flat = 2.0 * std::sqrt(2.0 * o.scallop_mm * o.tool_radius_mm);
  // The first pass sits on the convex crest (rho = 1 / (h w^2) = 5.56 mm): eq. 8.
  const double rho = 1.0 / (2.0 * 0.09);
  double second_x = -1.0;
  for (const auto& p : pts) {
    if (!p.rapid && p.cc_mm.x() > 1e-9) {
      second_x = p.cc_mm.x();
      break;
    }
  }
  // Arc length across to the second pass is the eq. 8 step (|S_u| = 1 at the crest).
  CHECK(second_x == Approx(flat * rho / (rho + o.tool_radius_mm)).epsilon(1e-6));
}

TEST_CASE("generator: eq. 11 turns the axis by tilt about K and yaw about N",
          "[geometry][generator]") {
  const Vec3d n(0, 0, 1), t(1, 0, 0);
  const Vec3d v = axis_from_tilt_yaw(n, t, deg_to_rad(30.0), deg_to_rad(90.0));
  // Tilt 30 towards the feed (+x), then yaw 90 about N: towards +y.
  CHECK((v - Vec3d(0, 0.5, std::sqrt(3.0) / 2)).norm() < 1e-12);
}

TEST_CASE(
    "surface: the bump's and the saddle's jets are their heightfields' derivatives, and the "
    "saddle bends by h / a^2 across and -h / b^2 along at its centre",
    "[geometry][surface]") {
  std::mt19937 rng(4403);
  std::uniform_real_distribution<double> ux(0.0, 20.0), uy(0.0, 80.0);
  const BumpField<double> bump{10.0, 10.0, 10.0, 40.0};
  const SaddleField<double> saddle{10.0, 10.0, 40.0, 10.0, 40.0};
  const double h = 1e-5;
  const auto check = [&](const auto& field) {
    for (int k = 0; k < 50; ++k) {
      const double x = ux(rng), y = uy(rng);
      const auto f = field.at(x, y);
      const auto fxp = field.at(x + h, y), fxm = field.at(x - h, y);
      const auto fyp = field.at(x, y + h), fym = field.at(x, y - h);
      INFO("x " << x << " y " << y);
      CHECK(f[1] == Approx((fxp[0] - fxm[0]) / (2 * h)).margin(1e-6));
      CHECK(f[2] == Approx((fyp[0] - fym[0]) / (2 * h)).margin(1e-6));
      CHECK(f[3] == Approx((fxp[1] - fxm[1]) / (2 * h)).margin(1e-6));
      CHECK(f[4] == Approx((fyp[1] - fym[1]) / (2 * h)).margin(1e-6));
      CHECK(f[5] == Approx((fyp[2] - fym[2]) / (2 * h)).margin(1e-6));
    }
  };
  check(bump);
  check(saddle);
  const HeightfieldSurface<double, SaddleField<double>> s{{0.0, 20.0, 0.0, 80.0}, saddle};
  const PrincipalCurvatures<double> pc = principal_curvatures(s.jet(10.0, 40.0));
  CHECK(pc.k1 == Approx(10.0 / 100.0));
  CHECK(pc.k2 == Approx(-10.0 / 1600.0));
  // The bump's top is convex by h / sigma^2 both ways.
  const HeightfieldSurface<double, BumpField<double>> b{{0.0, 20.0, 0.0, 80.0}, bump};
  const PrincipalCurvatures<double> top = principal_curvatures(b.jet(10.0, 40.0));
  CHECK(top.k1 == Approx(-0.1));
  CHECK(top.k2 == Approx(-0.1));
}
