#pragma once
/// @file Passages near the pole A = 0 of an A/C machine, re-planned in machine space.
///
/// On the pole every C gives the same tool axis; near it a small turn of the axis is a large
/// turn of C: a path of axes that passes the pole at a distance delta turns C by up to 180 deg
/// over a path of the order of delta, however smooth it is on the sphere. The paper's slerp
/// is smooth on the sphere and does not see this (it is a singularity of the machine, not of
/// the tool axis). The remedy is the one of Affouard et al. (2004), in machine space: in a
/// stretch of consecutive points with |A| < rho, C is re-planned in arc length between the C
/// of the points on either side of the stretch, A is kept. Two shapes: linear (the least
/// integral of omega_C^2 between the end values) and the cubic Hermite with the end values and
/// the rates of C just outside the stretch (the least integral of a_C^2 with those: no jump of
/// the rate at either end). An axis then turns by
/// 2 asin(|sin A| |sin(dC/2)|) <= 2 |A| < 2 rho, whatever the change dC of C. Where the stretch
/// reaches an end of the pass, that end takes the C of the stretch's one neighbour, with rate
/// 0 (the linear shape holds C there). A stretch keeps
/// its new C only when every new axis is acceptable (cone, machine, collision).
///
/// rho and the shape are chosen per pass from a ladder of radii: the pair whose result has the
/// lowest peak omega / peak omega_0 + peak a / peak a_0 (synthetic, eq. 16-18 corrected), among
/// those that raise neither peak; ties to the smaller radius. Deterministic.

#include <cstddef>
#include <vector>

#include "taxopt/kinematics/machine_kinematics.hpp"
#include "taxopt/plan/paper_optimiser.hpp"

namespace taxopt {

/// Options of smooth_pole_passages.
struct PolePassageOptions {
  /// Radii rho tried, deg, ascending.
  std::vector<double> radii_deg = {0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0};
};

/// Outcome of smooth_pole_passages.
struct PolePassage {
  /// The poses and axes of the pass afterwards (the input ones where nothing changed).
  std::vector<Posed> poses;
  std::vector<Vec3d> axes;
  /// Stretches re-planned, the radius chosen, deg (0: none), and whether with the cubic
  /// Hermite shape (else linear).
  std::size_t stretches = 0;
  double radius_deg = 0.0;
  bool hermite = false;
  /// Peak synthetic omega (deg/s) and a (deg/s^2) of the pass before and after.
  double omega_before_deg_s = 0.0, accel_before_deg_s2 = 0.0;
  double omega_after_deg_s = 0.0, accel_after_deg_s2 = 0.0;
};

/// Re-plans C near the pole along one pass.
/// @param machine     the machine (forward kinematics of the new poses)
/// @param axes        the unit tool axes of the pass's n points (kept where C is kept)
/// @param poses       their continuous poses (C unwrapped), n
/// @param segment_mm  path length from point i to i + 1, n - 1
/// @param feed_mm_min feed of the move from point i to i + 1, n - 1 (the metrics' feed)
/// @param acceptable  whether an axis is acceptable at point i of the pass
PolePassage smooth_pole_passages(const MachineKinematicsd& machine, const std::vector<Vec3d>& axes,
                                 const std::vector<Posed>& poses,
                                 const std::vector<double>& segment_mm,
                                 const std::vector<double>& feed_mm_min, const AxisTest& acceptable,
                                 const PolePassageOptions& options = {});

}  // namespace taxopt
