// The post stage: the machine's poses of the planned axes, and of the input axes for the
// "before" (stages.hpp).
#include "kinematics/pose_planning.hpp"
#include "pipeline/stages.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/kinematics/pose_planner.hpp"

namespace taxopt::pipeline {

namespace {

/// The operation as the program will carry it: its points (on the planned axes), feeds, tool
/// and spindle (the fallbacks where the CL file gives none: validate checked they exist),
/// arcs, coolant and events, before its poses.
PostedOperation operation_to_post(const Run& run, const OperationContext& o) {
  const Operationd& op = *o.op;
  PostedOperation po{op.name,
                     op.tool,
                     op.spindle_rpm,
                     op.spindle_clockwise,
                     posted_feeds(op, run.fallback_feed_mm_per_min),
                     {},
                     {},
                     {},
                     op.arcs,
                     op.coolant,
                     op.events};
  if (po.tool.number <= 0 && run.fallback_tool) po.tool.number = *run.fallback_tool;
  if (needs_spindle_speed(op) && run.fallback_spindle_rpm) {
    po.spindle_rpm = *run.fallback_spindle_rpm;
    po.spindle_clockwise = true;
  }
  po.swept_moves_checked = run.collision.has_value() && o.contact.recovered;
  if (run.options.part) {
    double top = -std::numeric_limits<double>::infinity();
    for (const Vec3d& v : run.options.part->mesh().vertices) top = std::max(top, v.z());
    if (std::isfinite(top)) po.part_top_z_mm = top;
  }
  if (o.optimised) {
    for (std::size_t i = 0; i < po.points.size(); ++i) {
      po.points[i].axis = o.optimised->axes[i];
      po.points[i].tip_mm = tip_for_axis(op.points[i], o.ball_radius_mm, po.points[i].axis);
    }
  }
  return po;
}

void missing_feed_finding(const Run& run, const OperationContext& o, JobResult& res) {
  const Operationd& op = *o.op;
  bool missing_feed = false;
  for (const CLPointd& p : op.points) {
    missing_feed = missing_feed || (p.motion == Motion::Feed && !(p.feed_mm_per_min > 0.0));
  }
  if (missing_feed) {
    add_finding(res, FindingCode::MissingFeed, o.index, 0,
                "operation " + op.name + ": feed moves without FEDRAT use " +
                    std::to_string(run.fallback_feed_mm_per_min) + " mm/min");
  }
}

/// Cutter-path feed reference: every feed block keeps the time of the input block at its
/// feed, so the ball centre and the contact point run as the CAM system programmed them,
/// whatever the tip does; within the feed ratio: where the new tip path would need an F above
/// max_feed_ratio times the programmed one, the block takes longer (the contact runs slower).
void keep_input_block_times(const Machine& machine, const OperationContext& o,
                            PostedOperation& po) {
  std::vector<CLPointd> in_points = po.points;
  for (std::size_t i = 0; i < in_points.size(); ++i) in_points[i].tip_mm = o.op->points[i].tip_mm;
  po.programmed_time_s = kept_block_times_s(
      programmed_block_times_s(in_points, o.input_poses.empty() ? po.poses : o.input_poses),
      programmed_block_times_s(po.points, po.poses), machine.gcode.max_feed_ratio,
      &po.feed_ratio_blocks);
}

}  // namespace

std::optional<std::vector<PostedOperation>> post_operations(const Run& run,
                                                            std::vector<OperationContext>& ops,
                                                            JobResult& res) {
  const Machine& machine = run.machine;
  const JobOptions& options = run.options;
  std::vector<PostedOperation> posted;
  std::optional<Posed> start, input_start;
  bool failed = false;
  // Per point: its pose, its pose before the method, the turns in the air.
  std::size_t items = 0;
  for (const OperationContext& o : ops) items += 3 * o.op->points.size();
  detail::StageProgress posting(options.progress, "posting", items, options.stop);
  for (OperationContext& o : ops) {
    const Operationd& op = *o.op;
    const std::size_t n = op.points.size();
    const std::size_t k = o.index;
    const auto t0 = Clock::now();
    PostedOperation po = operation_to_post(run, o);
    missing_feed_finding(run, o, res);
    std::vector<Vec3d> axes, in_axes;
    const std::vector<bool> rapid_into = rapid_into_of(op);
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      axes.push_back(po.points[i].axis);
      in_axes.push_back(op.points[i].axis);
    }
    const PosePlan plan = detail::plan_poses(
        machine.rotary, axes, rapid_into, start, options.pose_options,
        o.optimised ? o.optimised->preferred : std::vector<std::optional<Posed>>{}, &options.stop);
    posting.advance(n);
    // The input axes as the machine would have run them, for the "before" metrics.
    if (o.optimised) {
      const PosePlan before = detail::plan_poses(machine.rotary, in_axes, rapid_into, input_start,
                                                 options.pose_options, {}, &options.stop);
      if (before.ok()) input_start = before.poses.back();
      o.input_poses = before.ok() ? before.poses : std::vector<Posed>{};
    } else {
      o.input_poses = plan.ok() ? plan.poses : std::vector<Posed>{};
      if (plan.ok()) input_start = plan.poses.back();
    }
    posting.advance(n);
    if (!plan.ok()) {
      failed = true;
      add_finding(res, FindingCode::UnreachablePose, k, op.points[plan.failed_index].line,
                  format_location(run.tp.source, op.points[plan.failed_index].line,
                                  "operation " + op.name + ": " + plan.message +
                                      msys_remedy(run, op.points[plan.failed_index])));
      continue;
    }
    po.poses = plan.poses;
    if (o.optimised) {
      spread_turns_in_air(op, o.contacts, o.ball_radius_mm, run.planner_check(),
                          o.tool ? *o.tool : ToolModel{}, machine,
                          deg_to_rad(options.paper.max_deviation_deg), po, &options.stop);
    }
    posting.advance(n);
    if (o.optimised && machine.gcode.feed_reference == FeedReference::CutterPath) {
      keep_input_block_times(machine, o, po);
    }
    start = po.poses.back();
    posted.push_back(std::move(po));
    o.post_s = seconds_since(t0);
  }
  if (failed) return std::nullopt;
  return posted;
}

}  // namespace taxopt::pipeline
