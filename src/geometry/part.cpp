// The part's search structures (CGAL) and local jet fitting (Eigen).
#include "taxopt/geometry/part.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <iterator>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "geometry/mesh_surface.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/core/stop.hpp"
#include "util/parallel.hpp"

namespace taxopt {
namespace {

using detail::face_normal;
using detail::surface_and_chordal_error;
using detail::SurfaceModel;
using detail::width_across;

using K = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Traits = CGAL::AABB_traits<K, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;
using SearchTraits = CGAL::Search_traits_3<K>;

using Knn = CGAL::Orthogonal_k_neighbor_search<SearchTraits>;
using KdTree = Knn::Tree;

/// The AABB tree's split of a node's primitives (CGAL's own: at the median along the box's
/// longest axis), looking at the stop first.
struct StoppableSplit {
  Traits::Split_primitives split;
  const StopSource* stop;
  template <class Iterator, class Box>
  void operator()(Iterator first, Iterator beyond, const Box& box) const {
    stop->throw_if_stop_requested();
    split(first, beyond, box);
  }
};

K::Point_3 to_cgal(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }
Vec3d to_eigen(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }

/// Monomials of the height jet up to degree 3: 1, x, y, x2, xy, y2, x3, x2y, xy2, y3.
constexpr int kTerms3 = 10, kTerms2 = 6;

/// Barycentric coordinates w of point p in face f (false for a degenerate face).
bool barycentric(const TriangleMesh& m, const std::array<int, 3>& f, const Vec3d& p, double w[3]) {
  const Vec3d& A = m.vertices[static_cast<std::size_t>(f[0])];
  const Vec3d& B = m.vertices[static_cast<std::size_t>(f[1])];
  const Vec3d& C = m.vertices[static_cast<std::size_t>(f[2])];
  const Vec3d n = (B - A).cross(C - A);
  const double area2 = n.squaredNorm();
  if (!(area2 > 0.0)) return false;
  w[0] = (C - B).cross(p - B).dot(n) / area2;
  w[1] = (A - C).cross(p - C).dot(n) / area2;
  w[2] = (B - A).cross(p - A).dot(n) / area2;
  return true;
}

/// A barycentric weight at or below this: the point lies on the opposite edge.
constexpr double kOnVertexWeight = 1e-7;

/// The vertices of face f point p does not lie opposite to (weight above kOnVertexWeight):
/// three inside the face, two on an edge, one (or none: then f's first) at a vertex. False
/// for a degenerate face.
bool vertices_at(const TriangleMesh& m, const std::array<int, 3>& f, const Vec3d& p,
                 std::vector<int>& on) {
  double w[3];
  if (!barycentric(m, f, p, w)) return false;
  on.clear();
  for (int k = 0; k < 3; ++k) {
    if (w[k] > kOnVertexWeight) on.push_back(f[static_cast<std::size_t>(k)]);
  }
  if (on.empty()) on.push_back(f[0]);
  return true;
}
/// The exact normal of a point on a designed edge turns more than this off its face's: the
/// ball touches the edge, not the face beside it (1e-4 rad: far above the closest point's
/// rounding, far below any tessellation's turn).
constexpr double kOnFeatureRad = 1e-4;

}  // namespace

struct Part::Impl {
  TriangleMesh mesh;
  Triangles triangles;
  Tree tree;
  KdTree kd;
  double mean_edge = 0.0;
  double chordal_error = 0.0;
  SurfaceModel surface;
};

Part::Part(TriangleMesh mesh) : Part(std::move(mesh), StopSource()) {}

namespace {

/// What Part's constructor refuses: no faces, a vertex not finite or beyond any machine, a
/// face naming a vertex the mesh lacks.
void check_mesh(const TriangleMesh& mesh, const StopSource& stop) {
  // As the mesh readers check a file: a mesh built in code has not been read.
  if (mesh.faces.empty()) throw InputError("Part: the mesh has no faces");
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    detail::look_at_stop(&stop, v);
    // Beyond any machine (1 km, as the CL reader's reach) a coordinate is a broken mesh, and
    // FCL's fitting of its bounding volumes does not converge.
    if (!mesh.vertices[v].allFinite() ||
        mesh.vertices[v].cwiseAbs().maxCoeff() > kMaxCoordinateMm) {
      throw InputError("Part: vertex " + std::to_string(v) +
                       " is not a finite point within +-1e6 mm");
    }
  }
  const auto count = static_cast<long long>(mesh.vertices.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    detail::look_at_stop(&stop, f);
    for (int index : mesh.faces[f]) {
      if (index < 0 || index >= count) {
        throw InputError("Part: face " + std::to_string(f) + " names vertex " +
                         std::to_string(index) + " of " + std::to_string(count));
      }
    }
  }
}

/// Runs `build(*owner)`, one call that cannot be stopped inside, on a thread of its own while
/// the caller looks at `stop`. A stop ends the wait at once (Cancelled, or the stop's reason)
/// and hands `owner` to that thread, which frees it when the call returns; the caller never
/// waits for it. (CGAL's distance search tree takes 0.13 s at 490k faces in one call, and
/// CGAL's Kd_tree leaks its box when its build throws: a stop inside it cannot be thrown.)
template <class T, class F>
void build_or_leave(std::unique_ptr<T>& owner, const StopSource& stop, F build) {
  struct Shared {
    std::mutex mutex;
    std::condition_variable ended;
    bool done = false;
    std::exception_ptr error;
    std::unique_ptr<T> left;  // the owner, once the caller has left
  };
  const auto shared = std::make_shared<Shared>();
  std::thread worker([shared, target = owner.get(), build] {
    std::exception_ptr error;
    try {
      build(*target);
    } catch (...) {
      error = std::current_exception();
    }
    const std::lock_guard<std::mutex> lock(shared->mutex);
    shared->done = true;
    shared->error = error;
    shared->ended.notify_all();
  });
  std::unique_lock<std::mutex> lock(shared->mutex);
  while (!shared->done) {
    if (stop.stop_requested()) {
      shared->left = std::move(owner);
      lock.unlock();
      worker.detach();
      stop.throw_if_stop_requested();
    }
    shared->ended.wait_for(lock, std::chrono::milliseconds(2));
  }
  lock.unlock();
  worker.join();
  if (shared->error) std::rethrow_exception(shared->error);
}

}  // namespace

