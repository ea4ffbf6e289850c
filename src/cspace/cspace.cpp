#include "taxopt/cspace/cspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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
  std::vector<Vec3d> dir(static_cast<std::size_t>(g.yaw_cells()));
  for (int j = 0; j < g.yaw_cells(); ++j) {
    const double b = g.yaw_rad(j);
    dir[static_cast<std::size_t>(j)] = std::cos(b) * cp.feed_dir + std::sin(b) * cp.side;
  }
  for (int i = g.tilt_cells() / 2; i < g.tilt_cells(); ++i) {
    const double a = g.tilt_rad(i);
    if (a < -1e-12) continue;
    const double ca = std::cos(a), sa = std::sin(a);
    // Every axis of this row makes the angle a with N: skip rows the cone cannot reach.
    if (std::abs(a - angle_between(cp.normal, input)) > max_dev_rad + 1e-9) continue;
    for (int j = 0; j < g.yaw_cells(); ++j) {
      // eq. 11 written out: V = N cos a + sin a (T cos b + K sin b).
      const Vec3d v = ca * cp.normal + sa * dir[static_cast<std::size_t>(j)];
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

CSpaceRasteriser::CSpaceRasteriser(const TriangleMesh& mesh) {
  std::vector<Vec3d> centroids;
  for (const auto& f : mesh.faces) {
    const std::array<Vec3d, 3> t = {mesh.vertices[static_cast<std::size_t>(f[0])],
                                    mesh.vertices[static_cast<std::size_t>(f[1])],
                                    mesh.vertices[static_cast<std::size_t>(f[2])]};
    const Vec3d m = (t[0] + t[1] + t[2]) / 3.0;
    tri_.push_back(t);
    face_sphere_.push_back(
        {m, std::max({(t[0] - m).norm(), (t[1] - m).norm(), (t[2] - m).norm()})});
    centroids.push_back(m);
  }
  if (!tri_.empty()) build(0, static_cast<int>(tri_.size()), centroids);
}

/// Top-down: split the faces at the median centroid along the longest extent, four faces or
/// fewer to a leaf. Faces are reordered so that a leaf's are contiguous.
int CSpaceRasteriser::build(int first, int count, std::vector<Vec3d>& centroids) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int k = first; k < first + count; ++k) {
    for (const Vec3d& p : tri_[static_cast<std::size_t>(k)]) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  Sphere s{0.5 * (lo + hi), 0.0};
  for (int k = first; k < first + count; ++k) {
    for (const Vec3d& p : tri_[static_cast<std::size_t>(k)]) {
      s.radius = std::max(s.radius, (p - s.centre).norm());
    }
  }
  nodes_[static_cast<std::size_t>(id)].sphere = s;
  if (count <= 4) {
    nodes_[static_cast<std::size_t>(id)].first = first;
    nodes_[static_cast<std::size_t>(id)].count = count;
    return id;
  }
  Vec3d cl = Vec3d::Constant(std::numeric_limits<double>::infinity()), ch = -cl;
  for (int k = first; k < first + count; ++k) {
    cl = cl.cwiseMin(centroids[static_cast<std::size_t>(k)]);
    ch = ch.cwiseMax(centroids[static_cast<std::size_t>(k)]);
  }
  int axis = 0;
  (ch - cl).maxCoeff(&axis);
  std::vector<int> order(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) order[static_cast<std::size_t>(k)] = first + k;
  const auto mid = order.begin() + count / 2;
  std::nth_element(order.begin(), mid, order.end(), [&](int a, int b) {
    const double ka = centroids[static_cast<std::size_t>(a)][axis];
    const double kb = centroids[static_cast<std::size_t>(b)][axis];
    return ka < kb || (ka == kb && a < b);
  });
  std::vector<std::array<Vec3d, 3>> t;
  std::vector<Sphere> fs;
  std::vector<Vec3d> c;
  for (int k : order) {
    t.push_back(tri_[static_cast<std::size_t>(k)]);
    fs.push_back(face_sphere_[static_cast<std::size_t>(k)]);
    c.push_back(centroids[static_cast<std::size_t>(k)]);
  }
  std::copy(t.begin(), t.end(), tri_.begin() + first);
  std::copy(fs.begin(), fs.end(), face_sphere_.begin() + first);
  std::copy(c.begin(), c.end(), centroids.begin() + first);
  const int left = build(first, count / 2, centroids);
  const int right = build(first + count / 2, count - count / 2, centroids);
  nodes_[static_cast<std::size_t>(id)].left = left;
  nodes_[static_cast<std::size_t>(id)].right = right;
  return id;
}

CSpaceGrid CSpaceRasteriser::free_axes(const ToolModel& tool, const ContactPoint& cp,
                                       const Vec3d& centre, const Vec3d& input_axis,
                                       const CSpaceOptions& options) const {
  CSpaceGrid grid(options.cell_deg);
  if (cp.local_gouge) return grid;
  const double max_dev = deg_to_rad(options.max_deviation_deg);
  const std::vector<WindowCell> cells = window(grid, cp, input_axis, max_dev);
  if (cells.empty() || nodes_.empty()) return grid;
  std::vector<char> blocked(cells.size(), 0);
  const double cos_dev = std::cos(max_dev), sin_dev = std::sin(max_dev);
  // Window index of the half-grid cell (i, j), i >= tilt_cells / 2, or -1.
  const int n_yaw = grid.yaw_cells(), row0 = grid.tilt_cells() / 2;
  std::vector<int> cell_at(static_cast<std::size_t>((grid.tilt_cells() - row0) * n_yaw), -1);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    cell_at[static_cast<std::size_t>((cells[k].i - row0) * n_yaw + cells[k].j)] =
        static_cast<int>(k);
  }
  const double cell_rad = deg_to_rad(grid.cell_deg());

  struct Active {
    const ToolBody* body;
    double cos_lo;  // cells with axis . u below this cannot meet the body
  };
  std::vector<Active> active(tool.bodies.size());
  // The bodies a sphere (m, rho) can meet at some axis of the window, and their number. A
  // body (radius r, from `start` to `end`) needs axis . u >= cos_lo, the larger of cos phi,
  // phi = asin((r + rho) / d) (within r + rho of the axis line; where d > r + rho), and
  // (start - rho) / d (reaching the body's slab); the window needs angle(u, input) <= max_dev
  // + acos(cos_lo).
  const auto reach = [&](const Sphere& sp, Vec3d& u, double& d) {
    const Vec3d w = sp.centre - centre;
    d = w.norm();
    u = d > 1e-12 ? Vec3d(w / d) : Vec3d::UnitZ();
    const double cu_in = u.dot(input_axis);
    std::size_t n = 0;
    for (const ToolBody& body : tool.bodies) {
      if (d + sp.radius < body.start_mm ||
          d - sp.radius > std::hypot(body.radius_mm, body.end_mm)) {
        continue;
      }
      double lo = -1.0;
      if (d > body.radius_mm + sp.radius) {
        const double s = (body.radius_mm + sp.radius) / d;
        lo = std::sqrt(std::max(0.0, 1.0 - s * s));
      }
      if (d > 1e-12) lo = std::max(lo, (body.start_mm - sp.radius) / d);
      if (lo > 1.0) continue;
      // cos(max_dev + psi) with cos psi = lo, when max_dev + psi < pi.
      const double sin_lo = std::sqrt(std::max(0.0, 1.0 - lo * lo));
      if (max_dev + std::acos(std::max(-1.0, lo)) < Constants<double>::pi() &&
          cu_in < cos_dev * lo - sin_dev * sin_lo) {
        continue;
      }
      active[n++] = {&body, lo};
    }
    return n;
  };

  std::vector<int> stack = {0};
  std::vector<int> candidates;
  while (!stack.empty()) {
    const Node& node = nodes_[static_cast<std::size_t>(stack.back())];
    stack.pop_back();
    Vec3d u;
    double d = 0.0;
    if (reach(node.sphere, u, d) == 0) continue;
    if (node.left >= 0) {
      stack.push_back(node.right);
      stack.push_back(node.left);
      continue;
    }
    for (int f = node.first; f < node.first + node.count; ++f) {
      const Sphere& fs = face_sphere_[static_cast<std::size_t>(f)];
      const std::size_t n_active = reach(fs, u, d);
      if (n_active == 0) continue;
      // The window cells within psi of u (cos psi = the smallest cos_lo), row by row: on the
      // row of tilt a, cos(angle) = cos a cos th + sin a sin th cos(b - beta) >= cos psi.
      double cos_psi = 1.0;
      for (std::size_t b = 0; b < n_active; ++b) cos_psi = std::min(cos_psi, active[b].cos_lo);
      const double psi = std::acos(std::max(-1.0, cos_psi));
      const double th = std::acos(std::clamp(u.dot(cp.normal), -1.0, 1.0));
      const double beta = std::atan2(u.dot(cp.side), u.dot(cp.feed_dir));
      candidates.clear();
      for (int i = row0; i < grid.tilt_cells(); ++i) {
        const double a = grid.tilt_rad(i);
        if (std::abs(a - th) > psi + 1e-9) continue;
        const double sn = std::sin(a) * std::sin(th);
        double half = Constants<double>::pi();  // half-width of the yaw range
        if (sn > 1e-12) {
          const double c = (cos_psi - std::cos(a) * std::cos(th)) / sn;
          if (c > 1.0 + 1e-9) continue;
          half = std::acos(std::clamp(c, -1.0, 1.0)) + 1e-9;
        }
        if (half >= Constants<double>::pi()) {
          for (int j = 0; j < n_yaw; ++j) {
            const int k = cell_at[static_cast<std::size_t>((i - row0) * n_yaw + j)];
            if (k >= 0) candidates.push_back(k);
          }
          continue;
        }
        // Yaw of cell j: -pi + (j + 0.5) cell; cells with |b - beta| <= half, wrapped.
        const int j0 =
            static_cast<int>(std::floor((beta - half + Constants<double>::pi()) / cell_rad - 0.5));
        const int j1 =
            static_cast<int>(std::ceil((beta + half + Constants<double>::pi()) / cell_rad - 0.5));
        for (int j = j0; j <= j1 && j < j0 + n_yaw; ++j) {
          const int jw = ((j % n_yaw) + n_yaw) % n_yaw;
          const int k = cell_at[static_cast<std::size_t>((i - row0) * n_yaw + jw)];
          if (k >= 0) candidates.push_back(k);
        }
      }
      const auto& t = tri_[static_cast<std::size_t>(f)];
      for (int kk : candidates) {
        const std::size_t k = static_cast<std::size_t>(kk);
        if (blocked[k]) continue;
        const double cu = cells[k].axis.dot(u);
        for (std::size_t b = 0; b < n_active; ++b) {
          const ToolBody& body = *active[b].body;
          if (cu < active[b].cos_lo || d * cu + fs.radius < body.start_mm ||
              d * cu - fs.radius > body.end_mm) {
            continue;
          }
          if (triangle_meets_cylinder(t[0], t[1], t[2], centre, cells[k].axis, body.radius_mm,
                                      body.start_mm, body.end_mm)) {
            blocked[k] = 1;
            break;
          }
        }
      }
    }
  }
  for (std::size_t k = 0; k < cells.size(); ++k) {
    if (!blocked[k]) store(grid, cells[k]);
  }
  return grid;
}

