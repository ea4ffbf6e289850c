// Collision checks against closed forms: the holder reaching a flat part, the shank reaching
// a vertical wall, and the tool model's bodies.
#include <catch2/catch.hpp>

#include "taxopt/core/error.hpp"
#include "taxopt/cspace/collision.hpp"

using namespace taxopt;

namespace {

/// A rectangle split into many triangles (FCL's BVH wants more than a couple).
TriangleMesh rectangle(const Vec3d& origin, const Vec3d& du, const Vec3d& dv, int n) {
  TriangleMesh m;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) m.vertices.push_back(origin + du * i / n + dv * j / n);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j;
      m.faces.push_back({a, a + n + 1, a + n + 2});
      m.faces.push_back({a, a + n + 2, a + 1});
    }
  }
  return m;
}

/// Bisection for the angle where f changes sign on [lo, hi] (f(lo) < 0 < f(hi)).
template <class F>
double root(F f, double lo, double hi) {
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

TEST_CASE("collision: on a flat part everything is free until the holder reaches it",
          "[cspace][collision]") {
  const CollisionModel part(
      rectangle(Vec3d(-150, -150, 0), Vec3d(300, 0, 0), Vec3d(0, 300, 0), 30));
  const Tool t = Tool::ball_end_mill(6.0, 15.0);
  ToolOverrides o;
  o.gauge_length_mm = 40.0;
  o.holder_radius_mm = 20.0;
  o.holder_length_mm = 40.0;
  const ToolModel tool = ToolModel::ball_end(t, o);
  // Ball centre R above the plane; the holder's lowest rim point is at
  // R + (gauge - R) cos a - r_h sin a: it reaches the plane at a*.
  const double a_star =
      root([](double a) { return 20.0 * std::sin(a) - 3.0 - 37.0 * std::cos(a); }, 0.0, 1.5);
  for (double yaw : {0.0, 1.0, 2.5}) {
    const auto axis = [yaw](double a) {
      return Vec3d(std::sin(a) * std::cos(yaw), std::sin(a) * std::sin(yaw), std::cos(a));
    };
    const Vec3d c(1.0, -2.0, 3.0);
    for (double tilt_deg = 0.0; tilt_deg < rad_to_deg(a_star) - 0.3; tilt_deg += 5.0) {
      CHECK_FALSE(part.collides(tool, c, axis(deg_to_rad(tilt_deg))));
    }
    CHECK_FALSE(part.collides(tool, c, axis(a_star - deg_to_rad(0.3))));
    CHECK(part.collides(tool, c, axis(a_star + deg_to_rad(0.3))));
    // Without a holder, the shank alone never reaches the plane below 90 deg.
    const ToolModel no_holder = ToolModel::ball_end(t, ToolOverrides{});
    CHECK_FALSE(part.collides(no_holder, c, axis(deg_to_rad(85.0))));
  }
}

TEST_CASE("collision: a vertical wall blocks the tilt band of the closed form",
          "[cspace][collision]") {
  // Wall x = D, tall; ball centre at the origin. Tilting towards the wall by a, the body's
  // farthest point is its top rim: x = L sin a + r cos a.
  const double D = 25.0;
  const CollisionModel wall(rectangle(Vec3d(D, -60, -20), Vec3d(0, 120, 0), Vec3d(0, 0, 140), 30));
  const Tool t = Tool::ball_end_mill(6.0, 20.0);
  ToolOverrides o;
  o.gauge_length_mm = 53.0;  // the body ends L = 50 mm above the centre
  o.shank_radius_mm = 4.0;
  const ToolModel tool = ToolModel::ball_end(t, o);
  REQUIRE(tool.bodies.back().end_mm == Approx(50.0));
  const double a_star =
      root([](double a) { return 50.0 * std::sin(a) + 4.0 * std::cos(a) - 25.0; }, 0.0, 1.5);
  const auto axis = [](double a) { return Vec3d(std::sin(a), 0.0, std::cos(a)); };
  CHECK_FALSE(wall.collides(tool, Vec3d::Zero(), axis(a_star - deg_to_rad(0.3))));
  CHECK(wall.collides(tool, Vec3d::Zero(), axis(a_star + deg_to_rad(0.3))));
  // Tilting away from the wall is free at any angle.
  CHECK_FALSE(wall.collides(tool, Vec3d::Zero(), axis(-deg_to_rad(80.0))));
  // The ball counts only when asked: a ball touching the wall.
  CHECK_FALSE(wall.collides(tool, Vec3d(D - 2.9, 0, 0), Vec3d(-1, 0, 0)));
  CHECK(wall.collides(tool, Vec3d(D - 2.9, 0, 0), Vec3d(-1, 0, 0), true));
}

TEST_CASE("collision: the tool model follows the tool sheet and refuses contradictions",
          "[cspace][collision][bad-input]") {
  const Tool t = Tool::ball_end_mill(10.0, 25.0);
  const ToolModel m = ToolModel::ball_end(t);
  REQUIRE(m.bodies.size() == 2);
  CHECK(m.bodies[0].radius_mm == 5.0);
  CHECK(m.bodies[0].end_mm == 20.0);  // flutes: from the centre to 25 - R
  CHECK(m.bodies[1].end_mm == 95.0);  // shank to the default gauge 10 D = 100 from the tip
  CHECK(m.reach_mm() == Approx(std::hypot(5.0, 95.0)));
  ToolOverrides bad;
  bad.gauge_length_mm = 10.0;
  CHECK_THROWS_AS(ToolModel::ball_end(t, bad), InputError);
  ToolOverrides thin;
  thin.holder_radius_mm = 2.0;
  CHECK_THROWS_AS(ToolModel::ball_end(t, thin), InputError);
  Tool flat;
  flat.diameter_mm = 10.0;
  CHECK_THROWS_AS(ToolModel::ball_end(flat), InputError);
}
