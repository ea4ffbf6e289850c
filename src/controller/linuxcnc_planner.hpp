#pragma once
/// @file LinuxCNC's trajectory planner with tool centre point control on, as measured on its
/// motion controller (tests/controller, scripts/linuxcnc_controller.py): every block a straight
/// line in the program's axes (tip X Y Z, A, C) at the path velocity and acceleration within
/// every axis's limit, the joints following through the kinematics.

#include <string>
#include <vector>

#include "taxopt/core/stop.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/kinematics/machine.hpp"

namespace taxopt::controller {

/// One block with TCP on as LinuxCNC's planner moves it (GcodeProgram::tcp_joint_peaks): `from`
/// and `to` in the program's axes (tip X Y Z mm, A C deg), on a straight line in their space,
/// at the path velocity (at most `rate_per_s` of the block a second, the written F) and the
/// path acceleration that keep every axis within `limits`; from rest and to rest where the
/// block starts or ends a chain (LinuxCNC never blends a rapid with a feed block, measured),
/// else at that velocity through the end. `accel_share`: of that acceleration, the share
/// LinuxCNC gives the block (tcp_block_peaks).
struct TcpBlock {
  JointPosition from, to;
  JointLimits limits;
  double rate_per_s = 0.0;
  bool start_rest = true, end_rest = true;
  int line = 0;
  double accel_share = 1.0;
  /// Where the block starts is known: the program has stated every joint before it (else the
  /// start is the model's guess of where the machine stands, and so are the peaks).
  bool start_known = true;
};

/// The joints (the tip's machine position, A, C) on `b` with every axis's acceleration limit
/// scaled by `accel_scale` (1: the machine's), sampled each 1 ms servo period and differenced
/// over 10 (the window of scripts/linuxcnc_controller.py). Raises `peaks` (kJointCount of
/// them) where the block exceeds them.
void tcp_block_peaks(const Machine& machine, const TcpBlock& b, double accel_scale,
                     std::vector<JointPeak>& peaks);

/// GcodeProgram::tcp_joint_peaks of `blocks` with the axes' accelerations scaled by
/// `accel_scale`; `stop`, where given, looked at every few blocks.
std::vector<JointPeak> tcp_joint_peaks(const Machine& machine, const std::vector<TcpBlock>& blocks,
                                       double accel_scale, const StopSource* stop = nullptr);

/// The largest share of the axes' acceleration limits (0.001 steps, rounded down) at which
/// `blocks` keep every joint within its own (joint_accel_limit); 0 where none down to 0.05
/// does.
double tcp_axis_accel_scale(const Machine& machine, const JointLimits& limits,
                            const std::vector<TcpBlock>& blocks, const StopSource* stop = nullptr);

/// Which of `moves` (read back from `text`, LinuxCNC's program) its planner (tp.c, 2.9) runs at
/// half its acceleration: the rapids that keep the parabolic end they are queued with (G64).
/// A rapid followed by a rapid blends with it parabolically where either turns a rotary axis
/// (no blend arc is tried where rotary axes move), and keeps that end where no move follows
/// before the queue stops (a tool change, M428's synch, G43, the end): such a rapid runs at half
/// its acceleration from start to end. One followed by a feed block stops (full acceleration).
/// Measured on the bridge mill's controller: its first head turn 2.104 s (1.804 at the full
/// acceleration, 2.104 at half), a retract's three rapids that turn B 0.291, 0.448, 0.444 s
/// (0.223, 0.339, 0.324 at the full).
std::vector<bool> half_accel_rapids(const std::vector<GcodeMove>& moves, const std::string& text);

}  // namespace taxopt::controller
