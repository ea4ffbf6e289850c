// run_job and plan_axes: the stages of src/pipeline/ (stages.hpp) called in order.
#include "taxopt/job.hpp"

#include <algorithm>
#include <cmath>

#include "pipeline/stages.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt {

TriangleMesh part_mesh_for(const Toolpath& toolpath, TriangleMesh mesh, LengthUnit mesh_units) {
  const double scale = mm_per_unit(mesh_units);
  for (Vec3d& v : mesh.vertices) {
    if (!v.allFinite()) throw InputError("the part mesh has a vertex that is not a number");
    v *= scale;
  }
  if (toolpath.frames.empty()) return mesh;
  const ClFrame& f = toolpath.frames.front();
  for (const ClFrame& g : toolpath.frames) {
    if ((g.rotation - f.rotation).cwiseAbs().maxCoeff() > 1e-9 ||
        (g.origin_mm - f.origin_mm).norm() > 1e-9) {
      throw InputError(toolpath.source + ": its MSYS records name different frames (lines " +
                       std::to_string(f.line) + " and " + std::to_string(g.line) +
                       "): one part cannot be in all of them; read the file with its MSYS "
                       "records ignored (ClReadOptions::apply_msys = false; --msys ignore) or "
                       "split it");
    }
  }
  for (Vec3d& v : mesh.vertices) v = f.rotation.transpose() * (v - f.origin_mm);
  return mesh;
}

ToolOverrides tool_overrides(const ToolDimensions& given) {
  const double u = mm_per_unit(given.units);
  const auto mm = [u](const std::optional<double>& v) -> std::optional<double> {
    if (v && !(*v > 0.0 && std::isfinite(*v))) {
      throw InputError("tool dimensions must be positive");
    }
    return v ? std::optional<double>(*v * u) : std::nullopt;
  };
  ToolOverrides o;
  o.ball_radius_mm = mm(given.ball_radius);
  o.shank_radius_mm = mm(given.shank_radius);
  o.flute_length_mm = mm(given.flute_length);
  o.holder_radius_mm = mm(given.holder_radius);
  o.holder_length_mm = mm(given.holder_length);
  o.gauge_length_mm = mm(given.gauge_length);
  return o;
}

const char* to_string(FindingCode code) {
  switch (code) {
    case FindingCode::NoPart: return "no_part";
    case FindingCode::NoHolderModel: return "no_holder_model";
    case FindingCode::NoSafeRetract: return "no_safe_retract";
    case FindingCode::NoLinearisation: return "no_linearisation";
    case FindingCode::NotABallMill: return "not_a_ball_mill";
    case FindingCode::LocalGouge: return "local_gouge";
    case FindingCode::InputAxesKept: return "input_axes_kept";
    case FindingCode::MissingFeed: return "missing_feed";
    case FindingCode::JerkLimitExceeded: return "jerk_limit_exceeded";
    case FindingCode::LongerCycle: return "longer_cycle";
    case FindingCode::ClFileNote: return "cl_file_note";
    case FindingCode::NoFreeAxis: return "no_free_axis";
    case FindingCode::UnreachablePose: return "unreachable_pose";
    case FindingCode::AxisRangeExceeded: return "axis_range_exceeded";
    case FindingCode::TravelExceeded: return "travel_exceeded";
    case FindingCode::DynamicLimitExceeded: return "dynamic_limit_exceeded";
    case FindingCode::ToolLengthOffsetOff: return "tool_length_offset_off";
    case FindingCode::ReadBackMismatch: return "read_back_mismatch";
    case FindingCode::DeviationExceeded: return "deviation_exceeded";
    case FindingCode::PointCollision: return "point_collision";
    case FindingCode::MoveCollision: return "move_collision";
  }
  return "?";
}

const char* to_string(Severity severity) {
  switch (severity) {
    case Severity::Safety: return "safety";
    case Severity::Warning: return "warning";
    case Severity::Problem: return "problem";
  }
  return "?";
}

bool JobResult::has(FindingCode code) const {
  return std::any_of(findings.begin(), findings.end(),
                     [code](const Finding& f) { return f.code == code; });
}

const char* to_string(Method method) {
  switch (method) {
    case Method::None: return "none";
    case Method::Paper: return "paper";
    case Method::Global: return "global";
  }
  return "none";
}

bool AxisPlan::ok() const {
  return std::none_of(findings.begin(), findings.end(),
                      [](const Finding& f) { return f.severity == Severity::Problem; });
}

AxisPlan plan_axes(const Toolpath& tp, const Machine& machine, const JobOptions& options) {
  JobResult res;
  pipeline::Run run = pipeline::validate(tp, machine, options, res);
  std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
  pipeline::recover_contacts(run, ops, res);
  pipeline::plan_operations(run, ops, res);
  AxisPlan out;
  if (auto posted = pipeline::post_operations(run, ops, res)) out.operations = std::move(*posted);
  for (pipeline::OperationContext& o : ops) out.contacts.push_back(std::move(o.contacts));
  out.findings = std::move(res.findings);
  return out;
}

JobResult run_job(const Toolpath& tp, const Machine& machine, const JobOptions& options) {
  JobResult res;
  pipeline::Run run = pipeline::validate(tp, machine, options, res);
  std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
  pipeline::recover_contacts(run, ops, res);
  pipeline::plan_operations(run, ops, res);
  std::optional<std::vector<PostedOperation>> posted = pipeline::post_operations(run, ops, res);
  if (!posted) return res;
  const pipeline::Written written = pipeline::write_program(run, ops, *posted, res);
  pipeline::verify_operations(run, ops, *posted, written, res);
  return res;
}

}  // namespace taxopt
