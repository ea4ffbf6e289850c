// The plan stage: the method's tool axes per operation (paper's optimiser, global refinement,
// cycle-time objective), the guards after them, and the turns in the air (stages.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/stages.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/plan/air_turn.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"
#include "taxopt/plan/pole_passage.hpp"
#include "taxopt/plan/stretch_guard.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {
namespace {

/// The cut of a pass: from its first to its last point where the ball touches the part (empty
/// when it never does); the whole pass without contacts (no part).
IndexRange contact_span(const std::vector<ContactPoint>& contacts, const IndexRange& pass) {
  if (contacts.empty()) return pass;
  IndexRange span{pass.end, pass.end};
  for (std::size_t i = pass.begin; i < pass.end; ++i) {
    if (contacts[i].state != ContactState::Touching) continue;
    if (span.begin == pass.end) span.begin = i;
    span.end = i + 1;
  }
  return span.begin == pass.end ? IndexRange{pass.begin, pass.begin} : span;
}

/// Whether an axis is acceptable at point i of an operation: the machine reaches it and, with
/// a part, the tool above the ball (and the ball, where it is in the air) misses the part.
struct Acceptance {
  const Operationd& op;
  const std::vector<ContactPoint>& contacts;
  double ball_radius_mm;
  const PartCheck* model;
  const ToolModel* tool;
  const ACMachined& machine;
  /// The deviation cone's half-angle, rad (--max-deviation).
  double max_deviation_rad;
  bool operator()(std::size_t i, const Vec3d& axis) const {
    if (!machine.reachable(axis)) return false;
    if (!model) return true;
    const bool in_air = contacts.empty() || contacts[i].state != ContactState::Touching;
    return !model->collides(*tool, reference_point(op.points[i], ball_radius_mm), axis, in_air);
  }
  /// Acceptable and within the cone around point i's input axis.
  bool in_cone(std::size_t i, const Vec3d& axis) const {
    return angle_between(axis, op.points[i].axis) <= max_deviation_rad + 1e-12 && (*this)(i, axis);
  }
};

/// Point `to` takes the axis (and the preferred pose, if any) of point `from`, where that axis
/// is within its cone and acceptable.
void carry_axis(OptimisedOperation& out, const Acceptance& acceptable, std::size_t to,
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

/// What a method plans for one pass: the axes of `span` (the pass, or its cut) and, where the
/// method chose them, the poses (empty: the pose planner chooses).
struct PassAxes {
  IndexRange span;
  std::vector<Vec3d> axes;
  std::vector<Posed> poses;
};

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

/// Runs plan_pass_paper on every feed pass of `op` (in parallel over passes; each pass is
/// planned alone, so the result does not depend on the thread count). An axis is acceptable
/// when the machine reaches it and, with a part, the tool above the ball (and the ball, where
/// it is in the air) misses the part. Points outside the feed passes keep their axes. Then
/// each pass's stretches near the pole get C re-planned in machine space (pole_passage.hpp).
OptimisedOperation optimise_paper(const Operationd& op, const std::vector<ContactPoint>& contacts,
                                  double ball_radius_mm, const PartCheck* model,
                                  const ToolModel* tool, const Machine& machine,
                                  const std::vector<double>& metric_feed,
                                  const PosePlanOptions& pose_options, const PaperOptions& options,
                                  detail::StageProgress& progress) {
  OptimisedOperation out;
  for (const CLPointd& p : op.points) out.axes.push_back(p.axis);
  const double R = ball_radius_mm;
  const double max_dev_rad = deg_to_rad(options.max_deviation_deg);
  const auto touching = [&](std::size_t i) {
    return !contacts.empty() && contacts[i].state == ContactState::Touching;
  };
  const Acceptance acceptable_at{op, contacts, R, model, tool, machine.ac, max_dev_rad};
  std::vector<PassPlan> plans(feed_passes(op).size());
  std::vector<std::size_t> pole_stretches(plans.size(), 0);
  const auto plan_pass = [&](std::size_t q, const IndexRange& pass) {
    PassProblem problem;
    problem.segment_mm = segment_lengths_mm(op, R, pass);
    Vec3d mean = Vec3d::Zero();
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      problem.input_axes.push_back(op.points[i].axis);
      mean += op.points[i].axis;
    }
    problem.up = mean.norm() > 1e-9 ? Vec3d(mean.normalized()) : Vec3d::UnitZ();
    // The curve of the segmenter: the contact points; where the ball is in the air, the ball
    // centre offset by the normal of the nearest contact point (no jump of R at an approach);
    // without any contact, the ball centres (an offset of the contact curve).
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      const Vec3d centre = reference_point(op.points[i], R);
      if (touching(i)) {
        problem.curve_mm.push_back(contacts[i].cc_mm);
        continue;
      }
      std::optional<Vec3d> normal;
      for (std::size_t d = 1; !normal && d < pass.size(); ++d) {
        if (i >= pass.begin + d && touching(i - d)) normal = contacts[i - d].normal;
        if (i + d < pass.end && touching(i + d)) normal = contacts[i + d].normal;
      }
      problem.curve_mm.push_back(normal ? Vec3d(centre - R * *normal) : centre);
    }
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at(pass.begin + j, axis);
    };
    PassPlan plan = plan_pass_paper(problem, acceptable, options);
    std::vector<bool> rapid_into(pass.size(), false);
    rapid_into[0] = true;
    const PosePlan poses = plan_poses(machine.ac, plan.axes, rapid_into, {}, pose_options);
    if (poses.ok()) {
      const AxisTest in_cone = [&](std::size_t j, const Vec3d& axis) {
        return acceptable_at.in_cone(pass.begin + j, axis);
      };
      PolePassage pole =
          smooth_pole_passages(machine.ac, plan.axes, poses.poses, problem.segment_mm,
                               pass_feeds(metric_feed, pass), in_cone);
      plan.axes = std::move(pole.axes);
      pole_stretches[q] = pole.stretches;
    }
    PassAxes axes{pass, plan.axes, {}};
    plans[q] = std::move(plan);
    return std::optional<PassAxes>(std::move(axes));
  };
  const auto merge = [&](std::size_t q, const PassAxes& pass) {
    const PassPlan& plan = plans[q];
    out.intervals += plan.intervals();
    out.repairs += plan.repairs;
    out.smoothed_joints += plan.smoothed_joints;
    out.sharp_joints += plan.sharp_joints;
    out.pole_stretches += pole_stretches[q];
    for (std::size_t j : plan.keys) out.keys.push_back(pass.span.begin + j);
    for (std::size_t j : plan.no_free_axis) out.no_free_axis.push_back(pass.span.begin + j);
  };
  plan_passes(op, contacts, acceptable_at, out, progress, plan_pass, merge);
  return out;
}

