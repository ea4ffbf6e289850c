#pragma once
/// @file A/C table-table kinematics: forward (paper eq. 12-14), inverse with both branches
/// (erratum of eq. 15, DESIGN.md section 4), rotation sense and the machine-mode convention
/// of CLI.md.

#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "taxopt/core/export.hpp"
#include "taxopt/core/types.hpp"

namespace taxopt {

/// Machine rotary-axis values as written to the G-code, radians.
template <class S>
struct Pose {
  S tilt_rad = S(0);
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

/// The axis the tilting table turns about: X (an A/C machine, "ac-table-table") or Y (a B/C
/// machine, "bc-table-table": Haas UMC, Hermle, DMU eVo B/C). docs/kinematics.md.
enum class TiltAxis { X, Y };

/// Which rotary axes carry the workpiece and which the tool (docs/kinematics.md "Head
/// machines"):
/// - TableTable: the tilt and C both turn the table (ac-/bc-table-table);
/// - HeadTable: the head tilts the tool, the table turns the workpiece about C (a B head on a
///   C table: LinuxCNC's maxkins, "bc-head-table");
/// - HeadHead: both turn the tool, C about the vertical and the tilt in a fork (LinuxCNC's
///   5axiskins bridge mill, "bc-head-head").
/// The tool axis a pose gives in the workpiece is the same function in all three (the tilt
/// turns the tool relative to the C frame, C turns that frame relative to the workpiece), so
/// forward, inverse, branches and poles are shared; what differs is where the linear joints
/// stand (to_machine_mm): a head swings the tip about its pivot, `head_length_mm` away.
enum class RotaryLayout { TableTable, HeadTable, HeadHead };

/// Kinematics of a table-table machine whose table tilts about X (A) or Y (B) and turns about
/// Z (C). With t = s_T T (T the tilt axis's value, A or B) and c = s_C C the tool axis in
/// workpiece coordinates is
///   A/C: v = Rot(Z, c) Rot(X, t) [0 0 1]^T = (sin t sin c, -sin t cos c, cos t)  (eq. 14),
///   B/C: v = Rot(Z, c) Rot(Y, t) [0 0 1]^T = (sin t cos c,  sin t sin c, cos t)
/// (the convention of a real NX post for the Haas UMC-750, checked against its output:
/// tests/test_haas.cpp). The two differ only by the tilt axis (the B/C axis is the A/C axis at
/// C + 90 deg), so every stage that works in (tilt, C) works for both: `Pose::tilt_rad` is the
/// tilt axis's value (A or B), `tilt` its range and sense, `tilt_about` its direction,
/// `tilt_axis_point_mm` a point on it.
template <class S>
struct MachineKinematics {
  RotaryAxis<S> tilt;
  RotaryAxis<S> c;
  /// A point on the C axis (x, y, 0) and a point on the tilt axis: (0, y, z) for A, (x, 0, z)
  /// for B; workpiece mm.
  Vec3<S> c_axis_point_mm = Vec3<S>::Zero();
  Vec3<S> tilt_axis_point_mm = Vec3<S>::Zero();
  /// Below this sin|A| the axis is on the pole A = 0, where every C gives the same axis.
  S pole_tolerance = S(1e-7);
  TiltAxis tilt_about = TiltAxis::X;
  RotaryLayout layout = RotaryLayout::TableTable;
  /// A head (HeadTable, HeadHead): the distance from the tilt axis to the tool tip along the
  /// tool, mm: the head's pivot length plus the tool's gauge length (LinuxCNC's maxkins and
  /// 5axiskins: pivot-length plus the tool length offset). At tilt 0 the joints are the tip.
  S head_length_mm = S(0);

  /// The tilt axis's letter in G-code and reports: 'A' or 'B'.
  char tilt_letter() const { return tilt_about == TiltAxis::X ? 'A' : 'B'; }

  /// Tool axis for machine values (tilt, C). @param pose radians
  Vec3<S> forward(const Pose<S>& pose) const {
    const S ag = S(tilt.sense) * pose.tilt_rad, cg = S(c.sense) * pose.c_rad;
    if (tilt_about == TiltAxis::Y) {
      return Vec3<S>(std::sin(ag) * std::cos(cg), std::sin(ag) * std::sin(cg), std::cos(ag));
    }
    return Vec3<S>(std::sin(ag) * std::sin(cg), -std::sin(ag) * std::cos(cg), std::cos(ag));
  }

  /// True when `axis` (unit) is on the pole, where C is free.
  bool at_pole(const Vec3<S>& axis) const {
    return std::hypot(axis.x(), axis.y()) < pole_tolerance && axis.z() > S(0);
  }

  /// The angle of unit `axis` from the pole (Z), in [0, pi]: the magnitude of both inverse
  /// solutions' tilt. atan2 of (sin, cos) keeps accuracy near the pole where acos(z) loses it.
  static S tilt_from_pole(const Vec3<S>& axis) {
    const S k = std::max(S(-1), std::min(S(1), axis.z()));
    return std::atan2(std::hypot(axis.x(), axis.y()), k);
  }

