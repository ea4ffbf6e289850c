#include "taxopt/geometry/contact.hpp"

#include "util/parallel.hpp"

namespace taxopt {

double contact_tolerance_mm(const Part& part, const ContactOptions& options) {
  return options.tolerance_mm > 0.0 ? options.tolerance_mm
                                    : std::max(0.05, 0.1 * part.mean_edge_mm());
}

std::vector<ContactPoint> recover_contacts(const Part& part, const Operationd& op,
                                           double ball_radius_mm, const ContactOptions& options) {
  const double R = ball_radius_mm;
  const double tol = contact_tolerance_mm(part, options);
  const std::size_t n = op.points.size();
  std::vector<ContactPoint> out(n);
  // Contact point, normal and curvature per point: independent, so in parallel.
  detail::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const CLPointd& p = op.points[i];
    const Vec3d centre = p.tip_mm + R * p.axis;
    ContactPoint& c = out[i];
    const Part::Closest near = part.closest(centre);
    if (near.distance_mm > R + tol + 0.5 * part.mean_edge_mm()) {
      c.state = ContactState::InAir;
      c.gap_mm = near.distance_mm - R;
      return;
    }
    const LocalFit fit = part.fit_towards(centre, options.fit_neighbours);
    c.cc_mm = fit.jet.p;
    c.normal = unit_normal(fit.jet);
    c.curvature = principal_curvatures(fit.jet);
    c.gap_mm = std::min((centre - c.cc_mm).norm(), near.distance_mm) - R;
    // The fitted surface may lie a little off the facets; the mesh itself decides a gouge.
    if (near.distance_mm - R < -tol) {
      c.state = ContactState::Gouging;
    } else if (c.gap_mm > tol) {
      c.state = ContactState::InAir;
    } else {
      c.state = ContactState::Touching;
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
