#pragma once
/// @file What the global method's dynamic programmes over candidate poses share
/// (candidate_sequence.cpp: the least rotary objective; fastest_sequence.cpp: the least time).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "taxopt/kinematics/machine_kinematics.hpp"
#include "taxopt/plan/global_optimiser.hpp"

namespace taxopt::detail {

/// Relative tolerance under which two objective values are equal (ties keep the earlier).
inline constexpr double kTie = 1e-12;

/// Degrees per radian (the programmes' accelerations are in deg/s^2).
inline constexpr double kRadToDeg = 180.0 / Constants<double>::pi();

/// An objective value: the peak a^2 and the sum of a^2 (deg^2/s^4). Which one orders values
/// depends on the objective; the other breaks ties.
struct RotaryValue {
  double peak_sq = 0.0, sum_sq = 0.0;
};

inline bool less(const RotaryValue& x, const RotaryValue& y, GlobalObjective objective) {
  if (objective == GlobalObjective::Peak) {
    if (x.peak_sq < y.peak_sq * (1.0 - kTie)) return true;
    if (x.peak_sq > y.peak_sq * (1.0 + kTie)) return false;
  }
  return x.sum_sq < y.sum_sq * (1.0 - kTie) - 1e-300;
}

inline double scalar(const RotaryValue& v, GlobalObjective objective) {
  return objective == GlobalObjective::Peak ? std::sqrt(v.peak_sq) : v.sum_sq;
}

/// The sequence of a pair programme (states: pairs of consecutive candidates, index r K + s)
/// from its best final state and back pointers: back[i][state at i - 1] is the candidate at
/// i - 2.
inline std::vector<std::size_t> backtrack(const std::vector<std::vector<Posed>>& candidates,
                                          const std::vector<std::vector<std::uint8_t>>& back,
                                          std::size_t best) {
  const std::size_t n = candidates.size(), kl = candidates[n - 1].size();
  std::vector<std::size_t> seq(n);
  seq[n - 1] = best % kl;
  seq[n - 2] = best / kl;
  for (std::size_t i = n - 1; i >= 2; --i) {
    const std::size_t kn = candidates[i].size();
    seq[i - 2] = back[i][seq[i - 1] * kn + seq[i]];
  }
  return seq;
}

}  // namespace taxopt::detail