/// Points of `op` (and the moves into them) whose tool hits the part, among those marked in
/// `check`, for axes `axes` posed as `poses` (tips from the fixed ball centres); `machine` as
/// the path is run (machine mode with linearisation runs the straight tip line: pass TCP).
/// Nothing hits without a model.
std::vector<char> points_and_moves_hit(const Operationd& op,
                                       const std::vector<ContactPoint>& contacts,
                                       double ball_radius_mm, const PartCheck* model,
                                       const ToolModel* tool, const Machine& machine,
                                       const std::vector<Vec3d>& axes,
                                       const std::vector<Posed>& poses,
                                       const std::vector<char>& check) {
  const std::size_t n = op.points.size();
  std::vector<char> hit(n, 0);
  if (!model || !tool) return hit;
  std::vector<Vec3d> xyz;
  std::vector<double> a, c;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d tip = tip_for_axis(op.points[i], ball_radius_mm, axes[i]);
    xyz.push_back(written_xyz_mm(machine, tip, poses[i]));
    a.push_back(rad_to_deg(poses[i].a_rad));
    c.push_back(rad_to_deg(poses[i].c_rad));
  }
  std::vector<ContactPoint> air(n);  // no contacts known: treat every move as in the air
  for (std::size_t i :
       colliding_moves(*model, *tool, machine, xyz, a, c, contacts.empty() ? air : contacts,
                       nullptr, nullptr, &check)) {
    hit[i] = 1;
  }
  for (std::size_t i : colliding_points(*model, *tool, op, axes, contacts, nullptr, &check)) {
    hit[i] = 1;
  }
  return hit;
}

/// The guard after the optimiser (plan/stretch_guard.hpp): where the optimised axes would
/// raise a pass's peak omega or a, or sweep the tool through the part between two CL points as
/// the machine moves it, the pass keeps its input axes over those stretches, provided the
/// input pass is itself safe; whole when a few rounds of joins do not make it good.
/// With `reference` given (--method global against the paper's axes, with its preferred poses)
/// the stretches keep those instead, when the peak a rises or the moves hit.
/// With `rates` false (--objective time, whose objective is the schedule, not the peaks) only
/// the moves that hit give stretches back.
struct GuardReference {
  std::vector<Vec3d> axes;
  std::vector<std::optional<Posed>> preferred;
  bool rates = true;
};

