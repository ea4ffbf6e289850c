// --method global on every pass, and the turns between passes spread over the rapids in the air
// (plan_rooms.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

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

namespace {

/// One pass's global plan (plan_pass_global) over its cut from given start poses (the whole
/// operation's), at the program's timing, within the cone, with --objective time's context.
class PassSolver {
 public:
  PassSolver(const OperationPlanInputs& in, const GlobalOptions& options, const TimeContext* time,
             const Acceptance& acceptable_at)
      : in_(in), options_(options), time_(time), acceptable_at_(acceptable_at) {}

  std::optional<GlobalPassPlan> solve(const IndexRange& pass, const std::vector<Posed>& start,
                                      bool hold_tilt, bool hold_c,
                                      GlobalPassProblem::Admissible admissible = {}) const {
    const Operationd& op = in_.op;
    GlobalPassProblem problem;
    problem.hold_tilt = hold_tilt;
    problem.hold_c = hold_c;
    problem.keep_peaks = hold_tilt || hold_c;
    problem.admissible = std::move(admissible);
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      problem.input_axes.push_back(op.points[i].axis);
      problem.warm_start.push_back(start[i]);
    }
    // The program's own timing with the start's tips (move_times_s: the report's and the
    // guard's); a move too short to time gets a floor (it would divide).
    problem.segment_time_s =
        move_times_s(op, in_.ball_radius_mm, in_.machine.rotary, start, in_.timing, pass);
    for (double& t : problem.segment_time_s) t = std::max(t, 1e-6);
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at_.in_cone(pass.begin + j, axis);
    };
    if (time_) add_time_context(pass, acceptable, problem);
    return plan_pass_global(in_.machine.rotary, problem, acceptable, options_);
  }

 private:
  /// --objective time: the joints of a pose (the schedule's, whatever the G-code mode: the tip
  /// under the fixed ball centre, carried by the table), the programmed times, the limits, and
  /// the alternatives acceptable over the pass (holding what the problem holds).
  void add_time_context(const IndexRange& pass, const AxisTest& acceptable,
                        GlobalPassProblem& problem) const {
    const Operationd& op = in_.op;
    const Machine& machine = in_.machine;
    problem.joints_at = [&op, &machine, r = in_.ball_radius_mm, b = pass.begin](std::size_t j,
                                                                                const Posed& pose) {
      const Vec3d tip = tip_for_axis(op.points[b + j], r, machine.rotary.forward(pose));
      const Vec3d xyz = machine.rotary.to_machine_mm(tip, pose);
      return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.tilt_rad),
                           rad_to_deg(pose.c_rad)};
    };
    problem.programmed_time_s = slice(time_->programmed_s, pass.begin + 1, pass.end);
    problem.limits = time_->limits;
    for (const std::vector<Posed>& alt : time_->alternatives) {
      std::vector<Posed> poses = slice(alt, pass.begin, pass.end);
      bool ok = true;
      for (std::size_t j = 0; ok && j < poses.size(); ++j) {
        ok = machine.rotary.tilt.contains(poses[j].tilt_rad) &&
             acceptable(j, machine.rotary.forward(poses[j])) &&
             (!problem.hold_tilt || poses[j].tilt_rad == problem.warm_start[j].tilt_rad) &&
             (!problem.hold_c || poses[j].c_rad == problem.warm_start[j].c_rad);
      }
      if (ok) problem.alternatives.push_back(std::move(poses));
    }
  }

  const OperationPlanInputs& in_;
  const GlobalOptions& options_;
  const TimeContext* time_;
  const Acceptance& acceptable_at_;
};

/// Whether the input's axes clear the part at every point of a pass (without a part: true).
bool input_clear(const OperationPlanInputs& in, const IndexRange& pass) {
  if (!in.input_clear) return true;
  for (std::size_t i = pass.begin; i < pass.end && i < in.input_clear->size(); ++i) {
    if (!(*in.input_clear)[i]) return false;
  }
  return true;
}

