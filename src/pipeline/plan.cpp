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
        in_{op_,          o_.contacts, o.ball_radius_mm,     run.planner_check(), o.judged_tool(),
            run_.machine, timing_,     options_.pose_options} {}

  void run() {
    const auto t0 = Clock::now();
    o_.optimised = optimise_paper(in_, o_.metric_feed_mm_per_min, options_.paper, progress_);
    OptimisedOperation& out = *o_.optimised;
    out.guard = guard_passes(in_, out);
    std::string time_line;
    if (options_.method == Method::Global) {
      if (global_.objective == GlobalObjective::Time) {
        time_line = refine_time(in_, global_, run_.fallback_feed_mm_per_min, out, progress_);
      } else {
        refine_global(out);
      }
    }
    if (options_.method == Method::Paper && run_.collision && in_.tool &&
        run_.paper_fallback.count(k_)) {
      replan_refused(out);
    }
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

  void refine_global(OptimisedOperation& plan) {
    pipeline::refine_global(in_, global_, plan, progress_);
  }

  /// Points and moves of `plan` that hit as the verification judges them (FCL, the same grown
  /// bodies, every point and every move as the machine runs it).
  std::size_t hits(const OptimisedOperation& plan) const {
    const PosePlan pp = plan_poses(run_.machine.rotary, plan.axes, rapid_into_of(op_), {},
                                   options_.pose_options, plan.preferred);
    if (!pp.ok()) return 0;  // unposable axes are the verification's to report
    const std::vector<char> hit =
        points_and_moves_hit(in_.judged_by(&*run_.collision), plan.axes, pp.poses,
                             std::vector<char>(op_.points.size(), 1));
    return static_cast<std::size_t>(std::count(hit.begin(), hit.end(), 1));
  }

  /// The verification refused the paper's plan of this operation in a first run (run_job):
  /// the global method's plan of the operation where that is free as the verification judges
  /// it, else the input's axes over the stretches that hit (where those are free). The
  /// verification stays the judge of what is written.
  void replan_refused(OptimisedOperation& out) {
    const std::size_t paper_hits = hits(out);
    OptimisedOperation alt = out;
    refine_global(alt);
    std::string how;
    if (hits(alt) == 0) {
      out = std::move(alt);
      how = "the global method's plan is used for this operation";
    } else {
      const StretchGuardResult g = guard_passes(in_.judged_by(&*run_.collision), out);
      out.guard.points_hit += g.points_hit;
      out.guard.stretches += g.stretches;
      out.guard.whole_passes += g.whole_passes;
      how =
          "neither the global method's plan is free: the input's axes are kept where they "
          "hit, where those are free";
    }
    add_finding(res_, FindingCode::InputAxesKept, k_, 0,
                "operation " + op_.name +
                    ": the verification refused the paper method's plan (the tool hit the "
                    "part at " +
                    std::to_string(paper_hits) + " points or moves as it judges them); " + how);
  }

  /// The guard's kept stretches, and the points no free axis reaches.
  void findings(const OptimisedOperation& out) {
    if (const StretchGuardResult& g = out.guard; g.whole_passes + g.stretches > 0) {
      add_finding(res_, FindingCode::InputAxesKept, k_, 0,
                  "operation " + op_.name + ": " + std::to_string(g.points_hit + g.points_rate) +
                      " points keep their input axes (" + std::to_string(g.whole_passes) +
                      " whole passes, " + std::to_string(g.stretches) +
                      " stretches within passes, joined over " + std::to_string(g.points_blended) +
                      " points): there the optimised axes " +
                      (g.points_hit ? "swept the tool through the part between points" : "") +
                      (g.points_hit && g.points_rate ? " or " : "") +
                      (g.points_rate ? "raised the pass's peak omega or a" : ""));
    }
    for (std::size_t i : out.no_free_axis) {
      add_finding(
          res_, FindingCode::NoFreeAxis, k_, op_.points[i].line,
          format_location(run_.tp.source, op_.points[i].line,
                          "operation " + op_.name + ": no tool axis within " +
                              std::to_string(options_.paper.max_deviation_deg) +
                              " deg of the input axis is reachable and collision-free here" +
                              out_of_reach(run_.machine.rotary, op_.points[i].axis)));
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
    OperationPlanner(run, o, progress, res).run();
  }
}

}  // namespace taxopt::pipeline
