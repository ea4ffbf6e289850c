// The C-space grid: the exact face-versus-cylinder test against FCL, closed forms, and the
// fast rasteriser against one FCL query per cell on parts no test was tuned on.
#include <catch2/catch.hpp>
#include <random>

#include "cspace/triangle_tests.hpp"
#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/cspace/cspace.hpp"
#include "taxopt/io/cl_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

TriangleMesh one_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  TriangleMesh m;
  m.vertices = {a, b, c};
  m.faces = {{0, 1, 2}};
  return m;
}

struct HeightSurface {
  const Heightfield* hf;
  double u_min() const { return -10.0; }
  double u_max() const { return 60.0; }
  double v_min() const { return -10.0; }
  double v_max() const { return 60.0; }
  SurfaceJet<double> jet(double u, double v) const {
    SurfaceJet<double> j;
    j.p = Vec3d(u, v, hf->z(u, v));
    return j;
  }
};

/// A random height field's surface over [-10, 60]^2 as n x n cells of two triangles.
TriangleMesh height_mesh(const Heightfield& hf, int n) {
  const HeightSurface s{&hf};
  return tessellate(s, n, n);
}

}  // namespace

TEST_CASE("cspace: the exact face-cylinder test agrees with FCL", "[cspace]") {
  std::mt19937 rng(404);
  std::uniform_real_distribution<double> u(-6.0, 6.0), ur(0.3, 3.0);
  std::normal_distribution<double> nd(0.0, 1.0);
  int hits = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3d dir = Vec3d(nd(rng), nd(rng), nd(rng)).normalized();
    const double r = ur(rng), start = 0.5 * ur(rng), end = start + 4.0 * ur(rng);
    const CollisionModel fcl(one_triangle(a, b, c));
    ToolModel tool;
    tool.ball_radius_mm = r;
    tool.bodies = {{r, start, end}};
    const bool f = fcl.collides(tool, Vec3d::Zero(), dir);
    // Compare away from grazing contact: shrunk and grown by 1e-6 relative.
    if (triangle_meets_cylinder(a, b, c, Vec3d::Zero(), dir, r * (1 - 1e-6), start * (1 + 1e-6),
                                end * (1 - 1e-6))) {
      REQUIRE(f);
    }
    if (f) {
      REQUIRE(triangle_meets_cylinder(a, b, c, Vec3d::Zero(), dir, r * (1 + 1e-6),
                                      start * (1 - 1e-6), end * (1 + 1e-6)));
    }
    hits += f ? 1 : 0;
  }
  CHECK(hits > 300);  // both outcomes well represented
  CHECK(hits < 2700);
}

TEST_CASE("cspace: the grid's cells, mirror and sizes", "[cspace]") {
  const CSpaceGrid g(2.0);
  CHECK(g.tilt_cells() == 90);
  CHECK(g.yaw_cells() == 180);
  CHECK(rad_to_deg(g.tilt_rad(0)) == Approx(-89.0));
  CHECK(rad_to_deg(g.yaw_rad(179)) == Approx(179.0));
  CHECK_THROWS_AS(CSpaceGrid(7.0), InputError);
  CHECK_THROWS_AS(CSpaceGrid(0.0), InputError);
}

