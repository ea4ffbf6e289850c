#pragma once
/// @file The block time model: how long the controller takes for a feed block of the written
/// program, shared by the feed schedule, the guard, the global objective, the post and the
/// report (programmed_move_time_s in taxopt/io/gcode.hpp is its "tip" rule).

#include <cstddef>
#include <vector>

#include "taxopt/core/types.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"

namespace taxopt::controller {

/// How the written program times an operation's feed blocks (GcodeSettings::feed_reference):
/// each at its feed over the new tip path ("tip"), or at the input block's time, but never
/// shorter than the new tip path at max_feed_ratio times the feed ("cutter-path").
struct BlockTiming {
  /// The feed of the move into each point, mm/min (the metric feed).
  std::vector<double> feed_mm_per_min;
  /// "cutter-path": the input's time of the move into each point (0: none), s; empty: "tip".
  std::vector<double> kept_s;
  double max_feed_ratio = 1.0;
  /// The written time of the move into point i: tip path from_tip -> to_tip at the feed, or
  /// the kept time within the feed ratio.
  double move_time_s(std::size_t i, const Vec3d& from_tip_mm, const Posed& from,
                     const Vec3d& to_tip_mm, const Posed& to) const;
};
/// A block's written time under "cutter-path" (BlockTiming): the kept time, but no shorter than
/// its own time over `max_feed_ratio`; with no kept time (0), its own.
double kept_time_s(double kept_s, double own_s, double max_feed_ratio);
/// kept_time_s of every block. `capped`, when given, counts the blocks the ratio lengthened.
std::vector<double> kept_block_times_s(const std::vector<double>& kept_s,
                                       const std::vector<double>& own_s, double max_feed_ratio,
                                       std::size_t* capped = nullptr);
}  // namespace taxopt::controller
