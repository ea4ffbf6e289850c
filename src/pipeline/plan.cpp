// The plan stage: the method's tool axes per operation (paper's optimiser, global refinement,
// cycle-time objective), the guards after them, and the turns in the air (stages.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

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

/// Where the input axis itself lies outside the machine's rotary ranges, what it needs: the
/// range, not the cone, is then what stops the point (a machine with A in [30, 60] deg said
/// only "no tool axis within 1 deg").
std::string out_of_reach(const MachineKinematicsd& ac, const Vec3d& axis) {
  if (ac.reachable(axis)) return "";
  const auto poses = ac.inverse(axis);
  std::ostringstream os;
  os << "; the input axis itself is out of the machine's reach: it needs " << ac.tilt_letter()
     << " " << rad_to_deg(poses[0].tilt_rad) << " or " << rad_to_deg(poses[1].tilt_rad) << " deg";
  if (!ac.tilt.continuous) {
    os << ", and " << ac.tilt_letter() << " runs over [" << rad_to_deg(ac.tilt.min_rad) << ", "
       << rad_to_deg(ac.tilt.max_rad) << "] deg";
  }
  if (!ac.c.continuous) {
    os << ", C " << rad_to_deg(poses[0].c_rad) << " or " << rad_to_deg(poses[1].c_rad)
       << " deg within [" << rad_to_deg(ac.c.min_rad) << ", " << rad_to_deg(ac.c.max_rad)
       << "] deg";
  }
  return os.str();
}

/// The default least tilt's ceiling, deg: the effective cutting diameter there is 2 R sin 10 =
/// 0.35 R, well off the ball's dead centre; a larger tilt in the input is the CAM system's
/// choice for reach or clearance (the walls' 15-35 deg lean into the part), which the methods
/// exist to change.
constexpr double kDefaultLeastTiltCapDeg = 10.0;
/// Below this the input itself cuts on the ball's dead centre (2 R sin 1 = 0.035 R): it holds
/// no lead to keep, and by default none is held (the Haas job's outside chamfer, 0.5 deg at its
/// nearest: held, it cost the time objective its C a 110.7 -> 37.9).
constexpr double kDefaultLeastTiltFloorDeg = 1.0;

/// The operation's least tilt (OperationContext::least_tilt_deg) and each point's bound: the
/// lesser of it and the input's own angle there, on the touching feed points. Held by every
/// method at every written point (--min-tilt 0: none); a move between two points may
/// still pass the normal where the axis goes from one side of it to the other (the demo's
/// input hits the part on its lead side, and the free axes are on the other):
/// cutting_conditions counts those moves.
void least_tilt_of(const JobOptions& options, OperationContext& o) {
  const Operationd& op = *o.op;
  const std::size_t n = op.points.size();
  o.least_tilt_rad.assign(n, 0.0);
  o.least_tilt_relaxed.clear();
  if (o.contacts.size() != n) return;
  const auto cutting = [&](std::size_t i) {
    return op.points[i].motion == Motion::Feed && o.contacts[i].state == ContactState::Touching;
  };
  double least_rad = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    if (cutting(i)) least_rad = std::min(least_rad, o.contacts[i].tilt_rad);
  }
  if (!std::isfinite(least_rad)) return;
  o.least_tilt_given = options.min_tilt_deg.has_value();
  // Rounded down to 0.1 deg: the CAM's "5 deg" lead, read back through the mesh's contact
  // normals, is 4.99..; the bound is the lead the programmer set, not its last digit.
  // Capped at kDefaultLeastTiltCapDeg: past it the CAM system tilts for reach or clearance,
  // not for the cutting speed at the contact, and holding its least tilt as a floor would
  // forbid the repairs (leaning away from a wall the input hits).
  o.least_tilt_deg = options.min_tilt_deg.value_or(
      std::min(std::floor(rad_to_deg(least_rad) * 10.0) / 10.0, kDefaultLeastTiltCapDeg));
  o.least_tilt_held =
      o.least_tilt_given ? o.least_tilt_deg > 0.0 : o.least_tilt_deg >= kDefaultLeastTiltFloorDeg;
  if (!o.least_tilt_held) return;
  for (std::size_t i = 0; i < n; ++i) {
    if (cutting(i)) {
      o.least_tilt_rad[i] = std::min(deg_to_rad(o.least_tilt_deg), o.contacts[i].tilt_rad);
    }
  }
}