Part::Part(TriangleMesh mesh, const StopSource& stop) : Part(std::move(mesh), stop, {}) {}

Part::Part(TriangleMesh mesh, const StopSource& stop,
           const std::function<void(const std::string&, std::size_t, std::size_t)>& progress)
    : impl_(std::make_unique<Impl>()) {
  // Six steps, each counted as the faces: the mesh checked; the triangles, the surface model
  // and chordal error, the AABB tree, the vertices' k-d tree (two at a time); the AABB tree's
  // search tree.
  const std::size_t faces = mesh.faces.size();
  detail::StageProgress building(progress, "building the part", 6 * faces, stop);
  check_mesh(mesh, stop);
  building.advance(faces);
  impl_->mesh = std::move(mesh);
  const auto& m = impl_->mesh;
  // Side by side (each looks at the stop): the triangles and their AABB tree; the surface
  // model with its chordal error, and the vertices' k-d tree. The tree's search tree after
  // both (build_or_leave).
  detail::parallel_invoke(
      [&] {
        impl_->triangles.reserve(m.faces.size());
        double edges = 0.0;
        for (std::size_t k = 0; k < m.faces.size(); ++k) {
          detail::look_at_stop(&stop, k);
          const auto& f = m.faces[k];
          const Vec3d& a = m.vertices[static_cast<std::size_t>(f[0])];
          const Vec3d& b = m.vertices[static_cast<std::size_t>(f[1])];
          const Vec3d& c = m.vertices[static_cast<std::size_t>(f[2])];
          impl_->triangles.emplace_back(to_cgal(a), to_cgal(b), to_cgal(c));
          edges += (b - a).norm() + (c - b).norm() + (a - c).norm();
        }
        impl_->mean_edge = edges / (3.0 * static_cast<double>(m.faces.size()));
        building.advance(faces);
        impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
        impl_->tree.custom_build(
            impl_->tree.traits().compute_bbox_object(),
            StoppableSplit{impl_->tree.traits().split_primitives_object(), &stop});
        building.advance(faces);
      },
      [&] {
        impl_->surface = surface_and_chordal_error(m, impl_->chordal_error, &stop);
        building.advance(faces);
        for (std::size_t v = 0; v < m.vertices.size(); ++v) {
          detail::look_at_stop(&stop, v);
          impl_->kd.insert(to_cgal(m.vertices[v]));
        }
        stop.throw_if_stop_requested();
        impl_->kd.build();
        building.advance(faces);
      });
  // The k-d trees are CGAL's single calls (0.13 and 0.03 s at 490k faces): the search tree is
  // built apart and left to finish on its own when a stop comes.
  stop.throw_if_stop_requested();
  build_or_leave(impl_, stop, [](Impl& impl) { impl.tree.accelerate_distance_queries(); });
  building.advance(faces);
}

