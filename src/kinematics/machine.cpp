#include "taxopt/kinematics/machine.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "dialects/dialect_rules.hpp"
#include "machine/template_block.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"

namespace taxopt {

const char* to_string(GcodeDialect dialect) { return gcode::rules_of(dialect).name(); }

std::vector<GcodeDialect> gcode_dialects() {
  std::vector<GcodeDialect> out;
  for (const gcode::DialectRules* r : gcode::all_dialects()) out.push_back(r->id());
  return out;
}

bool has_inverse_time(GcodeDialect dialect) { return gcode::rules_of(dialect).inverse_time(); }

Machine default_machine() { return Machine{}; }

Machine make_machine(const std::string& kinematics, std::optional<double> head_pivot_length_mm) {
  Machine m;
  if (!kinematics_layout(kinematics, m.rotary.tilt_about, m.rotary.layout)) {
    throw InputError(
        "make_machine: '" + kinematics + "' is no kinematics (" + kKinematicsNames + ")",
        ErrorPlace{std::nullopt, std::nullopt, "Machine::kinematics"});
  }
  m.kinematics = kinematics;
  m.name = "generic-" + kinematics;
  m.head_pivot_length_mm = head_pivot_length_mm;
  validate(m);
  return m;
}

bool kinematics_layout(const std::string& name, TiltAxis& tilt, RotaryLayout& layout) {
  static const std::pair<const char*, RotaryLayout> kLayouts[] = {
      {"-table-table", RotaryLayout::TableTable},
      {"-head-table", RotaryLayout::HeadTable},
      {"-head-head", RotaryLayout::HeadHead}};
  if (name.size() < 2 || (name.compare(0, 2, "ac") != 0 && name.compare(0, 2, "bc") != 0)) {
    return false;
  }
  for (const auto& [suffix, l] : kLayouts) {
    if (name.substr(2) == suffix) {
      tilt = name[0] == 'b' ? TiltAxis::Y : TiltAxis::X;
      layout = l;
      return true;
    }
  }
  return false;
}

namespace {

[[noreturn]] void refuse(const std::string& field, const std::string& expected, double got) {
  std::ostringstream os;
  os << "Machine::" << field << " must be " << expected << ", got " << got;
  throw InputError(os.str(), ErrorPlace{std::nullopt, std::nullopt, "Machine::" + field});
}

/// The least linearisation tolerance, mm: the resolution of the written words.
constexpr double kLeastLinearisationMm = 1e-3;

void check_range(const std::string& field, double v, double lo, double hi,
                 const std::string& expected) {
  if (!(v >= lo && v <= hi)) refuse(field, expected, v);
}

void check_rotary(const char* name, const RotaryAxis<double>& axis) {
  const std::string f = std::string("rotary.") + name;
  if (axis.sense != 1 && axis.sense != -1) {
    refuse(f + ".sense", "+1 or -1", static_cast<double>(axis.sense));
  }
  if (axis.continuous) return;
  if (std::isnan(axis.min_rad)) refuse(f + ".min_rad", "a number", axis.min_rad);
  if (std::isnan(axis.max_rad)) refuse(f + ".max_rad", "a number", axis.max_rad);
  if (axis.min_rad > axis.max_rad) refuse(f + ".min_rad", "<= max_rad", axis.min_rad);
}

}  // namespace

namespace {

/// Joint j's field index and its letter on `m` ("[3]" and "the B joint"): the field is the
/// array's index, the letter the machine's (Joint::Tilt is A or B).
std::string joint_field(std::size_t j) { return "[" + std::to_string(j) + "]"; }
std::string joint_said(const Machine& m, std::size_t j) {
  return " (the " + joint_name(static_cast<Joint>(j), m.rotary.tilt_letter()) + " joint)";
}

/// The kinematics' name agrees with the rotary model; a head's pivot, and no machine mode.
void validate_kinematics(const Machine& m) {
  const bool bc = m.rotary.tilt_about == TiltAxis::Y;
  TiltAxis tilt = TiltAxis::X;
  RotaryLayout layout = RotaryLayout::TableTable;
  if (!kinematics_layout(m.kinematics, tilt, layout) || tilt != m.rotary.tilt_about ||
      layout != m.rotary.layout) {
    const char* where = m.rotary.layout == RotaryLayout::HeadHead    ? "-head-head"
                        : m.rotary.layout == RotaryLayout::HeadTable ? "-head-table"
                                                                     : "-table-table";
    throw InputError("Machine::kinematics '" + m.kinematics + "' does not name this machine: \"" +
                     (bc ? "bc" : "ac") + where + "\" for a tilt about " + (bc ? "Y" : "X") +
                     " (rotary.tilt_about) and its rotary.layout (" + kKinematicsNames + ")");
  }
  if (m.rotary.layout == RotaryLayout::TableTable && m.head_pivot_length_mm) {
    refuse("head_pivot_length_mm",
           "empty on a " + m.kinematics + " machine (its tilt axis turns the table, no head)",
           *m.head_pivot_length_mm);
  }
  if (m.rotary.layout != RotaryLayout::TableTable) {
    if (!m.head_pivot_length_mm) {
      throw InputError(
          "Machine::head_pivot_length_mm: a " + m.kinematics +
              " machine needs its head's pivot length, mm (from the tilt axis to the spindle's "
              "gauge line; 0 where the axis crosses it): without it the travel, the rapids' "
              "and the controller's times would run with no pivot",
          ErrorPlace{std::nullopt, std::nullopt, "Machine::head_pivot_length_mm"});
    }
    check_range("head_pivot_length_mm", *m.head_pivot_length_mm, 0.0, 5000.0, "within [0, 5000]");
    check_range("rotary.head_length_mm", m.rotary.head_length_mm, 0.0, 10000.0,
                "within [0, 10000]");
    if (m.gcode.mode == GcodeMode::Machine) {
      throw InputError("Machine::gcode.mode Machine on a " + m.kinematics +
                       " machine is not written (each block would depend on the tool's length "
                       "about the head's pivot): use GcodeMode::Tcp");
    }
  }
}

/// The rotary axes' ranges, their axes' points, the joints' limits, the linear travel.
void validate_axes(const Machine& m) {
  check_rotary("tilt", m.rotary.tilt);
  check_rotary("c", m.rotary.c);
  for (int q = 0; q < 3; ++q) {
    const std::string f =
        std::string("rotary.") + (q == 0 ? "c_axis_point_mm" : "tilt_axis_point_mm");
    const Vec3d& p = q == 0 ? m.rotary.c_axis_point_mm : m.rotary.tilt_axis_point_mm;
    if (!p.allFinite()) refuse(f, "finite", p.norm());
  }
  for (std::size_t j = 0; j < kJointCount; ++j) {
    const std::string f = "limits" + joint_field(j) + ".";
    const std::string finite = "finite and >= 0" + joint_said(m, j);
    const JointLimit& l = m.limits[j];
    check_range(f + "max_velocity_per_s", l.max_velocity_per_s, 0.0, 1e9, finite);
    check_range(f + "max_accel_per_s2", l.max_accel_per_s2, 0.0, 1e12, finite);
    check_range(f + "max_jerk_per_s3", l.max_jerk_per_s3, 0.0, 1e15, finite);
    check_range("joint_max_accel_per_s2" + joint_field(j), m.joint_max_accel_per_s2[j], 0.0, 1e12,
                finite);
  }
  for (std::size_t q = 0; q < 3; ++q) {
    const auto& r = m.linear_range[q];
    const std::string f = "linear_range" + joint_field(q);
    if (std::isnan(r.min_mm) || std::isnan(r.max_mm) || r.min_mm > r.max_mm) {
      refuse(f + ".min_mm", "a number <= max_mm" + joint_said(m, q), r.min_mm);
    }
  }
}

void validate_gcode(const GcodeSettings& g) {
  const std::string dialect = to_string(g.dialect);
  check_range("gcode.decimals", g.decimals, 0, max_decimals(g.dialect),
              "within [0, " + std::to_string(max_decimals(g.dialect)) + "] (the most " + dialect +
                  " takes)");
  if (g.feed_decimals != -1) {
    check_range(
        "gcode.feed_decimals", g.feed_decimals, 0, max_feed_decimals(g.dialect),
        "-1 (the dialect's) or within [0, " + std::to_string(max_feed_decimals(g.dialect)) + "]");
  }
  if (!has_inverse_time(g.dialect) && g.feed_mode == FeedMode::InverseTime) {
    throw InputError("Machine::gcode.feed_mode inverse-time is not written for the " + dialect +
                     " dialect (its ISO mode has no G93)");
  }
  check_range("gcode.max_feed_ratio", g.max_feed_ratio, 1.0, 100.0, "within [1, 100]");
}

/// The machine's [checks] and [holder], which a job uses where its options name none: the
/// bounds check_options puts on the options themselves.
void validate_checks_and_holder(const Machine& m) {
  for (const auto& [field, v] : {std::make_pair("shank_clearance_mm", m.shank_clearance_mm),
                                 std::make_pair("holder_clearance_mm", m.holder_clearance_mm)}) {
    if (v) check_range(field, *v, 0.0, 50.0, "within [0, 50]");
  }
  for (const auto& [field, v] :
       {std::make_pair("holder_radius_mm", m.holder_radius_mm),
        std::make_pair("holder_length_mm", m.holder_length_mm),
        std::make_pair("holder_gauge_length_mm", m.holder_gauge_length_mm)}) {
    if (v && !(*v > 0.0 && *v <= 1000.0)) refuse(field, "within (0, 1000]", *v);
  }
}

/// The template's blocks, written as they are and stepped over by the read-back, checked by
/// what they do in the machine's dialect (template_block_problem): a Machine built in code is
/// held to what a machine file's is (a header's "G0 X10" would move the tool unchecked).
void validate_template_blocks(const Machine& m) {
  const ProgramTemplate& t = m.gcode.program;
  for (const auto& [key, list] : kTemplateLists) {
    const std::vector<std::string>& blocks = t.*list;
    const std::string what = std::string("gcode.") + key;
    bool calls_tool = false;
    for (const std::string& block : blocks) {
      const std::string why =
          template_block_problem(block, what, m.gcode.dialect, std::string(key) == "footer");
      if (!why.empty()) throw InputError("Machine::" + what + ": '" + block + "' " + why);
      calls_tool = calls_tool || block.find("{tool}") != std::string::npos;
    }
    if (std::string(key) == "tool_change" && !blocks.empty() && !calls_tool) {
      throw InputError("Machine::" + what + " " + kToolChangeCallsTool);
    }
  }
  if (!t.work_offset.empty() && t.work_offset != "none") {
    const std::string why =
        template_block_problem(t.work_offset, "gcode.work_offset", m.gcode.dialect, false);
    if (!why.empty()) {
      throw InputError("Machine::gcode.work_offset: '" + t.work_offset + "' " + why);
    }
  }
}

void validate_program_template(const Machine& m) {
  const ProgramTemplate& t = m.gcode.program;
  validate_template_blocks(m);
  // Empty: "TAXOPT".
  if (t.name.size() > 24 || !program_name_characters_ok(t.name)) {
    throw InputError("Machine::gcode.program.name '" + t.name +
                     "' must have up to 24 letters, digits, '_' and '-'");
  }
  check_range("gcode.program.number", t.number, 1, 9999, "within [1, 9999]");
  check_range("gcode.program.retract_z_mm", t.retract_z_mm, -1e5, 1e5, "finite");
  check_range("gcode.program.linearise_tolerance_mm", t.linearise_tolerance_mm, 0.0, 1e3,
              "finite and >= 0");
  // Finer than the written words (0.001 mm) no program holds it; 1e-6 mm asked 4,096 blocks a
  // move (5 GB for a 3,000-point file).
  if (t.linearise_tolerance_mm > 0.0 && t.linearise_tolerance_mm < kLeastLinearisationMm) {
    refuse("gcode.program.linearise_tolerance_mm",
           "0 (off) or at least 0.001 mm, the written words' resolution", t.linearise_tolerance_mm);
  }
  check_range("gcode.program.blend_tolerance_mm", t.blend_tolerance_mm, 0.0, 1.0, "within [0, 1]");
  check_range("gcode.program.approach_clearance_mm", t.approach_clearance_mm, 0.0, 1000.0,
              "within [0, 1000]");
  check_range("gcode.program.index_threshold_deg", t.index_threshold_deg, 0.0, 360.0,
              "within [0, 360]");
  if (t.end_pose == EndPose::Home && (!m.rotary.tilt.contains(0.0) || !m.rotary.c.contains(0.0))) {
    throw InputError(
        "Machine::gcode.program.end_pose Home turns the rotaries to 0, outside their ranges");
  }
  if (t.end_park_xy_mm) {
    for (std::size_t q = 0; q < 2; ++q) {
      const double v = (*t.end_park_xy_mm)[q];
      if (!std::isfinite(v) || !m.linear_range[q].contains(v)) {
        refuse(
            "gcode.program.end_park_xy_mm" + joint_field(q),
            "finite and within the travel (linear_range" + joint_field(q) + ")" + joint_said(m, q),
            v);
      }
    }
  }
}

}  // namespace

void validate(const Machine& m) {
  validate_kinematics(m);
  validate_axes(m);
  validate_gcode(m.gcode);
  validate_checks_and_holder(m);
  validate_program_template(m);
}

int max_decimals(GcodeDialect dialect) { return gcode::rules_of(dialect).max_decimals(); }

int max_feed_decimals(GcodeDialect dialect) { return gcode::rules_of(dialect).max_feed_decimals(); }

int feed_decimals(const GcodeSettings& settings) {
  if (settings.feed_decimals >= 0) return settings.feed_decimals;
  return std::min(std::max(settings.decimals, 3), max_feed_decimals(settings.dialect));
}

JointLimits default_joint_limits() {
  JointLimits l;
  for (Joint j : {Joint::X, Joint::Y, Joint::Z})
    l[static_cast<std::size_t>(j)] = {500.0, 3000.0, 0.0};
  l[static_cast<std::size_t>(Joint::Tilt)] = {150.0, 1000.0, 0.0};
  l[static_cast<std::size_t>(Joint::C)] = {240.0, 1500.0, 0.0};
  return l;
}

JointLimits effective_limits(const Machine& machine) {
  JointLimits l = default_joint_limits();
  for (std::size_t j = 0; j < kJointCount; ++j) {
    const JointLimit& given = machine.limits[j];
    if (given.max_velocity_per_s > 0.0) l[j].max_velocity_per_s = given.max_velocity_per_s;
    if (given.max_accel_per_s2 > 0.0) l[j].max_accel_per_s2 = given.max_accel_per_s2;
    if (given.max_jerk_per_s3 > 0.0) l[j].max_jerk_per_s3 = given.max_jerk_per_s3;
  }
  return l;
}

}  // namespace taxopt
