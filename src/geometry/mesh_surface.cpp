// The designed surface as a part's mesh gives it (mesh_surface.hpp).
#include "geometry/mesh_surface.hpp"

#include <algorithm>
#include <cmath>

namespace taxopt::detail {

Vec3d face_normal(const TriangleMesh& m, const std::array<int, 3>& f) {
  const Vec3d& a = m.vertices[static_cast<std::size_t>(f[0])];
  const Vec3d n = (m.vertices[static_cast<std::size_t>(f[1])] - a)
                      .cross(m.vertices[static_cast<std::size_t>(f[2])] - a);
  const double l = n.norm();
  return l > 0.0 ? Vec3d(n / l) : Vec3d::Zero();
}

double width_across(const TriangleMesh& m, const std::array<int, 3>& f, int a, int b,
                    Vec3d* opposite) {
  int o = f[0];
  for (int v : f) {
    if (v != a && v != b) o = v;
  }
  const Vec3d& pa = m.vertices[static_cast<std::size_t>(a)];
  const Vec3d e = (m.vertices[static_cast<std::size_t>(b)] - pa).normalized();
  const Vec3d d = m.vertices[static_cast<std::size_t>(o)] - pa;
  if (opposite) *opposite = m.vertices[static_cast<std::size_t>(o)];
  return (d - d.dot(e) * e).norm();
}

namespace {

/// An edge of a face as (low vertex, high vertex, face).
struct HalfEdge {
  int a, b, face;
};

/// Every face's edges, sorted by (low vertex, high vertex, face) so that the faces sharing an
/// edge stand next to each other: placed by low vertex (a counting sort, linear), then each
/// vertex's few sorted.
std::vector<HalfEdge> sorted_half_edges(const TriangleMesh& m, const StopSource* stop) {
  std::vector<std::size_t> start(m.vertices.size() + 1, 0);
  const auto edge = [&](std::size_t f, int k) {
    const int a = m.faces[f][static_cast<std::size_t>(k)];
    const int b = m.faces[f][static_cast<std::size_t>((k + 1) % 3)];
    return HalfEdge{std::min(a, b), std::max(a, b), static_cast<int>(f)};
  };
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    look_at_stop(stop, f);
    for (int k = 0; k < 3; ++k) ++start[static_cast<std::size_t>(edge(f, k).a) + 1];
  }
  for (std::size_t v = 0; v + 1 < start.size(); ++v) start[v + 1] += start[v];
  std::vector<HalfEdge> edges(3 * m.faces.size());
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    look_at_stop(stop, f);
    for (int k = 0; k < 3; ++k) {
      const HalfEdge e = edge(f, k);
      edges[fill[static_cast<std::size_t>(e.a)]++] = e;
    }
  }
  for (std::size_t v = 0; v + 1 < start.size(); ++v) {
    look_at_stop(stop, v);
    std::sort(edges.begin() + static_cast<std::ptrdiff_t>(start[v]),
              edges.begin() + static_cast<std::ptrdiff_t>(start[v + 1]),
              [](const HalfEdge& x, const HalfEdge& y) {
                return x.b != y.b ? x.b < y.b : x.face < y.face;
              });
  }
  return edges;
}

/// A face smaller than this times the biggest face of a corner (by least height) does not
/// enter the corner's normal (an evenly or gradually refined mesh never has one).
constexpr double kSmallerFace = 0.25;

/// The faces around each vertex (compressed rows: vertex v's are around[start[v] ..
/// start[v + 1]]), each with the face's angle at the vertex.
struct VertexFaces {
  std::vector<std::size_t> start;
  std::vector<std::pair<int, double>> around;
};

VertexFaces faces_around_vertices(const TriangleMesh& m, const StopSource* stop) {
  const std::size_t nf = m.faces.size(), nv = m.vertices.size();
  VertexFaces vf;
  vf.start.assign(nv + 1, 0);
  for (const auto& f : m.faces) {
    for (int v : f) ++vf.start[static_cast<std::size_t>(v) + 1];
  }
  for (std::size_t v = 0; v < nv; ++v) vf.start[v + 1] += vf.start[v];
  vf.around.resize(vf.start[nv]);
  std::vector<std::size_t> fill(vf.start.begin(), vf.start.end() - 1);
  for (std::size_t f = 0; f < nf; ++f) {
    look_at_stop(stop, f);
    for (int k = 0; k < 3; ++k) {
      const auto& F = m.faces[f];
      const Vec3d& p = m.vertices[static_cast<std::size_t>(F[static_cast<std::size_t>(k)])];
      const Vec3d e1 =
          m.vertices[static_cast<std::size_t>(F[static_cast<std::size_t>((k + 1) % 3)])] - p;
      const Vec3d e2 =
          m.vertices[static_cast<std::size_t>(F[static_cast<std::size_t>((k + 2) % 3)])] - p;
      const double l = e1.norm() * e2.norm();
      const double angle = l > 0.0 ? std::acos(std::clamp(e1.dot(e2) / l, -1.0, 1.0)) : 0.0;
      vf.around[fill[static_cast<std::size_t>(F[static_cast<std::size_t>(k)])]++] = {
          static_cast<int>(f), angle};
    }
  }
  return vf;
}