/// The method's axes for one ball-end operation, and the findings of its guards. The stages:
/// the paper's optimiser and its guard, the global method (cone, pyramid, objective), the
/// plan again after the verification refused the paper's, the findings, the log line.
class OperationPlanner {
 public:
  OperationPlanner(const Run& run, OperationContext& o, detail::StageProgress& progress,
                   JobResult& res)
      : run_(run),
        options_(run.options),
        o_(o),
        op_(*o.op),
        k_(o.index),
        progress_(progress),
        res_(res),
        // The written program's timing (the guard's, the global objective's, the report's).
        timing_(block_timing(op_, run.machine, options_.pose_options, o.metric_feed_mm_per_min)),
        global_(global_options(options_)),
        input_clear_(input_clear_of(run, o)),
        in_{op_,
            o_.contacts,
            o.ball_radius_mm,
            run.planner_check(),
            o.judged_tool(),
            run_.machine,
            timing_,
            options_.pose_options,
            o.strict_tool ? &*o.strict_tool : nullptr,
            &input_clear_,
            &o.least_tilt_rad,
            run.clearance_bounds(),
            &run.options.stop} {}

  void run() {
    const auto t0 = Clock::now();
    const bool refused = run_.collision && in_.tool && run_.refused_operations.count(k_);
    plan_paper(refused);
    OptimisedOperation& out = *o_.optimised;
    hold_least_tilt(out);
    out.guard = guard_passes(in_, out);
    // The guard's joins blend on great circles, which can pass nearer the normal than either
    // end: those points take their input axes, and the guard judges the rates again.
    if (hold_least_tilt(out)) {
      const StretchGuardResult first = out.guard;
      out.guard = guard_passes(in_, out);
      for (std::size_t i = 0; i < first.why.size() && i < out.guard.why.size(); ++i) {
        if (out.guard.why[i] == KeptWhy::None) out.guard.why[i] = first.why[i];
      }
    }
    std::optional<OptimisedOperation> paper;
    if (refused && options_.method == Method::Global) paper = out;
    std::string time_line;
    if (options_.method == Method::Global) {
      if (global_.objective == GlobalObjective::Time) {
        time_line = refine_time(in_, global_, run_.fallback_feed_mm_per_min, out, progress_);
      } else {
        refine_global(out);
      }
    }
    if (refused) replan_refused(out, paper);
    findings(out);
    o_.optimise_s = seconds_since(t0);
    if (options_.log) options_.log(log_line(out, time_line));
  }

 private:
  /// The run's cone for the global method, its candidates no finer than half the cone, its
  /// pyramid down to the C-space cell size (refine_time uses it for one of its plans).
  static GlobalOptions global_options(const JobOptions& options) {
    GlobalOptions global = options.global;
    global.max_deviation_deg = options.paper.max_deviation_deg;
    global.candidate_step_deg =
        std::max(global.candidate_step_deg, options.paper.max_deviation_deg / 2.0);
    global.fine_step_deg = options.paper.grid_deg;
    return global;
  }

  /// Per point: the input axis's flutes clear the part by kInputDepthAllowanceMm (empty
  /// without a part).
  static std::vector<char> input_clear_of(const Run& run, const OperationContext& o) {
    if (!run.planner_check() || !o.strict_tool) return {};
    const Operationd& op = *o.op;
    std::vector<Vec3d> axes;
    for (const CLPointd& p : op.points) axes.push_back(p.axis);
    std::vector<char> clear(op.points.size(), 1);
    detail::StageProgress watch(op.points.size(), run.options.stop);  // the stop looked at
    for (std::size_t i :
         colliding_points(*run.planner_check(), *o.strict_tool, op, axes, o.contacts, &watch)) {
      clear[i] = 0;
    }
    return clear;
  }

