#include "taxopt/cspace/cspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "taxopt/core/error.hpp"

namespace taxopt {

CSpaceGrid::CSpaceGrid(double cell_deg) : cell_deg_(cell_deg) {
  const double n = 180.0 / cell_deg;
  if (!(cell_deg > 0.0 && cell_deg <= 90.0) || std::abs(n - std::round(n)) > 1e-9) {
    throw InputError("C-space cell size must divide 180 deg (for example 0.5, 1, 2, 3, 5)");
  }
  n_tilt_ = static_cast<int>(std::lround(n));
  n_yaw_ = 2 * n_tilt_;
  bits_.assign((static_cast<std::size_t>(n_tilt_) * static_cast<std::size_t>(n_yaw_) + 63) / 64, 0);
}

double CSpaceGrid::tilt_rad(int i) const { return deg_to_rad(-90.0 + (i + 0.5) * cell_deg_); }
double CSpaceGrid::yaw_rad(int j) const { return deg_to_rad(-180.0 + (j + 0.5) * cell_deg_); }

bool CSpaceGrid::free(int i, int j) const {
  const std::size_t k =
      static_cast<std::size_t>(i) * static_cast<std::size_t>(n_yaw_) + static_cast<std::size_t>(j);
  return (bits_[k / 64] >> (k % 64)) & 1u;
}

void CSpaceGrid::set_free(int i, int j, bool f) {
  const std::size_t k =
      static_cast<std::size_t>(i) * static_cast<std::size_t>(n_yaw_) + static_cast<std::size_t>(j);
  const std::uint64_t bit = std::uint64_t(1) << (k % 64);
  bits_[k / 64] = f ? (bits_[k / 64] | bit) : (bits_[k / 64] & ~bit);
}

std::size_t CSpaceGrid::free_count() const {
  std::size_t n = 0;
  for (std::uint64_t w : bits_) n += static_cast<std::size_t>(__builtin_popcountll(w));
  return n;
}

namespace {

/// A cell of the half grid a >= 0 inside the deviation cone, with its axis.
struct WindowCell {
  int i, j;
  Vec3d axis;
};

/// Cells of the half grid (tilt >= 0) whose axis is within the deviation cone of the input.
std::vector<WindowCell> window(const CSpaceGrid& g, const ContactPoint& cp, const Vec3d& input,
                               double max_dev_rad) {
  std::vector<WindowCell> out;
  const double cos_dev = std::cos(max_dev_rad);
  for (int i = g.tilt_cells() / 2; i < g.tilt_cells(); ++i) {
    const double a = g.tilt_rad(i);
    if (a < -1e-12) continue;
    const double ca = std::cos(a), sa = std::sin(a);
    for (int j = 0; j < g.yaw_cells(); ++j) {
      const double b = g.yaw_rad(j);
      // eq. 11 written out: V = N cos a + sin a (T cos b + K sin b).
      const Vec3d v = ca * cp.normal + sa * (std::cos(b) * cp.feed_dir + std::sin(b) * cp.side);
      if (v.dot(input) >= cos_dev) out.push_back({i, j, v});
    }
  }
  return out;
}

void store(CSpaceGrid& g, const WindowCell& c) {
  g.set_free(c.i, c.j, true);
  g.set_free(g.tilt_cells() - 1 - c.i, (c.j + g.yaw_cells() / 2) % g.yaw_cells(), true);
}

}  // namespace

bool triangle_meets_cylinder(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& origin,
                             const Vec3d& dir, double r, double start, double end) {
  const Vec3d e1 = dir.unitOrthogonal(), e2 = dir.cross(e1);
  // Vertices in the cylinder's frame: (x, y) across, z along.
  std::array<Vec3d, 8> poly{}, next{};
  int n = 0;
  for (const Vec3d* p : {&a, &b, &c}) {
    const Vec3d d = *p - origin;
    poly[static_cast<std::size_t>(n++)] = Vec3d(d.dot(e1), d.dot(e2), d.dot(dir));
  }
  // Clip to start <= z <= end (Sutherland-Hodgman, two planes).
  for (int side = 0; side < 2; ++side) {
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

CSpaceGrid rasterise_free_axes(const Part& part, const ToolModel& tool, const ContactPoint& cp,
                               const Vec3d& centre, const Vec3d& input_axis,
                               const CSpaceOptions& options) {
  CSpaceGrid grid(options.cell_deg);
  if (cp.local_gouge) return grid;
  const std::vector<WindowCell> cells =
      window(grid, cp, input_axis, deg_to_rad(options.max_deviation_deg));
  if (cells.empty()) return grid;
  std::vector<char> blocked(cells.size(), 0);
  const TriangleMesh& mesh = part.mesh();
  const double max_dev = deg_to_rad(options.max_deviation_deg);
  struct Active {
    const ToolBody* body;
    double cos_cone;  // cells whose axis is farther from the face than this cannot meet it
  };
  std::vector<Active> active;
  for (int f : part.faces_within(centre, tool.reach_mm())) {
    const auto& face = mesh.faces[static_cast<std::size_t>(f)];
    const Vec3d& a = mesh.vertices[static_cast<std::size_t>(face[0])];
    const Vec3d& b = mesh.vertices[static_cast<std::size_t>(face[1])];
    const Vec3d& c = mesh.vertices[static_cast<std::size_t>(face[2])];
    // Bounding sphere (m, rho) of the face, seen from the ball centre at distance d along u.
    const Vec3d m = (a + b + c) / 3.0;
    const double rho = std::max({(a - m).norm(), (b - m).norm(), (c - m).norm()});
    const double d = (m - centre).norm();
    const Vec3d u = d > 1e-12 ? Vec3d((m - centre) / d) : Vec3d::UnitZ();
    // Per body: a face can meet a body at axis v only if its sphere reaches the body's slab
    // (d (u.v) + rho >= start, d (u.v) - rho <= end) and comes within r of the axis line,
    // i.e. v lies within asin((r + rho) / d) of u.
    active.clear();
    for (const ToolBody& body : tool.bodies) {
      if (d + rho < body.start_mm || d - rho > std::hypot(body.radius_mm, body.end_mm)) continue;
      double cos_cone = -2.0;
      if (d > body.radius_mm + rho) {
        const double phi = std::asin((body.radius_mm + rho) / d);
        if (angle_between(u, input_axis) > max_dev + phi) continue;
        cos_cone = std::cos(phi);
      }
      active.push_back({&body, cos_cone});
    }
    if (active.empty()) continue;
    for (std::size_t k = 0; k < cells.size(); ++k) {
      if (blocked[k]) continue;
      const double cu = cells[k].axis.dot(u);
      for (const Active& act : active) {
        const ToolBody& body = *act.body;
        if (cu < act.cos_cone || d * cu + rho < body.start_mm || d * cu - rho > body.end_mm)
          continue;
        if (triangle_meets_cylinder(a, b, c, centre, cells[k].axis, body.radius_mm, body.start_mm,
                                    body.end_mm)) {
          blocked[k] = 1;
          break;
        }
      }
    }
  }
  for (std::size_t k = 0; k < cells.size(); ++k) {
    if (!blocked[k]) store(grid, cells[k]);
  }
  return grid;
}

CSpaceGrid brute_force_free_axes(const CollisionModel& model, const ToolModel& tool,
                                 const ContactPoint& cp, const Vec3d& centre,
                                 const Vec3d& input_axis, const CSpaceOptions& options) {
  CSpaceGrid grid(options.cell_deg);
  if (cp.local_gouge) return grid;
  for (const WindowCell& c : window(grid, cp, input_axis, deg_to_rad(options.max_deviation_deg))) {
    if (!model.collides(tool, centre, c.axis)) store(grid, c);
  }
  return grid;
}

}  // namespace taxopt
