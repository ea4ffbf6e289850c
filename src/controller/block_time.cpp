/// @file The time of a feed block as a controller runs it at its programmed feed.
#include "controller/block_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "controller/feed_word.hpp"
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
      std::hypot(rad_to_deg(to.tilt_rad - from.tilt_rad), rad_to_deg(to.c_rad - from.c_rad));
  // A move too small to time still gets a positive time: its words may differ after
  // rounding, and a feed schedule needs a bound for every move.
  const controller::FeedDistance d = controller::feed_distance(tip_mm, rot_deg);
  return 60.0 * (d.rotary ? std::max(d.distance, 1e-9) : d.distance) / feed_mm_per_min;
}

namespace controller {

double BlockTiming::move_time_s(std::size_t i, const Vec3d& from_tip_mm, const Posed& from,
                                const Vec3d& to_tip_mm, const Posed& to) const {
  const double feed = feed_mm_per_min[i];
  if (!(feed > 0.0)) return 0.0;
  const double own_s = programmed_move_time_s(from_tip_mm, from, to_tip_mm, to, feed);
  return kept_time_s(i < kept_s.size() ? kept_s[i] : 0.0, own_s, max_feed_ratio);
}

double kept_time_s(double kept_s, double own_s, double max_feed_ratio) {
  return kept_s > 0.0 ? std::max(kept_s, own_s / max_feed_ratio) : own_s;
}

std::vector<double> kept_block_times_s(const std::vector<double>& kept_s,
                                       const std::vector<double>& own_s, double max_feed_ratio,
                                       std::size_t* capped) {
  std::vector<double> t = own_s;
  for (std::size_t i = 0; i < t.size() && i < kept_s.size(); ++i) {
    t[i] = kept_time_s(kept_s[i], own_s[i], max_feed_ratio);
    if (capped && kept_s[i] > 0.0 && t[i] > kept_s[i]) ++*capped;
  }
  return t;
}

}  // namespace controller
}  // namespace taxopt
