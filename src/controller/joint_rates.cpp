/// @file The joints of an A/C machine along a block: linearisation in machine mode, the
/// joint-safe rate of a TCP rapid.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "taxopt/io/gcode.hpp"

namespace taxopt {

std::vector<double> linearise_fractions(const MachineKinematicsd& machine, const Vec3d& from_tip_mm,
                                        const Posed& from, const Vec3d& to_tip_mm, const Posed& to,
                                        double tolerance_mm) {
  std::vector<double> at = {0.0, 1.0};
  if (!(tolerance_mm > 0.0)) return at;
  const Vec3d from_joint = machine.to_machine_mm(from_tip_mm, from);
  const Vec3d to_joint = machine.to_machine_mm(to_tip_mm, to);
  // Largest distance of the tip from the straight line between t0 and t1 while the joints
  // run linearly from their values at t0 to those at t1 (sampled; the deviation is smooth).
  const auto joints_at = [&](double t) {
    const Posed pose{from.tilt_rad + t * (to.tilt_rad - from.tilt_rad),
                     from.c_rad + t * (to.c_rad - from.c_rad)};
    const Vec3d xyz =
        (t == 0.0 || t == 1.0)
            ? (t == 0.0 ? from_joint : to_joint)
            : machine.to_machine_mm(from_tip_mm + t * (to_tip_mm - from_tip_mm), pose);
    return std::make_pair(xyz, pose);
  };
  const auto deviation = [&](double t0, double t1) {
    const auto [x0, p0] = joints_at(t0);
    const auto [x1, p1] = joints_at(t1);
    const Vec3d a = from_tip_mm + t0 * (to_tip_mm - from_tip_mm);
    const Vec3d b = from_tip_mm + t1 * (to_tip_mm - from_tip_mm);
    double worst = 0.0;
    constexpr int kSamples = 16;
    for (int s = 1; s < kSamples; ++s) {
      const double u = static_cast<double>(s) / kSamples;
      const Posed pose{p0.tilt_rad + u * (p1.tilt_rad - p0.tilt_rad),
                       p0.c_rad + u * (p1.c_rad - p0.c_rad)};
      const Vec3d tip = machine.from_machine_mm(x0 + u * (x1 - x0), pose);
      const Vec3d ab = b - a;
      const double len2 = ab.squaredNorm();
      const double w = len2 > 0.0 ? std::clamp((tip - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      worst = std::max(worst, (tip - (a + w * ab)).norm());
    }
    return worst;
  };
  // Halve every piece that deviates more than the tolerance, at most 2^12 pieces a move.
  for (int depth = 0; depth < 12; ++depth) {
    std::vector<double> next = {0.0};
    bool split = false;
    for (std::size_t j = 1; j < at.size(); ++j) {
      if (deviation(at[j - 1], at[j]) > tolerance_mm) {
        next.push_back(0.5 * (at[j - 1] + at[j]));
        split = true;
      }
      next.push_back(at[j]);
    }
    at.swap(next);
    if (!split) break;
  }
  return at;
}

std::pair<double, Joint> joint_velocity_rate_per_s(const MachineKinematicsd& ac,
                                                   const JointLimits& limits,
                                                   const Vec3d& from_tip_mm, const Posed& from,
                                                   const Vec3d& to_tip_mm, const Posed& to) {
  // With A and C held the joints are an affine map of the tip: they move linearly, and the
  // chord (the schedule's own model) is exact.
  const double turn_rad = std::hypot(to.tilt_rad - from.tilt_rad, to.c_rad - from.c_rad);
  if (turn_rad == 0.0) return {std::numeric_limits<double>::infinity(), Joint::X};
  // Steps of at most 0.25 deg of turn: the joints' rate of change varies by less than the
  // step's turn (in rad) relative within a step, which the margin below covers (an end's turn
  // home unwinds C by up to the turns the program made: 5,161 deg on a real NX file).
  const int steps =
      std::clamp(static_cast<int>(std::ceil(rad_to_deg(turn_rad) / 0.25)), 1, 1 << 20);
  double rate = std::numeric_limits<double>::infinity();
  Joint by = Joint::X;
  const Vec3d d = to_tip_mm - from_tip_mm;
  Vec3d prev = ac.to_machine_mm(from_tip_mm, from);
  for (int s = 1; s <= steps; ++s) {
    const double u = static_cast<double>(s) / steps;
    const Posed pose{from.tilt_rad + u * (to.tilt_rad - from.tilt_rad),
                     from.c_rad + u * (to.c_rad - from.c_rad)};
    const Vec3d q = ac.to_machine_mm(from_tip_mm + u * d, pose);
    for (std::size_t j = 0; j < 3; ++j) {
      const double v = limits[j].max_velocity_per_s;
      const auto e = static_cast<Eigen::Index>(j);
      const double dq = std::abs(q[e] - prev[e]) * steps;
      if (v > 0.0 && dq > 0.0 && v / dq < rate) {
        rate = v / dq;
        by = static_cast<Joint>(j);
      }
    }
    prev = q;
  }
  return {rate * (1.0 - 1e-3 - turn_rad / steps), by};
}

std::optional<double> joint_safe_rate_per_s(const MachineKinematicsd& ac, const JointLimits& limits,
                                            const Vec3d& from_tip_mm, const Posed& from,
                                            const Vec3d& to_tip_mm, const Posed& to) {
  const double da_deg = rad_to_deg(to.tilt_rad - from.tilt_rad);
  const double dc_deg = rad_to_deg(to.c_rad - from.c_rad);
  const Vec3d d = to_tip_mm - from_tip_mm;
  const double axis_delta[kJointCount] = {d.x(), d.y(), d.z(), da_deg, dc_deg};
  // The rapid's own rate: every axis within its velocity limit.
  double axis_rate = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < kJointCount; ++k) {
    const double v = limits[k].max_velocity_per_s;
    if (v > 0.0 && axis_delta[k] != 0.0)
      axis_rate = std::min(axis_rate, v / std::abs(axis_delta[k]));
  }
  if (!std::isfinite(axis_rate)) return std::nullopt;
  double joint_rate = joint_velocity_rate_per_s(ac, limits, from_tip_mm, from, to_tip_mm, to).first;
  if (da_deg == 0.0 && dc_deg == 0.0) {
    // A and C held: the joints are the tip turned with the table, each a straight line, which
    // the axes' limits do not bound where the table is tilted or turned (a rapid along a tilted
    // tool axis is the spindle's Z alone, up to 1/cos A faster than the program's Z; an XY
    // rapid with C at -150 deg drove joint Y at 511 mm/s against 500).
    const Vec3d dq = ac.to_machine_mm(to_tip_mm, to) - ac.to_machine_mm(from_tip_mm, from);
    for (std::size_t j = 0; j < 3; ++j) {
      const double v = limits[j].max_velocity_per_s;
      const double q = std::abs(dq[static_cast<Eigen::Index>(j)]);
      if (v > 0.0 && q > 0.0) joint_rate = std::min(joint_rate, v / q);
    }
    // Within the axes' own rate (a table not tilted: the joints are the axes): a rapid.
    if (!(joint_rate < axis_rate * (1.0 - 1e-6))) return std::nullopt;
    joint_rate *= 1.0 - 1e-3;
  }
  if (!(joint_rate < axis_rate)) return std::nullopt;
  return joint_rate;
}

}  // namespace taxopt
