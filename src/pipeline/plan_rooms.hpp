#pragma once
// The plan stage's rooms, one a method (plan.cpp dispatches): the paper's optimiser per pass
// (plan_paper.cpp), the guard that gives passes back their reference axes (plan_guard.cpp),
// the global refinement and the turns in the air (plan_global.cpp), the cycle-time objective
// (plan_time.cpp).

#include <string>
#include <vector>

#include "pipeline/stages.hpp"
#include "plan/stretch_guard.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"
#include "util/parallel.hpp"

namespace taxopt::pipeline {

/// What the planners of one operation work with (the paper's optimiser, the guard, the
/// global method, the time objective): its points and contacts, the ball, the checks' model and
/// judged tool, the machine, the program's block timing, the pose planner's options.
struct OperationPlanInputs {
  const Operationd& op;
  const std::vector<ContactPoint>& contacts;
  double ball_radius_mm;
  const PartCheck* model;
  const ToolModel* tool;
  const Machine& machine;
  const BlockTiming& timing;
  const PosePlanOptions& pose_options;
  /// The tool with its flutes held to kInputDepthAllowanceMm, and per point whether the input
  /// axis clears the part so (both empty without a part): there a method's axis must clear it
  /// too. The part tolerance is the input's budget, never a method's: no new axis puts the
  /// tool's side deeper into the part than the input did.
  const ToolModel* strict_tool = nullptr;
  const std::vector<char>* input_clear = nullptr;
  /// Per point the least angle a new axis keeps from the designed surface's normal, rad
  /// (least_tilt_of; empty or 0: no bound).
  const std::vector<double>* least_tilt_rad = nullptr;
  /// The part's tree for the sweeps of moves to clear runs of samples at once (colliding_moves),
  /// or none.
  const CSpaceRasteriser* bounds = nullptr;
  /// The job's stop, looked at in the sweeps of every point and move (points_and_moves_hit),
  /// or none.
  const StopSource* stop = nullptr;
  /// The same, judged by another model (the verification's FCL model) with `other_bounds`.
  OperationPlanInputs judged_by(const PartCheck* other,
                                const CSpaceRasteriser* other_bounds) const {
    return {op,     contacts,     ball_radius_mm, other,       tool,           machine,
            timing, pose_options, strict_tool,    input_clear, least_tilt_rad, other_bounds,
            stop};
  }
  /// Whether `axis` keeps point i's least tilt from the surface normal.
  bool keeps_tilt(std::size_t i, const Vec3d& axis) const {
    if (!least_tilt_rad || i >= least_tilt_rad->size() || !((*least_tilt_rad)[i] > 0.0)) {
      return true;
    }
    return angle_between(axis, contacts[i].surface_normal) >= (*least_tilt_rad)[i] - 1e-9;
  }
  /// Whether point i's new axes are held to the input's depth (strict_tool).
  bool held_to_input(std::size_t i) const {
    return strict_tool && input_clear && i < input_clear->size() && (*input_clear)[i];
  }
};

/// Whether an axis is acceptable at point i of an operation: the machine reaches it and, with
/// a part, the tool above the ball (and the ball, where it is in the air) misses the part.
struct Acceptance {
  const OperationPlanInputs& in;
  /// The deviation cone's half-angle, rad (--max-deviation).
  double max_deviation_rad;
  bool operator()(std::size_t i, const Vec3d& axis) const {
    if (!in.machine.rotary.reachable(axis)) return false;
    if (!in.keeps_tilt(i, axis)) return false;
    if (!in.model) return true;
    const bool in_air = in.contacts.empty() || in.contacts[i].state != ContactState::Touching;
    const ToolModel& tool = in.held_to_input(i) ? *in.strict_tool : *in.tool;
    return !in.model->collides(tool, reference_point(in.op.points[i], in.ball_radius_mm), axis,
                               in_air);
  }
  /// Acceptable and within the cone around point i's input axis.
  bool in_cone(std::size_t i, const Vec3d& axis) const {
    return within_cone(axis, in.op.points[i].axis) && (*this)(i, axis);
  }
  /// angle_between(axis, input) <= max_deviation_rad + 1e-12, the angle's atan2 taken only
  /// where the cosine leaves it in doubt (unit vectors: their cosine is the dot to 1e-9).
  bool within_cone(const Vec3d& axis, const Vec3d& input) const {
    const double dot = axis.dot(input);
    if (std::abs(axis.squaredNorm() - 1.0) < 1e-9 && std::abs(input.squaredNorm() - 1.0) < 1e-9) {
      if (dot >= cos_cone + 3e-9) return true;
      if (dot <= cos_cone - 3e-9) return false;
    }
    return angle_between(axis, input) <= max_deviation_rad + 1e-12;
  }
  /// The cosine of the cone's half-angle (with its 1e-12 rad of slack).
  double cos_cone = std::cos(max_deviation_rad + 1e-12);
};

/// What a method plans for one pass: the axes of `span` (the pass, or its cut) and, where the
/// method chose them, the poses (empty: the pose planner chooses).
struct PassAxes {
  IndexRange span;
  std::vector<Vec3d> axes;
  std::vector<Posed> poses;
};

/// The guard after the optimiser (plan/stretch_guard.hpp): where the optimised axes would
/// raise any rotary axis's omega or a above the input's peak over its pass, or sweep the tool
/// through the part between two CL points as the machine moves it, the pass keeps its
/// reference axes over those stretches, provided the reference pass is itself safe; whole when
/// a few rounds of joins do not make it good, or when the pass gains nothing on the reference.
/// The reference is the input unless given (--method global against the paper's axes, with its
/// preferred poses); the bound on the rates is always the input's, axis by axis.
/// With `judge_gain` false (--objective time, whose objective is the schedule, judged after)
/// a pass within the bounds is not asked to gain on the reference's rates.
struct GuardReference {
  std::vector<Vec3d> axes;
  std::vector<std::optional<Posed>> preferred;
  bool judge_gain = true;
};

/// What --objective time adds to an operation's passes: the least time of the move into every
/// point (its programmed feed), the machine's limits, and whole-operation pose sequences each
/// pass weighs beside the paper's (the sum-squares plan, the input's).
struct TimeContext {
  std::vector<double> programmed_s;
  JointLimits limits{};
  std::vector<std::vector<Posed>> alternatives;
};

IndexRange contact_span(const std::vector<ContactPoint>& contacts, const IndexRange& pass);

/// The rates of a pass for poses of the whole operation (eq. 16-18) at the program's timing,
/// with their peaks per axis and the sums of squares of a over the interior points (metrics'
/// accumulate).
struct PassRates {
  RotaryKinematics k;
  RotarySummary summary;
};
PassRates pass_rates(const OperationPlanInputs& in, const IndexRange& pass,
                     const std::vector<Posed>& poses);

/// The largest share of its machine limit any rotary axis reaches: of the peaks of a (`rms`
/// false) or of the RMS of a (true), against the machine's effective limits.
double worst_accel_share(const RotarySummary& s, const JointLimits& limits, bool rms);

OptimisedOperation optimise_paper(const OperationPlanInputs& in,
                                  const std::vector<double>& metric_feed,
                                  const PaperOptions& options, detail::StageProgress& progress);

std::vector<char> points_and_moves_hit(const OperationPlanInputs& in,
                                       const std::vector<Vec3d>& axes,
                                       const std::vector<Posed>& poses,
                                       const std::vector<char>& check);

StretchGuardResult guard_passes(const OperationPlanInputs& in, OptimisedOperation& out,
                                const GuardReference* reference = nullptr);

void refine_global(const OperationPlanInputs& in, const GlobalOptions& options,
                   OptimisedOperation& out, detail::StageProgress& progress,
                   const TimeContext* time = nullptr, const GuardReference* reference = nullptr);

double operation_cycle_s(const OperationPlanInputs& in, double max_deviation_rad,
                         const std::vector<Vec3d>& axes,
                         const std::vector<std::optional<Posed>>& preferred, double fallback_feed,
                         const std::vector<double>& programmed_s);

std::string refine_time(const OperationPlanInputs& in, const GlobalOptions& options,
                        double fallback_feed, OptimisedOperation& out,
                        detail::StageProgress& progress);

/// Point `to` takes the axis (and the preferred pose, if any) of point `from`, where that axis
/// is within its cone and acceptable.
inline void carry_axis(OptimisedOperation& out, const Acceptance& acceptable, std::size_t to,
                       std::size_t from) {
  if (!acceptable.in_cone(to, out.axes[from])) return;
  out.axes[to] = out.axes[from];
  if (!out.preferred.empty()) out.preferred[to] = out.preferred[from];
}

/// The points of `pass` in the air before its cut (an approach) and after it (a retract) take
/// the axis of the cut's first and last point (`carry(to, from)`, which checks): the tool comes
/// down and leaves along the orientation it cuts with, as CAM systems do, and does not turn on
/// the way (which the points alone would not check).
template <class Carry>
void carry_from_cut(const IndexRange& pass, const IndexRange& cut, Carry&& carry) {
  if (cut.size() == 0) return;
  for (std::size_t i = cut.begin; i-- > pass.begin;) carry(i, i + 1);
  for (std::size_t i = cut.end; i < pass.end; ++i) carry(i, i - 1);
}

/// The points outside every pass (retracts, rapids between passes) turn the tool from one
/// pass's last axis to the next one's first in a single move, the one of the run with the
/// longest tip travel (on a clearance plane the rotation then costs no time beside the
/// traverse): the points before that move keep the axis of the point before them, those from
/// it on take the axis of the point after them (`carry(to, from)`, which checks).
template <class Carry>
void carry_between_passes(const Operationd& op, const std::vector<IndexRange>& passes,
                          Carry&& carry) {
  std::vector<char> in_pass(op.points.size(), 0);
  for (const IndexRange& pass : passes) {
    std::fill(in_pass.begin() + static_cast<long>(pass.begin),
              in_pass.begin() + static_cast<long>(pass.end), 1);
  }
  const std::size_t n = op.points.size();
  for (std::size_t a = 0; a < n;) {
    if (in_pass[a]) {
      ++a;
      continue;
    }
    std::size_t b = a;  // the run is [a, b)
    while (b < n && !in_pass[b]) ++b;
    if (a == 0 && b == n) break;  // no pass at all
    // Moves into points a .. b (those that exist): the turn goes into the longest one.
    std::size_t turn = a == 0 ? 0 : b;
    if (a > 0 && b < n) {
      double longest = -1.0;
      for (std::size_t j = a; j <= b; ++j) {
        const double travel = (op.points[j].tip_mm - op.points[j - 1].tip_mm).norm();
        if (travel > longest) longest = travel, turn = j;
      }
    }
    for (std::size_t i = a; i < turn; ++i) carry(i, i - 1);
    for (std::size_t i = b; i-- > turn;) carry(i, i + 1);  // turn == b when b == n
    a = b;
  }
}

/// The frame every method plugs into: the feed passes of `op` planned by `plan_pass(q, pass)`
/// in parallel (each alone, so the result does not depend on the thread count; empty: the pass
/// keeps its axes), then in pass order `merge(q, plan)` (the method's own counts), the plan's
/// axes and poses written, the points in the air before and after the pass's cut carried from
/// it, and the turns between passes made in one move. `out.axes` holds the axes on entry (and
/// `out.preferred`, sized, where a method gives poses).
template <class PlanPass, class Merge>
void plan_passes(const Operationd& op, const std::vector<ContactPoint>& contacts,
                 const Acceptance& acceptable, OptimisedOperation& out,
                 detail::StageProgress& progress, PlanPass&& plan_pass, Merge&& merge) {
  const std::vector<IndexRange> passes = feed_passes(op);
  std::vector<std::optional<PassAxes>> plans(passes.size());
  detail::parallel_for(std::size_t(0), passes.size(), [&](std::size_t q) {
    progress.check();  // a stopped job plans no more passes
    plans[q] = plan_pass(q, passes[q]);
    progress.advance();
  });
  const auto carry = [&](std::size_t to, std::size_t from) {
    carry_axis(out, acceptable, to, from);
  };
  for (std::size_t q = 0; q < passes.size(); ++q) {
    if (!plans[q]) continue;
    const PassAxes& plan = *plans[q];
    merge(q, plan);
    const auto at = static_cast<long>(plan.span.begin);
    std::copy(plan.axes.begin(), plan.axes.end(), out.axes.begin() + at);
    for (std::size_t j = 0; j < plan.poses.size(); ++j) {
      out.preferred[plan.span.begin + j] = plan.poses[j];
    }
    carry_from_cut(passes[q], contact_span(contacts, passes[q]), carry);
  }
  carry_between_passes(op, passes, carry);
}

}  // namespace taxopt::pipeline
