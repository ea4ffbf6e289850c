// Contacts on CAD-style meshes (tests/test_paper_method.cpp): big flat facets beside thin fillet
// strips, as CAD systems export them (binary STL). The contact is the mesh's exact nearest point to
// the ball centre, its normal the true face or edge normal; the default tolerance comes from the
// mesh's chordal error, not its facets' size. Checked against a brute-force nearest point written
// here (no CGAL).
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "support.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// A convex prism extruded along y over [y0, y1]: its profile in xz is a flat top at z = 0 from
/// x0 to x1 - r, a convex quarter fillet of radius r in `strips` chords down to (x1, -r), a
/// vertical side to -h, the bottom and the sharp left side. Each profile segment is one quad of
/// two triangles over the whole length (CAD-style: 60 mm facets beside 0.5 mm strips); with
/// `fine` the top is cut into a grid of 1 mm quads instead.
TriangleMesh cad_prism(double x0, double x1, double y0, double y1, double h, double r, int strips,
                       bool fine = false) {
  std::vector<Eigen::Vector2d> profile;  // (x, z), counter-clockwise seen from -y
  if (fine) {
    for (double x = x0; x < x1 - r - 1e-9; x += 1.0) profile.emplace_back(x, 0.0);
  } else {
    profile.emplace_back(x0, 0.0);
  }
  for (int k = 0; k <= strips; ++k) {
    const double t = 0.5 * M_PI * k / strips;
    profile.emplace_back(x1 - r + r * std::sin(t), -r + r * std::cos(t));
  }
  profile.emplace_back(x1, -h);
  profile.emplace_back(x0, -h);
  return extruded_profile(profile, y0, y1, fine ? static_cast<int>(std::round(y1 - y0)) : 1);
}

/// The mesh as a CAD system exports it: binary STL (float32), read back.
TriangleMesh via_binary_stl(const TriangleMesh& m, const TempDir& dir, const std::string& name) {
  write_file(dir.path(name), format_stl_binary(m));
  return read_mesh_file(dir.path(name));
}

Operationd pass_of(const std::vector<Vec3d>& tips, const std::vector<Vec3d>& axes) {
  Operationd op;
  op.tool = Tool::ball_end_mill(6.0, 30.0);
  for (std::size_t i = 0; i < tips.size(); ++i) {
    CLPointd p;
    p.tip_mm = tips[i];
    p.axis = axes[i];
    p.feed_mm_per_min = 1000.0;
    p.motion = i == 0 ? Motion::Rapid : Motion::Feed;
    op.points.push_back(p);
  }
  return op;
}

}  // namespace

TEST_CASE(
    "cad contacts: a ball on a two-triangle 60 mm top beside a 4 mm fillet in 12 strips touches "
    "where it stands, with the top's normal",
    "[geometry][contact][cad]") {
  TempDir dir;
  const TriangleMesh mesh = via_binary_stl(cad_prism(-40, 20, -30, 30, 30, 4, 12), dir, "p.stl");
  const Part part(mesh);
  const double R = 3.0;
  // A vertical tool on the flat top, then across it and over the fillet's first strips.
  std::vector<Vec3d> tips, axes;
  for (double x = -19.8; x <= 19.0; x += 0.2) {
    // On the top the tip is on it; over the fillet the ball rides the true arc (centre at
    // distance r + R from the fillet's axis).
    const double xc = 16.0;
    Vec3d centre(x, -10.0, R);
    if (x > xc) {
      const double phi = std::asin(std::min(1.0, (x - xc) / (4.0 + R)));
      centre = Vec3d(xc + (4.0 + R) * std::sin(phi), -10.0, -4.0 + (4.0 + R) * std::cos(phi));
    }
    tips.push_back(centre - R * Vec3d::UnitZ());
    axes.push_back(Vec3d::UnitZ());
  }
  const Operationd op = pass_of(tips, axes);
  const auto contacts = recover_contacts(part, op, R);
  // The first point: the case.
  REQUIRE(contacts[0].state == ContactState::Touching);
  CHECK((contacts[0].cc_mm - Vec3d(-19.8, -10.0, 0.0)).norm() < 1e-5);
  CHECK((contacts[0].normal - Vec3d::UnitZ()).norm() < 1e-9);
  CHECK(contacts[0].curvature_from == CurvatureSource::Facet);
  CHECK(contacts[0].curvature.k1 == 0.0);
  double worst = 0.0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const Vec3d centre = tips[i] + R * axes[i];
    const Vec3d exact = brute_nearest(mesh, centre);
    worst = std::max(worst, (contacts[i].cc_mm - exact).norm());
    CHECK(contacts[i].state == ContactState::Touching);
    CHECK(std::abs((centre - contacts[i].cc_mm).norm() - R) <= contact_tolerance_mm(part, {}));
  }
  CHECK(worst <= 1e-6);
  // The designed surface's normal: the top's on the top however big its facets (a corner
  // normal mixed with the fillet's strips would tilt the whole 60 mm facet), the arc's on the
  // fillet within half a strip's turn (3.75 deg / 2).
  double worst_top = 0.0, worst_fillet = 0.0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const Vec3d centre = tips[i] + R * axes[i];
    if (centre.x() <= 16.0) {
      worst_top = std::max(
          worst_top, rad_to_deg(angle_between(contacts[i].surface_normal, Vec3d(Vec3d::UnitZ()))));
    } else {
      const Vec3d truth = (centre - Vec3d(16.0, centre.y(), -4.0)).normalized();
      worst_fillet =
          std::max(worst_fillet, rad_to_deg(angle_between(contacts[i].surface_normal, truth)));
    }
    CHECK(contacts[i].place == SurfacePlace::Smooth);
  }
  CHECK(worst_top <= 0.01);
  CHECK(worst_fillet <= 0.5 * 7.5 / 2.0);
  // The default tolerance: the fillet strips' chordal error is 4 (1 - cos 3.75 deg) = 0.0086 mm,
  // below the 0.05 mm floor; the same part with a top of 1 mm facets has the same.
  const Part fine(via_binary_stl(cad_prism(-40, 20, -30, 30, 30, 4, 12, true), dir, "f.stl"));
  CHECK(contact_tolerance_mm(part, {}) == Approx(0.05));
  CHECK(contact_tolerance_mm(fine, {}) == Approx(0.05));
  CHECK(part.chordal_error_mm() == Approx(fine.chordal_error_mm()).epsilon(0.05));
  CHECK(part.chordal_error_mm() < 0.02);
  CHECK(part.mean_edge_mm() > 10.0 * fine.mean_edge_mm() / 2.0);
}

