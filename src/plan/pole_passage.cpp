#include "plan/pole_passage.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "taxopt/kinematics/metrics.hpp"

namespace taxopt {
namespace {

enum class Shape { Linear, Hermite };

/// Poses with C re-planned in every stretch of |A| < rho whose new axes are all acceptable;
/// `stretches` counts those.
std::vector<Posed> replan(const MachineKinematicsd& machine, const std::vector<Posed>& poses,
                          const std::vector<double>& arc_mm, const AxisTest& acceptable,
                          double rho_rad, Shape shape, std::size_t& stretches) {
  const std::size_t n = poses.size();
  std::vector<Posed> out = poses;
  stretches = 0;
  // Rate of C (rad/mm) on the move from point i to i + 1.
  const auto rate = [&](std::size_t i) {
    const double ds = arc_mm[i + 1] - arc_mm[i];
    return ds > 0.0 ? (poses[i + 1].c_rad - poses[i].c_rad) / ds : 0.0;
  };
  std::size_t b = 0;
  while (b < n) {
    if (std::abs(poses[b].tilt_rad) >= rho_rad) {
      ++b;
      continue;
    }
    std::size_t e = b;  // the stretch is [b, e)
    while (e < n && std::abs(poses[e].tilt_rad) < rho_rad) ++e;
    const bool has_before = b > 0, has_after = e < n;
    if (has_before || has_after) {
      // C and its rate at the two anchors; an end of the pass holds its one neighbour's C.
      const double c0 = has_before ? poses[b - 1].c_rad : poses[e].c_rad;
      const double c1 = has_after ? poses[e].c_rad : poses[b - 1].c_rad;
      const double s0 = has_before ? arc_mm[b - 1] : arc_mm[b];
      const double s1 = has_after ? arc_mm[e] : arc_mm[e - 1];
      const double m0 = has_before && b >= 2 ? rate(b - 2) : 0.0;
      const double m1 = has_after && e + 1 < n ? rate(e) : 0.0;
      const double h = s1 - s0;
      bool ok = true;
      std::vector<Posed> trial(poses.begin() + static_cast<long>(b),
                               poses.begin() + static_cast<long>(e));
      for (std::size_t i = b; i < e && ok; ++i) {
        const double t = h > 0.0 ? (arc_mm[i] - s0) / h : 0.5;
        double c = c0 + t * (c1 - c0);
        if (shape == Shape::Hermite) {
          const double t2 = t * t, t3 = t2 * t;
          c = (2 * t3 - 3 * t2 + 1) * c0 + (t3 - 2 * t2 + t) * h * m0 + (-2 * t3 + 3 * t2) * c1 +
              (t3 - t2) * h * m1;
        }
        trial[i - b].c_rad = c;
        ok = acceptable(i, machine.forward(trial[i - b]));
      }
      if (ok) {
        std::copy(trial.begin(), trial.end(), out.begin() + static_cast<long>(b));
        ++stretches;
      }
    }
    b = e;
  }
  return out;
}

}  // namespace

PolePassage smooth_pole_passages(const MachineKinematicsd& machine, const std::vector<Vec3d>& axes,
                                 const std::vector<Posed>& poses,
                                 const std::vector<double>& segment_mm,
                                 const std::vector<double>& feed_mm_min, const AxisTest& acceptable,
                                 const PolePassageOptions& options) {
  const std::size_t n = poses.size();
  if (axes.size() != n || (n > 0 && (segment_mm.size() != n - 1 || feed_mm_min.size() != n - 1))) {
    throw std::invalid_argument("smooth_pole_passages: sizes do not match");
  }
  PolePassage best;
  best.poses = poses;
  best.axes = axes;
  if (n < 3) return best;
  std::vector<double> arc(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) arc[i] = arc[i - 1] + segment_mm[i - 1];

  const PeakRates p0 = peak_rates(poses, segment_mm, feed_mm_min);
  best.omega_before_deg_s = best.omega_after_deg_s = p0.omega_deg_s;
  best.accel_before_deg_s2 = best.accel_after_deg_s2 = p0.accel_deg_s2;
  if (!(p0.omega_deg_s > 0.0) || !(p0.accel_deg_s2 > 0.0)) return best;
  double best_score = 2.0;  // the unchanged pass: 1 + 1
  for (double rho_deg : options.radii_deg) {
    for (Shape shape : {Shape::Linear, Shape::Hermite}) {
      std::size_t stretches = 0;
      std::vector<Posed> trial =
          replan(machine, poses, arc, acceptable, deg_to_rad(rho_deg), shape, stretches);
      if (stretches == 0) continue;
      const PeakRates p = peak_rates(trial, segment_mm, feed_mm_min);
      if (p.omega_deg_s > p0.omega_deg_s || p.accel_deg_s2 > p0.accel_deg_s2) continue;
      const double score = p.omega_deg_s / p0.omega_deg_s + p.accel_deg_s2 / p0.accel_deg_s2;
      if (!(score < best_score - 1e-12)) continue;
      best_score = score;
      best.poses = std::move(trial);
      best.stretches = stretches;
      best.radius_deg = rho_deg;
      best.omega_after_deg_s = p.omega_deg_s;
      best.accel_after_deg_s2 = p.accel_deg_s2;
      best.hermite = shape == Shape::Hermite;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (best.poses[i].c_rad != poses[i].c_rad) best.axes[i] = machine.forward(best.poses[i]);
  }
  return best;
}

}  // namespace taxopt
