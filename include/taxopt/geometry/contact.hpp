#pragma once
/// @file Contact recovery (paper section 2.1): from the CL points of a ball-end operation and
/// the part, the cutter-contact point Pc, normal N, feed direction T, K = N x T, the tilt and
/// yaw of the input axis (the inverse of eq. 11) and the principal curvatures at Pc.

#include <optional>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/toolpath.hpp"
#include "taxopt/geometry/part.hpp"

namespace taxopt {

/// Where a CL point's ball is relative to the part.
enum class ContactState {
  Touching,  ///< | |C - Pc| - R | within the tolerance: a contact point
  InAir,     ///< farther than R + tolerance: an approach or retract, no contact
  Gouging,   ///< nearer than R - tolerance: the ball cuts into the part
};

/// Where the curvature at a contact comes from (docs/method.md, "Contacts").
enum class CurvatureSource {
  Fit,     ///< the local jet fit, which agrees with the exact contact (point and normal)
  Facet,   ///< the mesh: inside a facet (flat)
  Edge,    ///< the mesh: on an edge (the turn of its two facets across it)
  Vertex,  ///< the mesh: at a vertex (its most concave and most convex edges)
};
TAXOPT_API const char* to_string(CurvatureSource source);

/// Where a contact lies on the designed surface the mesh stands for (Part::surface_normal).
enum class SurfacePlace {
  Smooth,  ///< on a tessellated curve or a face: the smooth normal holds
  Edge,    ///< on a crease, a border or a non-manifold edge, the ball rolling over it
  Corner,  ///< at a vertex of such edges
};
TAXOPT_API const char* to_string(SurfacePlace place);

/// Geometry at one CL point (the vectors are meaningful when Touching), in two estimates, each
/// for its use (docs/method.md, "Contacts"):
/// - the mesh's, for the checks: `cc_mm` the exact nearest point of the mesh to the ball
///   centre, `normal` the direction from it to the centre, `gap_mm`;
/// - the designed surface's, for the paper's parametrisation (the frame T, K, N of eq. 11,
///   tilt and yaw, the C-space grid), the curvature and the paper's metric: `surface_normal`
///   the smooth normal at the exact point, `surface_cc_mm` = centre - R surface_normal (the
///   exact ones on a feature).
struct ContactPoint {
  ContactState state = ContactState::InAir;
  Vec3d cc_mm = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  Vec3d surface_cc_mm = Vec3d::Zero();
  Vec3d surface_normal = Vec3d::UnitZ();
  SurfacePlace place = SurfacePlace::Smooth;
  /// The angle between the two normals (the facet's against the smooth one where Smooth; 0
  /// on a feature), rad: how far the mesh alone leaves the surface's normal unknown.
  double normal_uncertainty_rad = 0.0;
  Vec3d feed_dir = Vec3d::UnitX();  ///< T, unit, tangent to surface_normal
  Vec3d side = Vec3d::UnitY();      ///< K = N x T, N = surface_normal
  double tilt_rad = 0.0;            ///< of the input axis to surface_normal, in [0, pi]
  double yaw_rad = 0.0;             ///< in (-pi, pi]
  PrincipalCurvatures<double> curvature;
  /// |C - Pc| - R, mm.
  double gap_mm = 0.0;
  /// A concave principal radius at Pc is below R (local gouge, eq. 19).
  bool local_gouge = false;
  CurvatureSource curvature_from = CurvatureSource::Facet;
};

/// Options of recover_contacts.
struct ContactOptions {
  /// Largest | |C - Pc| - R | of a contact point, mm; 0: the default, max(0.05 mm, the
  /// mesh's own chordal error (Part::chordal_error_mm) + the CL file's tolerance band
  /// (Operation::cam_tolerance_mm)) -- never the facets' size.
  double tolerance_mm = 0.0;
  /// A fit's curvature is used where its point lies within the tolerance of the surface's
  /// contact and its normal within this angle of the surface's normal, deg.
  double fit_normal_agreement_deg = 3.0;
  /// Vertices of the local jet fit.
  int fit_neighbours = 30;
};

/// Tilt and yaw of axis v in the frame (T, K, N): v = N cos a + sin a (T cos b + K sin b).
inline void tilt_yaw_of(const Vec3d& v, const Vec3d& n, const Vec3d& t, double& tilt_rad,
                        double& yaw_rad) {
  const Vec3d k = n.cross(t);
  const double vn = v.dot(n), vt = v.dot(t), vk = v.dot(k);
  tilt_rad = std::atan2(std::hypot(vt, vk), vn);
  yaw_rad = std::atan2(vk, vt);
}

/// Recovers the contact geometry of every point of an operation cut by a ball of radius
/// ball_radius_mm (parallel over points; the result does not depend on the thread count).
TAXOPT_API std::vector<ContactPoint> recover_contacts(const Part& part, const Operationd& op,
                                                      double ball_radius_mm,
                                                      const ContactOptions& options = {});

/// The smallest default contact tolerance, mm: the order of CAM finishing tolerances and CAD
/// export chordal errors where nothing better is known.
constexpr double kContactToleranceFloorMm = 0.05;

/// The tolerance recover_contacts uses for `options` on `part`, for an operation whose CL file
/// keeps its path within `cam_tolerance_mm` of the surface (Operation::cam_tolerance_mm): as
/// given, else max(0.05 mm, the mesh's chordal error + that band).
TAXOPT_API double contact_tolerance_mm(const Part& part, const ContactOptions& options,
                                       std::optional<double> cam_tolerance_mm = std::nullopt);
/// Where contact_tolerance_mm's value comes from, for a message: "the mesh's chordal error
/// 0.031 mm + the CL file's tolerance (...) 0.02 mm", "the floor ...", "as given".
TAXOPT_API std::string contact_tolerance_source(const Part& part, const ContactOptions& options,
                                                std::optional<double> cam_tolerance_mm);

}  // namespace taxopt