StretchGuardResult guard_passes(const Operationd& op, const std::vector<ContactPoint>& contacts,
                                double ball_radius_mm, const PartCheck* model,
                                const ToolModel* tool, const Machine& machine,
                                const BlockTiming& timing, const PosePlanOptions& pose_options,
                                OptimisedOperation& out,
                                const GuardReference* reference = nullptr) {
  const std::size_t n = op.points.size();
  const std::vector<bool> rapid_into = rapid_into_of(op);
  std::vector<Vec3d> in_axes;
  for (const CLPointd& p : op.points) in_axes.push_back(p.axis);
  if (reference) in_axes = reference->axes;
  const std::vector<std::optional<Posed>> in_preferred =
      reference ? reference->preferred : std::vector<std::optional<Posed>>{};
  const PosePlan in_plan =
      plan_poses(machine.ac, in_axes, rapid_into, {}, pose_options, in_preferred);
  if (!in_plan.ok()) return {out.axes, std::vector<KeptWhy>(n, KeptWhy::None)};
  // In machine mode with linearisation the tip runs the straight line as in TCP mode.
  Machine path_machine = machine;
  if (machine.gcode.program.linearise_tolerance_mm > 0.0) path_machine.gcode.mode = GcodeMode::Tcp;
  const auto moves_hit = [&](const std::vector<Vec3d>& axes, const std::vector<Posed>& poses,
                             const std::vector<char>& check) {
    return points_and_moves_hit(op, contacts, ball_radius_mm, model, tool, path_machine, axes,
                                poses, check);
  };
  const std::vector<IndexRange> passes = feed_passes(op);
  const std::vector<char> in_hit = moves_hit(in_axes, in_plan.poses, std::vector<char>(n, 1));
  // The rates of a pass for poses of the whole operation (eq. 16-18), with their peaks and the
  // sum of squares of a over the interior points (metrics' accumulate).
  struct PassRates {
    RotaryKinematics k;
    RotarySummary summary;
    double mean_sq_accel() const {
      return summary.accel_samples
                 ? summary.sum_sq_accel / static_cast<double>(summary.accel_samples)
                 : 0.0;
    }
  };
  const auto rates = [&](const IndexRange& pass, const std::vector<Posed>& poses) {
    std::vector<double> a, c;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      a.push_back(rad_to_deg(poses[i].a_rad));
      c.push_back(rad_to_deg(poses[i].c_rad));
    }
    PassRates r{rotary_kinematics_from_times(
                    a, c, move_times_s(op, ball_radius_mm, machine.ac, poses, timing, pass)),
                {}};
    accumulate(r.summary, r.k, c);
    return r;
  };
  std::vector<char> guarded(passes.size(), 0);
  std::vector<PassRates> before(passes.size());
  for (std::size_t q = 0; q < passes.size(); ++q) {
    const IndexRange& pass = passes[q];
    bool input_safe = true;
    for (std::size_t i = pass.begin; i < pass.end; ++i) input_safe = input_safe && !in_hit[i];
    if (!input_safe || pass.size() == 0) continue;
    guarded[q] = 1;
    before[q] = rates(pass, in_plan.poses);
  }
  const std::vector<std::optional<Posed>> opt_preferred = out.preferred;
  // The preferred poses of a candidate: the optimiser's where optimised, the reference's where
  // kept, none on a join.
  const auto preferred_of = [&](const std::vector<KeptWhy>& why) {
    std::vector<std::optional<Posed>> preferred = opt_preferred;
    for (std::size_t i = 0; i < preferred.size() && i < why.size(); ++i) {
      if (why[i] == KeptWhy::Join) preferred[i] = std::nullopt;
      if (why[i] == KeptWhy::Collision || why[i] == KeptWhy::PeakRate) {
        preferred[i] = in_preferred.empty() ? std::nullopt : in_preferred[i];
      }
    }
    return preferred;
  };
  const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                         const std::vector<KeptWhy>& why,
                                         const std::vector<char>& check) {
    StretchVerdicts out_verdicts{std::vector<PointVerdict>(n, PointVerdict::Good),
                                 std::vector<char>(passes.size(), 0)};
    std::vector<PointVerdict>& verdict = out_verdicts.points;
    const PosePlan plan =
        plan_poses(machine.ac, axes, rapid_into, {}, pose_options, preferred_of(why));
    if (!plan.ok()) {
      for (std::size_t i = 0; i < n; ++i) {
        if (check[i]) verdict[i] = PointVerdict::Hits;
      }
      return out_verdicts;
    }
    const std::vector<char> hit = moves_hit(axes, plan.poses, check);
    for (std::size_t q = 0; q < passes.size(); ++q) {
      const IndexRange& pass = passes[q];
      if (pass.size() == 0 || !check[pass.begin]) continue;
      const PassRates after = rates(pass, plan.poses);
      const RotaryKinematics& k = after.k;
      // omega_j belongs to the segment j -> j + 1, a_j to the points j - 1, j, j + 1.
      const auto raises = [&](std::size_t lo, std::size_t hi) {
        for (std::size_t j = lo; j <= hi && j < pass.size(); ++j) {
          if (verdict[pass.begin + j] == PointVerdict::Good)
            verdict[pass.begin + j] = PointVerdict::RaisesRate;
        }
      };
      constexpr double kRel = 1.0 + 1e-9;
      const bool rates_count = !reference || reference->rates;
      for (std::size_t j = 0; rates_count && j < pass.size(); ++j) {
        if (!reference && k.omega_deg_s[j] > before[q].summary.max_omega_deg_s * kRel) {
          raises(j, j + 1);
        }
        if (k.accel_deg_s2[j] > before[q].summary.max_accel_deg_s2 * kRel) {
          raises(j ? j - 1 : 0, j + 1);
        }
      }
      for (std::size_t i = pass.begin; i < pass.end; ++i) {
        if (hit[i]) verdict[i] = PointVerdict::Hits;
      }
      out_verdicts.gains[q] =
          !rates_count ||
          after.summary.max_accel_deg_s2 * kRel < before[q].summary.max_accel_deg_s2 ||
          after.mean_sq_accel() * kRel < before[q].mean_sq_accel();
    }
    return out_verdicts;
  };
  StretchGuardResult guard = guard_stretches(passes, guarded, out.axes, in_axes, evaluate);
  out.axes = guard.axes;
  if (!out.preferred.empty()) out.preferred = preferred_of(guard.why);
  return guard;
}

/// What --objective time adds to an operation's passes: the least time of the move into every
/// point (its programmed feed), the machine's limits, and whole-operation pose sequences each
/// pass weighs beside the paper's (the sum-squares plan, the input's).
struct TimeContext {
  std::vector<double> programmed_s;
  JointLimits limits{};
  std::vector<std::vector<Posed>> alternatives;
};

