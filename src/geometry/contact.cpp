#include "taxopt/geometry/contact.hpp"

#include <sstream>

#include "geometry/contact_progress.hpp"
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

const char* to_string(SurfacePlace place) {
  switch (place) {
    case SurfacePlace::Smooth: return "smooth";
    case SurfacePlace::Edge: return "edge";
    case SurfacePlace::Corner: return "corner";
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

namespace {

/// The smooth normal of the mesh's point p where it points at `centre` (C - p parallel to
/// n(p)), from the exact point `start` and its smooth normal `n0`: Newton's method over p's
/// offset in the tangent plane of n0 (each offset projected on the mesh), the residual the
/// part of C - p across n(p), its Jacobian by differences. A plain fixed point (n <- the
/// normal under C - R n) contracts by R times the curvature a step: slowly where a concave
/// radius nears R (measured: 8 steps left 0.13 deg where two facets tie on the sine), and
/// not at all past a convex radius below R. Returns n0 where no step lowers the residual.
Vec3d normal_towards(const Part& part, const Vec3d& centre, const Part::Closest& start,
                     const Vec3d& n0) {
  const Vec3d t1 = n0.unitOrthogonal(), t2 = n0.cross(t1);
  struct Eval {
    Vec3d n = Vec3d::Zero();
    Eigen::Vector2d e = Eigen::Vector2d::Zero();
    double size = std::numeric_limits<double>::infinity();
  };
  const auto eval = [&](const Eigen::Vector2d& x) {
    Eval out;
    const Part::Closest c = part.closest(start.point + x(0) * t1 + x(1) * t2);
    out.n = part.smooth_normal(c, n0);
    if (out.n.isZero()) return out;
    const Vec3d w = centre - c.point;
    const Vec3d across = w - w.dot(out.n) * out.n;
    out.e = Eigen::Vector2d(across.dot(t1), across.dot(t2));
    out.size = out.e.norm();
    return out;
  };
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  Eval at = eval(x);
  if (!std::isfinite(at.size)) return n0;
  constexpr double kStepMm = 1e-5;
  for (int it = 0; it < 12 && at.size > 1e-10; ++it) {
    Eigen::Matrix2d J;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d xk = x;
      xk(k) += kStepMm;
      const Eval ek = eval(xk);
      if (!std::isfinite(ek.size)) return at.n;
      J.col(k) = (ek.e - at.e) / kStepMm;
    }
    if (!(std::abs(J.determinant()) > 1e-12)) break;
    Eigen::Vector2d d = -J.inverse() * at.e;
    bool lowered = false;
    for (int half = 0; half < 6 && !lowered; ++half, d *= 0.5) {
      const Eval next = eval(x + d);
      if (next.size < at.size) {
        x += d;
        at = next;
        lowered = true;
      }
    }
    if (!lowered) break;
  }
  return at.n;
}

}  // namespace

namespace {

/// One point's contact: the nearest point of the mesh (the exact answer) and its normal
/// towards the centre, the designed surface's estimate, the curvature; in the air beyond the
/// tolerance `tol`.
ContactPoint contact_of(const Part& part, const CLPointd& p, double R, double tol, double agree_cos,
                        const ContactOptions& options) {
  const Vec3d centre = p.tip_mm + R * p.axis;
  ContactPoint c;
  // The exact answer: the nearest point of the mesh, the normal towards the centre.
  const Part::Closest near = part.closest(centre);
  c.cc_mm = near.point;
  c.gap_mm = near.distance_mm - R;
  if (c.gap_mm > tol) {
    c.state = ContactState::InAir;
    return c;
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
  // The designed surface's estimate: the point of the mesh whose smooth normal points at
  // the centre (measured on 0.5 mm meshes of unseen heightfields against their analytic
  // normals: the facets' 3.45 deg at most, 0.41 on average; the smooth normal at the exact
  // point 1.89 / 0.13; where it points at the centre 0.29 / 0.035).
  const Part::SurfaceNormal surface = part.surface_normal(near, c.normal);
  c.surface_normal = surface.normal;
  c.surface_cc_mm = c.cc_mm;
  if (!surface.on_feature) {
    c.surface_normal = normal_towards(part, centre, near, c.surface_normal);
    c.surface_cc_mm = centre - R * c.surface_normal;
  }
  c.place = !surface.on_feature                      ? SurfacePlace::Smooth
            : surface.where == Part::Feature::Vertex ? SurfacePlace::Corner
                                                     : SurfacePlace::Edge;
  c.normal_uncertainty_rad = angle_between(c.normal, c.surface_normal);
  // Curvature: the local fit only where it agrees with the surface's contact, else the
  // mesh's.
  const LocalFit fit = part.fit_towards(centre, options.fit_neighbours);
  const Vec3d fit_normal = unit_normal(fit.jet);
  if (fit.samples > 0 && (fit.jet.p - c.surface_cc_mm).norm() <= tol && fit_normal.allFinite() &&
      fit_normal.dot(c.surface_normal) >= agree_cos) {
    c.curvature = principal_curvatures(fit.jet);
    c.curvature_from = CurvatureSource::Fit;
  } else {
    const Part::MeshCurvature mc = part.mesh_curvature(near, c.surface_normal);
    c.curvature = mc.curvature;
    c.curvature_from = mc.feature == Part::Feature::Facet  ? CurvatureSource::Facet
                       : mc.feature == Part::Feature::Edge ? CurvatureSource::Edge
                                                           : CurvatureSource::Vertex;
  }
  c.local_gouge = c.curvature.k1 > 0.0 && 1.0 / c.curvature.k1 < R;
  return c;
}

/// Feed direction from the neighbouring contact points of the same run, projected on the
/// tangent plane; then K and the tilt and yaw of the input axis.
void contact_frames(const Operationd& op, std::vector<ContactPoint>& out) {
  const std::size_t n = out.size();
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
    if (has_next) d += out[i + 1].surface_cc_mm - c.surface_cc_mm;
    if (has_prev) d += c.surface_cc_mm - out[i - 1].surface_cc_mm;
    if (d.norm() < 1e-12) {
      // A lone contact: the tool's own motion, else any tangent.
      if (i + 1 < n) d = op.points[i + 1].tip_mm - op.points[i].tip_mm;
      if (d.norm() < 1e-12 && i > 0) d = op.points[i].tip_mm - op.points[i - 1].tip_mm;
    }
    const Vec3d& n_s = c.surface_normal;
    Vec3d t = d - d.dot(n_s) * n_s;
    if (t.norm() < 1e-12) t = n_s.unitOrthogonal();
    c.feed_dir = t.normalized();
    c.side = n_s.cross(c.feed_dir);
    tilt_yaw_of(op.points[i].axis, n_s, c.feed_dir, c.tilt_rad, c.yaw_rad);
  }
}

}  // namespace

std::vector<ContactPoint> recover_contacts(const Part& part, const Operationd& op,
                                           double ball_radius_mm, const ContactOptions& options) {
  return detail::recover_contacts(part, op, ball_radius_mm, options, nullptr);
}

std::vector<ContactPoint> detail::recover_contacts(const Part& part, const Operationd& op,
                                                   double ball_radius_mm,
                                                   const ContactOptions& options,
                                                   StageProgress* progress) {
  const double tol = contact_tolerance_mm(part, options, op.cam_tolerance_mm);
  const double agree_cos = std::cos(deg_to_rad(options.fit_normal_agreement_deg));
  const std::size_t n = op.points.size();
  std::vector<ContactPoint> out(n);
  // Contact point, normal and curvature per point: independent, so in parallel.
  detail::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    out[i] = contact_of(part, op.points[i], ball_radius_mm, tol, agree_cos, options);
    if (progress) progress->advance();
  });
  contact_frames(op, out);
  return out;
}

}  // namespace taxopt
