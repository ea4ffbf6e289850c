// --objective time: the operation's scheduled cycle and the passes refined for it (plan_rooms.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "kinematics/pose_planning.hpp"
#include "pipeline/plan_rooms.hpp"
#include "pipeline/stages.hpp"
#include "plan/air_turn.hpp"
#include "plan/pole_passage.hpp"
#include "plan/stretch_guard.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {

/// An operation's scheduled cycle (feed moves and rapids at the machine's effective limits)
/// with tool axes `axes` about the fixed ball centres, posed as run_job poses them (the turns
/// between passes in one move); `programmed_s` the least time of every move. Infinite when the
/// axes cannot be posed.
double operation_cycle_s(const OperationPlanInputs& in, double max_deviation_rad,
                         const std::vector<Vec3d>& axes,
                         const std::vector<std::optional<Posed>>& preferred, double fallback_feed,
                         const std::vector<double>& programmed_s) {
  const Operationd& op = in.op;
  const Machine& machine = in.machine;
  const double ball_radius_mm = in.ball_radius_mm;
  const PosePlan plan = detail::plan_poses(machine.rotary, axes, rapid_into_of(op), {},
                                           in.pose_options, preferred, in.stop);
  if (!plan.ok()) return std::numeric_limits<double>::infinity();
  PostedOperation po;
  po.points = posted_feeds(op, fallback_feed);
  po.poses = plan.poses;
  for (std::size_t i = 0; i < po.points.size(); ++i) {
    po.points[i].axis = axes[i];
    po.points[i].tip_mm = tip_for_axis(op.points[i], ball_radius_mm, axes[i]);
  }
  spread_turns_in_air(op, in.contacts, ball_radius_mm, in.model, in.tool ? *in.tool : ToolModel{},
                      machine, max_deviation_rad, po, in.stop);
  std::vector<Vec3d> tips;
  for (const CLPointd& p : po.points) tips.push_back(p.tip_mm);
  std::vector<double> programmed = programmed_block_times_s(po.points, po.poses);
  if (machine.gcode.feed_reference == FeedReference::CutterPath) {
    // The input block's time, within the feed ratio (as posted: kept_block_times_s).
    programmed = kept_block_times_s(programmed_s, programmed, machine.gcode.max_feed_ratio);
  }
  return schedule_operation(po.points, joints_of(machine.rotary, tips, po.poses), programmed,
                            effective_limits(machine), machine.rotary, nullptr,
                            machine.gcode.mode == GcodeMode::Tcp ? &po.poses : nullptr, in.stop)
      .summary.cycle_time_s;
}

namespace {

/// --objective time on one operation (refine_time): its candidate plans, each timed as the
/// schedule runs it, and the choice among them.
class TimePlanner {
 public:
  TimePlanner(const OperationPlanInputs& in, const GlobalOptions& options, double fallback_feed,
              detail::StageProgress& progress)
      : options_(options),
        fallback_feed_(fallback_feed),
        in_(in),
        progress_(progress),
        rapid_into_(rapid_into_of(in.op)) {
    for (const CLPointd& p : in.op.points) in_axes_.push_back(p.axis);
  }