CSpaceGrid rasterise_free_axes(const Part& part, const ToolModel& tool, const ContactPoint& cp,
                               const Vec3d& centre, const Vec3d& input_axis,
                               const CSpaceOptions& options) {
  return CSpaceRasteriser(part.mesh()).free_axes(tool, cp, centre, input_axis, options);
}

Vec3d cell_axis(const CSpaceGrid& grid, int i, int j, const ContactPoint& cp) {
  const double a = grid.tilt_rad(i), b = grid.yaw_rad(j);
  return std::cos(a) * cp.normal +
         std::sin(a) * (std::cos(b) * cp.feed_dir + std::sin(b) * cp.side);
}

std::vector<Vec3d> free_axes_of(const CSpaceGrid& grid, const ContactPoint& cp) {
  std::vector<Vec3d> out;
  for (int i = grid.tilt_cells() / 2; i < grid.tilt_cells(); ++i) {
    for (int j = 0; j < grid.yaw_cells(); ++j) {
      if (grid.free(i, j)) out.push_back(cell_axis(grid, i, j, cp));
    }
  }
  return out;
}

std::vector<Posed> free_poses_of(const CSpaceGrid& grid, const ContactPoint& cp,
                                 const ACMachined& machine) {
  std::vector<Posed> out;
  for (const Vec3d& v : free_axes_of(grid, cp)) {
    for (const Posed& p : machine.inverse(v)) {
      if (machine.a.contains(p.a_rad)) {
        out.push_back(p);
        break;
      }
    }
  }
  return out;
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
