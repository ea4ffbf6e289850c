// What LinuxCNC's TCP planner does to the joints of the written program, judged against the
// machine's limits (GcodeProgram::tcp_joint_peaks; stages.hpp).
#include <iomanip>
#include <sstream>

#include "controller/linuxcnc_planner.hpp"
#include "pipeline/stages.hpp"
#include "taxopt/kinematics/machine.hpp"

namespace taxopt::pipeline {

using controller::TcpBlock;

namespace {

/// Whether joint j's velocity limit holds the program (tcp_joint_findings): the limit the
/// machine file gives, or with the feed schedule the effective one (as the verification holds
/// the feed blocks); past a default limit, a warning.
bool velocity_held(const Machine& machine, bool scheduled, std::size_t j) {
  return scheduled || machine.limits[j].max_velocity_per_s > 0.0;
}

/// Whether a block whose start the program states drives a joint past a velocity limit held
/// (tcp_joint_findings).
bool known_start_over(const Machine& machine, const JointLimits& limits, bool scheduled,
                      const std::vector<TcpBlock>& blocks, const StopSource* stop) {
  std::vector<TcpBlock> known;
  for (const TcpBlock& b : blocks) {
    if (b.start_known) known.push_back(b);
  }
  const std::vector<JointPeak> peaks = controller::tcp_joint_peaks(machine, known, 1.0, stop);
  for (std::size_t j = 0; j < peaks.size() && j < kJointCount; ++j) {
    const double v_max = limits[j].max_velocity_per_s;
    if (velocity_held(machine, scheduled, j) && v_max > 0.0 &&
        peaks[j].velocity_per_s > 1.001 * v_max)
      return true;
  }
  return false;
}

}  // namespace

/// Where a block with TCP on drives a joint past its limit as LinuxCNC moves it
/// (GcodeProgram::tcp_joint_peaks; 0.1 % for the filter's rounding). A velocity past the
/// joint's limit is a problem: the feed schedule, the joint-safe rapids and turns keep them,
/// and one left over is a block the writer did not make safe (past a default limit, where the
/// machine file gives none and no schedule asked for them, a warning). An acceleration past
/// the joint's own (joint_accel_limit) is a warning: no F word helps it, LinuxCNC accelerates
/// the program's axes at their [AXIS_*] limits whatever the F word (measured on LinuxCNC's
/// motion controller); the warning gives the share of those limits that keeps the joints
/// within theirs (GcodeProgram::tcp_axis_accel_scale).
void tcp_joint_findings(const Machine& machine, const JointLimits& limits, bool scheduled,
                        const std::vector<TcpBlock>& blocks, JobResult& res,
                        const StopSource* stop) {
  const std::vector<JointPeak>& peaks = res.gcode.tcp_joint_peaks;
  res.gcode.tcp_axis_accel_scale.reset();
  std::ostringstream velocity, accel;
  velocity.precision(4);
  accel.precision(4);
  int velocity_over = 0, warned = 0, velocity_line = 0, warned_line = 0;
  bool accel_over = false, default_velocity_over = false;
  for (std::size_t j = 0; j < peaks.size() && j < kJointCount; ++j) {
    const std::string name = joint_name(static_cast<Joint>(j), machine.rotary.tilt_letter());
    const std::string unit = j < 3 ? "mm" : "deg";
    const double v_max = limits[j].max_velocity_per_s;
    const double a_max = joint_accel_limit(machine, limits, j);
    const bool given = velocity_held(machine, scheduled, j);
    if (v_max > 0.0 && peaks[j].velocity_per_s > 1.001 * v_max) {
      std::ostringstream& os = given ? velocity : accel;
      os << ((given ? velocity_over++ : warned++) ? "; " : "") << "joint " << name << " at "
         << peaks[j].velocity_per_s << " " << unit << "/s against " << v_max
         << (given ? "" : " (a default limit)") << " (G-code line " << peaks[j].velocity_line
         << ")";
      int& first = given ? velocity_line : warned_line;
      if (!first) first = peaks[j].velocity_line;
      default_velocity_over = default_velocity_over || !given;
    }
    if (a_max > 0.0 && peaks[j].accel_per_s2 > 1.001 * a_max) {
      accel << (warned++ ? "; " : "") << "joint " << name << " at " << peaks[j].accel_per_s2 << " "
            << unit << "/s^2 against " << a_max << " (G-code line " << peaks[j].accel_line << ")";
      if (!warned_line) warned_line = peaks[j].accel_line;
      accel_over = true;
    }
  }
  const std::string velocity_remedy = "[AXIS_*] MAX_VELOCITY below the [JOINT_*] ones";
  if (velocity_over && !known_start_over(machine, limits, scheduled, blocks, stop)) {
    // Only blocks from where the program has not yet stated the joints pass: those peaks
    // are the model's guess of where the machine stands (blocks_not_checked), a warning.
    velocity_over = 0;
    accel << (warned++ ? "; " : "") << velocity.str() << " from a start the program does not state";
    if (!warned_line) warned_line = velocity_line;
    default_velocity_over = true;
  }
  if (velocity_over) {
    add_finding(res, FindingCode::DynamicLimitExceeded, std::nullopt, 0,
                "LinuxCNC with TCP on drives " + velocity.str() +
                    " past the joint's velocity limit (gcode.tcp_joint_peaks); remedy: " +
                    velocity_remedy + ", or machine mode",
                velocity_line);
  }
  if (!warned) return;
  std::ostringstream remedy;
  remedy << std::fixed;
  if (accel_over) {
    const double scale = controller::tcp_axis_accel_scale(machine, limits, blocks, stop);
    res.gcode.tcp_axis_accel_scale = scale;
    if (scale > 0.0) {
      remedy << "every [AXIS_*] MAX_ACCELERATION at " << std::setprecision(3) << scale
             << " of its value";
    } else {
      remedy << "no share of the [AXIS_*] accelerations down to 0.05 (their speed drives them)";
    }
  }
  if (default_velocity_over) remedy << (accel_over ? "; " : "") << velocity_remedy;
  // One line: what, where, the remedy's name; the report (gcode.tcp_joint_peaks,
  // gcode.tcp_axis_accel_scale) and docs/feed-schedule.md explain it.
  add_finding(res, FindingCode::TcpJointLimit, std::nullopt, 0,
              "LinuxCNC with TCP on accelerates the program's axes at their [AXIS_*] limits and "
              "drives " +
                  accel.str() + "; remedy: " + remedy.str() +
                  " (gcode.tcp_axis_accel_scale; docs/feed-schedule.md), or machine mode",
              warned_line);
}

}  // namespace taxopt::pipeline
