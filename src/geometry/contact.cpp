#include "taxopt/geometry/contact.hpp"

#include <sstream>

#include "util/parallel.hpp"

namespace taxopt {

const char* to_string(CurvatureSource source) {
  switch (source) {
    case CurvatureSource::Fit: return "fit";
    case CurvatureSource::Facet: return "facet";
    case CurvatureSource::Edge: return "edge";
    case CurvatureSource::Vertex: return "vertex";
  }
  return "?";
}

double contact_tolerance_mm(const Part& part, const ContactOptions& options,
                            std::optional<double> cam_tolerance_mm) {
  if (options.tolerance_mm > 0.0) return options.tolerance_mm;
  // A ball on the CAD surface sinks into the mesh by up to its chordal error, and the CAM's
  // path lies within its own tolerance band of that surface; where the file gives no band,
  // CAM finishing tolerances and CAD export chordal errors are hundredths of a millimetre.
  return std::max(kContactToleranceFloorMm,
                  part.chordal_error_mm() + cam_tolerance_mm.value_or(0.0));
}

std::string contact_tolerance_source(const Part& part, const ContactOptions& options,
                                     std::optional<double> cam_tolerance_mm) {
  std::ostringstream os;
  if (options.tolerance_mm > 0.0) return "as given";
  const double sum = part.chordal_error_mm() + cam_tolerance_mm.value_or(0.0);
  if (sum < kContactToleranceFloorMm) {
    os << "the floor " << kContactToleranceFloorMm << " mm, above the mesh's chordal error "
       << part.chordal_error_mm() << " mm";
    if (cam_tolerance_mm) os << " + the CL file's tolerance " << *cam_tolerance_mm << " mm";
    return os.str();
  }
  os << "the mesh's chordal error " << part.chordal_error_mm() << " mm";
  if (cam_tolerance_mm) {
    os << " + the CL file's tolerance (INTOL/OUTTOL/TOLER) " << *cam_tolerance_mm << " mm";
  }
  return os.str();
}

std::vector<ContactPoint> recover_contacts(const Part& part, const Operationd& op,
                                           double ball_radius_mm, const ContactOptions& options) {
  const double R = ball_radius_mm;
  const double tol = contact_tolerance_mm(part, options, op.cam_tolerance_mm);
  const double agree_cos = std::cos(deg_to_rad(options.fit_normal_agreement_deg));
  const std::size_t n = op.points.size();
  std::vector<ContactPoint> out(n);
  // Contact point, normal and curvature per point: independent, so in parallel.
  detail::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const CLPointd& p = op.points[i];
    const Vec3d centre = p.tip_mm + R * p.axis;
    ContactPoint& c = out[i];
    // The exact answer: the nearest point of the mesh, the normal towards the centre.
    const Part::Closest near = part.closest(centre);
    c.cc_mm = near.point;
    c.gap_mm = near.distance_mm - R;
    if (c.gap_mm > tol) {
      c.state = ContactState::InAir;
      return;
    }
    c.state = c.gap_mm < -tol ? ContactState::Gouging : ContactState::Touching;
    const Vec3d to_centre = centre - near.point;
    if (to_centre.norm() > 1e-9) {
      c.normal = to_centre.normalized();
    } else {
      // The centre on the mesh (a ball cut in by its radius): the facet's normal, towards the
      // tool.
      const auto& f = part.mesh().faces[static_cast<std::size_t>(near.face)];
      const auto& V = part.mesh().vertices;
      Vec3d fn = (V[static_cast<std::size_t>(f[1])] - V[static_cast<std::size_t>(f[0])])
                     .cross(V[static_cast<std::size_t>(f[2])] - V[static_cast<std::size_t>(f[0])])
                     .normalized();
      if (fn.dot(p.axis) < 0.0) fn = -fn;
      c.normal = fn;
    }
    // Curvature: the local fit only where it agrees with the exact contact, else the mesh's.
    const LocalFit fit = part.fit_towards(centre, options.fit_neighbours);
    const Vec3d fit_normal = unit_normal(fit.jet);
    if (fit.samples > 0 && (fit.jet.p - c.cc_mm).norm() <= tol && fit_normal.allFinite() &&
        fit_normal.dot(c.normal) >= agree_cos) {
      c.curvature = principal_curvatures(fit.jet);
      c.curvature_from = CurvatureSource::Fit;
    } else {
      const Part::MeshCurvature mc = part.mesh_curvature(near, c.normal);
      c.curvature = mc.curvature;
      c.curvature_from = mc.feature == Part::Feature::Facet  ? CurvatureSource::Facet
                         : mc.feature == Part::Feature::Edge ? CurvatureSource::Edge
                                                             : CurvatureSource::Vertex;
    }
    c.local_gouge = c.curvature.k1 > 0.0 && 1.0 / c.curvature.k1 < R;
  });
  // Feed direction from the neighbouring contact points of the same run, projected on the
  // tangent plane; then K and the tilt and yaw of the input axis.
  for (std::size_t i = 0; i < n; ++i) {
    ContactPoint& c = out[i];
    if (c.state != ContactState::Touching) continue;
    const auto touching = [&](std::size_t j) {
      return j < n && out[j].state == ContactState::Touching &&
             (j == 0 || op.points[j].motion == Motion::Feed || j < i);
    };
    const bool has_next = i + 1 < n && touching(i + 1) && op.points[i + 1].motion == Motion::Feed;
    const bool has_prev = i > 0 && touching(i - 1) && op.points[i].motion == Motion::Feed;
    Vec3d d = Vec3d::Zero();
    if (has_next) d += out[i + 1].cc_mm - c.cc_mm;
    if (has_prev) d += c.cc_mm - out[i - 1].cc_mm;
    if (d.norm() < 1e-12) {
      // A lone contact: the tool's own motion, else any tangent.
      if (i + 1 < n) d = op.points[i + 1].tip_mm - op.points[i].tip_mm;
      if (d.norm() < 1e-12 && i > 0) d = op.points[i].tip_mm - op.points[i - 1].tip_mm;
    }
    Vec3d t = d - d.dot(c.normal) * c.normal;
    if (t.norm() < 1e-12) t = c.normal.unitOrthogonal();
    c.feed_dir = t.normalized();
    c.side = c.normal.cross(c.feed_dir);
    tilt_yaw_of(op.points[i].axis, c.normal, c.feed_dir, c.tilt_rad, c.yaw_rad);
  }
  return out;
}

}  // namespace taxopt
