// The rasteriser's tree of bounding spheres over the part's faces (cspace.hpp): its build.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "taxopt/cspace/cspace.hpp"

namespace taxopt {

namespace {

/// The nodes of the tree over `count` faces: split in halves down to four faces or fewer.
std::size_t tree_nodes(std::size_t count) {
  return count <= 4 ? 1 : 1 + tree_nodes(count / 2) + tree_nodes(count - count / 2);
}

}  // namespace

CSpaceRasteriser::CSpaceRasteriser(const TriangleMesh& mesh)
    : CSpaceRasteriser(mesh, StopSource()) {}

CSpaceRasteriser::CSpaceRasteriser(const TriangleMesh& mesh, const StopSource& stop) {
  stop.throw_if_stop_requested();
  const std::size_t n = mesh.faces.size();
  std::vector<Vec3d> centroids;
  tri_.reserve(n);
  face_sphere_.reserve(n);
  centroids.reserve(n);
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
  stop.throw_if_stop_requested();
  if (tri_.empty()) return;
  // The tree is built over a permutation of the faces (the face at each place), and the faces
  // put in its order once at the end: no copy of the faces per level.
  Build b{centroids, std::vector<int>(n), std::vector<int>(n)};
  for (std::size_t k = 0; k < n; ++k) b.perm[k] = static_cast<int>(k);
  nodes_.reserve(tree_nodes(n));
  slab_.reserve(tree_nodes(n));
  build(0, static_cast<int>(n), b, stop);
  // The faces into the tree's order in place, cycle by cycle (no second copy of them).
  std::vector<bool> placed(n, false);
  for (std::size_t start = 0; start < n; ++start) {
    if (placed[start]) continue;
    const std::array<Vec3d, 3> first_tri = tri_[start];
    const Sphere first_sphere = face_sphere_[start];
    std::size_t at = start;
    for (;;) {
      placed[at] = true;
      const auto from = static_cast<std::size_t>(b.perm[at]);
      if (from == start) break;
      tri_[at] = tri_[from];
      face_sphere_[at] = face_sphere_[from];
      at = from;
    }
    tri_[at] = first_tri;
    face_sphere_[at] = first_sphere;
  }
}

/// The slab of the faces at places [first, first + count): the normal their area-weighted
/// mean (each face's turned to agree with the sum so far: a mesh's winding may be mixed), the
/// least and greatest height of their corners along it.
CSpaceRasteriser::Slab CSpaceRasteriser::slab_of(int first, int count, const Build& b) const {
  Vec3d sum = Vec3d::Zero();
  for (int k = first; k < first + count; ++k) {
    const auto& t = tri_[static_cast<std::size_t>(b.perm[static_cast<std::size_t>(k)])];
    const Vec3d n = (t[1] - t[0]).cross(t[2] - t[0]);
    sum += n.dot(sum) < 0.0 ? Vec3d(-n) : n;
  }
  Slab slab;
  if (sum.norm() > 0.0 && std::isfinite(sum.norm())) slab.normal = sum.normalized();
  slab.lo = std::numeric_limits<double>::infinity();
  slab.hi = -slab.lo;
  for (int k = first; k < first + count; ++k) {
    for (const Vec3d& p : tri_[static_cast<std::size_t>(b.perm[static_cast<std::size_t>(k)])]) {
      const double h = slab.normal.dot(p);
      slab.lo = std::min(slab.lo, h);
      slab.hi = std::max(slab.hi, h);
    }
  }
  return slab;
}

/// Top-down: split the faces at the median centroid along the longest extent, four faces or
/// fewer to a leaf. The faces at places [first, first + count) of the permutation are reordered
/// so that a leaf's are contiguous (ties by place).
int CSpaceRasteriser::build(int first, int count, Build& b, const StopSource& stop) {
  if (count >= 1024) stop.throw_if_stop_requested();  // a node's work: about 0.1 us a face
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  const auto face_at = [&](int k) {
    return static_cast<std::size_t>(b.perm[static_cast<std::size_t>(k)]);
  };
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int k = first; k < first + count; ++k) {
    for (const Vec3d& p : tri_[face_at(k)]) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  Sphere s{0.5 * (lo + hi), 0.0};
  for (int k = first; k < first + count; ++k) {
    for (const Vec3d& p : tri_[face_at(k)]) s.radius = std::max(s.radius, (p - s.centre).norm());
  }
  nodes_[static_cast<std::size_t>(id)].sphere = s;
  slab_.resize(nodes_.size());
  slab_[static_cast<std::size_t>(id)] = slab_of(first, count, b);
  nodes_[static_cast<std::size_t>(id)].first = first;
  nodes_[static_cast<std::size_t>(id)].count = count;
  if (count <= 4) return id;
  Vec3d cl = Vec3d::Constant(std::numeric_limits<double>::infinity()), ch = -cl;
  for (int k = first; k < first + count; ++k) {
    cl = cl.cwiseMin(b.centroids[face_at(k)]);
    ch = ch.cwiseMax(b.centroids[face_at(k)]);
  }
  int axis = 0;
  (ch - cl).maxCoeff(&axis);
  // The places in order, split at the median; then the faces at them.
  const auto order = b.scratch.begin() + first;
  for (int k = 0; k < count; ++k) order[k] = first + k;
  std::nth_element(order, order + count / 2, order + count, [&](int p, int q) {
    const double kp = b.centroids[face_at(p)][axis];
    const double kq = b.centroids[face_at(q)][axis];
    return kp < kq || (kp == kq && p < q);
  });
  for (int k = 0; k < count; ++k) order[k] = b.perm[static_cast<std::size_t>(order[k])];
  std::copy(order, order + count, b.perm.begin() + first);
  const int left = build(first, count / 2, b, stop);
  const int right = build(first + count / 2, count - count / 2, b, stop);
  nodes_[static_cast<std::size_t>(id)].left = left;
  nodes_[static_cast<std::size_t>(id)].right = right;
  return id;
}

}  // namespace taxopt