  /// The paper's optimiser, with the least tilt given up where it leaves no free axis, and,
  /// where the verification refused the plan (`refused`), over the passes where the plan the
  /// bound shaped hits the part as it judges them: the collision comes first.
  void plan_paper(bool refused) {
    // With a least tilt held the keys settle round the cap after the repair (without them
    // the sine's paper plan kept 0.2 % of its gain at its input's 4.8 deg).
    PaperOptions paper_options = options_.paper;
    if (o_.least_tilt_held) {
      paper_options.resettle_rounds = std::max(paper_options.resettle_rounds, 3);
    }
    o_.optimised = optimise_paper(in_, o_.metric_feed_mm_per_min, paper_options, progress_);
    bool again = relax_least_tilt(o_.optimised->no_free_axis);
    if (refused && o_.least_tilt_held) {
      const std::vector<char> hit = hit_points(*o_.optimised);
      std::vector<std::size_t> in_hit_passes;
      for (const IndexRange& pass : feed_passes(op_)) {
        const auto first = hit.begin() + static_cast<long>(pass.begin);
        if (std::find(first, first + static_cast<long>(pass.size()), 1) ==
            first + static_cast<long>(pass.size())) {
          continue;
        }
        for (std::size_t i = pass.begin; i < pass.end; ++i) in_hit_passes.push_back(i);
      }
      again = relax_least_tilt(in_hit_passes) || again;
    }
    if (again) {
      o_.optimised = optimise_paper(in_, o_.metric_feed_mm_per_min, paper_options, progress_);
    }
  }

  /// Where no free axis within the cone keeps the least tilt (the paper's optimiser found
  /// none), the point gives the bound up (the collision first) and the plan is made again;
  /// the report and a warning name those points (cutting_conditions, findings).
  bool relax_least_tilt(const std::vector<std::size_t>& points) {
    bool relaxed = false;
    for (std::size_t i : points) {
      if (!(o_.least_tilt_rad[i] > 0.0)) continue;
      o_.least_tilt_rad[i] = 0.0;
      o_.least_tilt_relaxed.push_back(i);
      relaxed = true;
    }
    return relaxed;
  }

  /// The paper's optimiser checks its keys and its interpolation, not the axes its joint
  /// smoothing and pole passages move: a point whose axis comes nearer the normal than its
  /// least tilt takes its input axis back before the guard judges the rates of the whole.
  bool hold_least_tilt(OptimisedOperation& out) const {
    bool changed = false;
    for (std::size_t i = 0; i < out.axes.size(); ++i) {
      if (in_.keeps_tilt(i, out.axes[i])) continue;
      out.axes[i] = op_.points[i].axis;
      if (!out.preferred.empty()) out.preferred[i] = std::nullopt;
      changed = true;
    }
    return changed;
  }

  void refine_global(OptimisedOperation& plan) {
    pipeline::refine_global(in_, global_, plan, progress_);
  }

  /// Points and moves of `plan` that hit as the verification judges them (FCL, the same grown
  /// bodies, every point and every move as the machine runs it).
  std::vector<char> hit_points(const OptimisedOperation& plan) const {
    const PosePlan pp = plan_poses(run_.machine.rotary, plan.axes, rapid_into_of(op_), {},
                                   options_.pose_options, plan.preferred);
    // Unposable axes are the verification's to report.
    if (!pp.ok()) return std::vector<char>(op_.points.size(), 0);
    return points_and_moves_hit(in_.judged_by(&*run_.collision, run_.clearance_bounds()), plan.axes,
                                pp.poses, std::vector<char>(op_.points.size(), 1));
  }
  std::size_t hits(const OptimisedOperation& plan) const {
    const std::vector<char> hit = hit_points(plan);
    return static_cast<std::size_t>(std::count(hit.begin(), hit.end(), 1));
  }

