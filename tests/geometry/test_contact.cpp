// Contact recovery on meshes of analytic surfaces: against the analytic contact points,
// normals and curvatures, and the tilt/yaw the CL file was made with.
#include <catch2/catch.hpp>
#include <random>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"
#include "taxopt/io/cl_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

TEST_CASE(
    "contact: on unseen heightfield meshes at 0.5 mm the contact is the mesh's exact nearest "
    "point, its error against the analytic surface the mesh's own, and the designed surface's "
    "normal a tenth of it",
    "[geometry][contact]") {
  std::mt19937 rng(31337);
  std::uniform_real_distribution<double> tilt(5.0, 15.0), yoff(-5.0, 5.0);
  for (int trial = 0; trial < 2; ++trial) {
    for (const Heightfield& hf : random_heightfields(rng)) {
      INFO(hf.name << " trial " << trial);
      const TriangleMesh mesh = heightfield_mesh(hf, 0.5);
      const Part part(mesh);
      const double tilt_deg = tilt(rng);
      const double y = 25.0 + yoff(rng);
      const GeneratedCl g = raster_cl(hf, 3.0, tilt_deg, 3, 0.5, y - 3.0, y + 3.0, 2.0, 48.0);
      const Toolpath tp = parse_cl(g.text, "gen.cls");
      const Operationd& op = tp.operations.at(0);
      const auto contacts = recover_contacts(part, op, 3.0);
      REQUIRE(contacts.size() == g.tips_mm.size());
      const double tol = contact_tolerance_mm(part, {});
      double worst_excess_n = 0, worst_excess_cc = 0, worst_excess_tilt = 0, worst_gap = 0;
      // The designed surface's estimate against the facets' own error, on the same mesh.
      double worst_s = 0, sum_s = 0, worst_facet = 0, sum_facet = 0, worst_cc_s = 0;
      std::size_t touching = 0;
      for (std::size_t i = 0; i < contacts.size(); ++i) {
        if (g.rapid[i]) {
          CHECK(contacts[i].state == ContactState::InAir);
          continue;
        }
        REQUIRE(contacts[i].state == ContactState::Touching);
        ++touching;
        const Vec3d centre = g.tips_mm[i] + 3.0 * g.axes[i];
        // Exact: the nearest point of the mesh to the ball centre (of the point as read), the
        // normal towards the centre.
        const Vec3d read = op.points[i].tip_mm + 3.0 * op.points[i].axis;
        worst_gap = std::max(worst_gap, std::abs((read - contacts[i].cc_mm).norm() - 3.0));
        CHECK((contacts[i].normal - (read - contacts[i].cc_mm).normalized()).norm() < 1e-9);
        CHECK((contacts[i].cc_mm - part.closest(read).point).norm() < 1e-12);
        // Truth: the analytic contact, the point whose normal passes through the centre.
        Vec3d n_true = Vec3d::UnitZ();
        double x = centre.x(), yy = centre.y();
        for (int it = 0; it < 50; ++it) {
          n_true = hf.normal(x, yy);
          const Vec3d p = centre - 3.0 * n_true;
          x = p.x();
          yy = p.y();
        }
        const Vec3d cc_true(x, yy, hf.z(x, yy));
        // The mesh's own error there: the normals of the facets the contact lies on against
        // the analytic normal. The exact normal lies among them (inside a facet it is the
        // facet's; on an edge or vertex between them), so it errs no more than they do.
        double facet_err = 0.0;
        for (int f : part.faces_within(contacts[i].cc_mm, 1e-6)) {
          const auto& t = mesh.faces[static_cast<std::size_t>(f)];
          const Vec3d& a = mesh.vertices[static_cast<std::size_t>(t[0])];
          Vec3d fn = (mesh.vertices[static_cast<std::size_t>(t[1])] - a)
                         .cross(mesh.vertices[static_cast<std::size_t>(t[2])] - a)
                         .normalized();
          if (fn.dot(n_true) < 0.0) fn = -fn;
          facet_err = std::max(facet_err, angle_between(fn, n_true));
        }
        const double n_err = angle_between(contacts[i].normal, n_true);
        const double s_err = angle_between(contacts[i].surface_normal, n_true);
        worst_s = std::max(worst_s, s_err);
        sum_s += s_err;
        worst_cc_s = std::max(worst_cc_s, (contacts[i].surface_cc_mm - cc_true).norm());
        CHECK(contacts[i].place == SurfacePlace::Smooth);
        worst_excess_n = std::max(worst_excess_n, rad_to_deg(n_err - facet_err));
        // The contact moves with its normal: C - R N against C - R N_true.
        worst_excess_cc =
            std::max(worst_excess_cc, (contacts[i].cc_mm - cc_true).norm() -
                                          2.0 * 3.0 * std::sin(0.5 * n_err) - 2.0 * tol);
        worst_facet = std::max(worst_facet, facet_err);
        sum_facet += facet_err;
        // The tilt is the input axis's to the surface's normal: off by that normal's error.
        worst_excess_tilt =
            std::max(worst_excess_tilt,
                     std::abs(rad_to_deg(contacts[i].tilt_rad) - tilt_deg) - rad_to_deg(s_err));
      }
      CHECK(touching > 100);
      CHECK(worst_gap <= tol);
      CHECK(worst_excess_n <= 1e-6);
      CHECK(worst_excess_cc <= 1e-3);
      CHECK(worst_excess_tilt <= 0.01);
      // The smooth normal where it points at the centre: a tenth of the facets' error at
      // most, at most a quarter on average (measured: 0.29 deg against 3.45, 0.035 against
      // 0.41); the contact C - R n within R times that of the analytic one.
      CHECK(worst_s <= 0.1 * worst_facet);
      CHECK(sum_s <= 0.25 * sum_facet);
      CHECK(worst_cc_s <= 3.0 * 0.1 * worst_facet + 1e-6);
    }
  }
}

