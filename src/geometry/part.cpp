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
#include <iterator>
#include <stdexcept>

namespace taxopt {
namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using SearchTraits = CGAL::Search_traits_3<K>;
using Knn = CGAL::Orthogonal_k_neighbor_search<SearchTraits>;
using KdTree = Knn::Tree;

K::Point_3 to_cgal(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }
Vec3d to_eigen(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }

/// Monomials of the height jet up to degree 3: 1, x, y, x2, xy, y2, x3, x2y, xy2, y3.
constexpr int kTerms3 = 10, kTerms2 = 6;

}  // namespace

struct Part::Impl {
  TriangleMesh mesh;
  Triangles triangles;
  Tree tree;
  KdTree kd;
  double mean_edge = 0.0;
};

Part::Part(TriangleMesh mesh) : impl_(std::make_unique<Impl>()) {
  if (mesh.faces.empty()) throw std::invalid_argument("Part: empty mesh");
  impl_->mesh = std::move(mesh);
  const auto& m = impl_->mesh;
  impl_->triangles.reserve(m.faces.size());
  double edges = 0.0;
  for (const auto& f : m.faces) {
    const Vec3d& a = m.vertices[static_cast<std::size_t>(f[0])];
    const Vec3d& b = m.vertices[static_cast<std::size_t>(f[1])];
    const Vec3d& c = m.vertices[static_cast<std::size_t>(f[2])];
    impl_->triangles.emplace_back(to_cgal(a), to_cgal(b), to_cgal(c));
    edges += (b - a).norm() + (c - b).norm() + (a - c).norm();
  }
  impl_->mean_edge = edges / (3.0 * static_cast<double>(m.faces.size()));
  impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
  for (const auto& v : m.vertices) impl_->kd.insert(to_cgal(v));
  impl_->kd.build();
}

Part::~Part() = default;
Part::Part(Part&&) noexcept = default;
Part& Part::operator=(Part&&) noexcept = default;

const TriangleMesh& Part::mesh() const { return impl_->mesh; }
double Part::mean_edge_mm() const { return impl_->mean_edge; }

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
  const Vec3d qa(0.0, 0.0, (q - c.point).dot(w));  // q in the local frame

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
  const int terms = local.size() >= 15 ? kTerms3 : (local.size() >= 8 ? kTerms2 : 0);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(kTerms3);
  if (terms > 0 && radius > 0.0) {
    // Least squares in coordinates scaled by the sample radius (well conditioned).
    const double s = radius;
    Eigen::MatrixXd A(static_cast<Eigen::Index>(local.size()), terms);
    Eigen::VectorXd b(static_cast<Eigen::Index>(local.size()));
    for (std::size_t i = 0; i < local.size(); ++i) {
      const double x = local[i].x() / s, y = local[i].y() / s;
      const double m[kTerms3] = {1,     x,         y,         x * x,     x * y,
                                 y * y, x * x * x, x * x * y, x * y * y, y * y * y};
      for (int k = 0; k < terms; ++k) A(static_cast<Eigen::Index>(i), k) = m[k];
      b(static_cast<Eigen::Index>(i)) = local[i].z();
    }
    const Eigen::VectorXd sol = A.colPivHouseholderQr().solve(b);
    // Back to unscaled coefficients.
    const double sc[kTerms3] = {1,     s,         s,         s * s,     s * s,
                                s * s, s * s * s, s * s * s, s * s * s, s * s * s};
    for (int k = 0; k < terms; ++k) a(k) = sol(k) / sc[k];
    out.samples = static_cast<int>(local.size());
  }
  // h and derivatives of the jet at (x, y).
  const auto eval = [&a](double x, double y, double d[6]) {
    d[0] = a(0) + a(1) * x + a(2) * y + a(3) * x * x + a(4) * x * y + a(5) * y * y +
           a(6) * x * x * x + a(7) * x * x * y + a(8) * x * y * y + a(9) * y * y * y;
    d[1] = a(1) + 2 * a(3) * x + a(4) * y + 3 * a(6) * x * x + 2 * a(7) * x * y + a(8) * y * y;
    d[2] = a(2) + a(4) * x + 2 * a(5) * y + a(7) * x * x + 2 * a(8) * x * y + 3 * a(9) * y * y;
    d[3] = 2 * a(3) + 6 * a(6) * x + 2 * a(7) * y;
    d[4] = a(4) + 2 * a(7) * x + 2 * a(8) * y;
    d[5] = 2 * a(5) + 2 * a(8) * x + 6 * a(9) * y;
  };
  // Point of the fitted surface nearest to q: Newton on |S(x, y) - q|^2.
  double x = 0.0, y = 0.0, d[6];
  for (int it = 0; it < 30; ++it) {
    eval(x, y, d);
    const double r = d[0] - qa.z();
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
  eval(x, y, d);
  out.jet.p = c.point + x * u + y * v + d[0] * w;
  out.jet.su = u + d[1] * w;
  out.jet.sv = v + d[2] * w;
  out.jet.suu = d[3] * w;
  out.jet.suv = d[4] * w;
  out.jet.svv = d[5] * w;
  return out;
}

}  // namespace taxopt