TEST_CASE(
    "cad contacts: on random CAD-style prisms every contact is the exact nearest point, its "
    "normal the true face or edge normal, and the segment lengths are the exact ones",
    "[geometry][contact][cad][property]") {
  std::mt19937 rng(2034);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TempDir dir;
  for (int trial = 0; trial < 6; ++trial) {
    const double L = 30.0 + 60.0 * u(rng), r = 1.0 + 6.0 * u(rng);
    const int strips = 3 + static_cast<int>(14 * u(rng));
    const TriangleMesh mesh =
        via_binary_stl(cad_prism(-L / 2, L / 2, -25, 25, 20, r, strips), dir, "r.stl");
    INFO("trial " << trial << " L " << L << " r " << r << " strips " << strips);
    const Part part(mesh);
    const double R = 1.0 + 4.0 * u(rng);
    // Outward normals of a convex solid point away from an inner point.
    const Vec3d inner(0.0, 0.0, -10.0);
    // Balls placed on the mesh: at a random point of a random facet (or edge) the centre
    // along its normal (or an edge's blend of normals) at R: convex, so that is its nearest.
    std::vector<Vec3d> tips, axes, want_cc, want_n;
    std::vector<bool> on_crease;  // rolling over an edge of 30 deg or more
    for (int k = 0; k < 300; ++k) {
      const auto& f = mesh.faces[static_cast<std::size_t>(rng() % mesh.faces.size())];
      const Vec3d a = mesh.vertices[static_cast<std::size_t>(f[0])];
      const Vec3d b = mesh.vertices[static_cast<std::size_t>(f[1])];
      const Vec3d c = mesh.vertices[static_cast<std::size_t>(f[2])];
      Vec3d n = (b - a).cross(c - a).normalized();
      if (n.dot(a - inner) < 0.0) n = -n;
      double s = u(rng), t = u(rng);
      if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;
      Vec3d p = a + s * (b - a) + t * (c - a);
      if (k % 5 == 0) {
        // On an edge: between the normals of its two faces.
        p = a + u(rng) * (b - a);
        const Vec3d mid = 0.5 * (a + b);
        Vec3d other = n;
        for (int g : part.faces_within(mid, 1e-6)) {
          const auto& fg = mesh.faces[static_cast<std::size_t>(g)];
          const Vec3d ga = mesh.vertices[static_cast<std::size_t>(fg[0])];
          const Vec3d gn = (mesh.vertices[static_cast<std::size_t>(fg[1])] - ga)
                               .cross(mesh.vertices[static_cast<std::size_t>(fg[2])] - ga)
                               .normalized();
          const Vec3d out = gn.dot(ga - inner) < 0.0 ? Vec3d(-gn) : gn;
          if ((out - n).norm() > 1e-9) other = out;
        }
        const double blend = u(rng);
        on_crease.push_back(angle_between(n, other) >= deg_to_rad(30.0) && blend > 0.01 &&
                            blend < 0.99);
        n = (n + blend * (other - n)).normalized();
      } else {
        on_crease.push_back(false);
      }
      // A tool axis within 40 deg of the normal.
      const Vec3d axis = (n + 0.8 * u(rng) * n.unitOrthogonal()).normalized();
      const Vec3d centre = p + R * n;
      tips.push_back(centre - R * axis);
      axes.push_back(axis);
      want_cc.push_back(brute_nearest(mesh, centre));
      want_n.push_back((centre - want_cc.back()).normalized());
    }
    const Operationd op = pass_of(tips, axes);
    const auto contacts = recover_contacts(part, op, R);
    double worst_cc = 0.0, worst_n = 0.0, worst_len = 0.0;
    std::size_t creases = 0;
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      REQUIRE(contacts[i].state == ContactState::Touching);
      // Rolling over a designed edge: a feature, and the designed surface's contact is the
      // exact one there.
      if (on_crease[i]) {
        ++creases;
        CHECK(contacts[i].place != SurfacePlace::Smooth);
        CHECK((contacts[i].surface_normal - contacts[i].normal).norm() < 1e-12);
        CHECK((contacts[i].surface_cc_mm - contacts[i].cc_mm).norm() < 1e-12);
      }
      worst_cc = std::max(worst_cc, (contacts[i].cc_mm - want_cc[i]).norm());
      worst_n = std::max(worst_n, rad_to_deg(angle_between(contacts[i].normal, want_n[i])));
      if (i > 0) {
        worst_len =
            std::max(worst_len, std::abs((contacts[i].cc_mm - contacts[i - 1].cc_mm).norm() -
                                         (want_cc[i] - want_cc[i - 1]).norm()));
      }
    }
    CHECK(worst_cc <= 0.01);
    CHECK(worst_n <= 0.01);
    CHECK(worst_len <= 0.02);
    CHECK(creases > 3);
  }
}