  /// Both inverse solutions of a unit axis, machine values, C in (-pi, pi]:
  /// [0] the branch a >= 0 (a = acos k, A/C: c = atan2(i, -j); B/C: c = atan2(j, i)),
  /// [1] the branch a <= 0 (a = -acos k, A/C: c = atan2(-i, j); B/C: c = atan2(-j, -i)) --
  /// for A/C the corrected eq. 15. At the pole both have A = 0 and C = 0 (any C is valid there).
  std::array<Pose<S>, 2> inverse(const Vec3<S>& axis) const {
    const S ag = tilt_from_pole(axis);
    const bool y = tilt_about == TiltAxis::Y;
    S c_pos = y ? std::atan2(axis.y(), axis.x()) : std::atan2(axis.x(), -axis.y());
    S c_neg = y ? std::atan2(-axis.y(), -axis.x()) : std::atan2(-axis.x(), axis.y());
    if (at_pole(axis)) c_pos = c_neg = S(0);
    const S sa = S(tilt.sense), sc = S(c.sense);
    return {Pose<S>{sa * ag, wrap_pi(sc * c_pos)}, Pose<S>{-sa * ag, wrap_pi(sc * c_neg)}};
  }

  /// True when some pose of unit `axis` has A within its range and a turn of C within its
  /// range (on the pole any C will do).
  bool reachable(const Vec3<S>& axis) const {
    if (c.continuous) {
      // Any C will do: the tilts of inverse(axis) alone, without its C.
      const S tilt_rad = S(tilt.sense) * tilt_from_pole(axis);
      return tilt.contains(tilt_rad) || tilt.contains(-tilt_rad);
    }
    for (const Pose<S>& p : inverse(axis)) {
      if (!tilt.contains(p.tilt_rad)) continue;
      if (c.continuous || (at_pole(axis) && c.min_rad <= c.max_rad)) return true;
      for (int turn = -2; turn <= 2; ++turn) {
        if (c.contains(p.c_rad + S(turn) * Constants<S>::two_pi())) return true;
      }
    }
    return false;
  }

  /// The tilt axis's direction: X or Y.
  Vec3<S> tilt_direction() const {
    return tilt_about == TiltAxis::Y ? Vec3<S>::UnitY() : Vec3<S>::UnitX();
  }

  /// Joint position of a workpiece point (the tip) for a pose (CLI.md's machine-mode
  /// convention), with R_T the rotation about the tilt axis, v = forward(pose), L =
  /// head_length_mm:
  ///   TableTable: p_m = R_T(-t) (Rot(Z, -c) (p_w - c0) + c0 - t0) + t0;
  ///   HeadTable:  p_m = Rot(Z, -c) (p_w - c0) + c0 + L (Rot(Z, -c) v - z)  (maxkins);
  ///   HeadHead:   p_m = p_w + L (v - z)                                     (5axiskins).
  Vec3<S> to_machine_mm(const Vec3<S>& p_w_mm, const Pose<S>& pose) const {
    const S ag = S(tilt.sense) * pose.tilt_rad, cg = S(c.sense) * pose.c_rad;
    const Mat3<S> rz = Eigen::AngleAxis<S>(-cg, Vec3<S>::UnitZ()).toRotationMatrix();
    if (layout == RotaryLayout::HeadHead) return p_w_mm + head_swing_mm(pose);
    if (layout == RotaryLayout::HeadTable) {
      return rz * (p_w_mm - c_axis_point_mm) + c_axis_point_mm + rz * head_swing_mm(pose);
    }
    const Mat3<S> rt = Eigen::AngleAxis<S>(-ag, tilt_direction()).toRotationMatrix();
    return rt * (rz * (p_w_mm - c_axis_point_mm) + c_axis_point_mm - tilt_axis_point_mm) +
           tilt_axis_point_mm;
  }

  /// Inverse of to_machine_mm: the workpiece point at joint position p_m for a pose.
  Vec3<S> from_machine_mm(const Vec3<S>& p_m_mm, const Pose<S>& pose) const {
    const S ag = S(tilt.sense) * pose.tilt_rad, cg = S(c.sense) * pose.c_rad;
    const Mat3<S> rz = Eigen::AngleAxis<S>(cg, Vec3<S>::UnitZ()).toRotationMatrix();
    if (layout == RotaryLayout::HeadHead) return p_m_mm - head_swing_mm(pose);
    if (layout == RotaryLayout::HeadTable) {
      return rz * (p_m_mm - c_axis_point_mm) + c_axis_point_mm - head_swing_mm(pose);
    }
    const Mat3<S> rt = Eigen::AngleAxis<S>(ag, tilt_direction()).toRotationMatrix();
    return rz * (rt * (p_m_mm - tilt_axis_point_mm) + tilt_axis_point_mm - c_axis_point_mm) +
           c_axis_point_mm;
  }

  /// A head's offset of the joints from the tip in the workpiece frame, L (v - z): the tip
  /// swung about the pivot (zero at tilt 0).
  Vec3<S> head_swing_mm(const Pose<S>& pose) const {
    return head_length_mm * (forward(pose) - Vec3<S>::UnitZ());
  }
};
using MachineKinematicsd = MachineKinematics<double>;

/// The built-in generic A/C table-table machine of CLI.md: A in [-120, 120] deg, C continuous.
TAXOPT_API MachineKinematicsd default_machine_kinematics();

}  // namespace taxopt