TEST_CASE("cspace: on a flat part the free cells are the tilts below the holder's closed form",
          "[cspace]") {
  // Plane z = 0 on a 10 mm grid, 400 mm square; contact at the origin, N = +z.
  TriangleMesh plane;
  const int n = 40;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j)
      plane.vertices.emplace_back(-200.0 + 10.0 * i, -200.0 + 10.0 * j, 0.0);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j;
      plane.faces.push_back({a, a + n + 1, a + n + 2});
      plane.faces.push_back({a, a + n + 2, a + 1});
    }
  }
  const Part part(plane);
  const Tool t = Tool::ball_end_mill(6.0, 15.0);
  ToolOverrides o;
  o.gauge_length_mm = 40.0;
  o.holder_radius_mm = 20.0;
  const ToolModel tool = ToolModel::ball_end(t, o);
  ContactPoint cp;
  cp.state = ContactState::Touching;
  cp.normal = Vec3d::UnitZ();
  cp.feed_dir = Vec3d::UnitX();
  cp.side = Vec3d::UnitY();
  const Vec3d centre(0, 0, 3.0);
  // The holder's lowest rim reaches the plane at 3 + 37 cos a = 20 sin a.
  double lo = 0.0, hi = 1.5;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (20.0 * std::sin(mid) - 3.0 - 37.0 * std::cos(mid) < 0 ? lo : hi) = mid;
  }
  const double a_star_deg = rad_to_deg(lo);
  CSpaceOptions opt;
  opt.cell_deg = 3.0;
  opt.max_deviation_deg = 89.9;
  const CSpaceGrid g = rasterise_free_axes(part, tool, cp, centre, Vec3d::UnitZ(), opt);
  for (int i = 0; i < g.tilt_cells(); ++i) {
    const double tilt = std::abs(rad_to_deg(g.tilt_rad(i)));
    for (int j = 0; j < g.yaw_cells(); ++j) {
      INFO("tilt " << tilt << " a* " << a_star_deg);
      REQUIRE(g.free(i, j) == (tilt < a_star_deg));
    }
  }
  // The free axes in workpiece and machine coordinates: each once, below a*, and the poses
  // give the same axes back (A within the default machine's range).
  const std::vector<Vec3d> axes = free_axes_of(g, cp);
  CHECK(axes.size() == g.free_count() / 2);
  for (const Vec3d& v : axes) {
    CHECK(v.norm() == Approx(1.0));
    CHECK(rad_to_deg(angle_between(v, cp.normal)) < a_star_deg);
  }
  const MachineKinematicsd m = default_machine_kinematics();
  const std::vector<Posed> poses = free_poses_of(g, cp, m);
  REQUIRE(poses.size() == axes.size());
  for (std::size_t k = 0; k < axes.size(); ++k) {
    CHECK(angle_between(m.forward(poses[k]), axes[k]) < 1e-9);
    CHECK(m.tilt.contains(poses[k].tilt_rad));
  }
  // The deviation cone bounds the free set too.
  opt.max_deviation_deg = 20.0;
  const CSpaceGrid w = rasterise_free_axes(part, tool, cp, centre, Vec3d::UnitZ(), opt);
  for (int i = 0; i < w.tilt_cells(); ++i) {
    for (int j = 0; j < w.yaw_cells(); ++j) {
      REQUIRE(w.free(i, j) == (std::abs(rad_to_deg(w.tilt_rad(i))) <= 20.0));
    }
  }
}

TEST_CASE("cspace: the fast rasteriser matches one FCL query per cell on unseen parts",
          "[cspace][integration]") {
  std::mt19937 rng(777);
  std::uniform_int_distribution<int> pick(0, 1 << 30);
  std::size_t cells = 0, free_fast = 0, only_brute = 0;
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const TriangleMesh mesh = height_mesh(hf, 70);
    const Part part(mesh);
    const CollisionModel fcl(mesh);
    const GeneratedCl g = raster_cl(hf, 3.0, 10.0, 1, 1.0, 25.0, 25.0, 5.0, 45.0);
    const Toolpath tp = parse_cl(g.text, "gen.cls");
    const Operationd& op = tp.operations[0];
    const auto contacts = recover_contacts(part, op, 3.0);
    const Tool t = Tool::ball_end_mill(6.0, 15.0);
    ToolOverrides o;
    o.gauge_length_mm = 35.0;
    o.shank_radius_mm = 4.0;
    o.holder_radius_mm = 12.0;
    o.holder_length_mm = 30.0;
    const ToolModel tool = ToolModel::ball_end(t, o);
    CSpaceOptions opt;
    for (int trial = 0; trial < 4; ++trial) {
      // Coarse cells over a wide window, and the fine cells the optimisers use (the spans of
      // the occlusion map are rounded per cell: both must agree with FCL).
      opt.cell_deg = trial < 3 ? 5.0 : 1.5;
      opt.max_deviation_deg = trial < 3 ? 45.0 : 30.0;
      const std::size_t i = static_cast<std::size_t>(pick(rng)) % op.points.size();
      if (contacts[i].state != ContactState::Touching) continue;
      const Vec3d c = op.points[i].tip_mm + 3.0 * op.points[i].axis;
      const CSpaceGrid fast =
          rasterise_free_axes(part, tool, contacts[i], c, op.points[i].axis, opt);
      const CSpaceGrid brute =
          brute_force_free_axes(fcl, tool, contacts[i], c, op.points[i].axis, opt);
      for (int a = 0; a < fast.tilt_cells(); ++a) {
        for (int b = 0; b < fast.yaw_cells(); ++b) {
          ++cells;
          // Never free where FCL finds the pose colliding.
          if (fast.free(a, b)) {
            REQUIRE(brute.free(a, b));
            ++free_fast;
          }
          only_brute += (brute.free(a, b) && !fast.free(a, b)) ? 1 : 0;
        }
      }
    }
  }
  CHECK(free_fast > 200);
  // Blocked by the exact test but free for FCL: grazing contacts only, a tiny share.
  CHECK(only_brute <= free_fast / 200);
}

