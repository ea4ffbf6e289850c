#include "plan/air_turn.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace taxopt {

double rest_to_rest_reach(double time_s, const JointLimit& limit) {
  const double v = limit.max_velocity_per_s, a = limit.max_accel_per_s2;
  if (!(v > 0.0) || !(a > 0.0)) return std::numeric_limits<double>::infinity();
  if (!(time_s > 0.0)) return 0.0;
  return time_s >= 2.0 * v / a ? v * (time_s - v / a) : 0.25 * a * time_s * time_s;
}

std::vector<double> spread_turn(const std::vector<double>& linear_time_s,
                                const std::vector<bool>& rapid, double turn_a_deg,
                                double turn_c_deg, const JointLimits& limits) {
  const std::size_t m = linear_time_s.size();
  if (rapid.size() != m) throw std::invalid_argument("spread_turn: one flag per move");
  if (std::abs(turn_a_deg) + std::abs(turn_c_deg) < 1e-12) return {};
  const JointLimit& la = limits[static_cast<std::size_t>(Joint::Tilt)];
  const JointLimit& lc = limits[static_cast<std::size_t>(Joint::C)];
  std::vector<double> capacity(m, 0.0);
  double total = 0.0;
  bool unlimited = false;
  for (std::size_t k = 0; k < m; ++k) {
    if (!rapid[k]) continue;
    double c = std::numeric_limits<double>::infinity();
    if (std::abs(turn_a_deg) > 0.0) {
      c = std::min(c, rest_to_rest_reach(linear_time_s[k], la) / std::abs(turn_a_deg));
    }
    if (std::abs(turn_c_deg) > 0.0) {
      c = std::min(c, rest_to_rest_reach(linear_time_s[k], lc) / std::abs(turn_c_deg));
    }
    unlimited = unlimited || std::isinf(c);
    capacity[k] = c;
    if (!std::isinf(c)) total += c;
  }
  if (unlimited) {
    // A joint without limits turns in no time: the rapids share the turn alike.
    total = 0.0;
    for (std::size_t k = 0; k < m; ++k) {
      capacity[k] = rapid[k] ? 1.0 : 0.0;
      total += capacity[k];
    }
  }
  if (!(total > 0.0)) return {};
  std::vector<double> share(m, 0.0);
  for (std::size_t k = 0; k < m; ++k) share[k] = capacity[k] / total;
  return share;
}

std::vector<double> best_turn_shares(
    const std::vector<std::vector<double>>& starts, const std::vector<bool>& may_turn,
    const std::function<double(const std::vector<double>&)>& time_of) {
  std::vector<double> best;
  double best_s = std::numeric_limits<double>::infinity();
  for (const std::vector<double>& start : starts) {
    if (start.size() != may_turn.size()) throw std::invalid_argument("best_turn_shares: sizes");
    std::vector<double> s = start;
    double t = time_of(s);
    for (double step = 0.5; step >= 1.0 / 256.0; step *= 0.5) {
      for (int round = 0; round < 8; ++round) {
        bool improved = false;
        for (std::size_t p = 0; p < s.size(); ++p) {
          for (std::size_t q = 0; q < s.size(); ++q) {
            if (p == q || !may_turn[p] || !may_turn[q] || !(s[p] > 0.0)) continue;
            std::vector<double> trial = s;
            const double d = std::min(step, s[p]);
            trial[p] -= d;
            trial[q] += d;
            const double tt = time_of(trial);
            if (tt < t - 1e-9) {
              s = std::move(trial);
              t = tt;
              improved = true;
            }
          }
        }
        if (!improved) break;
      }
    }
    if (t < best_s) best = s, best_s = t;
  }
  return best;
}

}  // namespace taxopt
