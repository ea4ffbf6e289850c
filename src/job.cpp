// run_job and plan_axes: the stages of src/pipeline/ (stages.hpp) called in order.
#include "taxopt/job.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "pipeline/stages.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/part.hpp"
#include "util/release_memory.hpp"

namespace taxopt {

namespace {

/// The CL points posted as written lie in the MCS their MSYS names (NX's convention). A mesh
/// exported in the same MCS fits them as it is; one exported in absolute coordinates must be
/// moved into the MCS. The evidence is where the ball touches the mesh: the share of sampled
/// feed points whose ball centre lies one radius from the mesh, in either frame.
TriangleMesh mesh_in_declared_frame(const Toolpath& toolpath, TriangleMesh mesh, MeshFrame frame,
                                    std::string* note, std::optional<double> ball_radius_mm) {
  const ClFrame& f = toolpath.declared_frames.front();
  if (frame != MeshFrame::Auto) {
    if (note) {
      *note = std::string("the part mesh is taken ") +
              (frame == MeshFrame::Mcs ? "as it is, in the MCS"
                                       : "as absolute and moved into the MCS") +
              " of the MSYS at line " + std::to_string(f.line) + ", as asked";
    }
    if (frame == MeshFrame::Absolute) {
      for (Vec3d& v : mesh.vertices) v = f.rotation.transpose() * (v - f.origin_mm);
    }
    return mesh;
  }
  bool one_frame = true;
  for (const ClFrame& g : toolpath.declared_frames) {
    one_frame = one_frame && (g.rotation - f.rotation).cwiseAbs().maxCoeff() <= 1e-9 &&
                (g.origin_mm - f.origin_mm).norm() <= 1e-9;
  }
  double radius = ball_radius_mm.value_or(0.0);
  std::vector<const CLPointd*> feed;
  for (const Operationd& op : toolpath.operations) {
    if (!(radius > 0.0) && op.tool.is_ball()) radius = op.tool.ball_radius_mm();
    for (const CLPointd& p : op.points) {
      if (p.motion == Motion::Feed) feed.push_back(&p);
    }
  }
  if (!(radius > 0.0) || feed.empty() || !one_frame) {
    if (note) {
      *note =
          "the part mesh is taken in the coordinates the CL points are posted in (the MCS "
          "the file's MSYS names); " +
          std::string(!one_frame ? "its MSYS records name different frames"
                                 : "no ball radius or feed move to judge the frame by");
    }
    return mesh;
  }
  TriangleMesh moved = mesh;
  for (Vec3d& v : moved.vertices) v = f.rotation.transpose() * (v - f.origin_mm);
  const std::size_t samples = std::min<std::size_t>(feed.size(), 400);
  const double tolerance_mm = std::max(0.05, 0.01 * radius);
  const auto touching = [&](const TriangleMesh& m) {
    const Part part(m);
    int n = 0;
    for (std::size_t k = 0; k < samples; ++k) {
      const CLPointd& p = *feed[k * feed.size() / samples];
      const Vec3d centre = p.tip_mm + radius * p.axis;
      n += std::abs(part.closest(centre).distance_mm - radius) <= tolerance_mm;
    }
    return static_cast<double>(n) / static_cast<double>(samples);
  };
  const double as_is = touching(mesh), in_mcs = touching(moved);
  std::ostringstream os;
  os.precision(3);
  os << "the ball touches the part mesh at " << 100.0 * as_is << " % of " << samples
     << " sampled feed points as the mesh is, and at " << 100.0 * in_mcs
     << " % moved into the MCS of the MSYS at line " << f.line;
  if (std::max(as_is, in_mcs) < 0.25) {
    throw InputError(toolpath.source + ": " + os.str() +
                     ": the mesh fits the CL points in neither frame (is it the part of this "
                     "file, in its units?)");
  }
  // A tie is no evidence: a floor under the points fits both frames and the boss the tool
  // hits stands in one of them only (issue 63: the run took "as it is" and missed it).
  if (std::abs(as_is - in_mcs) < 0.1) {
    throw InputError(toolpath.source + ": " + os.str() +
                     ": the mesh fits both frames alike, so where it is is not known; say which "
                     "(MeshFrame::Mcs or MeshFrame::Absolute; taxopt --part-frame mcs|absolute)");
  }
  if (note) {
    *note = os.str() + (in_mcs > as_is ? ": the mesh is taken as absolute and moved into the MCS"
                                       : ": the mesh is taken as it is, in the MCS");
  }
  return in_mcs > as_is ? moved : mesh;
}

}  // namespace

TriangleMesh part_mesh_for(const Toolpath& toolpath, TriangleMesh mesh, LengthUnit mesh_units,
                           std::string* note, std::optional<double> ball_radius_mm) {
  return part_mesh_for(toolpath, std::move(mesh), mesh_units, MeshFrame::Auto, note,
                       ball_radius_mm);
}

TriangleMesh part_mesh_for(const Toolpath& toolpath, TriangleMesh mesh, LengthUnit mesh_units,
                           MeshFrame frame, std::string* note,
                           std::optional<double> ball_radius_mm) {
  const double scale = mm_per_unit(mesh_units);
  for (Vec3d& v : mesh.vertices) {
    if (!v.allFinite()) throw InputError("the part mesh has a vertex that is not a number");
    v *= scale;
  }
  if (toolpath.frames.empty()) {
    return toolpath.declared_frames.empty()
               ? mesh
               : mesh_in_declared_frame(toolpath, std::move(mesh), frame, note, ball_radius_mm);
  }
  const ClFrame& f = toolpath.frames.front();
  for (const ClFrame& g : toolpath.frames) {
    if ((g.rotation - f.rotation).cwiseAbs().maxCoeff() > 1e-9 ||
        (g.origin_mm - f.origin_mm).norm() > 1e-9) {
      throw InputError(toolpath.source + ": its MSYS records name different frames (lines " +
                       std::to_string(f.line) + " and " + std::to_string(g.line) +
                       "): one part cannot be in all of them; read the file with its MSYS "
                       "records ignored (ClReadOptions::apply_msys = false) or "
                       "split it");
    }
  }
  for (Vec3d& v : mesh.vertices) v = f.rotation.transpose() * (v - f.origin_mm);
  return mesh;
}

ToolOverrides tool_overrides(const ToolDimensions& given) {
  const double u = mm_per_unit(given.units);
  // Converted only: check_options (and run_job) check each dimension in mm, naming its field.
  const auto mm = [u](const std::optional<double>& v) -> std::optional<double> {
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
    case FindingCode::NoToolModel: return "no_tool_model";
    case FindingCode::NoCoolant: return "no_coolant";
    case FindingCode::NoWorkOffset: return "no_work_offset";
    case FindingCode::NoSafeRetract: return "no_safe_retract";
    case FindingCode::NoLinearisation: return "no_linearisation";
    case FindingCode::NotABallMill: return "not_a_ball_mill";
    case FindingCode::LocalGouge: return "local_gouge";
    case FindingCode::InputAxesKept: return "input_axes_kept";
    case FindingCode::TcpJointLimit: return "tcp_joint_limit";
    case FindingCode::FeedInAir: return "feed_in_air";
    case FindingCode::MeshSlivers: return "mesh_slivers";
    case FindingCode::PartTolerance: return "part_tolerance";
    case FindingCode::AxisRateRose: return "axis_rate_rose";
    case FindingCode::LeastTiltNotKept: return "least_tilt_not_kept";
    case FindingCode::MissingFeed: return "missing_feed";
    case FindingCode::JerkLimitExceeded: return "jerk_limit_exceeded";
    case FindingCode::LongerCycle: return "longer_cycle";
    case FindingCode::ClFileNote: return "cl_file_note";
    case FindingCode::NoFreeAxis: return "no_free_axis";
    case FindingCode::UnreachablePose: return "unreachable_pose";
    case FindingCode::AxisRangeExceeded: return "axis_range_exceeded";
    case FindingCode::TurnInCut: return "turn_in_cut";
    case FindingCode::TravelExceeded: return "travel_exceeded";
    case FindingCode::DynamicLimitExceeded: return "dynamic_limit_exceeded";
    case FindingCode::ToolLengthOffsetOff: return "tool_length_offset_off";
    case FindingCode::ReadBackMismatch: return "read_back_mismatch";
    case FindingCode::DeviationExceeded: return "deviation_exceeded";
    case FindingCode::PointCollision: return "point_collision";
    case FindingCode::MoveCollision: return "move_collision";
    case FindingCode::NoToolCalled: return "no_tool_called";
    case FindingCode::SpindleOff: return "spindle_off";
    case FindingCode::CoolantMismatch: return "coolant_mismatch";
    case FindingCode::IndexWithoutRetract: return "index_without_retract";
    case FindingCode::DiagonalApproach: return "diagonal_approach";
    case FindingCode::EndPoseNotHome: return "end_pose_not_home";
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

const char* to_string(PointMark mark) {
  switch (mark) {
    case PointMark::PointCollision: return "point_collision";
    case PointMark::FluteGouge: return "flute_gouge";
    case PointMark::MoveCollision: return "move_collision";
    case PointMark::KeptCollision: return "kept_collision";
    case PointMark::KeptPeakRate: return "kept_peak_rate";
    case PointMark::KeptJoin: return "kept_join";
    case PointMark::NoFreeAxis: return "no_free_axis";
    case PointMark::AxisLimit: return "axis_limit";
    case PointMark::TravelExceeded: return "travel_exceeded";
    case PointMark::CFlip: return "c_flip";
    case PointMark::CFlipBefore: return "c_flip_before";
    case PointMark::NotChecked: return "not_checked";
  }
  return "?";
}

std::string point_marks_text(std::uint32_t marks) {
  std::string text;
  for (const PointMark m : kAllPointMarks) {
    if ((marks & static_cast<std::uint32_t>(m)) == 0) continue;
    if (!text.empty()) text += ';';
    text += to_string(m);
  }
  return text;
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

namespace {

/// Runs `f` in the job's own task arena (JobOptions::threads workers, else all cores): no
/// process-global state, another job's threads untouched. A stop requested before it starts
/// ends it at once.
template <class F>
void in_job_arena(const JobOptions& options, const F& f) {
  check_options(options);
  options.stop.throw_if_stop_requested();
  tbb::task_arena arena(options.threads ? static_cast<int>(options.threads)
                                        : tbb::task_arena::automatic);
  arena.execute(f);
}

/// The machine a run's joint model uses: a head's tilt-to-tip length is its pivot length plus
/// the tool's gauge length (the options', else the machine's holder's; else the pivot alone),
/// as LinuxCNC's head kinematics add the tool length offset to their pivot length.
Machine run_machine(const Machine& machine, const JobOptions& options) {
  Machine m = machine;
  // The tool's gauge length the writer puts below a retract (ProgramWriter::joints_).
  if (options.tool.gauge_length_mm) m.holder_gauge_length_mm = options.tool.gauge_length_mm;
  if (options.work_offset_mm) m.work_offset_mm = options.work_offset_mm;
  if (m.pivot_frame == PivotFrame::Machine && m.work_offset_mm) {
    // The rotary axes in the workpiece's frame: a table's axes stay where the machine has
    // them while the program's zero sits at the work offset. Along its own axis a point on C
    // or on the tilt axis may move freely: only the across components matter.
    const Vec3d& o = *m.work_offset_mm;
    m.rotary.c_axis_point_mm -= Vec3d(o.x(), o.y(), 0.0);
    m.rotary.tilt_axis_point_mm -=
        m.rotary.tilt_about == TiltAxis::Y ? Vec3d(o.x(), 0.0, o.z()) : Vec3d(0.0, o.y(), o.z());
    m.pivot_frame = PivotFrame::Workpiece;
  }
  if (m.rotary.layout != RotaryLayout::TableTable) {
    m.rotary.head_length_mm =
        m.head_pivot_length_mm.value_or(0.0) +
        options.tool.gauge_length_mm.value_or(m.holder_gauge_length_mm.value_or(0.0));
  }
  return m;
}

/// How far a tool axis built in code may be off unit length and still be the caller's
/// direction: a float normalisation (about 1e-7 off, issue 64.3 was refused against 1e-9).
constexpr double kFloatAxisLength = 1e-6;
/// What check_points takes as unit: such an axis is used as given, bit for bit.
constexpr double kUnitAxisTolerance = 1e-9;

/// The toolpath with every axis within kFloatAxisLength of unit length normalised, as the CL
/// reader normalises what it reads (the direction is the caller's, the length round-off);
/// empty where every axis is unit already or is refused anyway (check_points).
std::optional<Toolpath> with_unit_axes(const Toolpath& tp) {
  const auto rounded_off = [](const Vec3d& axis) {
    const double d = std::abs(axis.norm() - 1.0);
    return d > kUnitAxisTolerance && d <= kFloatAxisLength;
  };
  bool any = false;
  for (const Operationd& op : tp.operations) {
    for (const CLPointd& p : op.points) any = any || rounded_off(p.axis);
  }
  if (!any) return std::nullopt;
  Toolpath out = tp;
  for (Operationd& op : out.operations) {
    for (CLPointd& p : op.points) {
      if (rounded_off(p.axis)) p.axis.normalize();
    }
  }
  return out;
}

}  // namespace

AxisPlan plan_axes(const Toolpath& given_tp, const Machine& given_machine,
                   const JobOptions& options) {
  const Machine machine = run_machine(given_machine, options);
  const std::optional<Toolpath> unit = with_unit_axes(given_tp);
  const Toolpath& tp = unit ? *unit : given_tp;
  AxisPlan out;
  in_job_arena(options, [&] {
    JobResult res;
    const StopSource& stop = options.stop;
    pipeline::Run run = pipeline::validate(tp, machine, options, res);
    std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
    pipeline::recover_contacts(run, ops, res);
    stop.throw_if_stop_requested();
    pipeline::plan_operations(run, ops, res);
    stop.throw_if_stop_requested();
    if (auto posted = pipeline::post_operations(run, ops, res)) out.operations = std::move(*posted);
    stop.throw_if_stop_requested();
    for (pipeline::OperationContext& o : ops) out.contacts.push_back(std::move(o.contacts));
    out.findings = std::move(res.findings);
  });
  return out;
}

namespace {

/// One run of the pipeline; between its stages (and inside the long ones) a stop requested
/// ends it with Cancelled.
JobResult run_once(const Toolpath& tp, const Machine& machine, const JobOptions& options,
                   const std::set<std::size_t>& refused) {
  JobResult res;
  const StopSource& stop = options.stop;
  pipeline::Run run = pipeline::validate(tp, machine, options, res);
  run.refused_operations = refused;
  std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
  pipeline::recover_contacts(run, ops, res);
  stop.throw_if_stop_requested();
  detail::release_free_memory();
  pipeline::plan_operations(run, ops, res);
  stop.throw_if_stop_requested();
  detail::release_free_memory();
  std::optional<std::vector<PostedOperation>> posted = pipeline::post_operations(run, ops, res);
  stop.throw_if_stop_requested();
  if (!posted) return res;
  detail::release_free_memory();
  const pipeline::Written written = pipeline::write_program(run, ops, *posted, res);
  stop.throw_if_stop_requested();
  detail::release_free_memory();
  pipeline::verify_operations(run, ops, *posted, written, res);
  pipeline::mark_unverified(run, *posted, res);
  stop.throw_if_stop_requested();
  return res;
}

/// Every method's output verifies wherever a program exists (tests/test_paper_method.cpp):
/// operations whose points or moves the verification found hitting the part are planned again with
/// the fallbacks of plan.cpp (the other method's plan, else the input's axes where they hit).
/// Only failed runs pay for the second run.
JobResult run_with_fallback(const Toolpath& tp, const Machine& machine, const JobOptions& options) {
  JobResult res = run_once(tp, machine, options, {});
  if (options.method == Method::None || !options.part) return res;
  std::set<std::size_t> refused;
  for (const Finding& f : res.findings) {
    if ((f.code == FindingCode::PointCollision || f.code == FindingCode::MoveCollision) &&
        f.operation) {
      refused.insert(*f.operation);
    }
  }
  if (refused.empty()) return res;
  return run_once(tp, machine, options, refused);
}

}  // namespace

JobResult run_job(const Toolpath& tp, const Machine& given_machine, const JobOptions& options) {
  const Machine machine = run_machine(given_machine, options);
  const std::optional<Toolpath> unit = with_unit_axes(tp);
  JobResult res;
  in_job_arena(options, [&] { res = run_with_fallback(unit ? *unit : tp, machine, options); });
  return res;
}

}  // namespace taxopt