TEST_CASE("cspace: the tree's one-pose check agrees with FCL on unseen parts",
          "[cspace][integration]") {
  // The optimisers and the guard ask CSpaceRasteriser::collides; every output is verified with
  // FCL. A pose the tree calls free must be free for FCL, or a run would fail its verification.
  std::mt19937 rng(2611);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::size_t queries = 0, hits = 0, tree_free_fcl_hit = 0, tree_hit_fcl_free = 0;
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const TriangleMesh mesh = height_mesh(hf, 60);
    const CollisionModel fcl(mesh);
    const CSpaceRasteriser tree(mesh);
    const Tool t = Tool::ball_end_mill(6.0, 15.0);
    ToolOverrides o;
    o.gauge_length_mm = 30.0 + 20.0 * u01(rng);
    o.shank_radius_mm = 3.0 + 2.0 * u01(rng);
    o.holder_radius_mm = 10.0 + 6.0 * u01(rng);
    o.holder_length_mm = 30.0;
    const ToolModel tool = ToolModel::ball_end(t, o).judged({0.01, 0.5, 1.0});
    for (int q = 0; q < 1500; ++q) {
      // A ball centre at or near the surface (in the air or cutting into it), an axis within
      // 80 deg of straight up.
      const double x = 5.0 + 40.0 * u01(rng), y = 5.0 + 40.0 * u01(rng);
      const Vec3d centre(x, y, hf.z(x, y) + 1.0 + 4.0 * u01(rng));
      const double tilt = deg_to_rad(80.0) * u01(rng), yaw = deg_to_rad(360.0) * u01(rng);
      const Vec3d axis(std::sin(tilt) * std::cos(yaw), std::sin(tilt) * std::sin(yaw),
                       std::cos(tilt));
      const bool with_ball = q % 2 == 0;
      const bool f = fcl.collides(tool, centre, axis, with_ball);
      const bool r = tree.collides(tool, centre, axis, with_ball);
      ++queries;
      hits += f ? 1 : 0;
      tree_free_fcl_hit += (f && !r) ? 1 : 0;
      tree_hit_fcl_free += (r && !f) ? 1 : 0;
    }
  }
  INFO(queries << " queries, " << hits << " hits");
  CHECK(hits > queries / 10);
  CHECK(hits < queries - queries / 10);
  CHECK(tree_free_fcl_hit == 0);
  CHECK(tree_hit_fcl_free <= queries / 1000);
}

TEST_CASE("cspace: the tree's one-pose check is every face's own test with the tree only skipping",
          "[cspace]") {
  // collides walks the tree and drops a node by its sphere or its slab (the planes its faces
  // lie between); neither may drop a face the exact tests would find: the verdict is the
  // verdict of every face tested in turn, for the bodies, the ball, and bodies grown past the
  // ball centre as the move sweeps grow them.
  std::mt19937 rng(6502);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::size_t queries = 0, hits = 0;
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const TriangleMesh mesh = height_mesh(hf, 40);
    const CSpaceRasteriser tree(mesh);
    for (int q = 0; q < 400; ++q) {
      ToolModel tool;
      tool.ball_radius_mm = 1.0 + 3.0 * u01(rng);
      const double grow = q % 3 == 0 ? 2.0 * u01(rng) : 0.0;
      tool.bodies.push_back({tool.ball_radius_mm + grow, -grow, 10.0 + grow});
      tool.bodies.push_back(
          {tool.ball_radius_mm + 1.0 + grow, 10.0 - grow, 10.0 + 30.0 * u01(rng)});
      const double x = 5.0 + 40.0 * u01(rng), y = 5.0 + 40.0 * u01(rng);
      const Vec3d centre(x, y, hf.z(x, y) + 6.0 * u01(rng) - 0.5);
      const double tilt = deg_to_rad(100.0) * u01(rng), yaw = deg_to_rad(360.0) * u01(rng);
      const Vec3d axis(std::sin(tilt) * std::cos(yaw), std::sin(tilt) * std::sin(yaw),
                       std::cos(tilt));
      const bool with_ball = q % 2 == 0;
      bool every_face = false;
      for (const auto& f : mesh.faces) {
        const Vec3d& a = mesh.vertices[static_cast<std::size_t>(f[0])];
        const Vec3d& b = mesh.vertices[static_cast<std::size_t>(f[1])];
        const Vec3d& c = mesh.vertices[static_cast<std::size_t>(f[2])];
        if (with_ball && detail::squared_distance_to_triangle(centre, a, b, c) <=
                             tool.ball_radius_mm * tool.ball_radius_mm) {
          every_face = true;
        }
        for (const ToolBody& body : tool.bodies) {
          every_face = every_face || triangle_meets_cylinder(a, b, c, centre, axis, body.radius_mm,
                                                             body.start_mm, body.end_mm);
        }
        if (every_face) break;
      }
      INFO("query " << q);
      REQUIRE(tree.collides(tool, centre, axis, with_ball) == every_face);
      ++queries;
      hits += every_face ? 1 : 0;
    }
  }
  CHECK(hits > queries / 5);
  CHECK(hits < queries - queries / 5);
}
