#pragma once
/// @file What a part's mesh says of the designed surface it tessellates: the facets' normals,
/// the normal at each face corner (split across creases), the designed edges, and the chordal
/// error of the tessellation (Part::surface_normal, Part::chordal_error_mm). Internal.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "taxopt/core/stop.hpp"
#include "taxopt/geometry/part.hpp"
#include "util/progress.hpp"

namespace taxopt::detail {

/// A turn between two facets from this angle on is a designed edge, not a tessellated curve
/// (the chordal error's and the smooth normals' one threshold).
constexpr double kCreaseRad = 30.0 * 3.14159265358979323846 / 180.0;

/// Unit normal of face f (by its vertex order), zero for a degenerate face.
Vec3d face_normal(const TriangleMesh& m, const std::array<int, 3>& f);

/// Distance of face f's vertex opposite the edge (a, b) from that edge's line, and the vertex.
double width_across(const TriangleMesh& m, const std::array<int, 3>& f, int a, int b,
                    Vec3d* opposite = nullptr);

/// The designed surface as the mesh gives it (Part::surface_normal).
struct SurfaceModel {
  /// Per face corner (3 f + k): the surface's normal there, the angle-weighted mean of the
  /// normals of the corner's faces that turn less than kCreaseRad from this face (so split
  /// across creases); zero for a degenerate face. Floats: 36 bytes a face.
  std::vector<Eigen::Vector3f> corner_normal;
  /// The edges (low vertex, high vertex) that are no tessellated curve -- a crease, a border
  /// or a non-manifold edge --, sorted; and the vertices on them.
  std::vector<std::pair<int, int>> feature_edges;
  std::vector<bool> feature_vertex;
};

/// Builds the SurfaceModel of a mesh and the chordal error estimate of
/// Part::chordal_error_mm (into `chordal_error_mm`), the faces' edges sorted once; with
/// `stop`, looking at it every few milliseconds (StopSource::throw_if_stop_requested).
SurfaceModel surface_and_chordal_error(const TriangleMesh& m, double& chordal_error_mm,
                                       const StopSource* stop = nullptr);

}  // namespace taxopt::detail