Part::~Part() = default;
Part::Part(Part&&) noexcept = default;
Part& Part::operator=(Part&&) noexcept = default;

const TriangleMesh& Part::mesh() const { return impl_->mesh; }
double Part::mean_edge_mm() const { return impl_->mean_edge; }
double Part::chordal_error_mm() const { return impl_->chordal_error; }

Part::MeshCurvature Part::mesh_curvature(const Closest& c, const Vec3d& normal) const {
  const TriangleMesh& m = impl_->mesh;
  const std::array<int, 3>& f = m.faces[static_cast<std::size_t>(c.face)];
  MeshCurvature out;
  out.curvature.d1 = normal.unitOrthogonal();
  out.curvature.d2 = normal.cross(out.curvature.d1);
  std::vector<int> on;  // the face's vertices the point lies at or between
  if (!vertices_at(m, f, c.point, on)) return out;
  if (on.size() == 3) return out;  // inside the facet: flat
  // The curvature across edge (a, b) of this mesh, from the two faces on it.
  const auto across = [&](int a, int b, double& k, Vec3d& dir) {
    k = 0.0;
    const Vec3d& pa = m.vertices[static_cast<std::size_t>(a)];
    const Vec3d e = (m.vertices[static_cast<std::size_t>(b)] - pa).normalized();
    dir = e.cross(normal);
    if (dir.norm() < 1e-12) return false;
    dir.normalize();
    const Vec3d mid = 0.5 * (pa + m.vertices[static_cast<std::size_t>(b)]);
    std::vector<int> faces;
    for (int g : faces_within(mid, 1e-9 * std::max(1.0, mid.norm()))) {
      const auto& fg = m.faces[static_cast<std::size_t>(g)];
      if (std::count(fg.begin(), fg.end(), a) && std::count(fg.begin(), fg.end(), b)) {
        faces.push_back(g);
      }
    }
    if (faces.size() != 2) return false;  // a border or a non-manifold edge: no turn known
    Vec3d o1, o2;
    const auto& f1 = m.faces[static_cast<std::size_t>(faces[0])];
    const auto& f2 = m.faces[static_cast<std::size_t>(faces[1])];
    const double h = 0.5 * (width_across(m, f1, a, b, &o1) + width_across(m, f2, a, b, &o2));
    Vec3d n1 = face_normal(m, f1), n2 = face_normal(m, f2);
    if (n1.dot(normal) < 0.0) n1 = -n1;
    if (n2.dot(normal) < 0.0) n2 = -n2;
    const double angle = std::acos(std::clamp(n1.dot(n2), -1.0, 1.0));
    // Concave where a face's far vertex rises above the other face towards `normal`.
    const bool concave = (o2 - pa).dot(n1) > 0.0 || (o1 - pa).dot(n2) > 0.0;
    k = h > 0.0 ? (concave ? 1.0 : -1.0) * angle / h : 0.0;
    return true;
  };
  std::vector<std::pair<int, int>> edges;
  if (on.size() == 2) {
    out.feature = Feature::Edge;
    edges.push_back({on[0], on[1]});
  } else {
    out.feature = Feature::Vertex;
    const int v = on[0];
    for (int g : faces_within(m.vertices[static_cast<std::size_t>(v)], 1e-9)) {
      for (int u : m.faces[static_cast<std::size_t>(g)]) {
        if (u != v) edges.push_back({std::min(u, v), std::max(u, v)});
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
  double k_max = 0.0, k_min = 0.0;
  Vec3d d_max = out.curvature.d1, d_min = out.curvature.d2;
  for (const auto& [a, b] : edges) {
    double k = 0.0;
    Vec3d dir;
    if (!across(a, b, k, dir)) continue;
    if (k > k_max) k_max = k, d_max = dir;
    if (k < k_min) k_min = k, d_min = dir;
  }
  // k1 >= k2; the other direction is perpendicular in the tangent plane.
  if (k_max > 0.0) {
    out.curvature.k1 = k_max;
    out.curvature.d1 = d_max;
    out.curvature.d2 = normal.cross(d_max).normalized();
    out.curvature.k2 = k_min;
  } else if (k_min < 0.0) {
    out.curvature.k2 = k_min;
    out.curvature.d2 = d_min;
    out.curvature.d1 = d_min.cross(normal).normalized();
    out.curvature.k1 = 0.0;
  }
  return out;
}

Part::SurfaceNormal Part::surface_normal(const Closest& c, const Vec3d& exact_normal) const {
  const TriangleMesh& m = impl_->mesh;
  const SurfaceModel& sm = impl_->surface;
  const auto face = static_cast<std::size_t>(c.face);
  const std::array<int, 3>& f = m.faces[face];
  SurfaceNormal out;
  out.normal = exact_normal;
  std::vector<int> on;
  if (!vertices_at(m, f, c.point, on)) {
    out.on_feature = true;  // a degenerate face: no surface of its own
    return out;
  }
  out.where = on.size() == 3 ? Feature::Facet : (on.size() == 2 ? Feature::Edge : Feature::Vertex);
  bool on_feature_edge = false;
  if (out.where == Feature::Edge) {
    const std::pair<int, int> e{std::min(on[0], on[1]), std::max(on[0], on[1])};
    on_feature_edge = std::binary_search(sm.feature_edges.begin(), sm.feature_edges.end(), e);
  } else if (out.where == Feature::Vertex) {
    const int v = on[0];
    on_feature_edge = sm.feature_vertex[static_cast<std::size_t>(v)];
  }
  Vec3d own = face_normal(m, f);
  if (own.dot(exact_normal) < 0.0) own = -own;
  // The ball rolls over a designed edge: its normal turns off the face's own.
  if (on_feature_edge && angle_between(own, exact_normal) > kOnFeatureRad) {
    out.on_feature = true;
    return out;
  }
  const Vec3d n = smooth_normal(c, exact_normal);
  if (n.isZero()) {
    out.on_feature = true;
    return out;
  }
  out.normal = n;
  return out;
}

Vec3d Part::smooth_normal(const Closest& c, const Vec3d& side) const {
  const TriangleMesh& m = impl_->mesh;
  const auto face = static_cast<std::size_t>(c.face);
  double w[3];
  if (!barycentric(m, m.faces[face], c.point, w)) return Vec3d::Zero();
  Vec3d n = Vec3d::Zero();
  for (std::size_t k = 0; k < 3; ++k) {
    n += std::clamp(w[k], 0.0, 1.0) * impl_->surface.corner_normal[3 * face + k].cast<double>();
  }
  if (!(n.norm() > 1e-9)) return Vec3d::Zero();
  n.normalize();
  return n.dot(side) < 0.0 ? Vec3d(-n) : n;
}

Part::Closest Part::closest(const Vec3d& q) const {
  const auto hit = impl_->tree.closest_point_and_primitive(to_cgal(q));
  Closest c;
  c.point = to_eigen(hit.first);
  c.face = static_cast<int>(hit.second - impl_->triangles.cbegin());
  c.distance_mm = (c.point - q).norm();
  return c;
}

std::vector<int> Part::faces_within(const Vec3d& q, double radius_mm) const {
  const CGAL::Bbox_3 box(q.x() - radius_mm, q.y() - radius_mm, q.z() - radius_mm, q.x() + radius_mm,
                         q.y() + radius_mm, q.z() + radius_mm);
  std::vector<Tree::Primitive_id> hits;
  impl_->tree.all_intersected_primitives(box, std::back_inserter(hits));
  std::vector<int> out;
  out.reserve(hits.size());
  const K::Point_3 p = to_cgal(q);
  const double r2 = radius_mm * radius_mm;
  for (const auto& h : hits) {
    if (CGAL::squared_distance(p, *h) <= r2)
      out.push_back(static_cast<int>(h - impl_->triangles.cbegin()));
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

/// The monomials of the height jet at (x, y): 1, x, y, x2, xy, y2, x3, x2y, xy2, y3.
void monomials(double x, double y, double m[kTerms3]) {
  const double v[kTerms3] = {1,     x,         y,         x * x,     x * y,
                             y * y, x * x * x, x * x * y, x * y * y, y * y * y};
  std::copy(v, v + kTerms3, m);
}

/// The height jet's coefficients (kTerms3, zero beyond those fitted) by least squares through
/// `local` (x, y, height), of degree 3 from 15 samples, 2 from 8, else none (all zero).
Eigen::VectorXd fit_height_jet(const std::vector<Eigen::Vector3d>& local, double radius) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(kTerms3);
  const int terms = local.size() >= 15 ? kTerms3 : (local.size() >= 8 ? kTerms2 : 0);
  if (terms == 0 || !(radius > 0.0)) return a;
  // Least squares in coordinates scaled by the sample radius (well conditioned).
  const double s = radius;
  Eigen::MatrixXd A(static_cast<Eigen::Index>(local.size()), terms);
  Eigen::VectorXd b(static_cast<Eigen::Index>(local.size()));
  for (std::size_t i = 0; i < local.size(); ++i) {
    double m[kTerms3];
    monomials(local[i].x() / s, local[i].y() / s, m);
    for (int k = 0; k < terms; ++k) A(static_cast<Eigen::Index>(i), k) = m[k];
    b(static_cast<Eigen::Index>(i)) = local[i].z();
  }
  const Eigen::VectorXd sol = A.colPivHouseholderQr().solve(b);
  // Back to unscaled coefficients.
  double sc[kTerms3];
  monomials(s, s, sc);
  for (int k = 0; k < terms; ++k) a(k) = sol(k) / sc[k];
  return a;
}

/// The jet's height and derivatives at (x, y): h, hx, hy, hxx, hxy, hyy.
void jet_at(const Eigen::VectorXd& a, double x, double y, double d[6]) {
  d[0] = a(0) + a(1) * x + a(2) * y + a(3) * x * x + a(4) * x * y + a(5) * y * y +
         a(6) * x * x * x + a(7) * x * x * y + a(8) * x * y * y + a(9) * y * y * y;
  d[1] = a(1) + 2 * a(3) * x + a(4) * y + 3 * a(6) * x * x + 2 * a(7) * x * y + a(8) * y * y;
  d[2] = a(2) + a(4) * x + 2 * a(5) * y + a(7) * x * x + 2 * a(8) * x * y + 3 * a(9) * y * y;
  d[3] = 2 * a(3) + 6 * a(6) * x + 2 * a(7) * y;
  d[4] = a(4) + 2 * a(7) * x + 2 * a(8) * y;
  d[5] = 2 * a(5) + 2 * a(8) * x + 6 * a(9) * y;
}

/// The point (x, y) of the jet's surface nearest to (0, 0, qz): Newton on |S(x, y) - q|^2,
/// its steps at most half the sample radius.
Eigen::Vector2d nearest_on_jet(const Eigen::VectorXd& a, double qz, double radius) {
  double x = 0.0, y = 0.0, d[6];
  for (int it = 0; it < 30; ++it) {
    jet_at(a, x, y, d);
    const double r = d[0] - qz;
    const Eigen::Vector2d g(x + r * d[1], y + r * d[2]);
    Eigen::Matrix2d H;
    H << 1 + d[1] * d[1] + r * d[3], d[1] * d[2] + r * d[4], d[1] * d[2] + r * d[4],
        1 + d[2] * d[2] + r * d[5];
    Eigen::Vector2d step;
    if (H.determinant() > 1e-12 && H(0, 0) > 0) {
      step = -H.inverse() * g;
    } else {
      step = -0.5 * g;  // not convex here: a gradient step
    }
    const double lim = std::max(1e-3, 0.5 * radius);
    if (step.norm() > lim) step *= lim / step.norm();
    x += step.x();
    y += step.y();
    if (step.norm() < 1e-12) break;
  }
  return {x, y};
}

}  // namespace

LocalFit Part::fit_towards(const Vec3d& q, int neighbours) const {
  const Closest c = closest(q);
  const auto& f = impl_->mesh.faces[static_cast<std::size_t>(c.face)];
  const auto& V = impl_->mesh.vertices;
  Vec3d w = q - c.point;
  if (w.norm() > 1e-9) {
    w.normalize();
  } else {
    w = (V[static_cast<std::size_t>(f[1])] - V[static_cast<std::size_t>(f[0])])
            .cross(V[static_cast<std::size_t>(f[2])] - V[static_cast<std::size_t>(f[0])])
            .normalized();
  }
  const Vec3d u = w.unitOrthogonal(), v = w.cross(u);

  // Samples: nearest vertices, dropping those steeper than 60 deg off the tangent plane
  // (the far side of a thin wall or of a sharp edge).
  std::vector<Eigen::Vector3d> local;
  Knn search(impl_->kd, to_cgal(c.point), static_cast<unsigned>(std::max(neighbours, 6)));
  double radius = 0.0;
  for (const auto& nb : search) {
    const Vec3d d = to_eigen(nb.first) - c.point;
    const Eigen::Vector3d l(d.dot(u), d.dot(v), d.dot(w));
    if (std::abs(l.z()) > 1.7320508 * std::hypot(l.x(), l.y()) + 1e-12) continue;
    local.push_back(l);
    radius = std::max(radius, std::hypot(l.x(), l.y()));
  }
  LocalFit out;
  const Eigen::VectorXd a = fit_height_jet(local, radius);
  if (local.size() >= 8 && radius > 0.0) out.samples = static_cast<int>(local.size());
  const Eigen::Vector2d at = nearest_on_jet(a, (q - c.point).dot(w), radius);  // q: (0, 0, qz)
  double d[6];
  jet_at(a, at.x(), at.y(), d);
  out.jet.p = c.point + at.x() * u + at.y() * v + d[0] * w;
  out.jet.su = u + d[1] * w;
  out.jet.sv = v + d[2] * w;
  out.jet.suu = d[3] * w;
  out.jet.suv = d[4] * w;
  out.jet.svv = d[5] * w;
  return out;
}

}  // namespace taxopt
