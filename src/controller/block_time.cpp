/// @file The time of a feed block as a controller runs it at its programmed feed.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "taxopt/io/gcode.hpp"

namespace taxopt {

std::vector<double> programmed_block_times_s(const std::vector<CLPointd>& points,
                                             const std::vector<Posed>& poses) {
  if (poses.size() != points.size()) {
    throw std::invalid_argument("programmed_block_times_s: one pose per point is needed");
  }
  std::vector<double> t(points.size(), 0.0);
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].motion != Motion::Feed || !(points[i].feed_mm_per_min > 0.0)) continue;
    t[i] = programmed_move_time_s(points[i - 1].tip_mm, poses[i - 1], points[i].tip_mm, poses[i],
                                  points[i].feed_mm_per_min);
  }
  return t;
}

double programmed_move_time_s(const Vec3d& from_tip_mm, const Posed& from, const Vec3d& to_tip_mm,
                              const Posed& to, double feed_mm_per_min) {
  const double tip_mm = (to_tip_mm - from_tip_mm).norm();
  const double rot_deg =
      std::hypot(rad_to_deg(to.a_rad - from.a_rad), rad_to_deg(to.c_rad - from.c_rad));
  // A move too small to time still gets a positive time: its words may differ after
  // rounding, and a feed schedule needs a bound for every move.
  return 60.0 * (tip_mm > 1e-9 ? tip_mm : std::max(rot_deg, 1e-9)) / feed_mm_per_min;
}

}  // namespace taxopt
