#pragma once
/// @file Method::Global: the tool axes of one pass chosen in the machine's own coordinates,
/// minimising the rotary-axis acceleration of eq. 16-18 itself (docs/global-method.md).
///
/// Problem. A pass of n points with segment times t_i = L_i / v_i (n - 1). The decision
/// variables are the machine poses (A_i, C_i): the branch (the sign of A), the side of the pole
/// A = 0 a pass takes and the winding of C are all in them. For G = A and C,
///   omega_i^G = (G_{i+1} - G_i) / t_i,   a_i^G = (omega_i^G - omega_{i-1}^G) / ((t_{i-1} + t_i) /
///   2)
/// (the metrics of metrics.hpp, degrees). Objective, `GlobalObjective`:
///   sum-squares: J = sum_i (a_i^A)^2 + (a_i^C)^2  (+ w_j sum_i jerk_i^2, jerk_i = (a_{i+1} - a_i)
///   / t_i) peak:        P = max_i sqrt((a_i^A)^2 + (a_i^C)^2), ties broken by J.
/// Constraint: the axis of every pose is acceptable (`AxisTest`: within the deviation cone,
/// reachable, collision-free) and A within its range.
///
/// Solver. (1) Dynamic programme over a coarse set of candidate poses per point: the
/// warm start's pose, the input axis's poses and the acceptable axes of a cap grid of spacing
/// `candidate_step_deg` over the cone, each with both inverse solutions where the pass comes
/// near the pole (far from it a branch change mid-pass is never cheaper than keeping the
/// branch). Since a_i couples three points, the states are pairs of consecutive candidates:
/// O(n K^3), exact over the candidates (ties to the earlier candidate, so deterministic).
/// This settles the basin: branch, passing through the pole (A changes sign, C holds) or
/// around it (C turns), where the pass turns. (1b) The pyramid: the programme again over caps
/// around its own answer at half the spacing, level after level down to `fine_step_deg` (the
/// C-space cell size), each level exact over its candidates and never worse than the last
/// (the previous answer is every point's first candidate). (2) Continuous refinement in (A, C): J
/// is a convex quadratic, J = x^T H x with H = M^T W M pentadiagonal (M the second difference of
/// the times above); each step solves (H + lambda diag(H)) dx = -H x (Eigen sparse LDLT, O(n))
/// and moves every point as far along dx as its constraint allows (halving, at most
/// `bisection_steps` times, else it stays); the step is kept only when the objective falls,
/// else lambda grows. The peak objective reweights the rows (IRLS, w_i ~ (|a_i| / peak)^6).
/// Every iterate is feasible and the objective never rises: the result is never worse than
/// the better of the warm start and the programme's optimum.

#include <cstddef>
#include <functional>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"
#include "taxopt/plan/paper_optimiser.hpp"