/// --method global (global_optimiser.hpp) on every feed pass of `op`, from the paper's axes in
/// `out` (the warm start), in parallel over passes. The points between passes then follow the
/// new pass ends; a guard gives a pass back the paper's axes (or `reference`'s) where its peak
/// a would rise or its moves would hit the part. With `time` (--objective time) the passes get
/// their joints, programmed times and alternatives from it.
void refine_global(const Operationd& op, const std::vector<ContactPoint>& contacts,
                   double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                   const Machine& machine, const BlockTiming& timing,
                   const PosePlanOptions& pose_options, const GlobalOptions& options,
                   OptimisedOperation& out, detail::StageProgress& progress,
                   const TimeContext* time = nullptr, const GuardReference* reference = nullptr) {
  const std::size_t n = op.points.size();
  const std::vector<IndexRange> passes = feed_passes(op);
  const PosePlan warm = plan_poses(machine.ac, out.axes, rapid_into_of(op), {}, pose_options);
  if (!warm.ok()) {
    for (std::size_t q = 0; q < passes.size(); ++q) progress.advance();
    return;
  }
  const GuardReference paper{out.axes, {}};
  const Acceptance acceptable_at{
      op, contacts, ball_radius_mm, model, tool, machine.ac, deg_to_rad(options.max_deviation_deg)};
  // Each pass's cut: from the first to the last contact of the pass (all of it without a part).
  // The points in the air before and after keep the axis of the nearest contact, as with the
  // paper method: the tool comes down and leaves along the axis it cuts with.
  const auto plan_pass = [&](std::size_t, const IndexRange& whole) -> std::optional<PassAxes> {
    const IndexRange pass = contact_span(contacts, whole);
    if (pass.size() < 3) return std::nullopt;
    GlobalPassProblem problem;
    std::vector<double> a_deg, c_deg;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      problem.input_axes.push_back(op.points[i].axis);
      problem.warm_start.push_back(warm.poses[i]);
      a_deg.push_back(rad_to_deg(warm.poses[i].a_rad));
      c_deg.push_back(rad_to_deg(warm.poses[i].c_rad));
    }
    // The program's own timing with the warm start's tips (move_times_s: the report's and the
    // guard's); a move too short to time gets a floor (it would divide).
    problem.segment_time_s = move_times_s(op, ball_radius_mm, machine.ac, warm.poses, timing, pass);
    for (double& t : problem.segment_time_s) t = std::max(t, 1e-6);
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at.in_cone(pass.begin + j, axis);
    };
    if (time) {
      // The machine's joints of a pose (the schedule's, whatever the G-code mode): the tip
      // under the fixed ball centre, carried by the table.
      problem.joints_at = [&op, &machine, ball_radius_mm, b = pass.begin](std::size_t j,
                                                                          const Posed& pose) {
        const Vec3d tip = tip_for_axis(op.points[b + j], ball_radius_mm, machine.ac.forward(pose));
        const Vec3d xyz = machine.ac.to_machine_mm(tip, pose);
        return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.a_rad),
                             rad_to_deg(pose.c_rad)};
      };
      problem.programmed_time_s = slice(time->programmed_s, pass.begin + 1, pass.end);
      problem.limits = time->limits;
      for (const std::vector<Posed>& alt : time->alternatives) {
        std::vector<Posed> poses = slice(alt, pass.begin, pass.end);
        bool ok = true;
        for (std::size_t j = 0; ok && j < poses.size(); ++j) {
          ok = machine.ac.a.contains(poses[j].a_rad) && acceptable(j, machine.ac.forward(poses[j]));
        }
        if (ok) problem.alternatives.push_back(std::move(poses));
      }
    }
    std::optional<GlobalPassPlan> plan = plan_pass_global(machine.ac, problem, acceptable, options);
    if (!plan) return std::nullopt;
    return PassAxes{pass, std::move(plan->axes), std::move(plan->poses)};
  };
  out.preferred.assign(n, std::nullopt);
  plan_passes(op, contacts, acceptable_at, out, progress, plan_pass,
              [&](std::size_t, const PassAxes&) { ++out.global_passes; });
  out.global_guard = guard_passes(op, contacts, ball_radius_mm, model, tool, machine, timing,
                                  pose_options, out, reference ? reference : &paper);
}

}  // namespace