  std::string run(OptimisedOperation& out) {
    const OptimisedOperation paper = out;
    // Two sum-squares plans: the coarse programme's (the time plan's start and guard
    // reference: off the pyramid's, the time plan's schedule came out longer on three of the
    // eighteen cases of docs/results.md, up to +14 %) and the pyramid's (--method global's own
    // plan, so the time objective is never slower than it).
    OptimisedOperation smooth = out, fine = out;
    GlobalOptions sum_squares = options_;
    sum_squares.objective = GlobalObjective::SumSquares;
    sum_squares.fine_step_deg = 0.0;
    refine(sum_squares, smooth);
    const bool pyramid = options_.fine_step_deg > 0.0;
    if (pyramid) {
      sum_squares.fine_step_deg = options_.fine_step_deg;
      refine(sum_squares, fine);
    }
    const PosePlan in_plan = poses_of(in_axes_, {});
    const TimeContext time = time_context(in_plan, poses_of(smooth.axes, smooth.preferred));
    programmed_s_ = time.programmed_s;
    OptimisedOperation fast = out;
    const GuardReference reference{smooth.axes, smooth.preferred, false};
    refine(options_, fast, &time, &reference);
    OptimisedOperation input = paper;
    input.axes = in_axes_;
    input.preferred.clear();
    std::vector<Plan> plans = {
        {"sum-squares", &smooth, cycle(smooth), 0.0},
        {"sum-squares-fine", &fine, pyramid ? cycle(fine) : std::numeric_limits<double>::infinity(),
         0.0},
        {"paper", &paper, cycle(paper), 0.0},
        {"time", &fast, cycle(fast), 0.0},
        {"input", &input, input_cycle(in_plan), 0.0}};
    return choose(plans, out);
  }

 private:
  struct Plan {
    const char* name;
    const OptimisedOperation* plan;
    double cycle_s, peak_a;
  };

  void refine(const GlobalOptions& options, OptimisedOperation& plan,
              const TimeContext* time = nullptr, const GuardReference* reference = nullptr) {
    refine_global(in_, options, plan, progress_, time, reference);
  }

  PosePlan poses_of(const std::vector<Vec3d>& axes,
                    const std::vector<std::optional<Posed>>& preferred) const {
    return plan_poses(in_.machine.rotary, axes, rapid_into_, {}, in_.pose_options, preferred);
  }

  /// The time plan's context: the machine's effective limits; every feed block keeps the
  /// time the input block takes at its feed (cutter-path), as posted; with the tip-path
  /// reference that time moves with the tip (the input's here); the sum-squares and the
  /// input's poses as alternatives every pass weighs.
  TimeContext time_context(const PosePlan& in_plan, const PosePlan& smooth_plan) const {
    TimeContext time;
    time.limits = effective_limits(in_.machine);
    time.programmed_s = programmed_block_times_s(posted_feeds(in_.op, fallback_feed_),
                                                 in_plan.ok() ? in_plan.poses : smooth_plan.poses);
    if (smooth_plan.ok()) time.alternatives.push_back(smooth_plan.poses);
    if (in_plan.ok()) time.alternatives.push_back(in_plan.poses);
    return time;
  }

  double cycle_of(const std::vector<Vec3d>& axes,
                  const std::vector<std::optional<Posed>>& preferred) const {
    return operation_cycle_s(in_, deg_to_rad(options_.max_deviation_deg), axes, preferred,
                             fallback_feed_, programmed_s_);
  }
  double cycle(const OptimisedOperation& o) const { return cycle_of(o.axes, o.preferred); }

  /// The input's axes count where every point and move of theirs is free.
  double input_cycle(const PosePlan& in_plan) const {
    if (!in_plan.ok()) return std::numeric_limits<double>::infinity();
    const double input_s = cycle_of(in_axes_, {});
    if (!std::isfinite(input_s)) return input_s;
    const std::vector<char> hit = points_and_moves_hit(in_, in_axes_, in_plan.poses,
                                                       std::vector<char>(in_.op.points.size(), 1));
    return std::find(hit.begin(), hit.end(), 1) != hit.end()
               ? std::numeric_limits<double>::infinity()
               : input_s;
  }

  /// The peak a of a plan's passes, each move timed as the controller takes it from the words
  /// (move_times_s), as the report measures it.
  double peak_a(const OptimisedOperation& o) const {
    const PosePlan pp = poses_of(o.axes, o.preferred);
    if (!pp.ok()) return std::numeric_limits<double>::infinity();
    std::vector<double> a, c;
    for (const Posed& q : pp.poses) {
      a.push_back(rad_to_deg(q.tilt_rad));
      c.push_back(rad_to_deg(q.c_rad));
    }
    std::vector<double> into = {0.0};
    for (double t : move_times_s(in_.op, in_.ball_radius_mm, in_.machine.rotary, pp.poses,
                                 in_.timing, IndexRange{0, in_.op.points.size()})) {
      into.push_back(t);
    }
    return summarise_timed(in_.op, a, c, into).max_accel_deg_s2;
  }

