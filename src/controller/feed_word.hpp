#pragma once
/// @file What an F word measures of a move: one rule for the writer, which sets F, and for the
/// time models, which time a block from it.

namespace taxopt::controller {

/// A move's distance as a feed per minute (G94) measures it with tool centre point control: the
/// tip's (the joints' in machine mode), or, where that stands still, the rotary axes' in deg,
/// F then read as deg/min (LinuxCNC's canon and a Fanuc 30i's G43.4 alike: a block that only
/// turns A and C runs at F deg/min). "Still" is within 1e-9 mm: the words a controller reads
/// are rounded to 1e-4 mm at the finest, so their distances are 0 or far above it.
struct FeedDistance {
  double distance = 0.0;  ///< mm, or deg where `rotary`
  bool rotary = false;
  /// The factor from mm to the program's length unit (`units_per_mm`) for this distance and
  /// its feed: 1 where it is rotary (deg and deg/min whatever the unit, G20 too).
  double scale(double units_per_mm) const { return rotary ? 1.0 : units_per_mm; }
};

inline FeedDistance feed_distance(double linear_mm, double rotary_deg) {
  constexpr double kStillMm = 1e-9;
  return linear_mm > kStillMm ? FeedDistance{linear_mm, false} : FeedDistance{rotary_deg, true};
}

}  // namespace taxopt::controller
