#pragma once
/// @file One-way parallel (raster) finishing passes on a parametric surface for a ball-end
/// mill (paper section 2.1): side step from the scallop height (eq. 8 convex, eq. 9 concave,
/// flat: 2 sqrt(2 h R)), step length from the chord error (eq. 10, L = 2 sqrt(e (2 rho - e))),
/// tool axis from a fixed tilt and yaw (eq. 11), tip from the contact point (eq. 5).
///
/// Passes run along the surface's v direction (feed direction T = S_v / |S_v|) at constant u,
/// every pass from v_min to v_max, with a retract to a safe plane and rapids between them.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "taxopt/geometry/surface.hpp"

namespace taxopt {

/// Options of the raster generator (lengths mm, angles deg), with the paper's values.
struct RasterOptions {
  double tool_radius_mm = 3.0;
  double scallop_mm = 0.02;
  /// Not given by the paper; 0.05 mm makes the sine case's first step turn the axis by
  /// about 18 deg, as the paper's table does (19.2 -> 37.3 deg).
  double chord_error_mm = 0.05;
  double tilt_deg = 5.0;
  double yaw_deg = 0.0;
  /// Longest step along a pass (where the surface is flat along the feed).
  double max_step_mm = 2.0;
  /// Retract along the axis after a pass, and height of the safe plane above the part.
  double clearance_mm = 10.0;
};

/// A generated cutter location with the geometry it was made from (ground truth for tests).
struct GeneratedPoint {
  Vec3d tip_mm, axis;
  Vec3d cc_mm, normal;  // contact point and surface normal (feed moves only)
  double tilt_deg = 0.0, yaw_deg = 0.0;
  bool rapid = false;
  /// The concave principal radius at the contact point is below R (local gouge, eq. 19).
  bool gouges = false;
};

/// Tool axis for tilt and yaw (eq. 11): V = Rot(N, yaw) Rot(K, tilt) N, K = N x T.
/// A positive tilt leans the axis towards the feed direction T.
inline Vec3d axis_from_tilt_yaw(const Vec3d& n, const Vec3d& t, double tilt_rad, double yaw_rad) {
  const Vec3d k = n.cross(t);
  return Eigen::AngleAxisd(yaw_rad, n) * (Eigen::AngleAxisd(tilt_rad, k) * n);
}

/// Generates the passes. @throws std::invalid_argument for non-positive tool, scallop or
/// chord error, or a concave radius so small that eq. 9 has no side step.
template <class Surface>
std::vector<GeneratedPoint> generate_raster(const Surface& s, const RasterOptions& o) {
  const double R = o.tool_radius_mm;
  if (!(R > 0.0) || !(o.scallop_mm > 0.0) || !(o.chord_error_mm > 0.0) || !(o.max_step_mm > 0.0)) {
    throw std::invalid_argument(
        "raster: tool radius, scallop, chord error and step must be positive");
  }
  const double tilt = deg_to_rad(o.tilt_deg), yaw = deg_to_rad(o.yaw_deg);
  const double flat_side_step = 2.0 * std::sqrt(2.0 * o.scallop_mm * R);
  // Safe plane above the whole part.
  double z_top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 50; ++i) {
    for (int j = 0; j <= 200; ++j) {
      const double u = s.u_min() + (s.u_max() - s.u_min()) * i / 50.0;
      const double v = s.v_min() + (s.v_max() - s.v_min()) * j / 200.0;
      z_top = std::max(z_top, s.jet(u, v).p.z());
    }
  }
  const double z_safe = z_top + R + o.clearance_mm;

  std::vector<GeneratedPoint> out;
  double u = s.u_min();
  for (;;) {
    std::vector<GeneratedPoint> pass;
    double side_step = flat_side_step;
    double v = s.v_min();
    double su_norm = 1.0;
    for (;;) {
      const SurfaceJet<double> j = s.jet(u, v);
      const Vec3d n = unit_normal(j);
      const Vec3d t = j.sv.normalized();
      const PrincipalCurvatures<double> pc = principal_curvatures(j);
      GeneratedPoint g;
      g.cc_mm = j.p;
      g.normal = n;
      g.axis = axis_from_tilt_yaw(n, t, tilt, yaw);
      g.tip_mm = j.p + R * n - R * g.axis;
      g.tilt_deg = o.tilt_deg;
      g.yaw_deg = o.yaw_deg;
      g.gouges = pc.k1 > 0.0 && 1.0 / pc.k1 < R;
      pass.push_back(g);
      // Side step across the path (eq. 8 / 9), smallest along the pass.
      const double k_across = normal_curvature(pc, n.cross(t));
      double L = flat_side_step;
      if (k_across < -1e-12) {
        const double rho = -1.0 / k_across;
        L = flat_side_step * rho / (rho + R);
      } else if (k_across > 1e-12) {
        const double rho = 1.0 / k_across;
        if (rho <= R) throw std::invalid_argument("raster: concave radius across the path below R");
        L = flat_side_step * rho / (rho - R);
      }
      side_step = std::min(side_step, L);
      su_norm = std::max(su_norm, j.su.norm());
      if (v >= s.v_max()) break;
      // Step along the path from the chord error (eq. 10), with the curvature of both ends
      // of the step, then shortened until the chord really is that long.
      const auto step_for = [&](const PrincipalCurvatures<double>& c) {
        const double k = std::abs(normal_curvature(c, t));
        double st = o.max_step_mm;
        if (k > 1e-12 && o.chord_error_mm < 1.0 / k) {
          st = std::min(st, 2.0 * std::sqrt(o.chord_error_mm * (2.0 / k - o.chord_error_mm)));
        }
        return st;
      };
      double step = step_for(pc);
      double dv = step / j.sv.norm();
      for (int it = 0; it < 20; ++it) {
        const double v_next = std::min(s.v_max(), v + dv);
        const SurfaceJet<double> jn = s.jet(u, v_next);
        step = std::min(step, step_for(principal_curvatures(jn)));
        const double chord = (jn.p - j.p).norm();
        if (chord <= step * (1.0 + 1e-9) || v_next <= v) break;
        dv *= 0.98 * step / chord;
      }
      v = std::min(s.v_max(), v + dv);
    }
    // Approach from the safe plane along the first axis, retract along the last.
    GeneratedPoint up = pass.front();
    up.rapid = true;
    up.tip_mm = Vec3d(up.tip_mm.x(), up.tip_mm.y(), z_safe);
    out.push_back(up);
    GeneratedPoint approach = pass.front();
    approach.rapid = true;
    approach.tip_mm += o.clearance_mm * approach.axis;
    out.push_back(approach);
    out.insert(out.end(), pass.begin(), pass.end());
    GeneratedPoint retract = pass.back();
    retract.rapid = true;
    retract.tip_mm += o.clearance_mm * retract.axis;
    out.push_back(retract);
    retract.tip_mm = Vec3d(retract.tip_mm.x(), retract.tip_mm.y(), z_safe);
    out.push_back(retract);
    if (u >= s.u_max()) break;
    u = std::min(s.u_max(), u + side_step / su_norm);
  }
  return out;
}

}  // namespace taxopt
