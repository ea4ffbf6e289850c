#pragma once
/// @file Branch and C-winding policy: which of the two inverse solutions, and which turn of
/// C, each CL point gets.
///
/// The choice is a shortest path (dynamic programme) over the candidate poses of the points:
/// the sequence that keeps A and C within their ranges and minimises the weighted rotary
/// travel sum_i w_i (|A_{i+1} - A_i| + |C_{i+1} - C_i| + P [|C_{i+1} - C_i| > 90 deg]),
/// the penalty P making C jumps the last resort. Feed moves weigh 1, rapid moves
/// `rapid_weight`, so a branch flip, when one is needed, is put where the tool is not cutting.
/// On the pole (A = 0) C is undetermined: the points there are left out of the programme and
/// get C interpolated between their neighbours (held at the ends), so C never jumps there.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"

namespace taxopt {

/// Options of plan_poses.
struct PosePlanOptions {
  /// Weight of the travel of a move marked rapid, relative to a feed move.
  double rapid_weight = 0.01;
  /// Weight of C travel relative to A travel.
  double c_weight = 1.0;
  /// A step of C larger than this (per point) is a "C jump" (report's c_jumps) ...
  double c_jump_threshold_rad = Constants<double>::pi() / 2;
  /// ... and costs this much extra travel, so that a branch without jumps is taken whenever
  /// one exists (rad, weighted like the move).
  double c_jump_penalty_rad = 20.0 * Constants<double>::pi();
};

/// Outcome of plan_poses.
struct PosePlan {
  enum class Status { Ok, OutOfLimits };
  Status status = Status::Ok;
  std::vector<Posed> poses;
  /// With OutOfLimits: the first point with no pose within the axis ranges.
  std::size_t failed_index = 0;
  std::string message;
  bool ok() const { return status == Status::Ok; }
};

/// Chooses machine poses for unit tool axes.
/// @param axes       unit tool axes, workpiece coordinates
/// @param rapid_into rapid_into[i] is true when the move into point i is a rapid (size of axes)
/// @param start      pose before the first point (previous operation), if any
/// @param preferred  empty, or per point a pose the caller has chosen (its branch, and its C
///                   on the pole; a continuous C still takes the turn nearest the previous
///                   point's): Method::Global decides these by its own objective
TAXOPT_API PosePlan plan_poses(const MachineKinematicsd& machine, const std::vector<Vec3d>& axes,
                               const std::vector<bool>& rapid_into,
                               const std::optional<Posed>& start = {},
                               const PosePlanOptions& options = {},
                               const std::vector<std::optional<Posed>>& preferred = {});

}  // namespace taxopt