  /// Within the tie band of the shortest cycle, the smoothest plan wins (then the shorter,
  /// then the earlier in the list: deterministic). Its axes go to `out`; the log's line.
  std::string choose(std::vector<Plan>& plans, OptimisedOperation& out) const {
    double shortest = std::numeric_limits<double>::infinity();
    for (const Plan& p : plans) shortest = std::min(shortest, p.cycle_s);
    const Plan* best = nullptr;
    const Plan* fastest = nullptr;
    for (Plan& p : plans) {
      if (!std::isfinite(p.cycle_s)) continue;
      if (!fastest || p.cycle_s < fastest->cycle_s * (1.0 - 1e-9)) fastest = &p;
      if (p.cycle_s > shortest * (1.0 + options_.time_tie_band)) continue;
      p.peak_a = peak_a(*p.plan);
      if (!best || p.peak_a < best->peak_a * (1.0 - 1e-9) ||
          (p.peak_a <= best->peak_a * (1.0 + 1e-9) && p.cycle_s < best->cycle_s * (1.0 - 1e-9))) {
        best = &p;
      }
    }
    if (!best) return "no plan could be timed: the paper's axes kept";
    const std::string chosen = best->name;
    const double best_s = best->cycle_s, best_peak = best->peak_a;
    const double fastest_peak = fastest == best ? best_peak : peak_a(*fastest->plan);
    const std::string fastest_name = fastest->name;
    const double fastest_s = fastest->cycle_s;
    out = *best->plan;
    out.time_choice = OperationResult::TimeChoice{
        chosen, fastest_name, best_s, best_peak, fastest_s, fastest_peak, options_.time_tie_band};
    char line[640];
    std::snprintf(line, sizeof line,
                  "scheduled cycle %.3f s (paper), %.3f s (sum-squares), %.3f s (sum-squares, "
                  "fine), %.3f s (time plan), %.3f s (input): %s axes kept (%.3f s, peak a %.1f "
                  "deg/s^2; the shortest, %s, %.3f s with peak a %.1f: within the %.1f %% tie "
                  "band the smoother wins)",
                  plans[2].cycle_s, plans[0].cycle_s, plans[1].cycle_s, plans[3].cycle_s,
                  plans[4].cycle_s, chosen.c_str(), best_s, best_peak, fastest_name.c_str(),
                  fastest_s, fastest_peak, 100.0 * options_.time_tie_band);
    return line;
  }

  const GlobalOptions& options_;
  const double fallback_feed_;
  const OperationPlanInputs in_;
  detail::StageProgress& progress_;
  const std::vector<bool> rapid_into_;
  std::vector<Vec3d> in_axes_;
  std::vector<double> programmed_s_;  ///< every move's least time (TimeContext::programmed_s)
};

}  // namespace

/// --method global --objective time (docs/global-method.md): the sum-squares plan first (a
/// start and an alternative every pass weighs, and the reference of the guard, which gives it
/// back over stretches whose moves hit), then every pass planned for its scheduled time; of
/// the paper's, the sum-squares and the time plan the operation keeps the one with the
/// shortest scheduled cycle (ties to the sum-squares plan, then the paper's). `out` holds the
/// paper's plan on entry. The input's axes are kept instead where their cycle is shorter still
/// and none of their points or moves hits the part. Returns a line for the log.
std::string refine_time(const OperationPlanInputs& in, const GlobalOptions& options,
                        double fallback_feed, OptimisedOperation& out,
                        detail::StageProgress& progress) {
  return TimePlanner(in, options, fallback_feed, progress).run(out);
}

}  // namespace taxopt::pipeline
