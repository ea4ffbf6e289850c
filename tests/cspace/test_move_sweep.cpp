// The sweep of moves that clears runs of samples at once by the tool's bodies grown by the most
// they move over the run (colliding_moves with the part's tree): its verdicts the same as one
// query a sample, with FCL and with the tree as the model, on parts no test was tuned on.
#include <catch2/catch.hpp>
#include <random>

#include "pipeline/stages.hpp"
#include "support.hpp"
#include "taxopt/cspace/cspace.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

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

TEST_CASE("sweep: a move's sweep finds the same hits with and without the bounds",
          "[cspace][sweep]") {
  std::mt19937 rng(5150);
  std::uniform_real_distribution<double> u01(0.0, 1.0), u(-1.0, 1.0);
  const Machine machine = default_machine();
  std::size_t moves = 0, hits = 0;
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const TriangleMesh mesh = heightfield_mesh(hf, 70.0 / 60.0);
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