/// Whether a plan of a pass's cut (`cut`, its poses `plan`) keeps each rotary axis's peak
/// omega and a over the whole pass within the input's (a still axis within kStillOmegaDegS and
/// kStillAccelDegS2), as the guard holds it: the input's poses with the pass's replaced by the
/// plan's, the points in the air before and after the cut on its end poses.
bool within_input(const OperationPlanInputs& in, const IndexRange& whole, const IndexRange& cut,
                  const RotarySummary& input, std::vector<Posed> poses,
                  const std::vector<Posed>& plan) {
  for (std::size_t i = whole.begin; i < whole.end; ++i) {
    poses[i] = plan[std::clamp(i, cut.begin, cut.end - 1) - cut.begin];
  }
  return peaks_within(pass_rates(in, whole, poses).summary, input, kStillOmegaDegS,
                      kStillAccelDegS2);
}

}  // namespace

/// --method global (global_optimiser.hpp) on every feed pass of `op`, from the paper's axes in
/// `out` (the warm start), in parallel over passes. Where the input holds a rotary axis still
/// over a pass's cut (a 4-axis cut, a chamfer at a constant tilt), a second plan holds it at
/// the input's values and moves the other alone (GlobalPassProblem::hold_tilt, hold_c), never
/// above the input's peaks; the pass takes it where the free plan raises an axis above the
/// input's peaks (the guard gives such a pass back: a chamfer round a block, its tilt still at
/// 45 deg, kept its input's C a of 4,843 deg/s^2 whole; held, 215) or where it is better. The
/// points between passes then follow the new pass ends; a guard gives a pass back the paper's axes
/// (or `reference`'s) where its peak a would rise or its moves would hit the part. With `time`
/// (--objective time) the passes get their joints, programmed times and alternatives from it.
void refine_global(const OperationPlanInputs& in, const GlobalOptions& options,
                   OptimisedOperation& out, detail::StageProgress& progress,
                   const TimeContext* time, const GuardReference* reference) {
  const Operationd& op = in.op;
  const std::vector<IndexRange> passes = feed_passes(op);
  const PosePlan warm =
      plan_poses(in.machine.rotary, out.axes, rapid_into_of(op), {}, in.pose_options);
  if (!warm.ok()) {
    for (std::size_t q = 0; q < passes.size(); ++q) progress.advance();
    return;
  }
  const GuardReference paper{out.axes, {}};
  const Acceptance acceptable_at{in, deg_to_rad(options.max_deviation_deg)};
  std::vector<Vec3d> input_axes;
  for (const CLPointd& p : op.points) input_axes.push_back(p.axis);
  const PosePlan input_plan =
      plan_poses(in.machine.rotary, input_axes, rapid_into_of(op), {}, in.pose_options);
  const PassSolver solver(in, options, time, acceptable_at);
  // Each pass's cut: from the first to the last contact of the pass (all of it without a part).
  // The points in the air before and after keep the axis of the nearest contact, as with the
  // paper method: the tool comes down and leaves along the axis it cuts with.
  const auto plan_pass = [&](std::size_t, const IndexRange& whole) -> std::optional<PassAxes> {
    const IndexRange pass = contact_span(in.contacts, whole);
    if (pass.size() < 3) return std::nullopt;
    std::optional<GlobalPassPlan> plan = solver.solve(pass, warm.poses, false, false);
    if (input_plan.ok() && input_clear(in, whole)) {
      // Still over the whole pass, as the guard bounds it (where the input hits the part the
      // guard's bounds are the reference's too: the free plan is held to no still axis).
      const RotarySummary input = pass_rates(in, whole, input_plan.poses).summary;
      const bool still_tilt = input.tilt.max_omega_deg_s < kStillOmegaDegS;
      const bool still_c = input.c.max_omega_deg_s < kStillOmegaDegS;
      if (still_tilt != still_c) {
        const auto within_pass = [&](const std::vector<Posed>& poses) {
          return within_input(in, whole, pass, input, input_plan.poses, poses);
        };
        std::optional<GlobalPassPlan> held =
            solver.solve(pass, input_plan.poses, still_tilt, still_c, within_pass);
        if (held && within_pass(held->poses) &&
            (!plan || !within_pass(plan->poses) || held->objective < plan->objective)) {
          plan = std::move(held);
        }
      }
    }
    if (!plan) return std::nullopt;
    return PassAxes{pass, std::move(plan->axes), std::move(plan->poses)};
  };
  out.preferred.assign(op.points.size(), std::nullopt);
  plan_passes(op, in.contacts, acceptable_at, out, progress, plan_pass,
              [&](std::size_t, const PassAxes&) { ++out.global_passes; });
  out.global_guard = guard_passes(in, out, reference ? reference : &paper);
}

