#include "taxopt/cspace/cspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "cspace/triangle_tests.hpp"
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
    if (std::abs(a - angle_between(cp.surface_normal, input)) > max_dev_rad + 1e-9) continue;
    for (int j = 0; j < g.yaw_cells(); ++j) {
      // eq. 11 written out: V = N cos a + sin a (T cos b + K sin b).
      const Vec3d v = ca * cp.surface_normal + sa * dir[static_cast<std::size_t>(j)];
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

namespace {

constexpr double kPi = Constants<double>::pi();

/// The rows of the half grid (tilt >= 0) that hold window cells, and for each cell whether it
/// is still open (in the window and not yet blocked): one byte a cell, rows contiguous, so that
/// a span is marked with memset and searched with memchr.
struct OcclusionMap {
  int n_yaw = 0, r0 = 0, r1 = 0;
  double cell_rad = 0.0;
  std::vector<double> tilt, cos_tilt, sin_tilt;  // per row, index i - r0
  std::vector<unsigned char> blocked;            // 1: blocked or outside the window
  unsigned char* row(int i) {
    return blocked.data() + static_cast<std::size_t>(i - r0) * static_cast<std::size_t>(n_yaw);
  }
  const unsigned char* row(int i) const {
    return blocked.data() + static_cast<std::size_t>(i - r0) * static_cast<std::size_t>(n_yaw);
  }
};

/// acos within 2e-8 rad (Abramowitz and Stegun 4.4.46), several times faster than std::acos;
/// the rasteriser rounds every span it derives from it outward or inward by far more.
double acos_approx(double x) {
  const double ax = std::min(std::abs(x), 1.0);
  const double p =
      1.5707963050 +
      ax * (-0.2145988016 +
            ax * (0.0889789874 +
                  ax * (-0.0501743046 +
                        ax * (0.0308918810 +
                              ax * (-0.0170881256 + ax * (0.0066700901 + ax * -0.0012624911))))));
  const double r = std::sqrt(1.0 - ax) * p;
  return x < 0.0 ? kPi - r : r;
}

/// Where a sphere lies as seen from the ball centre: distance, and the direction u in the
/// contact frame (u . N, and u . T, u . K as a polar pair), so that a cell's axis V of tilt a
/// and yaw b has V . u = cos a cth + sin a sth cos(b - beta) (eq. 11).
struct Seen {
  double d = 0.0, cth = 1.0, sth = 0.0, beta = 0.0, th = 0.0;
  Vec3d u = Vec3d::UnitZ();
};

Seen seen_from(const Vec3d& centre, const Vec3d& m, const ContactPoint& cp) {
  Seen s;
  const Vec3d w = m - centre;
  s.d = w.norm();
  if (s.d <= 1e-12) return s;
  s.u = w / s.d;
  s.cth = s.u.dot(cp.surface_normal);
  const double t = s.u.dot(cp.feed_dir), k = s.u.dot(cp.side);
  s.sth = std::sqrt(t * t + k * k);
  s.beta = std::atan2(k, t);
  s.th = acos_approx(std::clamp(s.cth, -1.0, 1.0));  // within 2e-8 rad; rows are widened by 1e-7
  return s;
}

/// Calls f(j0, j1) for the cells [j0, j1) of a row whose yaw centre lies in [x, y] rad, the
/// bounds widened (eps > 0) or narrowed (eps < 0) by eps cells; wrapped into at most two
/// spans. Stops and returns true when f does.
template <class F>
bool yaw_spans(const OcclusionMap& g, double x, double y, double eps, F&& f) {
  const double lo = std::ceil((x + kPi) / g.cell_rad - 0.5 - eps);
  const double hi = std::floor((y + kPi) / g.cell_rad - 0.5 + eps);
  if (hi < lo) return false;
  if (hi - lo + 1.0 >= g.n_yaw) return f(0, g.n_yaw);
  const int len = static_cast<int>(hi - lo) + 1;
  const int j0 = ((static_cast<int>(lo) % g.n_yaw) + g.n_yaw) % g.n_yaw;
  if (j0 + len <= g.n_yaw) return f(j0, j0 + len);
  return f(j0, g.n_yaw) || f(0, j0 + len - g.n_yaw);
}

/// The cells with V . u in [c1, c2] for a direction u, cells rounded outward or inward by
/// 1e-7 rad (five times acos_approx's error), and the rows [i0, i1) that can hold them.
struct Ring {
  double c1 = 1.0, c2 = -1.0, eps = 0.0;
  int i0 = 0, i1 = 0;
};

Ring ring_of(const OcclusionMap& g, const Seen& s, double c1, double c2, bool outward) {
  Ring q;
  const double tol = outward ? 1e-9 : -1e-9;
  q.c1 = c1 - tol;
  q.c2 = c2 + tol;
  q.eps = (outward ? 1e-7 : -1e-7) / g.cell_rad;
  if (q.c1 > q.c2 || q.c1 > 1.0 || q.c2 < -1.0) return q;
  // Rows farther than the ring's outer angle from u hold none of its cells; row i's tilt is
  // -pi/2 + (i + 0.5) cell.
  const double th = s.th, th_out = acos_approx(q.c1) + 2e-7;
  q.i0 = std::max(g.r0, static_cast<int>(std::ceil((th - th_out + kPi / 2) / g.cell_rad - 0.5)));
  q.i1 =
      std::min(g.r1, static_cast<int>(std::floor((th + th_out + kPi / 2) / g.cell_rad - 0.5)) + 1);
  return q;
}

/// Calls f(j0, j1) for the spans of row i of the ring. Stops when f returns true.
template <class F>
bool ring_row(const OcclusionMap& g, const Seen& s, const Ring& q, int i, F&& f) {
  const std::size_t r = static_cast<std::size_t>(i - g.r0);
  const double A = g.cos_tilt[r] * s.cth, B = g.sin_tilt[r] * s.sth;
  if (B < 1e-12) return A >= q.c1 && A <= q.c2 && f(0, g.n_yaw);
  const double l = (q.c1 - A) / B, h = (q.c2 - A) / B;
  if (l > 1.0 || h < -1.0) return false;
  const double out = acos_approx(std::max(l, -1.0));
  if (h >= 1.0) return yaw_spans(g, s.beta - out, s.beta + out, q.eps, f);
  const double in = acos_approx(h);
  return yaw_spans(g, s.beta - out, s.beta - in, q.eps, f) ||
         yaw_spans(g, s.beta + in, s.beta + out, q.eps, f);
}

/// Calls f(i, j0, j1) for every span of the ring. Stops when f returns true.
template <class F>
bool ring_spans(const OcclusionMap& g, const Seen& s, const Ring& q, F&& f) {
  for (int i = q.i0; i < q.i1; ++i) {
    if (ring_row(g, s, q, i, [&](int j0, int j1) { return f(i, j0, j1); })) return true;
  }
  return false;
}

/// The axes V . u in [c1, c2] at which a body can meet something inside the sphere (centre at
/// distance d, radius rho): the sphere must reach the body's slab and come within r + rho of
/// its axis. Empty (c1 > c2) when it cannot meet the body at any axis.
std::pair<double, double> possible_range(const ToolBody& b, double d, double rho) {
  if (d <= rho + 1e-12) return {-1.0, 1.0};
  if (d - rho > std::sqrt(b.radius_mm * b.radius_mm + b.end_mm * b.end_mm) || d + rho < b.start_mm)
    return {1.0, -1.0};
  // |V . u| >= q keeps u's line within r + rho of the sphere's centre; V . u <= -q is also
  // allowed only where the slab reaches that far back.
  double c1 = (b.start_mm - rho) / d;
  const double s = (b.radius_mm + rho) / d;
  if (s < 1.0) {
    const double q = std::sqrt(1.0 - s * s);
    if (c1 > -q) c1 = std::max(c1, q);
  }
  return {std::max(c1, -1.0), std::min(1.0, (b.end_mm + rho) / d)};
}

/// The axes at which a point at distance d lies inside the body: d V . u within [start, end]
/// and d sin(angle) <= r.
std::pair<double, double> certain_range(const ToolBody& b, double d) {
  if (d <= 1e-12) return {1.0, -1.0};
  double c1 = b.start_mm / d;
  const double s = b.radius_mm / d;
  if (s < 1.0) c1 = std::max(c1, std::sqrt(1.0 - s * s));
  return {c1, std::min(1.0, b.end_mm / d)};
}

}  // namespace

/// One free_axes call: the occlusion map of the window's cells, and the two passes of the
/// walk over the tree (cspace.hpp) that block its cells.
class CSpaceRasteriser::Walk {
 public:
  Walk(const CSpaceRasteriser& part, const ToolModel& tool, const ContactPoint& cp,
       const Vec3d& centre, const Vec3d& input_axis, double max_dev_rad, const CSpaceGrid& grid,
       const std::vector<WindowCell>& cells)
      : part_(part),
        tool_(tool),
        cp_(cp),
        centre_(centre),
        input_axis_(input_axis),
        cos_dev_(std::cos(max_dev_rad)),
        sin_dev_(std::sin(max_dev_rad)),
        range_(tool.bodies.size()) {
    // The map over the window's rows; cells outside the window start blocked.
    g_.n_yaw = grid.yaw_cells();
    g_.cell_rad = deg_to_rad(grid.cell_deg());
    g_.r0 = cells.front().i;
    g_.r1 = cells.back().i + 1;
    for (int i = g_.r0; i < g_.r1; ++i) {
      const double a = grid.tilt_rad(i);
      g_.tilt.push_back(a);
      g_.cos_tilt.push_back(std::cos(a));
      g_.sin_tilt.push_back(std::sin(a));
    }
    g_.blocked.assign(static_cast<std::size_t>(g_.r1 - g_.r0) * static_cast<std::size_t>(g_.n_yaw),
                      1);
    for (const WindowCell& c : cells) g_.row(c.i)[c.j] = 0;
    // Per yaw: the direction of eq. 11 in the tangent plane and the one across it.
    yaw_dir_.resize(static_cast<std::size_t>(g_.n_yaw));
    yaw_side_.resize(yaw_dir_.size());
    for (int j = 0; j < g_.n_yaw; ++j) {
      const double b = grid.yaw_rad(j);
      yaw_dir_[static_cast<std::size_t>(j)] = std::cos(b) * cp.feed_dir + std::sin(b) * cp.side;
      yaw_side_[static_cast<std::size_t>(j)] = std::cos(b) * cp.side - std::sin(b) * cp.feed_dir;
    }
  }

  /// First pass, coarse: one point of the part per small subtree blocks its certain rings, so
  /// that the second pass finds most of the blocked region already marked.
  void coarse() {
    constexpr int kCoarseFaces = 64;
    std::vector<int> stack = {0};
    while (!part_.nodes_.empty() && !stack.empty()) {
      const Node& node = part_.nodes_[static_cast<std::size_t>(stack.back())];
      stack.pop_back();
      if (!possible(seen_from(centre_, node.sphere.centre, cp_), node.sphere.radius)) continue;
      if (node.left < 0 || node.count <= kCoarseFaces) {
        mark_certain(seen_from(
            centre_, part_.face_sphere_[static_cast<std::size_t>(node.first)].centre, cp_));
        continue;
      }
      stack.push_back(node.right);
      stack.push_back(node.left);
    }
  }

  /// Second pass: a subtree matters only while its possible rings hold an open cell; a face
  /// blocks its certain rings, and the exact test decides the open cells of its possible ones.
  void fine() {
    std::vector<int> stack(part_.nodes_.empty() ? 0 : 1, 0);
    while (!stack.empty()) {
      const Node& node = part_.nodes_[static_cast<std::size_t>(stack.back())];
      stack.pop_back();
      const Seen s = seen_from(centre_, node.sphere.centre, cp_);
      if (!possible(s, node.sphere.radius)) continue;
      bool open = false;
      for (std::size_t b = 0; b < range_.size() && !open; ++b) {
        open = ring_spans(g_, s, ring_of(g_, s, range_[b].first, range_[b].second, true),
                          [this](int i, int j0, int j1) { return has_open(i, j0, j1); });
      }
      if (!open) continue;
      if (node.left >= 0) {
        stack.push_back(node.right);
        stack.push_back(node.left);
        continue;
      }
      for (int f = node.first; f < node.first + node.count; ++f) face(f);
    }
  }

  bool blocked(const WindowCell& c) const { return g_.row(c.i)[c.j] != 0; }

 private:
  /// For a sphere seen at s with radius rho: each body's possible range of V . u, emptied
  /// where the whole range lies outside the deviation window; true when any is left.
  bool possible(const Seen& s, double rho) {
    bool any = false;
    for (std::size_t b = 0; b < range_.size(); ++b) {
      auto r = possible_range(tool_.bodies[b], s.d, rho);
      if (r.first <= r.second && s.d > rho + 1e-12) {
        // Within psi of u (cos psi = c1) and within max_dev of the input axis.
        const double sin_psi = std::sqrt(std::max(0.0, 1.0 - r.first * r.first));
        if (r.first > -cos_dev_ + 1e-12 &&  // max_dev + psi < pi
            s.u.dot(input_axis_) < cos_dev_ * r.first - sin_dev_ * sin_psi - 1e-9) {
          r = {1.0, -1.0};
        }
      }
      range_[b] = r;
      any = any || r.first <= r.second;
    }
    return any;
  }

  bool has_open(int i, int j0, int j1) const {
    return std::memchr(g_.row(i) + j0, 0, static_cast<std::size_t>(j1 - j0)) != nullptr;
  }
  bool mark(int i, int j0, int j1) {
    std::memset(g_.row(i) + j0, 1, static_cast<std::size_t>(j1 - j0));
    return false;
  }

  /// Cells blocked for certain by a point of the part: those whose body holds the point.
  void mark_certain(const Seen& p) {
    for (const ToolBody& body : tool_.bodies) {
      const auto [c1, c2] = certain_range(body, p.d);
      ring_spans(g_, p, ring_of(g_, p, c1, c2, false),
                 [this](int i, int j0, int j1) { return mark(i, j0, j1); });
    }
  }

  /// One face, row by row: where the possible ring holds an open cell, the certain ring (the
  /// centroid inside the body) blocks its cells, and the exact test decides the rest.
  void face(int f) {
    const Sphere& sphere = part_.face_sphere_[static_cast<std::size_t>(f)];
    const Seen fs = seen_from(centre_, sphere.centre, cp_);
    if (!possible(fs, sphere.radius)) return;
    const auto& t = part_.tri_[static_cast<std::size_t>(f)];
    const std::array<Vec3d, 3> rel = {t[0] - centre_, t[1] - centre_, t[2] - centre_};
    for (std::size_t b = 0; b < range_.size(); ++b) {
      if (range_[b].first > range_[b].second) continue;
      const ToolBody& body = tool_.bodies[b];
      const Ring maybe = ring_of(g_, fs, range_[b].first, range_[b].second, true);
      const auto [c1, c2] = certain_range(body, fs.d);
      const Ring sure = ring_of(g_, fs, c1, c2, false);
      for (int i = maybe.i0; i < maybe.i1; ++i) {
        unsigned char* row = g_.row(i);
        const auto open_here = [&](int j0, int j1) { return has_open(i, j0, j1); };
        if (!ring_row(g_, fs, maybe, i, open_here)) continue;
        if (i >= sure.i0 && i < sure.i1) {
          ring_row(g_, fs, sure, i, [&](int j0, int j1) { return mark(i, j0, j1); });
        }
        const std::size_t r = static_cast<std::size_t>(i - g_.r0);
        const double ca = g_.cos_tilt[r], sa = g_.sin_tilt[r];
        ring_row(g_, fs, maybe, i, [&](int j0, int j1) {
          for (int j = j0; j < j1; ++j) {
            if (row[j]) continue;
            // The cell's axis and a frame across it: d/da and d/db of eq. 11, normalised.
            const Vec3d& dj = yaw_dir_[static_cast<std::size_t>(j)];
            const Vec3d v = ca * cp_.surface_normal + sa * dj;
            const Vec3d e1 = ca * dj - sa * cp_.surface_normal;
            if (detail::meets_in_frame(rel, v, e1, yaw_side_[static_cast<std::size_t>(j)],
                                       body.radius_mm, body.start_mm, body.end_mm)) {
              row[j] = 1;
            }
          }
          return false;
        });
      }
    }
  }

  const CSpaceRasteriser& part_;
  const ToolModel& tool_;
  const ContactPoint& cp_;
  const Vec3d centre_, input_axis_;
  const double cos_dev_, sin_dev_;
  OcclusionMap g_;
  std::vector<Vec3d> yaw_dir_, yaw_side_;
  /// Each body's possible range of V . u for the sphere last asked about (possible).
  std::vector<std::pair<double, double>> range_;
};

CSpaceGrid CSpaceRasteriser::free_axes(const ToolModel& tool, const ContactPoint& cp,
                                       const Vec3d& centre, const Vec3d& input_axis,
                                       const CSpaceOptions& options) const {
  CSpaceGrid grid(options.cell_deg);
  if (cp.local_gouge) return grid;
  const double max_dev = deg_to_rad(options.max_deviation_deg);
  const std::vector<WindowCell> cells = window(grid, cp, input_axis, max_dev);
  if (cells.empty()) return grid;
  Walk walk(*this, tool, cp, centre, input_axis, max_dev, grid, cells);
  walk.coarse();
  walk.fine();
  for (const WindowCell& c : cells) {
    if (!walk.blocked(c)) store(grid, c);
  }
  return grid;
}

/// The slabs' slack for rounding (coordinates of a few metres: 1e-12 of them).
constexpr double kSlabMarginMm = 1e-6;

bool CSpaceRasteriser::collides(const ToolModel& tool, const Vec3d& centre, const Vec3d& axis,
                                bool with_ball) const {
  if (nodes_.empty()) return false;
  const Vec3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  const double ball_r = tool.ball_radius_mm;
  double reach = with_ball ? ball_r : 0.0;
  for (const ToolBody& b : tool.bodies) {
    reach = std::max(reach, std::sqrt(b.radius_mm * b.radius_mm + b.end_mm * b.end_mm));
  }
  // Whether a sphere (m, rho) can meet some body, or the ball (squared distances only).
  const auto near = [&](const Sphere& sp) {
    const Vec3d w = sp.centre - centre;
    const double w2 = w.squaredNorm(), rho = sp.radius;
    if (w2 > (reach + rho) * (reach + rho)) return false;
    if (with_ball && w2 <= (ball_r + rho) * (ball_r + rho)) return true;
    const double z = w.dot(axis), radial2 = w2 - z * z;
    for (const ToolBody& b : tool.bodies) {
      if (z + rho >= b.start_mm && z - rho <= b.end_mm &&
          radial2 <= (b.radius_mm + rho) * (b.radius_mm + rho)) {
        return true;
      }
    }
    return false;
  };
  // Whether some body, or the ball, reaches a node's slab: each body's extent along the slab's
  // normal n is n.c + [min, max](start n.a, end n.a) -/+ radius sqrt(1 - (n.a)^2).
  const auto reaches = [&](const Slab& slab) {
    const double nc = slab.normal.dot(centre), na = slab.normal.dot(axis);
    const double across = std::sqrt(std::max(0.0, 1.0 - na * na));
    const double lo = slab.lo - kSlabMarginMm, hi = slab.hi + kSlabMarginMm;
    if (with_ball && nc + ball_r >= lo && nc - ball_r <= hi) return true;
    for (const ToolBody& b : tool.bodies) {
      const double z0 = b.start_mm * na, z1 = b.end_mm * na;
      if (nc + std::max(z0, z1) + b.radius_mm * across >= lo &&
          nc + std::min(z0, z1) - b.radius_mm * across <= hi) {
        return true;
      }
    }
    return false;
  };
  // Depth-first; the tree is balanced (median splits), so its depth is about log2(faces / 4)
  // and a stack of 2 per level holds the walk.
  std::array<int, 256> stack{};
  std::size_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const auto id = static_cast<std::size_t>(stack[--top]);
    const Node& node = nodes_[id];
    if (!near(node.sphere) || !reaches(slab_[id])) continue;
    if (node.left >= 0) {
      stack[top++] = node.right;
      stack[top++] = node.left;
      continue;
    }
    for (int f = node.first; f < node.first + node.count; ++f) {
      if (!near(face_sphere_[static_cast<std::size_t>(f)])) continue;
      const auto& t = tri_[static_cast<std::size_t>(f)];
      if (with_ball &&
          detail::squared_distance_to_triangle(centre, t[0], t[1], t[2]) <= ball_r * ball_r) {
        return true;
      }
      const std::array<Vec3d, 3> rel = {t[0] - centre, t[1] - centre, t[2] - centre};
      for (const ToolBody& b : tool.bodies) {
        if (detail::meets_in_frame(rel, axis, e1, e2, b.radius_mm, b.start_mm, b.end_mm))
          return true;
      }
    }
  }
  return false;
}

CSpaceGrid rasterise_free_axes(const Part& part, const ToolModel& tool, const ContactPoint& cp,
                               const Vec3d& centre, const Vec3d& input_axis,
                               const CSpaceOptions& options) {
  return CSpaceRasteriser(part.mesh()).free_axes(tool, cp, centre, input_axis, options);
}

Vec3d cell_axis(const CSpaceGrid& grid, int i, int j, const ContactPoint& cp) {
  const double a = grid.tilt_rad(i), b = grid.yaw_rad(j);
  return std::cos(a) * cp.surface_normal +
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
                                 const MachineKinematicsd& machine) {
  std::vector<Posed> out;
  for (const Vec3d& v : free_axes_of(grid, cp)) {
    for (const Posed& p : machine.inverse(v)) {
      if (machine.tilt.contains(p.tilt_rad)) {
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