  /// The verification refused the method's plan of this operation in a first run (run_job):
  /// the other method's plan where that is free as the verification judges it (the global
  /// method's for the paper's, the paper's — `paper` — for the global method and the time
  /// objective), else the input's axes over the stretches that hit (where those are free). The
  /// verification stays the judge of what is written.
  void replan_refused(OptimisedOperation& out, const std::optional<OptimisedOperation>& paper) {
    const std::size_t method_hits = hits(out);
    // The plan made again without the least tilt where it hit (plan_paper) is free: it stays.
    if (method_hits == 0 && !o_.least_tilt_relaxed.empty()) return;
    OptimisedOperation alt = paper ? *paper : out;
    if (!paper) refine_global(alt);
    const std::string other = paper ? "the paper method's" : "the global method's";
    std::string how;
    if (hits(alt) == 0) {
      out = std::move(alt);
      how = other + " plan is used for this operation";
    } else {
      const StretchGuardResult g =
          guard_passes(in_.judged_by(&*run_.collision, run_.clearance_bounds()), out);
      out.guard.points_hit += g.points_hit;
      out.guard.stretches += g.stretches;
      out.guard.whole_passes += g.whole_passes;
      for (std::size_t i = 0; i < g.why.size() && i < out.guard.why.size(); ++i) {
        if (g.why[i] != KeptWhy::None) out.guard.why[i] = g.why[i];
      }
      how = "nor is " + other +
            " plan free: the input's axes are kept where they hit, where those are free";
    }
    add_finding(res_, FindingCode::InputAxesKept, k_, 0,
                "operation " + op_.name + ": the verification refused the " +
                    to_string(options_.method) + " method's plan (the tool hit the part at " +
                    std::to_string(method_hits) + " points or moves as it judges them); " + how);
  }

  /// The points no free axis reaches (the kept points are counted on the written axes, by
  /// the verification).
  void findings(const OptimisedOperation& out) {
    if (!o_.least_tilt_relaxed.empty()) {
      const std::size_t i =
          *std::min_element(o_.least_tilt_relaxed.begin(), o_.least_tilt_relaxed.end());
      std::ostringstream os;
      os << "operation " << op_.name << ": " << o_.least_tilt_relaxed.size()
         << " points give up the least tilt of " << o_.least_tilt_deg
         << " deg from the surface's normal: no free axis within "
         << options_.paper.max_deviation_deg
         << " deg of the input axis keeps it there, or the plan that kept it hit the part as "
            "the verification judges it (the first is written "
         << rad_to_deg(angle_between(out.axes[i], o_.contacts[i].surface_normal))
         << " deg from the normal); the collision comes first";
      add_finding(res_, FindingCode::LeastTiltNotKept, k_, op_.points[i].line,
                  format_location(run_.tp.source, op_.points[i].line, os.str()));
    }
    for (std::size_t i : out.no_free_axis) {
      add_finding(res_, FindingCode::NoFreeAxis, k_, op_.points[i].line,
                  format_location(run_.tp.source, op_.points[i].line,
                                  "operation " + op_.name + ", point " + std::to_string(i) +
                                      ": no tool axis within " +
                                      std::to_string(options_.paper.max_deviation_deg) +
                                      " deg of the input axis is reachable and collision-free" +
                                      out_of_reach(run_.machine.rotary, op_.points[i].axis) +
                                      msys_remedy(run_, op_.points[i])));
    }
  }

  std::string log_line(const OptimisedOperation& out, const std::string& time_line) const {
    return "operation " + op_.name + ": " + std::to_string(out.intervals) + " intervals, " +
           std::to_string(out.repairs) + " repair keys, " + std::to_string(out.smoothed_joints) +
           " joints smoothed, " + std::to_string(out.sharp_joints) + " left sharp, " +
           std::to_string(out.pole_stretches) + " pole passages re-planned" +
           (options_.method == Method::Global
                ? "; global: " + std::to_string(out.global_passes) + " passes refined, " +
                      std::to_string(out.global_guard.whole_passes) + " kept the paper's axes, " +
                      std::to_string(out.global_guard.stretches) + " stretches kept them"
                : std::string()) +
           (time_line.empty() ? std::string() : "; time: " + time_line);
  }

  const Run& run_;
  const JobOptions& options_;
  OperationContext& o_;
  const Operationd& op_;
  const std::size_t k_;
  detail::StageProgress& progress_;
  JobResult& res_;
  const BlockTiming timing_;
  const GlobalOptions global_;
  const std::vector<char> input_clear_;
  /// What every planner of the operation takes (the ball, the judged tool), judged by the
  /// planner's check.
  const OperationPlanInputs in_;
};

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
                  not_a_ball(op, run.options) + ", the input tool axes are kept");
      continue;
    }
    if (options.part && !o.contact.recovered) continue;
    least_tilt_of(options, o);
    OperationPlanner(run, o, progress, res).run();
  }
}

}  // namespace taxopt::pipeline