namespace {

/// The turn of the rotary axes between two passes (made in one move by carry_between_passes)
/// spread over the rapids of the chain in the air (air_turn.hpp), where that makes the chain
/// faster and every new pose and move is acceptable: within the cone of its point's input
/// axis, within the machine's ranges and, with a part, free (points and swept moves). The ball
/// centres stay where the CAM system put them.
class AirTurnSpreader {
 public:
  AirTurnSpreader(const Operationd& op, const std::vector<ContactPoint>& contacts,
                  double ball_radius_mm, const PartCheck* model, const ToolModel& tool,
                  const Machine& machine, double max_deviation_rad, PostedOperation& po,
                  const StopSource* stop)
      : op_(op),
        contacts_(contacts),
        ball_radius_mm_(ball_radius_mm),
        model_(model),
        tool_(tool),
        machine_(machine),
        max_deviation_rad_(max_deviation_rad),
        po_(po),
        stop_(stop),
        n_(op.points.size()),
        limits_(effective_limits(machine)) {}

  void run() {
    if (n_ < 3 || po_.poses.size() != n_) return;
    std::vector<char> in_pass(n_, 0);
    for (const IndexRange& pass : feed_passes(op_)) {
      std::fill(in_pass.begin() + static_cast<long>(pass.begin),
                in_pass.begin() + static_cast<long>(pass.end), 1);
    }
    std::vector<Posed> trial = po_.poses;
    std::vector<std::pair<std::size_t, std::size_t>> changed;  // chains [a, b) taken
    for (std::size_t a = 1; a < n_;) {
      detail::look_at_stop(stop_, a, detail::kPointStride);
      if (in_pass[a]) {
        ++a;
        continue;
      }
      std::size_t b = a;
      while (b < n_ && !in_pass[b]) ++b;
      const std::size_t first = a;
      a = b;
      if (b == n_) break;  // after the last pass: nothing to turn to
      if (spread_chain(first, b, trial)) changed.emplace_back(first, b);
    }
    if (changed.empty()) return;
    if (model_) keep_hits_where_they_were(changed, trial);
    for (std::size_t i = 0; i < n_; ++i) {
      if (trial[i].tilt_rad == po_.poses[i].tilt_rad && trial[i].c_rad == po_.poses[i].c_rad) {
        continue;
      }
      po_.points[i].axis = machine_.rotary.forward(trial[i]);
      po_.points[i].tip_mm = tip_for_axis(op_.points[i], ball_radius_mm_, po_.points[i].axis);
    }
    po_.poses = std::move(trial);
  }

