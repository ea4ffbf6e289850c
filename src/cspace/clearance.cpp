// Lower bounds on the distance of the tool's bodies from the part (CSpaceRasteriser::
// clearances_mm): what lets colliding_moves skip the samples of a move that cannot reach it.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "cspace/triangle_tests.hpp"
#include "taxopt/cspace/cspace.hpp"

namespace taxopt {

namespace {

/// A body (or the ball: a body of one point, no slab) for the bounds: a flat-ended solid
/// cylinder is the intersection of its capsule (the points within its radius of the axis
/// segment) and its slab (start <= z <= end along the axis), so its distance from anything is
/// at least the larger of the distances from those two.
struct Body {
  Vec3d from = Vec3d::Zero(), to = Vec3d::Zero(), axis = Vec3d::UnitZ();
  double z_from = 0.0, z_to = 0.0, radius_mm = 0.0;
  bool slab = false;
  /// How far values z_lo..z_hi along the axis lie outside the slab (0 inside or without one).
  double slab_gap(double z_lo, double z_hi) const {
    if (!slab) return 0.0;
    return std::max({z_from - z_hi, z_lo - z_to, 0.0});
  }
  /// A lower bound on the distance from any point of the sphere (m, rho).
  double sphere_bound(const Vec3d& m, double rho) const {
    const Vec3d d = to - from;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((m - from).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double capsule = (m - (from + t * d)).norm() - rho - radius_mm;
    const double z = m.dot(axis);
    return std::max(capsule, slab_gap(z - rho, z + rho));
  }
  /// A lower bound on the distance from the triangle t, from `known` (its sphere's bound) up:
  /// the exact capsule distance is worked out only where the slab leaves it the larger.
  double triangle_bound(const std::array<Vec3d, 3>& t, double known, double best) const {
    const double z0 = t[0].dot(axis), z1 = t[1].dot(axis), z2 = t[2].dot(axis);
    const double gap = std::max(known, slab_gap(std::min({z0, z1, z2}), std::max({z0, z1, z2})));
    if (gap >= best) return gap;
    return std::max(gap,
                    detail::distance_segment_to_triangle(from, to, t[0], t[1], t[2]) - radius_mm);
  }
};

}  // namespace

std::vector<double> CSpaceRasteriser::clearances_mm(const ToolModel& tool, const Vec3d& ball_centre,
                                                    const Vec3d& axis, bool with_ball,
                                                    double cap_mm, double floor_mm) const {
  const std::size_t nb = tool.bodies.size();
  std::vector<Body> bodies;
  for (const ToolBody& b : tool.bodies) {
    const Vec3d from = ball_centre + b.start_mm * axis, to = ball_centre + b.end_mm * axis;
    bodies.push_back({from, to, axis, from.dot(axis), to.dot(axis), b.radius_mm, true});
  }
  if (with_ball) {
    bodies.push_back({ball_centre, ball_centre, axis, 0.0, 0.0, tool.ball_radius_mm, false});
  }
  std::vector<double> best(bodies.size(), cap_mm);
  // Per body the bound of the sphere last judged, and whether anything within it can come
  // nearer to some body than that body's best.
  std::array<double, 8> low{};
  const auto worth = [&](const Sphere& sp) {
    bool any = false;
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      low[k] = bodies[k].sphere_bound(sp.centre, sp.radius);
      any = any || low[k] < best[k];
    }
    return any;
  };
  // Every bound 0 when a body is near (or the tool has more bodies than the walk keeps).
  const auto result = [&](bool near) {
    std::vector<double> out(nb + 1, std::numeric_limits<double>::infinity());
    for (std::size_t k = 0; k < bodies.size(); ++k) out[k] = near ? 0.0 : std::max(best[k], 0.0);
    return out;
  };
  if (nodes_.empty() || bodies.size() > low.size()) return result(bodies.size() > low.size());
  std::array<int, 256> stack{};
  std::size_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[static_cast<std::size_t>(stack[--top])];
    if (!worth(node.sphere)) continue;
    if (node.left >= 0) {
      stack[top++] = node.right;
      stack[top++] = node.left;
      continue;
    }
    for (int f = node.first; f < node.first + node.count; ++f) {
      if (!worth(face_sphere_[static_cast<std::size_t>(f)])) continue;
      const auto& t = tri_[static_cast<std::size_t>(f)];
      for (std::size_t k = 0; k < bodies.size(); ++k) {
        if (!(low[k] < best[k])) continue;
        best[k] = std::min(best[k], bodies[k].triangle_bound(t, low[k], best[k]));
        if (best[k] <= floor_mm) return result(true);
      }
    }
  }
  return result(false);
}

}  // namespace taxopt
