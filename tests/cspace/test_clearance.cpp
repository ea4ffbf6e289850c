// The clearance bounds of the tool's bodies (CSpaceRasteriser::clearances_mm) and the sweep of
// moves that skips samples by them (colliding_moves): the distance routines against brute
// force, every bound a lower bound as FCL judges it, and the sweep's verdicts the same with and
// without the bounds, on parts no test was tuned on.
#include <catch2/catch.hpp>
#include <random>

#include "cspace/triangle_tests.hpp"
#include "pipeline/stages.hpp"
#include "support.hpp"
#include "taxopt/cspace/cspace.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

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

ToolModel random_tool(std::mt19937& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  ToolOverrides o;
  o.gauge_length_mm = 30.0 + 20.0 * u01(rng);
  o.shank_radius_mm = 3.0 + 2.0 * u01(rng);
  o.holder_radius_mm = 10.0 + 6.0 * u01(rng);
  o.holder_length_mm = 30.0;
  return ToolModel::ball_end(Tool::ball_end_mill(6.0, 15.0), o).judged({0.01, 0.5, 1.0});
}

Vec3d random_axis(std::mt19937& rng, double max_tilt_deg) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double tilt = deg_to_rad(max_tilt_deg) * u01(rng), yaw = deg_to_rad(360.0) * u01(rng);
  return {std::sin(tilt) * std::cos(yaw), std::sin(tilt) * std::sin(yaw), std::cos(tilt)};
}

}  // namespace

TEST_CASE("clearance: segment-to-triangle distance is the least over both, by sampling",
          "[cspace][clearance]") {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  int meeting = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3d p(u(rng), u(rng), u(rng)), q(u(rng), u(rng), u(rng));
    const double d = detail::distance_segment_to_triangle(p, q, a, b, c);
    // Every sampled pair is at least d apart, and the closest sampled pair within the samples'
    // spacing of it.
    constexpr int kN = 60;
    double least = 1e300;
    for (int i = 0; i <= kN; ++i) {
      const Vec3d s = p + (static_cast<double>(i) / kN) * (q - p);
      for (int j = 0; j <= kN; ++j) {
        for (int l = 0; j + l <= kN; ++l) {
          const Vec3d t =
              a + (static_cast<double>(j) / kN) * (b - a) + (static_cast<double>(l) / kN) * (c - a);
          least = std::min(least, (s - t).norm());
        }
      }
    }
    const double spacing =
        ((q - p).norm() + (b - a).norm() + (c - a).norm()) / kN;  // a bound on the sampling error
    INFO("case " << k << ": d " << d << ", sampled " << least);
    REQUIRE(d <= least + 1e-9);
    REQUIRE(d >= least - spacing);
    meeting += d == 0.0 ? 1 : 0;
  }
  CHECK(meeting > 10);  // segments through the face are among the cases
  CHECK(meeting < 390);
}

TEST_CASE("clearance: each body grown within its bound stays free for FCL", "[cspace][clearance]") {
  std::mt19937 rng(3907);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::size_t poses = 0, bounded = 0;
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const TriangleMesh mesh = tessellate(HeightSurface{&hf}, 60, 60);
    const CollisionModel fcl(mesh);
    const CSpaceRasteriser tree(mesh);
    const ToolModel tool = random_tool(rng);
    for (int q = 0; q < 300; ++q) {
      const double x = 5.0 + 40.0 * u01(rng), y = 5.0 + 40.0 * u01(rng);
      const Vec3d centre(x, y, hf.z(x, y) + 3.0 + 4.0 * u01(rng));
      const Vec3d axis = random_axis(rng, 80.0);
      const bool with_ball = q % 2 == 0;
      const std::vector<double> clear = tree.clearances_mm(tool, centre, axis, with_ball, 6.0);
      REQUIRE(clear.size() == tool.bodies.size() + 1);
      ++poses;
      // Each body alone, grown by its bound over sqrt 2 in radius and at both ends: every point
      // of it lies within the bound of the body.
      for (std::size_t k = 0; k < tool.bodies.size(); ++k) {
        if (!(clear[k] > 1e-6)) continue;
        const double g = (clear[k] - 1e-6) / std::sqrt(2.0);
        ToolModel one;
        one.ball_radius_mm = tool.ball_radius_mm;
        one.bodies = {
            {tool.bodies[k].radius_mm + g, tool.bodies[k].start_mm - g, tool.bodies[k].end_mm + g}};
        INFO("pose " << q << " body " << k << " bound " << clear[k]);
        REQUIRE_FALSE(fcl.collides(one, centre, axis, false));
        bounded += clear[k] > 0.5 ? 1 : 0;
      }
      if (with_ball && clear.back() > 1e-6) {
        ToolModel ball;
        ball.ball_radius_mm = tool.ball_radius_mm + clear.back() - 1e-6;
        REQUIRE_FALSE(fcl.collides(ball, centre, axis, true));
      } else if (!with_ball) {
        CHECK(std::isinf(clear.back()));
      }
    }
  }
  INFO(poses << " poses, " << bounded << " body bounds above 0.5 mm");
  CHECK(bounded > poses / 2);  // the bounds are of use, not all 0
}

TEST_CASE("clearance: a move's sweep finds the same hits with and without the bounds",
          "[cspace][clearance]") {
  std::mt19937 rng(5150);
  std::uniform_real_distribution<double> u01(0.0, 1.0), u(-1.0, 1.0);
  const Machine machine = default_machine();
  std::size_t moves = 0, hits = 0;
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const TriangleMesh mesh = tessellate(HeightSurface{&hf}, 60, 60);
    const CollisionModel fcl(mesh);
    const CSpaceRasteriser tree(mesh);
    const ToolModel tool = random_tool(rng);
    for (int q = 0; q < 120; ++q) {
      // A move of up to 4 mm and 12 deg from a ball centre 2.5 to 5 mm above the surface
      // (touching moves check the bodies only, the others the ball too).
      std::vector<Vec3d> xyz;
      std::vector<double> a, c;
      const double x = 5.0 + 40.0 * u01(rng), y = 5.0 + 40.0 * u01(rng);
      Vec3d centre(x, y, hf.z(x, y) + 2.5 + 2.5 * u01(rng));
      Vec3d axis = random_axis(rng, 60.0);
      for (int end = 0; end < 2; ++end) {
        const Posed pose = machine.rotary.inverse(axis)[0];
        xyz.push_back(written_xyz_mm(machine, centre - tool.ball_radius_mm * axis, pose));
        a.push_back(rad_to_deg(pose.tilt_rad));
        c.push_back(rad_to_deg(pose.c_rad));
        centre += 2.0 * Vec3d(u(rng), u(rng), u(rng));
        axis = (axis + 0.1 * Vec3d(u(rng), u(rng), u(rng))).normalized();
      }
      std::vector<ContactPoint> contacts(2);
      if (q % 2 == 0) contacts[0].state = contacts[1].state = ContactState::Touching;
      for (const PartCheck* model :
           {static_cast<const PartCheck*>(&fcl), static_cast<const PartCheck*>(&tree)}) {
        const auto plain = pipeline::colliding_moves(*model, tool, machine, xyz, a, c, contacts);
        const auto fast = pipeline::colliding_moves(*model, tool, machine, xyz, a, c, contacts,
                                                    nullptr, nullptr, nullptr, &tree);
        INFO("move " << q);
        REQUIRE(plain == fast);
        ++moves;
        hits += plain.size();
      }
    }
  }
  INFO(moves << " sweeps, " << hits << " hit");
  CHECK(hits > moves / 10);
  CHECK(hits < moves - moves / 10);
}
