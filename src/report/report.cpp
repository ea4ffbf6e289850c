// JSON report and per-point CSV of a run (CLI.md "JSON report", "Per-point CSV").
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <numeric>

#include "taxopt/core/version.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/job.hpp"

namespace taxopt {
namespace {

nlohmann::json summary_json(const RotarySummary& s, const std::optional<long>& colliding,
                            const FeedSummary& f) {
  nlohmann::json j;
  j["max_omega_deg_s"] = s.max_omega_deg_s;
  j["max_accel_deg_s2"] = s.max_accel_deg_s2;
  j["rms_accel_deg_s2"] = s.rms_accel_deg_s2;
  j["rms_omega_deg_s"] = s.rms_omega_deg_s;
  j["c_jumps"] = s.c_jumps;
  // Counted only when a part is given; null says "not checked", not "none".
  j["colliding_points"] = colliding ? nlohmann::json(*colliding) : nlohmann::json(nullptr);
  // The feed schedule at the machine's limits (feed_schedule.hpp).
  j["cycle_time_s"] = f.cycle_time_s;
  j["feed_time_s"] = f.feed_time_s;
  j["rapid_time_s"] = f.rapid_time_s;
  j["table_turn_s"] = f.table_turn_s;
  j["transition_excess_s"] = f.transition_excess_s;
  j["feed_limited_fraction"] = f.feed_limited_fraction;
  j["min_feed_mm_min"] = f.min_feed_mm_min;
  j["feed_path_mm"] = f.feed_path_mm;
  j["limiting_axis"] =
      f.limiting_axis.empty() ? nlohmann::json(nullptr) : nlohmann::json(f.limiting_axis);
  j["limiting_kind"] =
      f.limiting_kind.empty() ? nlohmann::json(nullptr) : nlohmann::json(f.limiting_kind);
  nlohmann::json why = nlohmann::json::object();
  if (colliding < 0) why["colliding_points"] = "not checked (no part, or no ball-end mill)";
  if (f.limiting_axis.empty()) why["limiting_axis"] = "no axis limit binds: the programmed feed";
  if (f.limiting_kind.empty()) why["limiting_kind"] = "no axis limit binds: the programmed feed";
  if (!why.empty()) j["null_reasons"] = why;
  return j;
}

/// Numbers as a reader wants them: 12 significant digits at most (no 30.000000000000004), and
/// no negative zero.
void tidy_numbers(nlohmann::json& j) {
  if (j.is_object() || j.is_array()) {
    for (auto& e : j) tidy_numbers(e);
  } else if (j.is_number_float()) {
    const double v = j.get<double>();
    if (!std::isfinite(v)) return;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.12g", v);
    double r = std::strtod(buf, nullptr);
    if (r == 0.0) r = 0.0;  // -0 -> 0
    j = r;
  }
}

/// The bodies of an operation's tool as the checks model them (mm from the ball centre along
/// the axis), or null with the reason.
nlohmann::json tool_json(const Tool& tool, const JobOptions& options) {
  // A ball radius given overrides the file's diameter and corner radius.
  const std::optional<double>& ball = options.tool.ball_radius_mm;
  nlohmann::json t = {{"number", tool.number},
                      {"name", tool.name},
                      {"from_file", tool.from_file},
                      {"diameter_mm", ball ? 2.0 * *ball : tool.diameter_mm},
                      {"corner_radius_mm", ball ? *ball : tool.corner_radius_mm},
                      {"flute_length_mm", tool.flute_length_mm},
                      {"taper_deg", rad_to_deg(tool.taper_rad)}};
  try {
    const ToolModel m = ToolModel::ball_end(tool, options.tool);
    nlohmann::json bodies = nlohmann::json::array();
    for (std::size_t i = 0; i < m.bodies.size(); ++i) {
      const ToolBody& b = m.bodies[i];
      const bool holder = options.tool.holder_radius_mm && i + 1 == m.bodies.size() &&
                          static_cast<int>(i) >= m.flute_bodies;
      bodies.push_back({{"kind", static_cast<int>(i) < m.flute_bodies ? "flutes"
                                 : holder                             ? "holder"
                                                                      : "shank"},
                        {"radius_mm", b.radius_mm},
                        {"from_mm", b.start_mm},
                        {"to_mm", b.end_mm}});
    }
    t["model"] = {{"ball_radius_mm", m.ball_radius_mm}, {"bodies", bodies}};
  } catch (const std::exception& e) {
    t["model"] = nullptr;
    t["null_reasons"] = {{"model", e.what()}};
  }
  return t;
}

/// The run, to reproduce it: command line, time, the machine file by digest, the part.
nlohmann::json run_json(const RunInfo& run) {
  nlohmann::json j;
  j["run"] = {
      {"command_line", run.command_line},
      {"started_utc", run.started_utc},
      {"machine_file",
       run.machine_file.empty() ? nlohmann::json(nullptr) : nlohmann::json(run.machine_file)},
      {"machine_file_sha256",
       run.machine_sha256.empty() ? nlohmann::json(nullptr) : nlohmann::json(run.machine_sha256)},
      {"part_file",
       run.part_file.empty() ? nlohmann::json(nullptr) : nlohmann::json(run.part_file)}};
  if (run.machine_file.empty()) j["run"]["null_reasons"] = {{"machine_file", "built-in machine"}};
  return j["run"];
}

/// The options the run applied and the machine's G-code settings.
nlohmann::json options_json(const JobOptions& options, const Machine& machine) {
  nlohmann::json j;
  j["options"] = {
      {"method", to_string(options.method)},
      {"max_deviation_deg", options.paper.max_deviation_deg},
      {"grid_deg", options.paper.grid_deg},
      {"objective", to_string(options.global.objective)},
      {"jerk_weight_s2", options.global.jerk_weight_s2},
      {"feed_mm_min", options.feed_mm_per_min ? nlohmann::json(*options.feed_mm_per_min)
                                              : nlohmann::json(nullptr)},
      {"feed_schedule", options.feed_schedule},
      {"shank_clearance_mm", *options.shank_clearance_mm},
      {"holder_clearance_mm", *options.holder_clearance_mm},
      // The tolerances in force: as given, else the part's default (the mesh's chordal error,
      // at least 0.05 mm: contact.hpp); null without a part.
      {"part_tolerance_mm",
       options.part_tolerance_mm ? nlohmann::json(*options.part_tolerance_mm)
       : options.part ? nlohmann::json(contact_tolerance_mm(*options.part, options.contact))
                      : nlohmann::json(nullptr)},
      {"contact_tolerance_mm",
       options.part ? nlohmann::json(contact_tolerance_mm(*options.part, options.contact))
                    : nlohmann::json(nullptr)},
      {"part_chordal_error_mm",
       options.part ? nlohmann::json(options.part->chordal_error_mm()) : nlohmann::json(nullptr)},
      {"gcode",
       {{"dialect", to_string(machine.gcode.dialect)},
        {"mode", machine.gcode.mode == GcodeMode::Tcp ? "tcp" : "machine"},
        {"feed_mode",
         machine.gcode.feed_mode == FeedMode::InverseTime ? "inverse-time" : "units-per-minute"},
        {"decimals", machine.gcode.decimals},
        {"feed_decimals", feed_decimals(machine.gcode)},
        {"safe_retract", machine.gcode.program.retract == SafeRetract::None ? "none" : "machine-z"},
        {"retract_z_mm", machine.gcode.program.retract_z_mm},
        {"linearise_tolerance_mm", machine.gcode.program.linearise_tolerance_mm},
        {"blend_tolerance_mm", machine.gcode.program.blend_tolerance_mm}}}};
  return j["options"];
}

/// Every finding with its operation, CL line and G-code line.
nlohmann::json findings_json(const JobResult& result, const Toolpath& toolpath) {
  nlohmann::json findings = nlohmann::json::array();
  for (const Finding& f : result.findings) {
    nlohmann::json one = {
        {"code", to_string(f.code)}, {"severity", to_string(f.severity)}, {"message", f.message}};
    one["operation"] = f.operation && *f.operation < toolpath.operations.size()
                           ? nlohmann::json(toolpath.operations[*f.operation].name)
                           : nlohmann::json();
    one["line"] = f.line > 0 ? nlohmann::json(f.line) : nlohmann::json();
    one["gcode_line"] = f.gcode_line ? nlohmann::json(*f.gcode_line) : nlohmann::json();
    findings.push_back(one);
  }
  return findings;
}

/// How the CL file was read (docs/cl-files.md): its CAM system, the sense of its arcs and why,
/// and the motion that splines, drilling cycles and MSYS frames contributed.
nlohmann::json cl_input_json(const Toolpath& toolpath) {
  const ClReadSummary& rd = toolpath.reading;
  nlohmann::json cl;
  cl["dialect"] = to_string(rd.dialect);
  cl["dialect_evidence"] =
      rd.dialect_evidence.empty() ? nlohmann::json(nullptr) : nlohmann::json(rd.dialect_evidence);
  cl["motion_records"] = rd.motion_records;
  cl["arcs"] = {{"count", rd.arcs},
                {"convention", to_string(rd.arc_convention)},
                {"convention_from", rd.arc_convention_source},
                {"decidable", rd.arcs_decidable},
                {"contradicting", rd.arcs_contradicting},
                {"reversed_by_tangents", rd.arcs_reversed},
                {"reversed_lines", rd.reversed_arc_lines}};
  cl["splines"] = {{"count", rd.splines}, {"points", rd.spline_points}};
  cl["drill_cycle_holes"] = rd.cycle_holes;
  cl["msys_applied"] = rd.msys_applied;
  cl["skipped_records"] = toolpath.skipped_records;
  cl["skipped_by_option"] = toolpath.skipped_by_option;
  cl["notices"] = toolpath.notices;
  return cl;
}

/// The program: what was written, its time, LinuxCNC's joint peaks on its rapids.
nlohmann::json gcode_json(const JobResult& result) {
  nlohmann::json j;
  j["gcode"] = {
      {"arcs_kept", result.gcode.arcs_kept},
      {"arcs_chorded", result.gcode.arcs_chorded},
      {"linearised_blocks", result.gcode.linearised_blocks},
      {"arc_blocks", result.gcode.arc_blocks},
      {"index_moves", result.gcode.index_moves},
      {"index_passed_over_points",
       std::accumulate(result.gcode.passed_over.begin(), result.gcode.passed_over.end(),
                       std::size_t{0}, [](std::size_t n, const auto& v) { return n + v.size(); })},
      {"joint_safe_rapids", result.gcode.joint_safe_rapids.size()},
      {"time_s", result.gcode.time_s},
      {"time_from_line", result.gcode.time_from_line},
      {"time_tool_length_mm", result.gcode.time_tool_length_mm}};
  // LinuxCNC tcp: the joints on the rapids as its planner moves them, by joint name.
  if (result.gcode.tcp_joint_peaks.empty()) {
    j["gcode"]["tcp_joint_peaks"] = nullptr;
    j["gcode"]["null_reasons"] = {
        {"tcp_joint_peaks",
         "no rapid planned in the program's axes (not LinuxCNC with TCP on, or no rapid)"}};
  } else {
    nlohmann::json peaks = nlohmann::json::object();
    for (std::size_t q = 0; q < result.gcode.tcp_joint_peaks.size() && q < kJointCount; ++q) {
      const JointPeak& p = result.gcode.tcp_joint_peaks[q];
      peaks[joint_name(static_cast<Joint>(q), result.tilt_letter)] = {
          {"velocity_per_s", p.velocity_per_s},
          {"velocity_line", p.velocity_line},
          {"accel_per_s2", p.accel_per_s2},
          {"accel_line", p.accel_line}};
    }
    j["gcode"]["tcp_joint_peaks"] = peaks;
  }
  if (result.gcode.tcp_axis_accel_scale) {
    j["gcode"]["tcp_axis_accel_scale"] = *result.gcode.tcp_axis_accel_scale;
  } else {
    j["gcode"]["tcp_axis_accel_scale"] = nullptr;
    j["gcode"]["null_reasons"]["tcp_axis_accel_scale"] =
        "no joint passes its acceleration limit in tcp_joint_peaks";
  }
  return j["gcode"];
}

/// What the run proved about an operation's program, and why a value is null.
nlohmann::json verification_json(const OperationResult& r, const JobResult& result,
                                 const JobOptions& options) {
  nlohmann::json v;
  v["roundtrip_max_mm"] = r.verification.roundtrip_max_mm;
  v["roundtrip_max_deg"] = r.verification.roundtrip_max_deg;
  v["collision_free"] = r.verification.collision_free
                            ? nlohmann::json(*r.verification.collision_free)
                            : nlohmann::json(nullptr);
  v["min_clearance_mm"] = r.verification.min_clearance_mm
                              ? nlohmann::json(*r.verification.min_clearance_mm)
                              : nlohmann::json(nullptr);
  if (r.verification.min_clearance_mm) {
    v["min_clearance_point"] = r.verification.min_clearance_index;
  }
  // A count, or null where it was not checked.
  const auto count = [](const std::optional<long>& n) {
    return n ? nlohmann::json(*n) : nlohmann::json(nullptr);
  };
  v["flute_gouge_points"] = count(r.verification.flute_gouge_points);
  v["within_axis_limits"] = r.verification.within_axis_limits;
  v["tool_length_active"] = r.verification.tool_length_active;
  v["within_dynamic_limits"] = r.verification.within_dynamic_limits;
  v["blocks_swept"] = count(r.verification.blocks_swept);
  v["blocks_not_checked"] = count(r.verification.blocks_not_checked);
  v["colliding_blocks"] = count(r.verification.colliding_blocks);
  v["colliding_moves"] = count(r.verification.colliding_moves);
  // Why a value is null.
  nlohmann::json why = nlohmann::json::object();
  const std::string no_part = "no part given (" + options.name_of("part") + "): not checked";
  const std::string no_ball = "the tool is no ball-end mill: no contact recovery, not checked";
  const std::string unchecked = result.collision_checked ? no_ball : no_part;
  if (!r.verification.collision_free) why["collision_free"] = unchecked;
  if (!r.verification.colliding_moves) why["colliding_moves"] = unchecked;
  if (!r.verification.blocks_swept) why["blocks_swept"] = unchecked;
  if (!r.verification.colliding_blocks) why["colliding_blocks"] = unchecked;
  if (!r.verification.blocks_not_checked) why["blocks_not_checked"] = unchecked;
  if (!r.verification.flute_gouge_points) why["flute_gouge_points"] = unchecked;
  if (!r.verification.min_clearance_mm) {
    why["min_clearance_mm"] =
        r.verification.collision_free
            ? "no shank or holder past the flutes to measure (the flutes reach the holder)"
            : unchecked;
  }
  if (!why.empty()) v["null_reasons"] = why;
  return v;
}

/// The paper's metric of an operation (eq. 16-18) before and after, on the designed surface
/// and on the mesh's facets.
nlohmann::json paper_metric_json(const OperationResult& r) {
  const auto paper_json = [](const RotarySummary& p) {
    return nlohmann::json{{"max_omega_deg_s", p.max_omega_deg_s},
                          {"max_accel_deg_s2", p.max_accel_deg_s2},
                          {"rms_accel_deg_s2", p.rms_accel_deg_s2}};
  };
  return {{"before", paper_json(r.paper_before)},
          {"after", paper_json(r.paper_after)},
          {"facets",
           {{"before", paper_json(r.paper_before_facets)},
            {"after", paper_json(r.paper_after_facets)}}},
          {"claimed", r.paper_gain_claimed},
          {"what",
           "eq. 16-18 over the designed surface's contact-point arc lengths "
           "at the metric feed (the paper's comparison; before/after are "
           "the program's own timing); `facets` over the mesh's own contact "
           "points; `claimed`: its peak a falls under both"}};
}

/// How the guard and the time objective chose an operation's axes, where they ran.
void add_choices_json(const OperationResult& r, nlohmann::json& o) {
  if (r.kept_input_points) {
    const auto& kept = *r.kept_input_points;
    o["kept_input_points"] = {{"total", kept.total()},
                              {"by_reason",
                               {{"collision", kept.collision},
                                {"peak_rate", kept.peak_rate},
                                {"no_gain", kept.no_gain},
                                {"no_free_axis", kept.no_free_axis},
                                {"method_choice", kept.method_choice}}},
                              {"join_points", kept.join_points},
                              {"whole_passes", kept.passes},
                              {"stretches", kept.stretches}};
  }
  if (r.time_choice) {
    const auto& t = *r.time_choice;
    o["time_objective"] = {{"plan", t.plan},
                           {"cycle_s", t.cycle_s},
                           {"peak_accel_deg_s2", t.peak_accel_deg_s2},
                           {"shortest_plan", t.shortest_plan},
                           {"shortest_cycle_s", t.shortest_cycle_s},
                           {"shortest_peak_accel_deg_s2", t.shortest_peak_accel_deg_s2},
                           {"tie_band", t.tie_band}};
  }
}

/// Each rotary axis's peaks, and where the machine file gives its limit, their shares of it.
nlohmann::json axes_json(const RotarySummary& s, const Machine& machine) {
  nlohmann::json axes = nlohmann::json::object();
  const auto axis = [&](Joint joint, const AxisPeaks& p) {
    const JointLimit& limit = machine.limits[static_cast<std::size_t>(joint)];
    nlohmann::json j = {{"max_omega_deg_s", p.max_omega_deg_s},
                        {"max_accel_deg_s2", p.max_accel_deg_s2},
                        {"rms_accel_deg_s2", p.rms_accel_deg_s2}};
    nlohmann::json why = nlohmann::json::object();
    const auto share = [&](const char* key, double peak, double limit_value) {
      if (limit_value > 0.0) {
        j[key] = peak / limit_value;
      } else {
        j[key] = nullptr;
        why[key] = "the machine file gives no limit for this axis";
      }
    };
    share("omega_share", p.max_omega_deg_s, limit.max_velocity_per_s);
    share("accel_share", p.max_accel_deg_s2, limit.max_accel_per_s2);
    if (!why.empty()) j["null_reasons"] = why;
    axes[joint_name(joint, machine.rotary.tilt_letter())] = j;
  };
  axis(Joint::Tilt, s.tilt);
  axis(Joint::C, s.c);
  return axes;
}

/// The axis nearest its limit (OperationResult::worst_axis), or null with the reason.
void worst_axis_json(const OperationResult& r, nlohmann::json& o) {
  if (!r.worst_axis) {
    o["worst_axis"] = nullptr;
    o["null_reasons"]["worst_axis"] =
        "the machine file gives no rotary limit: the combined figure (before, after) is the "
        "headline";
    return;
  }
  const AxisShare& w = *r.worst_axis;
  o["worst_axis"] = {{"axis", std::string(1, w.axis)},
                     {"rate", w.rate},
                     {"limit", w.limit},
                     {"share_before", w.before},
                     {"share_after", w.after}};
}

/// The cutting conditions at the contacts (OperationResult::Cutting), or null with the reason.
void cutting_json(const OperationResult& r, nlohmann::json& o) {
  if (!r.cutting) {
    o["cutting"] = nullptr;
    o["null_reasons"]["cutting"] = "no contacts: no part, or no ball-end mill";
    return;
  }
  const OperationResult::Cutting& c = *r.cutting;
  const auto speed = [&](double diameter_mm) {
    // pi D n, m/min: the cutting speed at the contact.
    return c.spindle_rpm > 0.0
               ? nlohmann::json(Constants<double>::pi() * diameter_mm * c.spindle_rpm / 1000.0)
               : nlohmann::json(nullptr);
  };
  o["cutting"] = {{"least_tilt_deg", c.least_tilt_deg},
                  {"least_tilt_from", c.least_tilt_given ? "option" : "input"},
                  {"least_tilt_held", c.least_tilt_held},
                  {"points", c.points},
                  {"points_below_least_tilt", c.points_below},
                  {"first_line_below",
                   c.points_below ? nlohmann::json(c.first_line_below) : nlohmann::json(nullptr)},
                  {"moves_past_normal", c.moves_past_normal},
                  {"first_line_past", c.moves_past_normal ? nlohmann::json(c.first_line_past)
                                                          : nlohmann::json(nullptr)},
                  {"before",
                   {{"least_tilt_deg", c.least_tilt_before_deg},
                    {"least_diameter_mm", c.least_diameter_before_mm},
                    {"mean_diameter_mm", c.mean_diameter_before_mm},
                    {"least_speed_m_min", speed(c.least_diameter_before_mm)},
                    {"mean_speed_m_min", speed(c.mean_diameter_before_mm)}}},
                  {"after",
                   {{"least_tilt_deg", c.least_tilt_after_deg},
                    {"least_diameter_mm", c.least_diameter_after_mm},
                    {"mean_diameter_mm", c.mean_diameter_after_mm},
                    {"least_speed_m_min", speed(c.least_diameter_after_mm)},
                    {"mean_speed_m_min", speed(c.mean_diameter_after_mm)}}},
                  {"spindle_rpm",
                   c.spindle_rpm > 0.0 ? nlohmann::json(c.spindle_rpm) : nlohmann::json(nullptr)}};
}

/// One operation: its rates before and after, its tool, contacts, verification and timings.
nlohmann::json operation_json(const OperationResult& r, const JobResult& result,
                              const Toolpath& toolpath, const JobOptions& options,
                              const Machine& machine) {
  nlohmann::json o;
  o["name"] = r.name;
  o["points"] = r.points;
  o["feed_mm_min"] = r.feed_mm_min;
  o["before"] = summary_json(r.before, r.colliding_before, r.feed_before);
  o["after"] = summary_json(r.after, r.colliding_after, r.feed_after);
  o["before"]["axes"] = axes_json(r.before, machine);
  o["after"]["axes"] = axes_json(r.after, machine);
  worst_axis_json(r, o);
  cutting_json(r, o);
  o["paper_metric"] = paper_metric_json(r);
  o["feed_schedule_written"] = options.feed_schedule;
  if (r.feed_words) {
    o["feed_words"] = {{"blocks", r.feed_words->blocks},
                       {"min_written_over_programmed", r.feed_words->min_ratio},
                       {"max_written_over_programmed", r.feed_words->max_ratio},
                       {"max_feed_ratio", r.feed_words->max_feed_ratio},
                       {"lengthened_blocks", r.feed_words->lengthened_blocks}};
  } else {
    o["feed_words"] = nullptr;
  }
  const std::size_t k = static_cast<std::size_t>(&r - result.operations.data());
  if (k < toolpath.operations.size()) o["tool"] = tool_json(toolpath.operations[k].tool, options);
  o["max_axis_change_deg"] = r.max_axis_change_deg;
  o["segments"] = r.segments;
  if (r.contact.recovered) {
    o["contact"] = {{"touching_points", r.contact.touching},
                    {"points_in_air", r.contact.in_air},
                    {"local_gouge_points", r.contact.local_gouges},
                    {"max_gap_mm", r.contact.max_abs_gap_mm},
                    {"tolerance_mm", r.contact.tolerance_mm},
                    {"edge_points", r.contact.edge_points},
                    {"corner_points", r.contact.corner_points},
                    {"max_normal_uncertainty_deg", r.contact.max_normal_uncertainty_deg}};
    if (k < toolpath.operations.size()) {
      const auto& band = toolpath.operations[k].cam_tolerance_mm;
      o["contact"]["cam_tolerance_mm"] = band ? nlohmann::json(*band) : nlohmann::json(nullptr);
    }
  }
  o["verification"] = verification_json(r, result, options);
  o["timings_s"] = {{"contacts", r.time_contacts_s},
                    {"cspace", r.time_cspace_s},
                    {"optimise", r.time_optimise_s},
                    {"post", r.time_post_s},
                    {"verify", r.time_verify_s}};
  add_choices_json(r, o);
  return o;
}

/// The limits used, per joint by its name.
nlohmann::json axis_limits_json(const Machine& machine) {
  nlohmann::json limits = nlohmann::json::object();
  const JointLimits effective = effective_limits(machine);
  for (std::size_t q = 0; q < kJointCount; ++q) {
    const std::string unit = q < 3 ? "mm" : "deg";
    nlohmann::json l = {{"max_velocity_" + unit + "_s", effective[q].max_velocity_per_s},
                        {"max_accel_" + unit + "_s2", effective[q].max_accel_per_s2}};
    if (effective[q].max_jerk_per_s3 > 0.0)
      l["max_jerk_" + unit + "_s3"] = effective[q].max_jerk_per_s3;
    if (machine.joint_max_accel_per_s2[q] > 0.0)
      l["joint_max_accel_" + unit + "_s2"] = machine.joint_max_accel_per_s2[q];
    limits[joint_name(static_cast<Joint>(q), machine.rotary.tilt_letter())] = l;
  }
  return limits;
}

}  // namespace

std::string report_json(const JobResult& result, const Toolpath& toolpath, const Machine& machine,
                        const JobOptions& given, const RunInfo& run) {
  // What the run applied: every default made explicit (the cone without a part, the machine
  // file's holder and clearances).
  const JobOptions options = resolved_options(given, machine);
  nlohmann::json j;
  j["taxopt_version"] = kVersion;
  j["method"] = to_string(options.method);
  j["input"] = toolpath.source;
  j["machine"] = machine.name;
  j["kinematics"] = machine.kinematics;
  j["run"] = run_json(run);
  j["options"] = options_json(options, machine);
  j["units"] = {{"cl", to_string(toolpath.units)}, {"gcode", to_string(result.gcode_units)}};
  j["ok"] = result.ok();
  j["findings"] = findings_json(result, toolpath);
  j["problems"] = result.problems;
  j["warnings"] = result.warnings;
  j["safety_warnings"] = result.safety_warnings;
  j["collision_checked"] = result.collision_checked;
  // How the bodies are judged (docs/cli.md "What is checked").
  j["clearances_mm"] = {{"shank", *options.shank_clearance_mm},
                        {"holder", *options.holder_clearance_mm},
                        {"holder_modelled", options.tool.holder_radius_mm.has_value()}};
  j["cl_input"] = cl_input_json(toolpath);
  j["gcode"] = gcode_json(result);
  nlohmann::json ops = nlohmann::json::array();
  for (const OperationResult& r : result.operations) {
    ops.push_back(operation_json(r, result, toolpath, options, machine));
  }
  j["operations"] = ops;
  j["axis_limits"] = axis_limits_json(machine);
  tidy_numbers(j);
  return j.dump(2) + "\n";
}

std::string points_csv(const JobResult& result) {
  std::string out =
      "op,index,arc_mm,tip_x,tip_y,tip_z,axis_i,axis_j,axis_k,cc_x,cc_y,cc_z,n_x,n_y,n_z,"
      "tilt_deg,yaw_deg,A_deg,C_deg,omega_deg_s,accel_deg_s2,free_cells,feed_mm_min,cl_line,"
      "findings,gap_mm,surface,normal_uncertainty_deg,omega_tilt_deg_s,omega_C_deg_s,"
      "accel_tilt_deg_s2,accel_C_deg_s2,tilt_after_deg,cutting_diameter_before_mm,"
      "cutting_diameter_mm\n";
  char buf[512];
  // A value that rounds to zero is written without its sign ("-0.000000" would say a side).
  const auto no_negative_zero = [](char* text) {
    std::string t = text, kept;
    std::size_t start = 0;
    while (start <= t.size()) {
      std::size_t end = t.find(',', start);
      if (end == std::string::npos) end = t.size();
      std::string field = t.substr(start, end - start);
      if (!field.empty() && field[0] == '-' &&
          field.find_first_not_of("-0.") == std::string::npos) {
        field.erase(0, 1);
      }
      kept += field;
      if (end < t.size()) kept += ',';
      start = end + 1;
    }
    std::snprintf(text, 512, "%s", kept.c_str());
  };
  for (const auto& r : result.operations) {
    std::string op = r.name;
    if (op.find_first_of(",\"\n") != std::string::npos) {
      std::string q = "\"";
      for (char c : op) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
      op = q + "\"";
    }
    for (const auto& p : r.rows) {
      std::snprintf(buf, sizeof buf, ",%zu,%.6f,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,", p.index, p.arc_mm,
                    p.tip_mm.x(), p.tip_mm.y(), p.tip_mm.z(), p.axis.x(), p.axis.y(), p.axis.z());
      no_negative_zero(buf);
      out += op;
      out += buf;
      if (p.has_contact) {
        std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.4f,%.4f,", p.cc_mm.x(),
                      p.cc_mm.y(), p.cc_mm.z(), p.normal.x(), p.normal.y(), p.normal.z(),
                      p.tilt_deg, p.yaw_deg);
        no_negative_zero(buf);
        out += buf;
      } else {
        out += ",,,,,,,,";
      }
      std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.6f,", p.tilt_axis_deg, p.c_deg,
                    p.omega_deg_s, p.accel_deg_s2);
      no_negative_zero(buf);
      out += buf;
      if (p.free_cells) out += std::to_string(*p.free_cells);
      out += ",";
      if (p.feed_mm_min) {
        std::snprintf(buf, sizeof buf, "%.3f", *p.feed_mm_min);
        out += buf;
      }
      // The marks hold only letters, '_' and ';': no quoting needed.
      out += "," + std::to_string(p.line) + "," + point_marks_text(p.marks);
      if (p.has_contact) {
        std::snprintf(buf, sizeof buf, ",%.6f,%s,%.4f", p.gap_mm, to_string(p.place),
                      p.normal_uncertainty_deg);
        no_negative_zero(buf);
        out += buf;
      } else {
        out += ",,,";
      }
      std::snprintf(buf, sizeof buf, ",%.6f,%.6f,%.6f,%.6f", p.omega_tilt_deg_s, p.omega_c_deg_s,
                    p.accel_tilt_deg_s2, p.accel_c_deg_s2);
      no_negative_zero(buf);
      out += buf;
      if (p.has_contact) {
        std::snprintf(buf, sizeof buf, ",%.4f,%.6f,%.6f", p.tilt_after_deg,
                      p.cutting_diameter_before_mm, p.cutting_diameter_mm);
        out += buf;
      } else {
        out += ",,,";
      }
      out += "\n";
    }
  }
  return out;
}

}  // namespace taxopt
