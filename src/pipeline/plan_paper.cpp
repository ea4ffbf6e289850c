// The paper's optimiser over an operation's passes, the points between passes carried
// (plan_rooms.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/plan_rooms.hpp"
#include "pipeline/stages.hpp"
#include "plan/air_turn.hpp"
#include "plan/paper_single.hpp"
#include "plan/pole_passage.hpp"
#include "plan/stretch_guard.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {

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

namespace {

/// The worst axis's share of its limit of the peak a of `axes` over `pass` (their own poses,
/// the program's timing): how plan_pass_paper's two plans of a held least tilt are weighed.
double pass_worst_share(const OperationPlanInputs& in, const IndexRange& pass,
                        const std::vector<Vec3d>& axes) {
  std::vector<bool> rapid_into(axes.size(), false);
  if (!rapid_into.empty()) rapid_into[0] = true;
  const PosePlan plan = plan_poses(in.machine.rotary, axes, rapid_into, {}, in.pose_options);
  if (!plan.ok()) return std::numeric_limits<double>::infinity();
  std::vector<Posed> poses(in.op.points.size());
  std::copy(plan.poses.begin(), plan.poses.end(), poses.begin() + static_cast<long>(pass.begin));
  return worst_accel_share(pass_rates(in, pass, poses).summary, effective_limits(in.machine),
                           false);
}

/// The pass's stretches near the pole re-planned in machine space (pole_passage.hpp), each
/// axis within its point's cone and acceptable; their count.
std::size_t replan_pole_passages(const Acceptance& acceptable_at, const IndexRange& pass,
                                 const std::vector<double>& segment_mm,
                                 const std::vector<double>& feeds, PassPlan& plan) {
  const OperationPlanInputs& in = acceptable_at.in;
  std::vector<bool> rapid_into(pass.size(), false);
  rapid_into[0] = true;
  const PosePlan poses = plan_poses(in.machine.rotary, plan.axes, rapid_into, {}, in.pose_options);
  if (!poses.ok()) return 0;
  const AxisTest in_cone = [&](std::size_t j, const Vec3d& axis) {
    return acceptable_at.in_cone(pass.begin + j, axis);
  };
  PolePassage pole =
      smooth_pole_passages(in.machine.rotary, plan.axes, poses.poses, segment_mm, feeds, in_cone);
  plan.axes = std::move(pole.axes);
  return pole.stretches;
}

}  // namespace

/// Runs plan_pass_paper on every feed pass of `op` (in parallel over passes; each pass is
/// planned alone, so the result does not depend on the thread count). An axis is acceptable
/// when the machine reaches it and, with a part, the tool above the ball (and the ball, where
/// it is in the air) misses the part. Points outside the feed passes keep their axes. Then
/// each pass's stretches near the pole get C re-planned in machine space (pole_passage.hpp).
OptimisedOperation optimise_paper(const OperationPlanInputs& in,
                                  const std::vector<double>& metric_feed,
                                  const PaperOptions& options, detail::StageProgress& progress) {
  const Operationd& op = in.op;
  const std::vector<ContactPoint>& contacts = in.contacts;
  OptimisedOperation out;
  for (const CLPointd& p : op.points) out.axes.push_back(p.axis);
  const double R = in.ball_radius_mm;
  const double max_dev_rad = deg_to_rad(options.max_deviation_deg);
  const auto touching = [&](std::size_t i) {
    return !contacts.empty() && contacts[i].state == ContactState::Touching;
  };
  const Acceptance acceptable_at{in, max_dev_rad};
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
        problem.curve_mm.push_back(contacts[i].surface_cc_mm);
        continue;
      }
      std::optional<Vec3d> normal;
      for (std::size_t d = 1; !normal && d < pass.size(); ++d) {
        if (i >= pass.begin + d && touching(i - d)) normal = contacts[i - d].surface_normal;
        if (i + d < pass.end && touching(i + d)) normal = contacts[i + d].surface_normal;
      }
      problem.curve_mm.push_back(normal ? Vec3d(centre - R * *normal) : centre);
    }
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at(pass.begin + j, axis);
    };
    const auto pole_passages = [&](PassPlan& plan) {
      return replan_pole_passages(acceptable_at, pass, problem.segment_mm,
                                  pass_feeds(metric_feed, pass), plan);
    };
    std::optional<PassPlan> single;
    PassPlan plan = detail::plan_pass_paper(problem, acceptable, options, single);
    pole_stretches[q] = pole_passages(plan);
    if (single) {
      // The keys resettled round a held least tilt's cap, or the paper's single repair where
      // that turns the axes less (the repairs round a collision settle either way: the Haas
      // job's curve fillet, resettled, raised B 740 -> 987 deg/s^2).
      const std::size_t single_poles = pole_passages(*single);
      if (pass_worst_share(in, pass, single->axes) <= pass_worst_share(in, pass, plan.axes)) {
        plan = std::move(*single);
        pole_stretches[q] = single_poles;
      }
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

}  // namespace taxopt::pipeline
