#pragma once
/// @file The part: a triangle mesh with its search structures (CGAL AABB tree for closest
/// points, k-d tree over the vertices for local fitting), built once and then queried from
/// any number of threads.

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/stop.hpp"
#include "taxopt/geometry/surface.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"

namespace taxopt {

/// A local fit of the part around a point: a height function over the tangent plane
/// (jet fitting, degree 2 or 3), evaluated at the fitted surface's point nearest to a query.
struct LocalFit {
  /// Point of the fitted surface nearest to the query, and its jet (world coordinates,
  /// u and v along the fit's tangent axes, normal towards the query's side).
  SurfaceJet<double> jet;
  /// Vertices that entered the fit (0 when the fit fell back to the nearest facet).
  int samples = 0;
};

class TAXOPT_API Part {
 public:
  /// Builds the search structures. @throws InputError for an empty mesh, a vertex not finite
  /// or beyond 1e6 mm, a face naming a vertex the mesh lacks.
  explicit Part(TriangleMesh mesh);
  /// As Part(mesh), looking at `stop` as it goes (a few milliseconds of work apart): a stop
  /// requested from another thread ends the build with Cancelled (or the stop's reason) and
  /// no Part (bench/bench_stop measures how soon).
  Part(TriangleMesh mesh, const StopSource& stop);
  /// As Part(mesh, stop), reporting the build's progress to `progress` as JobOptions::progress
  /// reports a job's: stage "building the part", items done of total, from 0 and once per
  /// whole percent up to done == total, on the calling thread. An exception it throws ends the
  /// build as a stop does (it is requested on `stop` with that exception) and is what the
  /// constructor throws.
  Part(TriangleMesh mesh, const StopSource& stop,
       const std::function<void(const std::string& stage, std::size_t done, std::size_t total)>&
           progress);
  ~Part();
  Part(Part&&) noexcept;
  Part& operator=(Part&&) noexcept;
  Part(const Part&) = delete;
  Part& operator=(const Part&) = delete;

  const TriangleMesh& mesh() const;
  /// Mean edge length of the mesh, mm.
  double mean_edge_mm() const;

  /// Closest point of the mesh to q, and its distance.
  struct Closest {
    Vec3d point = Vec3d::Zero();
    int face = -1;
    double distance_mm = 0.0;
  };
  Closest closest(const Vec3d& q) const;

  /// Fits the part around its point closest to q (jet fitting over the `neighbours` nearest
  /// vertices, in the frame whose normal points from the mesh to q) and returns the fitted
  /// surface's point nearest to q, i.e. where a ball centred at q touches it.
  LocalFit fit_towards(const Vec3d& q, int neighbours = 30) const;

  /// Indices of the faces within `radius_mm` of q (exact triangle distance), ascending.
  std::vector<int> faces_within(const Vec3d& q, double radius_mm) const;

  /// The mesh's chordal error, mm: the largest distance its facets may lie from the curved
  /// surfaces they stand for, measured on the mesh itself. Each edge between two facets that
  /// meet at less than 30 deg spans an arc of that angle over the narrower facet's width h,
  /// whose sagitta is h/2 tan(angle/4) (about h angle / 8); this is the largest of those over
  /// the edges of tessellated curves: edges whose two facets' far vertices turn too (by a
  /// quarter of the edge's turn or more). A crease between flat faces, a lone chamfer, or big
  /// flat facets beside a fillet do not raise it (0 for a mesh of flat faces and sharp edges).
  /// The largest, not a percentile: a ball on the CAD surface sinks into the mesh by up to
  /// that much where chords cut a concave surface, anywhere on the part.
  double chordal_error_mm() const;

  /// Where a closest point lies on the mesh, and the curvature the mesh itself gives there.
  enum class Feature { Facet, Edge, Vertex };
  struct MeshCurvature {
    Feature feature = Feature::Facet;
    PrincipalCurvatures<double> curvature;
  };
  /// The curvature of the mesh at its closest point `c` seen from the side `normal` points
  /// to (positive: concave, curving towards that side): 0 inside a facet; across an edge the
  /// turn of its two facets' normals over their mean width (none along it); at a vertex the
  /// most concave and most convex of its edges.
  MeshCurvature mesh_curvature(const Closest& c, const Vec3d& normal) const;

  /// The designed surface's normal at the mesh's closest point `c`, on the side of
  /// `exact_normal` (from c towards the query). Where c lies on a tessellated curve: the
  /// normals of its face's corners -- each the angle-weighted mean of the normals of the
  /// corner's faces that turn less than 30 deg from this one, so split across creases --
  /// interpolated at c (smooth from facet to facet; the facet's own normal strays from the
  /// curve's by up to half the turn between facets). Where c lies on an edge or a vertex of a
  /// crease (30 deg or more), a border or a non-manifold edge, and the exact normal leaves
  /// its face's (the ball rolls over the edge): `on_feature`, no smooth surface there, and
  /// the normal is the exact one.
  struct SurfaceNormal {
    Vec3d normal = Vec3d::UnitZ();
    Feature where = Feature::Facet;  ///< c inside its face, on an edge or at a vertex
    bool on_feature = false;
  };
  SurfaceNormal surface_normal(const Closest& c, const Vec3d& exact_normal) const;
  /// The corner normals of c's face interpolated at c, on the side of `side` (zero for a
  /// degenerate face): surface_normal's smooth normal, with no feature test.
  Vec3d smooth_normal(const Closest& c, const Vec3d& side) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace taxopt