 private:
  /// The point as the machine's joints reach it (what the schedule times: in TCP mode too the
  /// linear joints follow the turning table), and as the G-code writes it.
  Vec3d tip_at(std::size_t i, const Posed& pose) const {
    return tip_for_axis(op_.points[i], ball_radius_mm_, machine_.rotary.forward(pose));
  }
  JointPosition joints_at(std::size_t i, const Posed& pose) const {
    const Vec3d xyz = machine_.rotary.to_machine_mm(tip_at(i, pose), pose);
    return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.tilt_rad),
                         rad_to_deg(pose.c_rad)};
  }

  /// A chain's time: its rapids on their trapezoids, its feed moves at their feed.
  /// `chain[k]` is the pose of point a - 1 + k (k = 0 .. b - a + 1).
  double chain_time(std::size_t a, std::size_t b, const std::vector<Posed>& chain) const {
    double t = 0.0;
    for (std::size_t j = a; j <= b; ++j) {
      const JointPosition from = joints_at(j - 1, chain[j - a]),
                          to = joints_at(j, chain[j - a + 1]);
      if (op_.points[j].motion == Motion::Rapid) {
        t += rapid_time_s(from, to, limits_);
      } else if (po_.points[j].feed_mm_per_min > 0.0) {
        t += 60.0 * Vec3d(to[0] - from[0], to[1] - from[1], to[2] - from[2]).norm() /
             po_.points[j].feed_mm_per_min;
      }
    }
    return t;
  }

  /// The chain in the air between passes, moves first .. b: the turn from the pose before it
  /// to the pose after it spread where that is faster and every pose acceptable, written into
  /// `trial`. Only chains whose turn is made by rapids now (a feed move in the air keeps its
  /// axis). True when the chain was taken.
  bool spread_chain(std::size_t first, std::size_t b, std::vector<Posed>& trial) const {
    const Posed from = po_.poses[first - 1], to = po_.poses[b];
    bool rapid_turn = true;
    std::vector<double> linear_s, now;  // per move: its time without the turn, its share now
    std::vector<bool> rapid;
    const double turn_rad = std::abs(to.tilt_rad - from.tilt_rad) + std::abs(to.c_rad - from.c_rad);
    for (std::size_t j = first; j <= b; ++j) {
      const double turned = std::abs(po_.poses[j].tilt_rad - po_.poses[j - 1].tilt_rad) +
                            std::abs(po_.poses[j].c_rad - po_.poses[j - 1].c_rad);
      rapid.push_back(op_.points[j].motion == Motion::Rapid);
      if (turned > 1e-12 && !rapid.back()) rapid_turn = false;
      now.push_back(turn_rad > 0.0 ? turned / turn_rad : 0.0);
      JointPosition p = joints_at(j - 1, po_.poses[j - 1]), q = joints_at(j, po_.poses[j]);
      q[3] = p[3];
      q[4] = p[4];
      linear_s.push_back(rapid.back() ? rapid_time_s(p, q, limits_) : 0.0);
    }
    if (!rapid_turn || turn_rad < 1e-9) return false;
    // The chain's poses for per-move shares of the turn, and their time.
    const std::vector<Posed> current(po_.poses.begin() + static_cast<long>(first - 1),
                                     po_.poses.begin() + static_cast<long>(b + 1));
    const auto poses_for = [&](const std::vector<double>& share) {
      std::vector<Posed> cand = current;
      double f = 0.0;
      for (std::size_t j = first; j < b; ++j) {
        f += share[j - first];
        cand[j - first + 1] = Posed{from.tilt_rad + f * (to.tilt_rad - from.tilt_rad),
                                    from.c_rad + f * (to.c_rad - from.c_rad)};
      }
      return cand;
    };
    std::vector<std::vector<double>> starts = {now};
    const std::vector<double> by_capacity =
        spread_turn(linear_s, rapid, rad_to_deg(to.tilt_rad - from.tilt_rad),
                    rad_to_deg(to.c_rad - from.c_rad), limits_);
    if (!by_capacity.empty()) starts.push_back(by_capacity);
    const std::vector<double> share = best_turn_shares(
        starts, rapid,
        [&](const std::vector<double>& sh) { return chain_time(first, b, poses_for(sh)); });
    const std::vector<Posed> cand = poses_for(share);
    const MachineKinematicsd& rotary = machine_.rotary;
    for (std::size_t j = first; j < b; ++j) {
      const Posed& pose = cand[j - first + 1];
      if (!(angle_between(rotary.forward(pose), op_.points[j].axis) <= max_deviation_rad_ + 1e-12 &&
            rotary.tilt.contains(pose.tilt_rad) &&
            (rotary.c.continuous || rotary.c.contains(pose.c_rad)))) {
        return false;
      }
    }
    if (chain_time(first, b, cand) >= chain_time(first, b, current) - 1e-6) return false;
    std::copy(cand.begin() + 1, cand.end() - 1, trial.begin() + static_cast<long>(first));
    return true;
  }

  /// The new poses and the moves into and out of them must be free; a chain with any hit
  /// keeps its turn where it was.
  void keep_hits_where_they_were(const std::vector<std::pair<std::size_t, std::size_t>>& changed,
                                 std::vector<Posed>& trial) const {
    std::vector<char> check_point(n_, 0), check_move(n_, 0);
    for (const auto& [first, b] : changed) {
      std::fill(check_point.begin() + static_cast<long>(first),
                check_point.begin() + static_cast<long>(b), 1);
      std::fill(check_move.begin() + static_cast<long>(first),
                check_move.begin() + static_cast<long>(b) + 1, 1);
    }
    std::vector<Vec3d> axes, xyz;
    std::vector<double> tilt_deg, c_deg;
    for (std::size_t i = 0; i < n_; ++i) {
      axes.push_back(machine_.rotary.forward(trial[i]));
      xyz.push_back(written_xyz_mm(machine_, tip_at(i, trial[i]), trial[i]));
      tilt_deg.push_back(rad_to_deg(trial[i].tilt_rad));
      c_deg.push_back(rad_to_deg(trial[i].c_rad));
    }
    std::vector<ContactPoint> air(n_);  // no contacts known: every point in the air
    const std::vector<ContactPoint>& state = contacts_.empty() ? air : contacts_;
    std::vector<char> hit(n_, 0);
    // A watch on the stop, where one is given (the checks report no progress of their own).
    const StopSource no_stop;
    detail::StageProgress watch(2 * n_, stop_ ? *stop_ : no_stop);
    for (std::size_t i : colliding_points(*model_, tool_, op_, axes, state, &watch, &check_point)) {
      hit[i] = 1;
    }
    for (std::size_t i : colliding_moves(*model_, tool_, machine_, xyz, tilt_deg, c_deg, state,
                                         &watch, nullptr, &check_move)) {
      hit[i] = 1;
    }
    for (const auto& [first, b] : changed) {
      if (std::any_of(hit.begin() + static_cast<long>(first),
                      hit.begin() + static_cast<long>(b) + 1, [](char h) { return h != 0; })) {
        std::copy(po_.poses.begin() + static_cast<long>(first),
                  po_.poses.begin() + static_cast<long>(b),
                  trial.begin() + static_cast<long>(first));
      }
    }
  }

  const Operationd& op_;
  const std::vector<ContactPoint>& contacts_;
  const double ball_radius_mm_;
  const PartCheck* model_;
  const ToolModel& tool_;
  const Machine& machine_;
  const double max_deviation_rad_;
  PostedOperation& po_;
  const StopSource* stop_;
  const std::size_t n_;
  const JointLimits limits_;
};

}  // namespace

void spread_turns_in_air(const Operationd& op, const std::vector<ContactPoint>& contacts,
                         double ball_radius_mm, const PartCheck* model, const ToolModel& tool,
                         const Machine& machine, double max_deviation_rad, PostedOperation& po,
                         const StopSource* stop) {
  AirTurnSpreader(op, contacts, ball_radius_mm, model, tool, machine, max_deviation_rad, po, stop)
      .run();
}

}  // namespace taxopt::pipeline