TEST_CASE("contact: jet-fitted curvature of sphere and cylinder meshes", "[geometry][contact]") {
  // Sphere of radius 20 from outside (convex: both curvatures -1/20).
  TriangleMesh sphere;
  const int nu = 240, nv = 120;
  for (int j = 0; j <= nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const double th = Constants<double>::pi() * j / nv, ph = Constants<double>::two_pi() * i / nu;
      sphere.vertices.emplace_back(20.0 * std::sin(th) * std::cos(ph),
                                   20.0 * std::sin(th) * std::sin(ph), 20.0 * std::cos(th));
    }
  }
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const int a = j * nu + i, b = j * nu + (i + 1) % nu, c = (j + 1) * nu + i,
                d = (j + 1) * nu + (i + 1) % nu;
      sphere.faces.push_back({a, c, d});
      sphere.faces.push_back({a, d, b});
    }
  }
  const Part sp(std::move(sphere));
  for (const Vec3d& dir : {Vec3d(1, 0.2, 0.3), Vec3d(-0.3, 1, -0.5), Vec3d(0.1, -0.4, 0.6)}) {
    const Vec3d q = 25.0 * dir.normalized();
    const LocalFit fit = sp.fit_towards(q);
    const auto pc = principal_curvatures(fit.jet);
    CHECK(pc.k1 == Approx(-0.05).epsilon(0.03));
    CHECK(pc.k2 == Approx(-0.05).epsilon(0.03));
    CHECK(fit.jet.p.norm() == Approx(20.0).margin(0.01));
    CHECK(rad_to_deg(angle_between(unit_normal(fit.jet), dir.normalized())) < 0.2);
  }
  // Inside of a cylinder of radius 10 about z (concave: +1/10 around, 0 along).
  TriangleMesh cyl;
  const int na = 360, nz = 40;
  for (int j = 0; j <= nz; ++j) {
    for (int i = 0; i < na; ++i) {
      const double ph = Constants<double>::two_pi() * i / na;
      cyl.vertices.emplace_back(10.0 * std::cos(ph), 10.0 * std::sin(ph), 0.5 * j);
    }
  }
  for (int j = 0; j < nz; ++j) {
    for (int i = 0; i < na; ++i) {
      const int a = j * na + i, b = j * na + (i + 1) % na, c = (j + 1) * na + i,
                d = (j + 1) * na + (i + 1) % na;
      cyl.faces.push_back({a, b, d});
      cyl.faces.push_back({a, d, c});
    }
  }
  const Part cp(std::move(cyl));
  const LocalFit fit = cp.fit_towards(Vec3d(6.0, 1.0, 10.0));
  const auto pc = principal_curvatures(fit.jet);
  CHECK(pc.k1 == Approx(0.1).epsilon(0.03));
  CHECK(pc.k2 == Approx(0.0).margin(0.003));
  CHECK(std::abs(pc.d2.z()) == Approx(1.0).margin(0.01));
}

TEST_CASE("contact: a CL file in the wrong units touches nothing -- a ball cutting in is named",
          "[geometry][contact][bad-input]") {
  std::mt19937 rng(8);
  const auto hfs = random_heightfields(rng);
  const Part part(heightfield_mesh(hfs[1], 0.5));
  const GeneratedCl g = raster_cl(hfs[1], 3.0, 5.0, 2, 0.5, 20.0, 24.0, 5.0, 40.0);
  ClReadOptions inch;
  inch.units = LengthUnit::Inch;
  const Toolpath wrong = parse_cl(g.text, "gen.cls", inch);
  std::size_t touching = 0;
  for (const auto& c : recover_contacts(part, wrong.operations[0], 3.0 * 25.4)) {
    touching += c.state == ContactState::Touching ? 1 : 0;
  }
  CHECK(touching == 0);
  Toolpath deep = parse_cl(g.text, "gen.cls");
  deep.operations[0].points[10].tip_mm -= 0.5 * deep.operations[0].points[10].axis;
  const auto c = recover_contacts(part, deep.operations[0], 3.0);
  CHECK(c[10].state == ContactState::Gouging);
  CHECK(c[10].gap_mm == Approx(-0.5).margin(0.02));
  CHECK(c[11].state == ContactState::Touching);
}
