// The exact tests of a triangle against the tool's bodies (triangle_tests.hpp).
#include "cspace/triangle_tests.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "taxopt/cspace/cspace.hpp"

namespace taxopt {

namespace detail {

/// triangle_meets_cylinder with the vertices given relative to the axis origin and the axis
/// in an orthonormal frame (e1, e2, dir).
bool meets_in_frame(const std::array<Vec3d, 3>& rel, const Vec3d& dir, const Vec3d& e1,
                    const Vec3d& e2, double r, double start, double end) {
  // Vertices in the cylinder's frame: (x, y) across, z along.
  std::array<Vec3d, 8> poly{}, next{};
  int n = 0;
  for (const Vec3d& d : rel) poly[static_cast<std::size_t>(n++)] = Vec3d(0.0, 0.0, d.dot(dir));
  // All three vertices on one side of the slab (the common case): no need to project.
  const double za = poly[0].z(), zb = poly[1].z(), zc = poly[2].z();
  if ((za < start && zb < start && zc < start) || (za > end && zb > end && zc > end)) return false;
  for (std::size_t k = 0; k < 3; ++k) {
    poly[k].x() = rel[k].dot(e1);
    poly[k].y() = rel[k].dot(e2);
  }
  // Clip to start <= z <= end (Sutherland-Hodgman, two planes), where the face crosses them.
  const bool within = std::min({za, zb, zc}) >= start && std::max({za, zb, zc}) <= end;
  for (int side = within ? 2 : 0; side < 2; ++side) {
    const auto inside = [&](const Vec3d& p) { return side == 0 ? p.z() >= start : p.z() <= end; };
    const double plane = side == 0 ? start : end;
    int m = 0;
    for (int k = 0; k < n; ++k) {
      const Vec3d& p = poly[static_cast<std::size_t>(k)];
      const Vec3d& q = poly[static_cast<std::size_t>((k + 1) % n)];
      const bool pin = inside(p), qin = inside(q);
      if (pin) next[static_cast<std::size_t>(m++)] = p;
      if (pin != qin) {
        const double t = (plane - p.z()) / (q.z() - p.z());
        next[static_cast<std::size_t>(m++)] = p + t * (q - p);
      }
    }
    n = m;
    poly = next;
    if (n == 0) return false;
  }
  // The clipped face meets the solid cylinder iff its projection comes within r of the axis.
  const double r2 = r * r;
  double sign = 0.0;
  bool origin_inside = n >= 3;
  for (int k = 0; k < n; ++k) {
    const Vec3d& p = poly[static_cast<std::size_t>(k)];
    const Vec3d& q = poly[static_cast<std::size_t>((k + 1) % n)];
    const double ex = q.x() - p.x(), ey = q.y() - p.y();
    const double len2 = ex * ex + ey * ey;
    double t = len2 > 0.0 ? -(p.x() * ex + p.y() * ey) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const double dx = p.x() + t * ex, dy = p.y() + t * ey;
    if (dx * dx + dy * dy <= r2) return true;
    const double cross = ex * (-p.y()) - ey * (-p.x());
    if (std::abs(cross) < 1e-15) {
      origin_inside = false;
    } else if (sign == 0.0) {
      sign = cross;
    } else if (cross * sign < 0.0) {
      origin_inside = false;
    }
  }
  return origin_inside;
}

}  // namespace detail

bool triangle_meets_cylinder(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& origin,
                             const Vec3d& dir, double r, double start, double end) {
  const Vec3d e1 = dir.unitOrthogonal(), e2 = dir.cross(e1);
  return detail::meets_in_frame({a - origin, b - origin, c - origin}, dir, e1, e2, r, start, end);
}

namespace detail {

/// Squared distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
double squared_distance_to_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b,
                                    const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).squaredNorm();
  }
  const double denom = 1.0 / (va + vb + vc);
  return (ap - (vb * denom) * ab - (vc * denom) * ac).squaredNorm();
}

}  // namespace detail

}  // namespace taxopt
