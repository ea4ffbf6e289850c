#pragma once
/// @file Feed scheduling: the fastest feed profile a machine can hold along a path of joint
/// positions, within the programmed feed and every joint's velocity and acceleration limit.
///
/// **Model.** The controller moves linearly in the joints between points. Segment i (point i
/// to i + 1) takes t_i seconds; joint j moves dq_ij, so its velocity is w_ij = dq_ij / t_i
/// (eq. 16 of the paper per joint) and its acceleration at point i + 1, between segments i
/// and i + 1, is (w_{i+1,j} - w_ij) / ((t_i + t_{i+1}) / 2) (eq. 18 with its erratum). A
/// chain of feed moves starts and ends at rest: before its first and after its last segment
/// sits a virtual segment of zero length and zero time, so the first velocity must be reached
/// within half the first segment's time. These are `joint_rates`.
///
/// **Problem.** With rates u_i = 1 / t_i: maximise every u_i subject to u_i <= U_i (the
/// programmed feed and the velocity limits, |dq_ij| u_i <= V_j) and, at each point and joint,
/// |q u - p w| <= (A/2)(1/w + 1/u) with w, p the rate and displacement of the segment before
/// and u, q those of the segment after. That set is not a lattice: a crawling segment
/// "absorbs" any velocity change of its neighbour in this discrete model (its long time
/// enters the mean), so no profile is largest in it.
///
/// **Inner set.** Per joint and point the constraint is replaced by a sufficient one that is
/// a lattice: u <= phi(w) and w <= psi(u) with phi, psi increasing --
///  - same direction (p q > 0): phi(w) = u+(max(w, w*)) with u+(w) the root of
///    |q| u - |p| w = (A/2)(1/w + 1/u) above the constant-velocity ray, and w* = sqrt(A / 2|p|)
///    where u+ is least (below w* the exact bound rises again: the crawl effect, dropped);
///    psi likewise with the roles of the segments exchanged;
///  - reversal, start or stop (p q <= 0): |p| w <= A / (2w) and |q| u <= A / (2u), i.e. each
///    side sheds or builds its own velocity within half its own time.
/// The intersection over joints is again {u <= phi(w), w <= psi(u)} with increasing phi and
/// psi, so the feasible profiles form a lattice with a greatest element: the schedule that
/// is at least as fast as any other on every segment, hence of least total time.
///
/// **Algorithm.** From u = U, backward sweeps (u_{i} <= psi(u_{i+1})) and forward sweeps
/// (u_{i+1} <= phi(u_i)) alternate until nothing changes: the iteration of a monotone
/// operator from the top converges to its greatest fixed point, which is the greatest
/// feasible profile. One backward and one forward sweep suffice when one joint binds at each
/// point (the classic look-ahead); conflicting joints can need more, counted in `sweeps`.
/// Each sweep is linear in the number of points. If `max_sweeps` runs out first, the
/// profile is scaled down uniformly until the exact model holds (feasible, maybe not
/// fastest), and `converged` is false.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// The five joints of the machine, in this order everywhere: X, Y, Z, the tilt axis (A on an
/// A/C machine, B on a B/C one) and C.
enum class Joint : std::uint8_t { X, Y, Z, Tilt, C };
inline constexpr std::size_t kJointCount = 5;
/// "X", "Y", "Z", "tilt", "C": the tilt joint is A or B by the machine (joint_name gives the
/// letter).
TAXOPT_API const char* to_string(Joint joint);
/// The joint's letter on a machine whose tilt axis is `tilt_letter` (A, or B on a B/C machine:
/// Joint::Tilt is the tilt axis whatever its letter).
TAXOPT_API std::string joint_name(Joint joint, char tilt_letter);

/// Joint positions of one point: X, Y, Z in mm, the tilt and C in degrees (C unwound).
using JointPosition = std::array<double, kJointCount>;

/// Dynamic limits of one joint, per second: mm for X Y Z, degrees for A C; 0: no limit.
struct JointLimit {
  double max_velocity_per_s = 0.0;
  double max_accel_per_s2 = 0.0;
  double max_jerk_per_s3 = 0.0;
};
using JointLimits = std::array<JointLimit, kJointCount>;

/// A chain of feed moves to schedule.
struct FeedChain {
  /// n joint positions.
  std::vector<JointPosition> joints;
  /// n - 1 segment times at the programmed feed, s (the fastest the program allows).
  std::vector<double> min_time_s;
  bool start_at_rest = true;
  bool end_at_rest = true;
};

/// What bounds a segment of the schedule.
enum class FeedBound : std::uint8_t { Programmed, Velocity, Acceleration };

struct ScheduleOptions {
  /// Limits are applied times (1 - margin), so that the feed words written with 8
  /// significant digits cannot carry a block over a limit.
  double margin = 1e-5;
  int max_sweeps = 1000;
};

/// Result of schedule_feed.
struct TAXOPT_API FeedSchedule {
  /// n - 1 segment times, s; a segment that moves no joint takes 0.
  std::vector<double> time_s;
  /// What bounds each segment, and which joint (for Velocity and Acceleration).
  std::vector<FeedBound> bound;
  std::vector<Joint> bound_joint;
  int sweeps = 0;
  bool converged = true;
  double total_time_s() const;
};

/// The greatest feasible feed profile of a chain (see the file comment).
/// @throws std::invalid_argument when sizes disagree or a moving segment has no positive time
TAXOPT_API FeedSchedule schedule_feed(const FeedChain& chain, const JointLimits& limits,
                                      const ScheduleOptions& options = {});

/// Peak velocity and acceleration of each joint along a chain run with segment times
/// `time_s` (the model of the file comment, rests included), and the segment or point where
/// each peak occurs (acceleration: the point index, 0 and n - 1 being the rests).
struct JointRates {
  std::array<double, kJointCount> max_velocity_per_s{}, max_accel_per_s2{}, max_jerk_per_s3{};
  std::array<std::size_t, kJointCount> velocity_at{}, accel_at{}, jerk_at{};
};
/// Segments of zero time are skipped (they move nothing). Jerk is the change of
/// acceleration between consecutive points over the time between them.
TAXOPT_API JointRates joint_rates(const std::vector<JointPosition>& joints,
                                  const std::vector<double>& time_s, bool start_at_rest = true,
                                  bool end_at_rest = true);

/// Time of a rest-to-rest move (a rapid) with every joint on its own trapezoid at its
/// velocity and acceleration limits: the slowest joint's. Joints without limits take no time.
TAXOPT_API double rapid_time_s(const JointPosition& from, const JointPosition& to,
                               const JointLimits& limits);

}  // namespace taxopt