namespace taxopt {

/// Time: the pass's scheduled feed time at the machine's joint limits (feed_schedule.hpp),
/// with the sum of squares as the tie-breaker (docs/global-method.md, the time objective).
enum class GlobalObjective { SumSquares, Peak, Time };
/// "sum-squares", "peak", "time".
TAXOPT_API const char* to_string(GlobalObjective objective);

/// Options of plan_pass_global.
struct GlobalOptions {
  GlobalObjective objective = GlobalObjective::SumSquares;
  /// Weight of the squared jerk (deg/s^3)^2 against the squared acceleration, s^2 (0: off).
  /// Only the refinement sees it (the programme's states are pairs of points).
  double jerk_weight_s2 = 0.0;
  /// Radius of the cap of candidate axes around each input axis, deg (the deviation cone;
  /// the AxisTest holds the cone itself).
  double max_deviation_deg = 30.0;
  /// Spacing of the programme's candidate axes, deg.
  double candidate_step_deg = 15.0;
  /// The pyramid (sum-squares and peak objectives): the programme runs again over caps around
  /// its own answer at half the spacing each time (a cap of radius twice the spacing, so it
  /// covers the gap between the coarser candidates), down to this spacing, deg (run_job: the
  /// C-space cell size, PaperOptions::grid_deg); 0: the coarse programme alone. Each level keeps the previous
  /// answer when it finds nothing better, so it never makes the pass worse.
  double fine_step_deg = 2.0;
  /// GlobalObjective::Time: a plan whose scheduled cycle is within this fraction of the shortest
  /// wins on smoothness (the lowest peak a of the rotary axes): a millisecond is not worth a
  /// tripled peak acceleration (tests/test_paper_method.cpp). 0.001 = 0.1 %, below the 0.1 % within
  /// which the scheduled feed moves agree with LinuxCNC's own controller (the measurement in
  /// tests/controller).
  double time_tie_band = 0.001;
  /// Refinement: largest number of accepted steps, and of halvings of a point's step.
  int max_iterations = 40;
  int bisection_steps = 4;
};

/// One pass as the global method sees it.
struct GlobalPassProblem {
  /// Input tool axes (n, unit).
  std::vector<Vec3d> input_axes;
  /// Segment times t_i = L_i / v_i, s (n - 1, positive).
  std::vector<double> segment_time_s;
  /// A feasible start (n poses, continuous C), e.g. the paper method's; its axes must be
  /// acceptable.
  std::vector<Posed> warm_start;
  /// GlobalObjective::Time only. The machine's joints of point i at a pose (X Y Z mm, A C deg;
  /// C as the pose has it), each segment's least time at the programmed feed, s (n - 1,
  /// positive), the joints' limits, and other feasible pose sequences (n poses each, continuous
  /// C; e.g. the sum-squares plan) that join the warm start as starts and candidates.
  std::function<JointPosition(std::size_t, const Posed&)> joints_at;
  std::vector<double> programmed_time_s;
  JointLimits limits{};
  std::vector<std::vector<Posed>> alternatives;
  /// Rotary axes held at the warm start's values, each pose's own: the programme's candidates
  /// and the refinement move only the other axis. For an axis the input holds still over the
  /// pass (a 4-axis cut, a chamfer at a constant tilt): the promise that no axis runs faster
  /// than the input's keeps it still, so a plan that moves it is never written, and the other
  /// axis alone can still be smoothed (a chamfer's C round its corners). Alternatives must hold
  /// them too.
  bool hold_tilt = false, hold_c = false;
  /// No axis's peak omega or a above the warm start's (each axis on its own, at
  /// segment_time_s): the programme's answer and every refinement step that would raise one are
  /// refused. With the warm start the input's, the plan keeps the promise the guard holds it to
  /// (a sum of squares can fall while one axis's peak rate rises: a chamfer's C smoothed round
  /// a corner turned faster into it).
  bool keep_peaks = false;
  /// The caller's own test of a plan (n poses), where it judges more than the pass's cut (the
  /// rates into and out of it): when given, the programme's answer, every low-passed plan of a
  /// held axis and every refinement step must pass it. The warm start should.
  using Admissible = std::function<bool(const std::vector<Posed>&)>;
  Admissible admissible;
};

/// The poses of a pass and how they came about.
struct GlobalPassPlan {
  /// Poses (continuous C) and their axes, n.
  std::vector<Posed> poses;
  std::vector<Vec3d> axes;
  /// Objective (rotary_objective; for GlobalObjective::Time the pass's scheduled time, s,
  /// pass_time_s) of the warm start, of the programme's best sequence, and in the end.
  double objective_warm = 0.0, objective_dp = 0.0, objective = 0.0;
  /// Largest number of candidates of a point, and refinement steps accepted.
  std::size_t max_candidates = 0;
  /// Levels of the pyramid run, and the objective after them (before the refinement).
  int pyramid_levels = 0;
  double objective_pyramid = 0.0;
  int iterations = 0;
};

/// The objective of poses (continuous C) over segment times: J or P of the file comment,
/// degrees and seconds. GlobalObjective::Time needs the machine's joints: pass_time_s
/// (std::invalid_argument here).
TAXOPT_API double rotary_objective(const std::vector<Posed>& poses,
                                   const std::vector<double>& segment_time_s,
                                   GlobalObjective objective, double jerk_weight_s2 = 0.0);

/// The exact minimiser over discrete candidates: one index per point into `candidates[i]`,
/// by the programme of the file comment; `value` gets the objective of the sequence (jerk not
/// counted). With `wrap_c` (a continuous C) C is taken modulo a turn: each step of C is
/// wrapped to (-180, 180] deg. Candidates per point: 1 to 255.
TAXOPT_API std::vector<std::size_t> best_candidate_sequence(
    const std::vector<std::vector<Posed>>& candidates, const std::vector<double>& segment_time_s,
    GlobalObjective objective, double* value, bool wrap_c = true);

/// The time objective's programme (docs/global-method.md): one index per point into
/// `candidates[i]` minimising the surrogate time sum_i tau_i + sum_i e_i, where
/// tau_i = max(T_i, max_j |dq_ij| / V_j) is segment i's least time at the velocity limits and
/// e_i = ((tau_{i-1} + tau_i) / 2) (sqrt(max_j |a_ij| / A_j) - 1)^+ what point i's acceleration at
/// those times adds when both segments stretch alike; ties broken by the sum of squared rotary
/// accelerations at `segment_time_s`. `joints[i][k]` are the joints of `candidates[i][k]`;
/// `surrogate_s` gets the sequence's surrogate time. Exact over the candidates.
TAXOPT_API std::vector<std::size_t> fastest_candidate_sequence(
    const std::vector<std::vector<Posed>>& candidates,
    const std::vector<std::vector<JointPosition>>& joints,
    const std::vector<double>& programmed_time_s, const std::vector<double>& segment_time_s,
    const JointLimits& limits, double* surrogate_s, bool wrap_c = true);

/// Scheduled time, s, of a pass run rest to rest through `joints` (n) with least segment times
/// `programmed_time_s` (n - 1): schedule_feed's total.
TAXOPT_API double pass_time_s(const std::vector<JointPosition>& joints,
                              const std::vector<double>& programmed_time_s,
                              const JointLimits& limits);

/// Plans one pass. `acceptable(i, axis)` may be called from several threads at once for
/// different passes; the result does not depend on the thread count.
TAXOPT_API GlobalPassPlan plan_pass_global(const MachineKinematicsd& machine,
                                           const GlobalPassProblem& problem,
                                           const AxisTest& acceptable,
                                           const GlobalOptions& options = {});

}  // namespace taxopt