/// A face's size: its least height (2 area / longest edge), the width of a fillet's strip.
std::vector<double> face_sizes(const TriangleMesh& m) {
  std::vector<double> size(m.faces.size(), 0.0);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    const auto& F = m.faces[f];
    const Vec3d& a = m.vertices[static_cast<std::size_t>(F[0])];
    const Vec3d& b = m.vertices[static_cast<std::size_t>(F[1])];
    const Vec3d& c = m.vertices[static_cast<std::size_t>(F[2])];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (longest > 0.0) size[f] = (b - a).cross(c - a).norm() / longest;
  }
  return size;
}

/// SurfaceModel::corner_normal, from the faces' normals `fn`.
std::vector<Eigen::Vector3f> corner_normals(const TriangleMesh& m, const std::vector<Vec3d>& fn,
                                            const StopSource* stop) {
  const std::size_t nf = m.faces.size();
  const VertexFaces vf = faces_around_vertices(m, stop);
  const std::vector<double> size = face_sizes(m);
  const double crease_cos = std::cos(kCreaseRad);
  std::vector<Eigen::Vector3f> out(3 * nf, Eigen::Vector3f::Zero());
  for (std::size_t f = 0; f < nf; ++f) {
    look_at_stop(stop, f);
    if (fn[f].isZero()) continue;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(m.faces[f][static_cast<std::size_t>(k)]);
      // The corner's faces on this side of any crease (either orientation: a mesh's faces
      // need not agree on theirs), and the biggest of them.
      const auto same_side = [&](int g) {
        return std::abs(fn[static_cast<std::size_t>(g)].dot(fn[f])) >= crease_cos;
      };
      double biggest = 0.0;
      for (std::size_t r = vf.start[v]; r < vf.start[v + 1]; ++r) {
        if (same_side(vf.around[r].first)) {
          biggest = std::max(biggest, size[static_cast<std::size_t>(vf.around[r].first)]);
        }
      }
      // A big face beside a fillet's thin strips is a designed plane, tangent to the fillet
      // where they meet: the corner takes its normal alone (mixed with the strips', a CAD
      // part's 60 mm top tilted by 1.9 deg beside a 4 mm fillet in 12 strips, and a fillet's
      // first strip by half its turn where it meets the floor).
      Vec3d sum = Vec3d::Zero();
      for (std::size_t r = vf.start[v]; r < vf.start[v + 1]; ++r) {
        const auto [g, angle] = vf.around[r];
        if (!same_side(g) || size[static_cast<std::size_t>(g)] < kSmallerFace * biggest) continue;
        const Vec3d& ng = fn[static_cast<std::size_t>(g)];
        sum += (ng.dot(fn[f]) < 0.0 ? -angle : angle) * ng;
      }
      if (sum.norm() > 0.0)
        out[3 * f + static_cast<std::size_t>(k)] = sum.normalized().cast<float>();
    }
  }
  return out;
}

/// SurfaceModel::feature_edges and feature_vertex: the edges no tessellated curve runs over
/// (not shared by exactly two faces, or turning by kCreaseRad or more between them).
void feature_edges(const TriangleMesh& m, const std::vector<Vec3d>& fn,
                   const std::vector<HalfEdge>& edges, SurfaceModel& s, const StopSource* stop) {
  const double crease_cos = std::cos(kCreaseRad);
  s.feature_vertex.assign(m.vertices.size(), false);
  std::size_t runs = 0;
  for (std::size_t i = 0; i < edges.size();) {
    look_at_stop(stop, runs++);
    std::size_t j = i;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
    bool feature = j - i != 2;
    if (!feature) {
      const Vec3d& n1 = fn[static_cast<std::size_t>(edges[i].face)];
      const Vec3d& n2 = fn[static_cast<std::size_t>(edges[i + 1].face)];
      feature = n1.isZero() || n2.isZero() || std::abs(n1.dot(n2)) < crease_cos;
    }
    if (feature) {
      s.feature_edges.push_back({edges[i].a, edges[i].b});
      s.feature_vertex[static_cast<std::size_t>(edges[i].a)] = true;
      s.feature_vertex[static_cast<std::size_t>(edges[i].b)] = true;
    }
    i = j;
  }
}

