// The cutting conditions at the contacts (OperationResult::Cutting): the written axes' angles
// from the designed surface's normal, the ball's effective cutting diameter before and after,
// and the points where a method came nearer the normal than the least tilt (stages.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/stages.hpp"

namespace taxopt::pipeline {

void cutting_conditions(const OperationContext& o, const PostedOperation& po, OperationResult& r) {
  const Operationd& op = *o.op;
  if (!(o.ball_radius_mm > 0.0) || o.contacts.size() != op.points.size()) return;
  OperationResult::Cutting c;
  c.least_tilt_deg = o.least_tilt_deg;
  c.least_tilt_given = o.least_tilt_given;
  c.spindle_rpm = po.spindle_rpm;
  c.least_tilt_before_deg = c.least_tilt_after_deg = std::numeric_limits<double>::infinity();
  c.least_diameter_before_mm = c.least_diameter_after_mm = std::numeric_limits<double>::infinity();
  const double diameter_mm = 2.0 * o.ball_radius_mm;
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    const ContactPoint& contact = o.contacts[i];
    if (op.points[i].motion != Motion::Feed || contact.state != ContactState::Touching) continue;
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
    if (row.tilt_after_deg < c.least_tilt_deg - kTiltAllowanceDeg) {
      if (c.points_below++ == 0) c.first_line_below = op.points[i].line;
    }
  }
  if (c.points == 0) return;
  c.mean_diameter_before_mm /= static_cast<double>(c.points);
  c.mean_diameter_after_mm /= static_cast<double>(c.points);
  r.cutting = c;
}

}  // namespace taxopt::pipeline
