// The cutting conditions at the contacts (OperationResult::Cutting): the written axes' angles
// from the designed surface's normal, the ball's effective cutting diameter before and after,
// and the points where a method came nearer the normal than the least tilt (stages.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/stages.hpp"

namespace taxopt::pipeline {

namespace {

/// The least angle, rad, between the axis and the designed normal as both turn through the move
/// from point i - 1 to point i (each along its chord, sampled): where it dips below both ends'
/// the axis passes the normal within the move.
double least_angle_in_move_rad(const Vec3d& axis0, const Vec3d& axis1, const Vec3d& normal0,
                               const Vec3d& normal1) {
  constexpr int kSamples = 16;
  double least = Constants<double>::pi();
  for (int s = 1; s < kSamples; ++s) {
    const double t = static_cast<double>(s) / kSamples;
    const Vec3d axis = (1.0 - t) * axis0 + t * axis1;
    const Vec3d normal = (1.0 - t) * normal0 + t * normal1;
    if (axis.norm() < 1e-12 || normal.norm() < 1e-12) continue;
    least = std::min(least, angle_between(Vec3d(axis.normalized()), Vec3d(normal.normalized())));
  }
  return least;
}

}  // namespace

void cutting_conditions(const OperationContext& o, const PostedOperation& po, OperationResult& r,
                        const StopSource& stop) {
  const Operationd& op = *o.op;
  if (!(o.ball_radius_mm > 0.0) || o.contacts.size() != op.points.size()) return;
  OperationResult::Cutting c;
  c.least_tilt_deg = o.least_tilt_deg;
  c.least_tilt_given = o.least_tilt_given;
  c.least_tilt_held = o.least_tilt_held;
  c.spindle_rpm = po.spindle_rpm;
  c.least_tilt_before_deg = c.least_tilt_after_deg = std::numeric_limits<double>::infinity();
  c.least_diameter_before_mm = c.least_diameter_after_mm = std::numeric_limits<double>::infinity();
  const double diameter_mm = 2.0 * o.ball_radius_mm;
  const auto touching_feed = [&](std::size_t i) {
    return op.points[i].motion == Motion::Feed && o.contacts[i].state == ContactState::Touching;
  };
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    detail::look_at_stop(&stop, i, detail::kPointStride);
    const ContactPoint& contact = o.contacts[i];
    if (!touching_feed(i)) continue;
    const double before_rad = angle_between(op.points[i].axis, contact.surface_normal);
    const double after_rad = angle_between(po.points[i].axis, contact.surface_normal);
    PointRow& row = r.rows[i];
    row.tilt_after_deg = rad_to_deg(after_rad);
    // A tilt past 90 deg cuts with the ball's far side: the diameter is the ball's at most.
    row.cutting_diameter_before_mm =
        diameter_mm * std::sin(std::min(before_rad, Constants<double>::pi() / 2.0));
    row.cutting_diameter_mm =
        diameter_mm * std::sin(std::min(after_rad, Constants<double>::pi() / 2.0));
    ++c.points;
    c.least_tilt_before_deg = std::min(c.least_tilt_before_deg, rad_to_deg(before_rad));
    c.least_tilt_after_deg = std::min(c.least_tilt_after_deg, row.tilt_after_deg);
    c.least_diameter_before_mm =
        std::min(c.least_diameter_before_mm, row.cutting_diameter_before_mm);
    c.least_diameter_after_mm = std::min(c.least_diameter_after_mm, row.cutting_diameter_mm);
    c.mean_diameter_before_mm += row.cutting_diameter_before_mm;
    c.mean_diameter_after_mm += row.cutting_diameter_mm;
    // The bound asked at the point: the least tilt, or the input's own angle where nearer.
    const double asked_deg = std::min(c.least_tilt_deg, rad_to_deg(before_rad));
    if (row.tilt_after_deg < asked_deg - kTiltAllowanceDeg) {
      if (c.points_below++ == 0) c.first_line_below = op.points[i].line;
    } else if (i > 0 && touching_feed(i - 1) && c.least_tilt_held) {
      const ContactPoint& prev = o.contacts[i - 1];
      const double asked_move_deg = std::min(
          asked_deg, rad_to_deg(angle_between(op.points[i - 1].axis, prev.surface_normal)));
      const double least_deg = rad_to_deg(least_angle_in_move_rad(
          po.points[i - 1].axis, po.points[i].axis, prev.surface_normal, contact.surface_normal));
      if (least_deg < asked_move_deg - kTiltAllowanceDeg) {
        if (c.moves_past_normal++ == 0) c.first_line_past = op.points[i].line;
      }
    }
  }
  if (c.points == 0) return;
  c.mean_diameter_before_mm /= static_cast<double>(c.points);
  c.mean_diameter_after_mm /= static_cast<double>(c.points);
  r.cutting = c;
}

}  // namespace taxopt::pipeline