/// The turn of the rotary axes between two passes (made in one move by carry_between_passes)
/// spread over the rapids of the chain in the air (air_turn.hpp), where that makes the chain
/// faster and every new pose and move is acceptable: within the cone of its point's input
/// axis, within the machine's ranges and, with a part, free (points and swept moves). The ball
/// centres stay where the CAM system put them.
void spread_turns_in_air(const Operationd& op, const std::vector<ContactPoint>& contacts,
                         double ball_radius_mm, const PartCheck* model, const ToolModel& tool,
                         const Machine& machine, double max_deviation_rad, PostedOperation& po) {
  const std::size_t n = op.points.size();
  if (n < 3 || po.poses.size() != n) return;
  const JointLimits limits = effective_limits(machine);
  // The point as the machine's joints reach it (what the schedule times: in TCP mode too the
  // linear joints follow the turning table), and as the G-code writes it.
  const auto tip_at = [&](std::size_t i, const Posed& pose) {
    return tip_for_axis(op.points[i], ball_radius_mm, machine.ac.forward(pose));
  };
  const auto joints_at = [&](std::size_t i, const Posed& pose) {
    const Vec3d xyz = machine.ac.to_machine_mm(tip_at(i, pose), pose);
    return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.a_rad), rad_to_deg(pose.c_rad)};
  };
  // A chain's time: its rapids on their trapezoids, its feed moves at their feed.
  // `chain[k]` is the pose of point a - 1 + k (k = 0 .. b - a + 1).
  const auto chain_time = [&](std::size_t a, std::size_t b, const std::vector<Posed>& chain) {
    double t = 0.0;
    for (std::size_t j = a; j <= b; ++j) {
      const JointPosition from = joints_at(j - 1, chain[j - a]),
                          to = joints_at(j, chain[j - a + 1]);
      if (op.points[j].motion == Motion::Rapid) {
        t += rapid_time_s(from, to, limits);
      } else if (po.points[j].feed_mm_per_min > 0.0) {
        t += 60.0 * Vec3d(to[0] - from[0], to[1] - from[1], to[2] - from[2]).norm() /
             po.points[j].feed_mm_per_min;
      }
    }
    return t;
  };
  std::vector<char> in_pass(n, 0);
  for (const IndexRange& pass : feed_passes(op)) {
    std::fill(in_pass.begin() + static_cast<long>(pass.begin),
              in_pass.begin() + static_cast<long>(pass.end), 1);
  }
  std::vector<Posed> trial = po.poses;
  std::vector<std::pair<std::size_t, std::size_t>> changed;  // chains [a, b) taken
  for (std::size_t a = 1; a < n;) {
    if (in_pass[a]) {
      ++a;
      continue;
    }
    std::size_t b = a;
    while (b < n && !in_pass[b]) ++b;
    const std::size_t first = a;
    a = b;
    if (b == n) break;  // after the last pass: nothing to turn to
    // Moves first .. b; the turn from the pose before the chain to the pose after it. Only
    // chains whose turn is made by rapids now (a feed move in the air keeps its axis).
    const Posed from = po.poses[first - 1], to = po.poses[b];
    bool rapid_turn = true;
    std::vector<double> linear_s, now;  // per move: its time without the turn, its share now
    std::vector<bool> rapid;
    const double turn_rad = std::abs(to.a_rad - from.a_rad) + std::abs(to.c_rad - from.c_rad);
    for (std::size_t j = first; j <= b; ++j) {
      const double turned = std::abs(po.poses[j].a_rad - po.poses[j - 1].a_rad) +
                            std::abs(po.poses[j].c_rad - po.poses[j - 1].c_rad);
      rapid.push_back(op.points[j].motion == Motion::Rapid);
      if (turned > 1e-12 && !rapid.back()) rapid_turn = false;
      now.push_back(turn_rad > 0.0 ? turned / turn_rad : 0.0);
      JointPosition p = joints_at(j - 1, po.poses[j - 1]), q = joints_at(j, po.poses[j]);
      q[3] = p[3];
      q[4] = p[4];
      linear_s.push_back(rapid.back() ? rapid_time_s(p, q, limits) : 0.0);
    }
    if (!rapid_turn || turn_rad < 1e-9) continue;
    // The chain's poses for per-move shares of the turn, and their time.
    const std::vector<Posed> current(po.poses.begin() + static_cast<long>(first - 1),
                                     po.poses.begin() + static_cast<long>(b + 1));
    const auto poses_for = [&](const std::vector<double>& share) {
      std::vector<Posed> cand = current;
      double f = 0.0;
      for (std::size_t j = first; j < b; ++j) {
        f += share[j - first];
        cand[j - first + 1] = Posed{from.a_rad + f * (to.a_rad - from.a_rad),
                                    from.c_rad + f * (to.c_rad - from.c_rad)};
      }
      return cand;
    };
    std::vector<std::vector<double>> starts = {now};
    const std::vector<double> by_capacity =
        spread_turn(linear_s, rapid, rad_to_deg(to.a_rad - from.a_rad),
                    rad_to_deg(to.c_rad - from.c_rad), limits);
    if (!by_capacity.empty()) starts.push_back(by_capacity);
    const std::vector<double> share = best_turn_shares(
        starts, rapid,
        [&](const std::vector<double>& sh) { return chain_time(first, b, poses_for(sh)); });
    const std::vector<Posed> cand = poses_for(share);
    bool ok = true;
    for (std::size_t j = first; j < b && ok; ++j) {
      const Posed& pose = cand[j - first + 1];
      ok =
          angle_between(machine.ac.forward(pose), op.points[j].axis) <= max_deviation_rad + 1e-12 &&
          machine.ac.a.contains(pose.a_rad) &&
          (machine.ac.c.continuous || machine.ac.c.contains(pose.c_rad));
    }
    if (!ok || chain_time(first, b, cand) >= chain_time(first, b, current) - 1e-6) continue;
    std::copy(cand.begin() + 1, cand.end() - 1, trial.begin() + static_cast<long>(first));
    changed.emplace_back(first, b);
  }
  if (changed.empty()) return;
  // The new poses and the moves into and out of them must be free; a chain with any hit keeps
  // its turn where it was.
  if (model) {
    std::vector<char> check_point(n, 0), check_move(n, 0);
    for (const auto& [first, b] : changed) {
      std::fill(check_point.begin() + static_cast<long>(first),
                check_point.begin() + static_cast<long>(b), 1);
      std::fill(check_move.begin() + static_cast<long>(first),
                check_move.begin() + static_cast<long>(b) + 1, 1);
    }
    std::vector<Vec3d> axes, xyz;
    std::vector<double> a_deg, c_deg;
    for (std::size_t i = 0; i < n; ++i) {
      axes.push_back(machine.ac.forward(trial[i]));
      const Vec3d tip = tip_at(i, trial[i]);
      xyz.push_back(written_xyz_mm(machine, tip, trial[i]));
      a_deg.push_back(rad_to_deg(trial[i].a_rad));
      c_deg.push_back(rad_to_deg(trial[i].c_rad));
    }
    std::vector<ContactPoint> air(n);  // no contacts known: every point in the air
    const std::vector<ContactPoint>& state = contacts.empty() ? air : contacts;
    std::vector<char> hit(n, 0);
    for (std::size_t i : colliding_points(*model, tool, op, axes, state, nullptr, &check_point)) {
      hit[i] = 1;
    }
    for (std::size_t i : colliding_moves(*model, tool, machine, xyz, a_deg, c_deg, state, nullptr,
                                         nullptr, &check_move)) {
      hit[i] = 1;
    }
    for (const auto& [first, b] : changed) {
      if (std::any_of(hit.begin() + static_cast<long>(first),
                      hit.begin() + static_cast<long>(b) + 1, [](char h) { return h != 0; })) {
        std::copy(po.poses.begin() + static_cast<long>(first),
                  po.poses.begin() + static_cast<long>(b),
                  trial.begin() + static_cast<long>(first));
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (trial[i].a_rad == po.poses[i].a_rad && trial[i].c_rad == po.poses[i].c_rad) continue;
    po.points[i].axis = machine.ac.forward(trial[i]);
    po.points[i].tip_mm = tip_for_axis(op.points[i], ball_radius_mm, po.points[i].axis);
  }
  po.poses = std::move(trial);
}

namespace {

/// An operation's scheduled cycle (feed moves and rapids at the machine's effective limits)
/// with tool axes `axes` about the fixed ball centres, posed as run_job poses them (the turns
/// between passes in one move); `programmed_s` the least time of every move. Infinite when the
/// axes cannot be posed.
double operation_cycle_s(const Operationd& op, const std::vector<ContactPoint>& contacts,
                         double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                         const Machine& machine, double max_deviation_rad,
                         const std::vector<Vec3d>& axes,
                         const std::vector<std::optional<Posed>>& preferred,
                         const PosePlanOptions& pose_options, double fallback_feed,
                         const std::vector<double>& programmed_s) {
  const PosePlan plan =
      plan_poses(machine.ac, axes, rapid_into_of(op), {}, pose_options, preferred);
  if (!plan.ok()) return std::numeric_limits<double>::infinity();
  PostedOperation po;
  po.points = posted_feeds(op, fallback_feed);
  po.poses = plan.poses;
  for (std::size_t i = 0; i < po.points.size(); ++i) {
    po.points[i].axis = axes[i];
    po.points[i].tip_mm = tip_for_axis(op.points[i], ball_radius_mm, axes[i]);
  }
  spread_turns_in_air(op, contacts, ball_radius_mm, model, tool ? *tool : ToolModel{}, machine,
                      max_deviation_rad, po);
  std::vector<Vec3d> tips;
  for (const CLPointd& p : po.points) tips.push_back(p.tip_mm);
  std::vector<double> programmed = programmed_block_times_s(po.points, po.poses);
  if (machine.gcode.feed_reference == FeedReference::CutterPath) {
    // The input block's time, within the feed ratio (as posted: kept_block_times_s).
    programmed = kept_block_times_s(programmed_s, programmed, machine.gcode.max_feed_ratio);
  }
  return schedule_operation(po.points, joints_of(machine.ac, tips, po.poses), programmed,
                            effective_limits(machine), machine.ac, nullptr,
                            machine.gcode.mode == GcodeMode::Tcp ? &po.poses : nullptr)
      .summary.cycle_time_s;
}

/// --method global --objective time (docs/global-method.md): the sum-squares plan first (a
/// start and an alternative every pass weighs, and the reference of the guard, which gives it
/// back over stretches whose moves hit), then every pass planned for its scheduled time; of
/// the paper's, the sum-squares and the time plan the operation keeps the one with the
/// shortest scheduled cycle (ties to the sum-squares plan, then the paper's). `out` holds the
/// paper's plan on entry. The input's axes are kept instead where their cycle is shorter still
/// and none of their points or moves hits the part. Returns a line for the log.
std::string refine_time(const Operationd& op, const std::vector<ContactPoint>& contacts,
                        double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                        const Machine& machine, const BlockTiming& timing,
                        const PosePlanOptions& pose_options, const GlobalOptions& options,
                        double fallback_feed, OptimisedOperation& out,
                        detail::StageProgress& progress) {
  const OptimisedOperation paper = out;
  // Two sum-squares plans: the coarse programme's (the time plan's start and guard reference:
  // off the pyramid's, the time plan's schedule came out longer on three of the eighteen cases
  // of docs/results.md, up to +14 %) and the pyramid's (--method global's own plan, so the time
  // objective is never slower than it).
  OptimisedOperation smooth = out, fine = out;
  GlobalOptions sum_squares = options;
  sum_squares.objective = GlobalObjective::SumSquares;
  sum_squares.fine_step_deg = 0.0;
  refine_global(op, contacts, ball_radius_mm, model, tool, machine, timing, pose_options,
                sum_squares, smooth, progress);
  const bool pyramid = options.fine_step_deg > 0.0;
  if (pyramid) {
    sum_squares.fine_step_deg = options.fine_step_deg;
    refine_global(op, contacts, ball_radius_mm, model, tool, machine, timing, pose_options,
                  sum_squares, fine, progress);
  }
  const std::vector<bool> rapid_into = rapid_into_of(op);
  std::vector<Vec3d> in_axes;
  for (const CLPointd& p : op.points) in_axes.push_back(p.axis);
  const PosePlan in_plan = plan_poses(machine.ac, in_axes, rapid_into, {}, pose_options);
  const PosePlan smooth_plan =
      plan_poses(machine.ac, smooth.axes, rapid_into, {}, pose_options, smooth.preferred);
  TimeContext time;
  time.limits = effective_limits(machine);
  // Every feed block keeps the time the input block takes at its feed (cutter-path), as
  // posted; with the tip-path reference that time moves with the tip (the input's here).
  time.programmed_s = programmed_block_times_s(posted_feeds(op, fallback_feed),
                                               in_plan.ok() ? in_plan.poses : smooth_plan.poses);
  if (smooth_plan.ok()) time.alternatives.push_back(smooth_plan.poses);
  if (in_plan.ok()) time.alternatives.push_back(in_plan.poses);
  OptimisedOperation fast = out;
  const GuardReference reference{smooth.axes, smooth.preferred, false};
  refine_global(op, contacts, ball_radius_mm, model, tool, machine, timing, pose_options, options,
                fast, progress, &time, &reference);
  const auto cycle = [&](const OptimisedOperation& o) {
    return operation_cycle_s(op, contacts, ball_radius_mm, model, tool, machine,
                             deg_to_rad(options.max_deviation_deg), o.axes, o.preferred,
                             pose_options, fallback_feed, time.programmed_s);
  };
  const double paper_s = cycle(paper), smooth_s = cycle(smooth), fast_s = cycle(fast);
  const double fine_s = pyramid ? cycle(fine) : std::numeric_limits<double>::infinity();
  // The input's axes count where every point and move of theirs is free.
  double input_s = in_plan.ok()
                       ? operation_cycle_s(op, contacts, ball_radius_mm, model, tool, machine,
                                           deg_to_rad(options.max_deviation_deg), in_axes, {},
                                           pose_options, fallback_feed, time.programmed_s)
                       : std::numeric_limits<double>::infinity();
  OptimisedOperation input = paper;
  input.axes = in_axes;
  input.preferred.clear();
  if (std::isfinite(input_s)) {
    Machine path_machine = machine;
    if (machine.gcode.program.linearise_tolerance_mm > 0.0) {
      path_machine.gcode.mode = GcodeMode::Tcp;
    }
    const std::vector<char> hit =
        points_and_moves_hit(op, contacts, ball_radius_mm, model, tool, path_machine, in_axes,
                             in_plan.poses, std::vector<char>(op.points.size(), 1));
    if (std::find(hit.begin(), hit.end(), 1) != hit.end()) {
      input_s = std::numeric_limits<double>::infinity();
    }
  }
  // The peak a of a plan's passes, each move timed as the controller takes it from the words
  // (move_times_s), as the report measures it.
  const auto peak_a = [&](const OptimisedOperation& o) {
    const PosePlan pp = plan_poses(machine.ac, o.axes, rapid_into, {}, pose_options, o.preferred);
    if (!pp.ok()) return std::numeric_limits<double>::infinity();
    std::vector<double> a, c;
    for (const Posed& q : pp.poses) {
      a.push_back(rad_to_deg(q.a_rad));
      c.push_back(rad_to_deg(q.c_rad));
    }
    std::vector<double> into = {0.0};
    for (double t : move_times_s(op, ball_radius_mm, machine.ac, pp.poses, timing,
                                 IndexRange{0, op.points.size()})) {
      into.push_back(t);
    }
    return summarise_timed(op, a, c, into).max_accel_deg_s2;
  };
  struct Plan {
    const char* name;
    const OptimisedOperation* plan;
    double cycle_s, peak_a;
  };
  std::vector<Plan> plans = {{"sum-squares", &smooth, smooth_s, 0.0},
                             {"sum-squares-fine", &fine, fine_s, 0.0},
                             {"paper", &paper, paper_s, 0.0},
                             {"time", &fast, fast_s, 0.0},
                             {"input", &input, input_s, 0.0}};
  double shortest = std::numeric_limits<double>::infinity();
  for (const Plan& p : plans) shortest = std::min(shortest, p.cycle_s);
  // Within the tie band of the shortest cycle, the smoothest plan wins (then the shorter, then
  // the earlier in the list: deterministic).
  const Plan* best = nullptr;
  const Plan* fastest = nullptr;
  for (Plan& p : plans) {
    if (!std::isfinite(p.cycle_s)) continue;
    if (!fastest || p.cycle_s < fastest->cycle_s * (1.0 - 1e-9)) fastest = &p;
    if (p.cycle_s > shortest * (1.0 + options.time_tie_band)) continue;
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
      chosen, fastest_name, best_s, best_peak, fastest_s, fastest_peak, options.time_tie_band};
  char line[640];
  std::snprintf(line, sizeof line,
                "scheduled cycle %.3f s (paper), %.3f s (sum-squares), %.3f s (sum-squares, "
                "fine), %.3f s (time plan), %.3f s (input): %s axes kept (%.3f s, peak a %.1f "
                "deg/s^2; the shortest, %s, %.3f s with peak a %.1f: within the %.1f %% tie band "
                "the smoother wins)",
                paper_s, smooth_s, fine_s, fast_s, input_s, chosen.c_str(), best_s, best_peak,
                fastest_name.c_str(), fastest_s, fastest_peak, 100.0 * options.time_tie_band);
  return line;
}

}  // namespace

namespace {

/// The method's axes for one ball-end operation, and the findings of its guards.
void plan_operation(const Run& run, OperationContext& o, detail::StageProgress& progress,
                    JobResult& res) {
  const JobOptions& options = run.options;
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const double R = o.ball_radius_mm;
  const PartCheck* check = run.planner_check();
  const ToolModel* tool = o.judged_tool();
  const auto t0 = Clock::now();
  // The written program's timing (the guard's, the global objective's, the report's).
  const BlockTiming timing =
      block_timing(op, run.machine, options.pose_options, o.metric_feed_mm_per_min);
  o.optimised =
      optimise_paper(op, o.contacts, R, check, tool, run.machine, o.metric_feed_mm_per_min,
                     options.pose_options, options.paper, progress);
  OptimisedOperation& out = *o.optimised;
  out.guard =
      guard_passes(op, o.contacts, R, check, tool, run.machine, timing, options.pose_options, out);
  std::string time_line;
  GlobalOptions global = options.global;
  global.max_deviation_deg = options.paper.max_deviation_deg;
  global.candidate_step_deg =
      std::max(global.candidate_step_deg, options.paper.max_deviation_deg / 2.0);
  // The pyramid down to the C-space cell size (refine_time uses it for one of its plans).
  global.fine_step_deg = options.paper.grid_deg;
  if (options.method == Method::Global) {
    if (global.objective == GlobalObjective::Time) {
      time_line =
          refine_time(op, o.contacts, R, check, tool, run.machine, timing, options.pose_options,
                      global, run.fallback_feed_mm_per_min, out, progress);
    } else {
      refine_global(op, o.contacts, R, check, tool, run.machine, timing, options.pose_options,
                    global, out, progress);
    }
  }
  if (options.method == Method::Paper && run.collision && tool && run.paper_fallback.count(k)) {
    // The verification refused the paper's plan of this operation in a first run (run_job):
    // the global method's plan of the operation where that is free as the verification judges
    // it (FCL, the same grown bodies, every point and every move as the machine runs it), else
    // the input's axes over the stretches that hit (where those are free). The verification
    // stays the judge of what is written.
    const std::size_t n = op.points.size();
    Machine path_machine = run.machine;
    if (path_machine.gcode.program.linearise_tolerance_mm > 0.0) {
      path_machine.gcode.mode = GcodeMode::Tcp;
    }
    const auto hits = [&](const OptimisedOperation& plan) -> std::size_t {
      const PosePlan pp = plan_poses(run.machine.ac, plan.axes, rapid_into_of(op), {},
                                     options.pose_options, plan.preferred);
      if (!pp.ok()) return 0;  // unposable axes are the verification's to report
      const std::vector<char> hit =
          points_and_moves_hit(op, o.contacts, R, &*run.collision, tool, path_machine, plan.axes,
                               pp.poses, std::vector<char>(n, 1));
      return static_cast<std::size_t>(std::count(hit.begin(), hit.end(), 1));
    };
    {
      const std::size_t paper_hits = hits(out);
      OptimisedOperation alt = out;
      refine_global(op, o.contacts, R, check, tool, run.machine, timing, options.pose_options,
                    global, alt, progress);
      std::string how;
      if (hits(alt) == 0) {
        out = std::move(alt);
        how = "the global method's plan is used for this operation";
      } else {
        const StretchGuardResult g = guard_passes(op, o.contacts, R, &*run.collision, tool,
                                                  run.machine, timing, options.pose_options, out);
        out.guard.points_hit += g.points_hit;
        out.guard.stretches += g.stretches;
        out.guard.whole_passes += g.whole_passes;
        how =
            "neither the global method's plan is free: the input's axes are kept where they "
            "hit, where those are free";
      }
      add_finding(res, FindingCode::InputAxesKept, k, 0,
                  "operation " + op.name +
                      ": the verification refused the paper method's plan (the tool hit the "
                      "part at " +
                      std::to_string(paper_hits) + " points or moves as it judges them); " + how);
    }
  }
  if (const StretchGuardResult& g = out.guard; g.whole_passes + g.stretches > 0) {
    add_finding(res, FindingCode::InputAxesKept, k, 0,
                "operation " + op.name + ": " + std::to_string(g.points_hit + g.points_rate) +
                    " points keep their input axes (" + std::to_string(g.whole_passes) +
                    " whole passes, " + std::to_string(g.stretches) +
                    " stretches within passes, joined over " + std::to_string(g.points_blended) +
                    " points): there the optimised axes " +
                    (g.points_hit ? "swept the tool through the part between points" : "") +
                    (g.points_hit && g.points_rate ? " or " : "") +
                    (g.points_rate ? "raised the pass's peak omega or a" : ""));
  }
  for (std::size_t i : out.no_free_axis) {
    add_finding(res, FindingCode::NoFreeAxis, k, op.points[i].line,
                format_location(run.tp.source, op.points[i].line,
                                "operation " + op.name + ": no tool axis within " +
                                    std::to_string(options.paper.max_deviation_deg) +
                                    " deg of the input axis is reachable and collision-free here"));
  }
  o.optimise_s = seconds_since(t0);
  if (options.log) {
    options.log(
        "operation " + op.name + ": " + std::to_string(out.intervals) + " intervals, " +
        std::to_string(out.repairs) + " repair keys, " + std::to_string(out.smoothed_joints) +
        " joints smoothed, " + std::to_string(out.sharp_joints) + " left sharp, " +
        std::to_string(out.pole_stretches) + " pole passages re-planned" +
        (options.method == Method::Global
             ? "; global: " + std::to_string(out.global_passes) + " passes refined, " +
                   std::to_string(out.global_guard.whole_passes) + " kept the paper's axes, " +
                   std::to_string(out.global_guard.stretches) + " stretches kept them"
             : std::string()) +
        (time_line.empty() ? std::string() : "; time: " + time_line));
  }
}

}  // namespace

void plan_operations(const Run& run, std::vector<OperationContext>& ops, JobResult& res) {
  const JobOptions& options = run.options;
  if (options.method == Method::None) return;
  std::size_t all_passes = 0;
  for (const OperationContext& o : ops) all_passes += feed_passes(*o.op).size();
  detail::StageProgress progress(
      options.progress, "optimisation",
      all_passes * (options.method != Method::Global                    ? 1
                    : options.global.objective == GlobalObjective::Time ? 3
                                                                        : 2),
      options.stop);
  for (OperationContext& o : ops) {
    const Operationd& op = *o.op;
    if (!(o.ball_radius_mm > 0.0)) {
      add_finding(res, FindingCode::NotABallMill, o.index,
                  op.points.empty() ? 0 : op.points.front().line,
                  not_a_ball(op) + ", the input tool axes are kept");
      continue;
    }
    if (options.part && !o.contact.recovered) continue;
    plan_operation(run, o, progress, res);
  }
}

}  // namespace taxopt::pipeline
