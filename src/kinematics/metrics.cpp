#include "taxopt/kinematics/metrics.hpp"

#include <algorithm>
#include <stdexcept>

namespace taxopt {

std::vector<double> segment_times_s(const std::vector<double>& length_mm,
                                    const std::vector<double>& feed_mm_per_min,
                                    const std::vector<double>& tilt_deg,
                                    const std::vector<double>& c_deg) {
  const std::size_t m = length_mm.size();
  if (feed_mm_per_min.size() != m || tilt_deg.size() != m + 1 || c_deg.size() != m + 1) {
    throw std::invalid_argument("segment_times_s: sizes do not match");
  }
  std::vector<double> t(m, 0.0);
  for (std::size_t i = 0; i < m; ++i) {
    if (!(feed_mm_per_min[i] > 0.0)) throw std::invalid_argument("segment_times_s: feed <= 0");
    const double per_s = feed_mm_per_min[i] / 60.0;
    if (length_mm[i] > 1e-9) {
      t[i] = length_mm[i] / per_s;
    } else {
      const double rot = std::hypot(tilt_deg[i + 1] - tilt_deg[i], c_deg[i + 1] - c_deg[i]);
      t[i] = rot / per_s;
    }
  }
  return t;
}

RotaryKinematics rotary_kinematics(const std::vector<double>& tilt_deg,
                                   const std::vector<double>& c_deg,
                                   const std::vector<double>& length_mm,
                                   const std::vector<double>& feed_mm_per_min) {
  const std::size_t n = tilt_deg.size();
  RotaryKinematics k;
  for (auto* v : {&k.omega_tilt_deg_s, &k.omega_c_deg_s, &k.omega_deg_s, &k.accel_tilt_deg_s2,
                  &k.accel_c_deg_s2, &k.accel_deg_s2}) {
    v->assign(n, 0.0);
  }
  if (n < 2) return k;
  return rotary_kinematics_from_times(tilt_deg, c_deg,
                                      segment_times_s(length_mm, feed_mm_per_min, tilt_deg, c_deg));
}

RotaryKinematics rotary_kinematics_from_times(const std::vector<double>& tilt_deg,
                                              const std::vector<double>& c_deg,
                                              const std::vector<double>& t) {
  const std::size_t n = tilt_deg.size();
  if (c_deg.size() != n || (n > 0 && t.size() + 1 != n)) {
    throw std::invalid_argument("rotary_kinematics_from_times: sizes do not match");
  }
  RotaryKinematics k;
  for (auto* v : {&k.omega_tilt_deg_s, &k.omega_c_deg_s, &k.omega_deg_s, &k.accel_tilt_deg_s2,
                  &k.accel_c_deg_s2, &k.accel_deg_s2}) {
    v->assign(n, 0.0);
  }
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (t[i] > 0.0) {
      k.omega_tilt_deg_s[i] = (tilt_deg[i + 1] - tilt_deg[i]) / t[i];
      k.omega_c_deg_s[i] = (c_deg[i + 1] - c_deg[i]) / t[i];
    }
    k.omega_deg_s[i] = std::hypot(k.omega_tilt_deg_s[i], k.omega_c_deg_s[i]);
  }
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double dt = 0.5 * (t[i - 1] + t[i]);
    if (dt > 0.0) {
      k.accel_tilt_deg_s2[i] = (k.omega_tilt_deg_s[i] - k.omega_tilt_deg_s[i - 1]) / dt;
      k.accel_c_deg_s2[i] = (k.omega_c_deg_s[i] - k.omega_c_deg_s[i - 1]) / dt;
    }
    k.accel_deg_s2[i] = std::hypot(k.accel_tilt_deg_s2[i], k.accel_c_deg_s2[i]);
  }
  return k;
}

PeakRates peak_rates(const std::vector<Posed>& poses, const std::vector<double>& length_mm,
                     const std::vector<double>& feed_mm_per_min) {
  std::vector<double> a, c;
  for (const Posed& p : poses) {
    a.push_back(rad_to_deg(p.tilt_rad));
    c.push_back(rad_to_deg(p.c_rad));
  }
  const RotaryKinematics k = rotary_kinematics(a, c, length_mm, feed_mm_per_min);
  PeakRates out;
  for (double w : k.omega_deg_s) out.omega_deg_s = std::max(out.omega_deg_s, w);
  for (double x : k.accel_deg_s2) out.accel_deg_s2 = std::max(out.accel_deg_s2, x);
  return out;
}

void accumulate(RotarySummary& s, const RotaryKinematics& k, const std::vector<double>& c_deg) {
  const std::size_t n = k.omega_deg_s.size();
  for (std::size_t i = 0; i < n; ++i) {
    s.max_omega_deg_s = std::max(s.max_omega_deg_s, k.omega_deg_s[i]);
    s.max_accel_deg_s2 = std::max(s.max_accel_deg_s2, k.accel_deg_s2[i]);
    s.tilt.max_omega_deg_s = std::max(s.tilt.max_omega_deg_s, std::abs(k.omega_tilt_deg_s[i]));
    s.c.max_omega_deg_s = std::max(s.c.max_omega_deg_s, std::abs(k.omega_c_deg_s[i]));
    s.tilt.max_accel_deg_s2 = std::max(s.tilt.max_accel_deg_s2, std::abs(k.accel_tilt_deg_s2[i]));
    s.c.max_accel_deg_s2 = std::max(s.c.max_accel_deg_s2, std::abs(k.accel_c_deg_s2[i]));
    if (i + 1 < n) {
      s.sum_sq_omega += k.omega_deg_s[i] * k.omega_deg_s[i];
      ++s.omega_samples;
    }
    if (i > 0 && i + 1 < n) {
      s.sum_sq_accel += k.accel_deg_s2[i] * k.accel_deg_s2[i];
      s.tilt.sum_sq_accel += k.accel_tilt_deg_s2[i] * k.accel_tilt_deg_s2[i];
      s.c.sum_sq_accel += k.accel_c_deg_s2[i] * k.accel_c_deg_s2[i];
      ++s.accel_samples;
    }
    if (i > 0 && std::abs(c_deg[i] - c_deg[i - 1]) > 90.0) ++s.c_jumps;
  }
  s.rms_accel_deg_s2 =
      s.accel_samples ? std::sqrt(s.sum_sq_accel / static_cast<double>(s.accel_samples)) : 0.0;
  for (AxisPeaks* axis : {&s.tilt, &s.c}) {
    axis->rms_accel_deg_s2 =
        s.accel_samples ? std::sqrt(axis->sum_sq_accel / static_cast<double>(s.accel_samples))
                        : 0.0;
  }
  s.rms_omega_deg_s =
      s.omega_samples ? std::sqrt(s.sum_sq_omega / static_cast<double>(s.omega_samples)) : 0.0;
}

}  // namespace taxopt