/// Every face's unit normal (face_normal).
std::vector<Vec3d> face_normals(const TriangleMesh& m, const StopSource* stop) {
  std::vector<Vec3d> fn(m.faces.size());
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    look_at_stop(stop, f);
    fn[f] = face_normal(m, m.faces[f]);
  }
  return fn;
}

/// The chordal error estimate of Part::chordal_error_mm, from the faces' normals and the
/// sorted half-edges.
double chordal_error(const TriangleMesh& m, const std::vector<Vec3d>& fn,
                     const std::vector<HalfEdge>& edges, const StopSource* stop) {
  // Every edge two facets share, with its turn below 30 deg (sharper is a designed edge).
  struct Turn {
    int a, b, f1, f2;
    double angle_rad;
  };
  std::vector<Turn> turns;
  const double sharp = kCreaseRad;
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    look_at_stop(stop, i);
    const HalfEdge& e = edges[i];
    const HalfEdge& g = edges[i + 1];
    if (e.a != g.a || e.b != g.b) continue;
    if (i + 2 < edges.size() && edges[i + 2].a == e.a && edges[i + 2].b == e.b) continue;
    const Vec3d& n1 = fn[static_cast<std::size_t>(e.face)];
    const Vec3d& n2 = fn[static_cast<std::size_t>(g.face)];
    if (n1.isZero() || n2.isZero()) continue;
    // Consistently oriented neighbours share the edge in opposite directions: the angle
    // between their normals is the turn; else one is flipped.
    const double angle = std::acos(std::clamp(std::abs(n1.dot(n2)), 0.0, 1.0));
    // Below 1e-5 rad: one plane (an STL's float coordinates turn its facets by about 1e-7).
    if (angle > 1e-5 && angle < sharp) turns.push_back({e.a, e.b, e.face, g.face, angle});
  }
  // The largest turn at each vertex: a facet's far vertex on a curved surface carries a turn
  // of the same order; on a flat face beside a designed crease (or chamfer) it carries none.
  std::vector<double> vertex_turn(m.vertices.size(), 0.0);
  for (const Turn& t : turns) {
    for (int v : {t.a, t.b}) {
      double& w = vertex_turn[static_cast<std::size_t>(v)];
      w = std::max(w, t.angle_rad);
    }
  }
  double largest = 0.0;
  for (std::size_t k = 0; k < turns.size(); ++k) {
    look_at_stop(stop, k);
    const Turn& t = turns[k];
    const std::array<int, 3>& f1 = m.faces[static_cast<std::size_t>(t.f1)];
    const std::array<int, 3>& f2 = m.faces[static_cast<std::size_t>(t.f2)];
    const auto far_vertex_turn = [&](const std::array<int, 3>& f) {
      for (int v : f) {
        if (v != t.a && v != t.b) return vertex_turn[static_cast<std::size_t>(v)];
      }
      return 0.0;
    };
    // A curved surface's tessellation: both facets' far vertices turn too (by at least a
    // quarter of this edge's turn); a crease between flat faces, or a lone chamfer, not.
    if (far_vertex_turn(f1) < 0.25 * t.angle_rad || far_vertex_turn(f2) < 0.25 * t.angle_rad) {
      continue;
    }
    const double h = std::min(width_across(m, f1, t.a, t.b), width_across(m, f2, t.a, t.b));
    // The sagitta of an arc turning by the angle over a chord h: h/2 tan(angle/4) (h angle/8
    // to first order; exact for a circle tessellated evenly, so never below it there).
    largest = std::max(largest, 0.5 * h * std::tan(0.25 * t.angle_rad));
  }
  return largest;
}

}  // namespace

SurfaceModel surface_and_chordal_error(const TriangleMesh& m, double& chordal_error_mm,
                                       const StopSource* stop) {
  const std::vector<Vec3d> fn = face_normals(m, stop);
  const std::vector<HalfEdge> edges = sorted_half_edges(m, stop);
  SurfaceModel s;
  s.corner_normal = corner_normals(m, fn, stop);
  feature_edges(m, fn, edges, s, stop);
  chordal_error_mm = chordal_error(m, fn, edges, stop);
  return s;
}

}  // namespace taxopt::detail
