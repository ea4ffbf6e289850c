#pragma once
/// @file A/C table-table kinematics: forward (paper eq. 12-14), inverse with both branches
/// (erratum of eq. 15, DESIGN.md section 4), rotation sense and the machine-mode convention
/// of CLI.md.

#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "taxopt/core/types.hpp"

namespace taxopt {

/// Machine rotary-axis values as written to the G-code, radians.
template <class S>
struct Pose {
  S a_rad = S(0);
  S c_rad = S(0);
};
using Posed = Pose<double>;

/// Range and sense of one rotary axis. Radians inside; the machine file is in degrees.
template <class S>
struct RotaryAxis {
  S min_rad = -std::numeric_limits<S>::infinity();
  S max_rad = std::numeric_limits<S>::infinity();
  /// A continuous axis (C on most tables) has no range: any multi-turn value is valid.
  bool continuous = false;
  /// +1: right-hand rotation as in eq. 12; -1: the machine turns the other way.
  int sense = 1;

  /// True when `value_rad` is within the range (with a tolerance of 1e-9 rad).
  bool contains(S value_rad) const {
    const S tol = S(1e-9);
    return continuous || (value_rad >= min_rad - tol && value_rad <= max_rad + tol);
  }
};

/// Kinematics of an A/C table-table machine: the tool axis in workpiece coordinates is
/// v = Rot(Z, s_C C) Rot(X, s_A A) [0 0 1]^T = (sin a sin c, -sin a cos c, cos a) with
/// a = s_A A and c = s_C C (eq. 14 for s = +1).
template <class S>
struct ACMachine {
  RotaryAxis<S> a;
  RotaryAxis<S> c;
  /// A point on the C axis (x, y, 0) and a point on the A axis (0, y, z), workpiece mm.
  Vec3<S> c_axis_point_mm = Vec3<S>::Zero();
  Vec3<S> a_axis_point_mm = Vec3<S>::Zero();
  /// Below this sin|A| the axis is on the pole A = 0, where every C gives the same axis.
  S pole_tolerance = S(1e-7);

  /// Tool axis for machine values (A, C). @param pose radians
  Vec3<S> forward(const Pose<S>& pose) const {
    const S ag = S(a.sense) * pose.a_rad, cg = S(c.sense) * pose.c_rad;
    return Vec3<S>(std::sin(ag) * std::sin(cg), -std::sin(ag) * std::cos(cg), std::cos(ag));
  }

  /// True when `axis` (unit) is on the pole, where C is free.
  bool at_pole(const Vec3<S>& axis) const {
    return std::hypot(axis.x(), axis.y()) < pole_tolerance && axis.z() > S(0);
  }

  /// Both inverse solutions of a unit axis, machine values, C in (-pi, pi]:
  /// [0] the branch a >= 0 (a = acos k, c = atan2(i, -j)),
  /// [1] the branch a <= 0 (a = -acos k, c = atan2(-i, j)) -- the corrected eq. 15.
  /// At the pole both have A = 0 and C = 0 (any C is valid there).
  std::array<Pose<S>, 2> inverse(const Vec3<S>& axis) const {
    const S k = std::max(S(-1), std::min(S(1), axis.z()));
    // atan2 of (sin, cos) keeps accuracy near the pole where acos(k) loses it.
    const S ag = std::atan2(std::hypot(axis.x(), axis.y()), k);
    S c_pos = std::atan2(axis.x(), -axis.y());
    S c_neg = std::atan2(-axis.x(), axis.y());
    if (at_pole(axis)) c_pos = c_neg = S(0);
    const S sa = S(a.sense), sc = S(c.sense);
    return {Pose<S>{sa * ag, wrap_pi(sc * c_pos)}, Pose<S>{-sa * ag, wrap_pi(sc * c_neg)}};
  }

  /// True when some pose of unit `axis` has A within its range and a turn of C within its
  /// range (on the pole any C will do).
  bool reachable(const Vec3<S>& axis) const {
    for (const Pose<S>& p : inverse(axis)) {
      if (!a.contains(p.a_rad)) continue;
      if (c.continuous || (at_pole(axis) && c.min_rad <= c.max_rad)) return true;
      for (int turn = -2; turn <= 2; ++turn) {
        if (c.contains(p.c_rad + S(turn) * Constants<S>::two_pi())) return true;
      }
    }
    return false;
  }

  /// Machine-mode joint position of a workpiece point for a pose (CLI.md):
  /// p_m = Rot(X, -a) (Rot(Z, -c) (p_w - c0) + c0 - a0) + a0.
  Vec3<S> to_machine_mm(const Vec3<S>& p_w_mm, const Pose<S>& pose) const {
    const S ag = S(a.sense) * pose.a_rad, cg = S(c.sense) * pose.c_rad;
    const Mat3<S> rz = Eigen::AngleAxis<S>(-cg, Vec3<S>::UnitZ()).toRotationMatrix();
    const Mat3<S> rx = Eigen::AngleAxis<S>(-ag, Vec3<S>::UnitX()).toRotationMatrix();
    return rx * (rz * (p_w_mm - c_axis_point_mm) + c_axis_point_mm - a_axis_point_mm) +
           a_axis_point_mm;
  }

  /// Inverse of to_machine_mm: the workpiece point at joint position p_m for a pose.
  Vec3<S> from_machine_mm(const Vec3<S>& p_m_mm, const Pose<S>& pose) const {
    const S ag = S(a.sense) * pose.a_rad, cg = S(c.sense) * pose.c_rad;
    const Mat3<S> rz = Eigen::AngleAxis<S>(cg, Vec3<S>::UnitZ()).toRotationMatrix();
    const Mat3<S> rx = Eigen::AngleAxis<S>(ag, Vec3<S>::UnitX()).toRotationMatrix();
    return rz * (rx * (p_m_mm - a_axis_point_mm) + a_axis_point_mm - c_axis_point_mm) +
           c_axis_point_mm;
  }
};
using ACMachined = ACMachine<double>;

/// The built-in generic A/C table-table machine of CLI.md: A in [-120, 120] deg, C continuous.
ACMachined default_ac_machine();

}  // namespace taxopt
