#pragma once
/// @file plan_poses with a job's stop, internal to the library.

#include <optional>
#include <vector>

#include "taxopt/core/stop.hpp"
#include "taxopt/kinematics/pose_planner.hpp"

namespace taxopt::detail {

/// plan_poses looking at `stop`, where given, as it goes (a few milliseconds of work apart).
PosePlan plan_poses(const MachineKinematicsd& machine, const std::vector<Vec3d>& axes,
                    const std::vector<bool>& rapid_into, const std::optional<Posed>& start,
                    const PosePlanOptions& options,
                    const std::vector<std::optional<Posed>>& preferred, const StopSource* stop);

}  // namespace taxopt::detail
