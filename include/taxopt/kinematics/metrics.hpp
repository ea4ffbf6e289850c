#pragma once
/// @file Rotary-axis kinematics of a pass (paper eq. 16-18, with the erratum of eq. 18:
/// the denominator is L_{i+1} + L_i, not T).
///
/// For a pass of n points with segment lengths L_i (point i to i+1) and feeds v_i:
///   t_i       = L_i / v_i                                   (segment time)
///   omega_i^G = (theta_{i+1}^G - theta_i^G) / t_i            (eq. 16, G = A or C)
///   a_i^G     = (omega_i^G - omega_{i-1}^G) / ((t_{i-1} + t_i) / 2)   at interior point i
/// With a constant feed v these are exactly eq. 16: omega = v (dtheta / L) and
/// a = 2 v (omega_i - omega_{i-1}) / (L_{i-1} + L_i). Synthetic values are
/// sqrt(x_A^2 + x_C^2) (eq. 17-18). omega is 0 at the last point, a at the first and last.
/// A segment of zero length that still turns the axes takes the time LinuxCNC gives it under
/// G94: the rotary distance (deg) divided by the feed read as deg/min.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"

namespace taxopt {

/// Per-point rotary kinematics of one pass, degree units as in the paper.
struct RotaryKinematics {
  std::vector<double> omega_tilt_deg_s, omega_c_deg_s, omega_deg_s;
  std::vector<double> accel_tilt_deg_s2, accel_c_deg_s2, accel_deg_s2;
};

/// One rotary axis's peaks (absolute values): a machine limits each axis on its own, and a
/// combined figure can fall while one axis rises.
struct AxisPeaks {
  double max_omega_deg_s = 0.0;
  double max_accel_deg_s2 = 0.0;
  /// RMS of a over the interior points.
  double rms_accel_deg_s2 = 0.0;
  double sum_sq_accel = 0.0;
};

/// Summary of the rotary kinematics of one or more passes.
struct RotarySummary {
  /// Synthetic sqrt(tilt^2 + C^2) (eq. 17-18), the paper's combined figure.
  double max_omega_deg_s = 0.0;
  double max_accel_deg_s2 = 0.0;
  /// Per axis: the tilt axis (A or B) and C.
  AxisPeaks tilt, c;
  double rms_accel_deg_s2 = 0.0;
  /// RMS of omega over the segments (every point but each pass's last).
  double rms_omega_deg_s = 0.0;
  /// Consecutive points whose C differs by more than 90 deg.
  int c_jumps = 0;
  /// Number of interior points that entered the RMS.
  std::size_t accel_samples = 0;
  double sum_sq_accel = 0.0;
  std::size_t omega_samples = 0;
  double sum_sq_omega = 0.0;
};

/// Segment times in seconds. @param length_mm n-1 segment lengths
/// @param feed_mm_per_min n-1 feeds (> 0) @param tilt_deg,c_deg n axis values
TAXOPT_API std::vector<double> segment_times_s(const std::vector<double>& length_mm,
                                               const std::vector<double>& feed_mm_per_min,
                                               const std::vector<double>& tilt_deg,
                                               const std::vector<double>& c_deg);

/// Rotary kinematics of one pass (eq. 16-18). All vectors of a pass: tilt_deg and c_deg have
/// n values, length_mm and feed_mm_per_min n-1.
TAXOPT_API RotaryKinematics rotary_kinematics(const std::vector<double>& tilt_deg,
                                              const std::vector<double>& c_deg,
                                              const std::vector<double>& length_mm,
                                              const std::vector<double>& feed_mm_per_min);

/// The same from the segment times t_i (n - 1, s) instead of lengths and feeds.
TAXOPT_API RotaryKinematics rotary_kinematics_from_times(const std::vector<double>& tilt_deg,
                                                         const std::vector<double>& c_deg,
                                                         const std::vector<double>& segment_time_s);

/// Peak synthetic omega (deg/s) and a (deg/s^2) of one pass.
struct PeakRates {
  double omega_deg_s = 0.0, accel_deg_s2 = 0.0;
};

/// Peaks of one pass given by its machine poses (radians, C unwound), n of them;
/// length_mm and feed_mm_per_min n-1 as for rotary_kinematics.
TAXOPT_API PeakRates peak_rates(const std::vector<Posed>& poses,
                                const std::vector<double>& length_mm,
                                const std::vector<double>& feed_mm_per_min);

/// Whether a rate rises above its bound: its magnitude more than a relative 1e-9 above
/// `bound` and above `still`, the rate under which an axis counts as still (0: none).
inline bool rate_above(double value, double bound, double still = 0.0) noexcept {
  return std::abs(value) > std::max(bound * (1.0 + 1e-9), still);
}

/// Whether no rotary axis's peak omega or a in `s` rises above `bound`'s (rate_above, with the
/// still rates of omega in deg/s and a in deg/s^2).
inline bool peaks_within(const RotarySummary& s, const RotarySummary& bound,
                         double still_omega_deg_s = 0.0, double still_accel_deg_s2 = 0.0) noexcept {
  return !rate_above(s.tilt.max_omega_deg_s, bound.tilt.max_omega_deg_s, still_omega_deg_s) &&
         !rate_above(s.c.max_omega_deg_s, bound.c.max_omega_deg_s, still_omega_deg_s) &&
         !rate_above(s.tilt.max_accel_deg_s2, bound.tilt.max_accel_deg_s2, still_accel_deg_s2) &&
         !rate_above(s.c.max_accel_deg_s2, bound.c.max_accel_deg_s2, still_accel_deg_s2);
}

/// Adds one pass to a summary (maxima, RMS of a over interior points, C jumps).
TAXOPT_API void accumulate(RotarySummary& summary, const RotaryKinematics& k,
                           const std::vector<double>& c_deg);

}  // namespace taxopt
