#include "taxopt/kinematics/machine.hpp"

#include <algorithm>

namespace taxopt {

const char* to_string(GcodeDialect dialect) {
  switch (dialect) {
    case GcodeDialect::LinuxCNC: return "linuxcnc";
    case GcodeDialect::Fanuc: return "fanuc";
    case GcodeDialect::Siemens: return "siemens";
    case GcodeDialect::Heidenhain: return "heidenhain";
    case GcodeDialect::Haas: return "haas";
  }
  return "?";
}

Machine default_machine() { return Machine{}; }

int max_decimals(GcodeDialect dialect) {
  switch (dialect) {
    case GcodeDialect::Fanuc:
    case GcodeDialect::Haas:
    case GcodeDialect::Heidenhain: return 4;
    default: return 8;
  }
}

int max_feed_decimals(GcodeDialect dialect) { return dialect == GcodeDialect::Heidenhain ? 3 : 15; }

int feed_decimals(const GcodeSettings& settings) {
  if (settings.feed_decimals >= 0) return settings.feed_decimals;
  return std::min(std::max(settings.decimals, 3), max_feed_decimals(settings.dialect));
}

JointLimits default_joint_limits() {
  JointLimits l;
  for (Joint j : {Joint::X, Joint::Y, Joint::Z})
    l[static_cast<std::size_t>(j)] = {500.0, 3000.0, 0.0};
  l[static_cast<std::size_t>(Joint::A)] = {150.0, 1000.0, 0.0};
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
