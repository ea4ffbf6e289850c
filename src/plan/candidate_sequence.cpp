// The global method's programme over candidate poses for the rotary objectives
// (global_optimiser.hpp: best_candidate_sequence): states are pairs of consecutive candidates,
// K^3 work per point, the hot loop of --method global.
#include <algorithm>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "plan/candidate_paths.hpp"
#include "taxopt/plan/global_optimiser.hpp"

namespace taxopt {
namespace {

using detail::kRadToDeg;
using detail::less;
using detail::scalar;
using Value = detail::RotaryValue;

/// Candidates at points i - 1, i and i + 1 of one step of the programme.
struct Sizes3 {
  std::size_t before, here, next;
};

/// The rates (rad/s) of A and C of every pair of candidates of one segment, index r K + s.
struct PairRates {
  const std::vector<double>& a;
  const std::vector<double>& c;
};

/// The squared acceleration (deg/s^2)^2 between two segments' rates (rad/s) of A and C: each
/// change of rate times c, the centred second difference's 2 / (t_before + t_after) in deg.
double squared_step(double c, double da_rad_s, double dc_rad_s) {
  const double da = c * da_rad_s, dc = c * dc_rad_s;
  return da * da + dc * dc;
}

/// One step of the programme for any objective: the states (s, u) of point i + 1 from those
/// (r, s) of point i, `cost` replaced, `back` filled. The rule every step keeps: the first r
/// of the least value (`less`, ties within kTie keep the earlier).
void general_step(const Sizes3& k, double c, const PairRates& in, const PairRates& out,
                  GlobalObjective objective, std::vector<Value>& cost,
                  std::vector<std::uint8_t>& back) {
  std::vector<Value> next(k.here * k.next);
  for (std::size_t s = 0; s < k.here; ++s) {
    for (std::size_t u = 0; u < k.next; ++u) {
      const double a1 = out.a[s * k.next + u], c1 = out.c[s * k.next + u];
      Value best{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
      std::uint8_t arg = 0;
      for (std::size_t r = 0; r < k.before; ++r) {
        const double sq = squared_step(c, a1 - in.a[r * k.here + s], c1 - in.c[r * k.here + s]);
        const Value& before = cost[r * k.here + s];
        const Value v{std::max(before.peak_sq, sq), before.sum_sq + sq};
        if (less(v, best, objective)) best = v, arg = static_cast<std::uint8_t>(r);
      }
      next[s * k.next + u] = best;
      back[s * k.next + u] = arg;
    }
  }
  cost.swap(next);
}

/// The same step for the sum of squares, the default objective and the programme's hot loop
/// (K^3 per point), without general_step's branches: for each s, every u at once over r, the
/// least value, its first r and the second least. Where the least stands alone (the second
/// above the bound below) it is general_step's choice, else general_step's scan decides.
class SumSquaresStep {
 public:
  void run(const Sizes3& k, double c, const PairRates& in, const PairRates& out,
           std::vector<Value>& cost, std::vector<std::uint8_t>& back) {
    next_.assign(k.here * k.next, Value{});
    least_.resize(k.next);
    second_.resize(k.next);
    arg_.resize(k.next);
    for (std::size_t s = 0; s < k.here; ++s) {
      const double* a1 = out.a.data() + s * k.next;
      const double* c1 = out.c.data() + s * k.next;
      std::fill(least_.begin(), least_.end(), std::numeric_limits<double>::infinity());
      std::fill(second_.begin(), second_.end(), std::numeric_limits<double>::infinity());
      std::fill(arg_.begin(), arg_.end(), 0.0);
      for (std::size_t r = 0; r < k.before; ++r) {
        const double a0 = in.a[r * k.here + s], c0 = in.c[r * k.here + s];
        const double sum = cost[r * k.here + s].sum_sq, index = static_cast<double>(r);
        for (std::size_t u = 0; u < k.next; ++u) {
          const double v = value(c, sum, a1[u] - a0, c1[u] - c0);
          const double m = least_[u];
          const bool lower = v < m;
          second_[u] = std::min(second_[u], std::max(m, v));
          least_[u] = lower ? v : m;
          arg_[u] = lower ? index : arg_[u];
        }
      }
      for (std::size_t u = 0; u < k.next; ++u) {
        // general_step's scan ends on a value within [m, (m + 1e-300) / (1 - kTie)] of the
        // least m: one value alone within a wider bound is the scan's.
        const double bound = least_[u] * (1.0 + 4.0 * detail::kTie) + 1e-290;
        const std::size_t r = second_[u] > bound ? static_cast<std::size_t>(arg_[u])
                                                 : scan(k, c, in, cost, s, a1[u], c1[u]);
        next_[s * k.next + u].sum_sq =
            value(c, cost[r * k.here + s].sum_sq, a1[u] - in.a[r * k.here + s],
                  c1[u] - in.c[r * k.here + s]);
        back[s * k.next + u] = static_cast<std::uint8_t>(r);
      }
    }
    cost.swap(next_);
  }

 private:
  /// general_step's value of a predecessor: its sum plus the squared step.
  static double value(double c, double before, double da_rad_s, double dc_rad_s) {
    return before + squared_step(c, da_rad_s, dc_rad_s);
  }

  /// general_step's scan for one state (s, u).
  static std::size_t scan(const Sizes3& k, double c, const PairRates& in,
                          const std::vector<Value>& cost, std::size_t s, double a1, double c1) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t at = 0;
    for (std::size_t r = 0; r < k.before; ++r) {
      const double v = value(c, cost[r * k.here + s].sum_sq, a1 - in.a[r * k.here + s],
                             c1 - in.c[r * k.here + s]);
      if (less(Value{0.0, v}, Value{0.0, best}, GlobalObjective::SumSquares)) best = v, at = r;
    }
    return at;
  }

  std::vector<Value> next_;
  std::vector<double> least_, second_, arg_;
};

}  // namespace

std::vector<std::size_t> best_candidate_sequence(const std::vector<std::vector<Posed>>& candidates,
                                                 const std::vector<double>& segment_time_s,
                                                 GlobalObjective objective, double* value,
                                                 bool wrap_c) {
  const std::size_t n = candidates.size();
  if (n == 0) return {};
  if (segment_time_s.size() + 1 != n) {
    throw std::invalid_argument("best_candidate_sequence: n points need n - 1 segment times");
  }
  for (const auto& c : candidates) {
    if (c.empty() || c.size() > 255) {
      throw std::invalid_argument("best_candidate_sequence: 1 to 255 candidates per point");
    }
  }
  if (n <= 2) {
    if (value) *value = 0.0;
    return std::vector<std::size_t>(n, 0);
  }
  const auto& t = segment_time_s;
  // Rates (rad/s) of A and C of every pair of candidates of segment i; C steps wrapped.
  const auto rates = [&](std::size_t i, std::vector<double>& wa, std::vector<double>& wc) {
    const auto& p = candidates[i];
    const auto& q = candidates[i + 1];
    wa.resize(p.size() * q.size());
    wc.resize(p.size() * q.size());
    for (std::size_t r = 0; r < p.size(); ++r) {
      for (std::size_t s = 0; s < q.size(); ++s) {
        wa[r * q.size() + s] = (q[s].tilt_rad - p[r].tilt_rad) / t[i];
        const double step = q[s].c_rad - p[r].c_rad;
        wc[r * q.size() + s] = (wrap_c ? wrap_pi(step) : step) / t[i];
      }
    }
  };
  // State of point i: (candidate r at i - 1, candidate s at i), index r * K_i + s.
  std::vector<Value> cost(candidates[0].size() * candidates[1].size());
  std::vector<std::vector<std::uint8_t>> back(n);
  std::vector<double> wa0, wc0, wa1, wc1;
  SumSquaresStep sum_step;
  rates(0, wa0, wc0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    rates(i, wa1, wc1);
    const Sizes3 k{candidates[i - 1].size(), candidates[i].size(), candidates[i + 1].size()};
    const double c = kRadToDeg * 2.0 / (t[i - 1] + t[i]);
    back[i + 1].assign(k.here * k.next, 0);
    if (objective == GlobalObjective::SumSquares) {
      sum_step.run(k, c, {wa0, wc0}, {wa1, wc1}, cost, back[i + 1]);
    } else {
      general_step(k, c, {wa0, wc0}, {wa1, wc1}, objective, cost, back[i + 1]);
    }
    wa0.swap(wa1);
    wc0.swap(wc1);
  }
  // Best final state, then back through the pointers.
  std::size_t best = 0;
  for (std::size_t st = 1; st < cost.size(); ++st) {
    if (less(cost[st], cost[best], objective)) best = st;
  }
  if (value) *value = scalar(cost[best], objective);
  return detail::backtrack(candidates, back, best);
}

}  // namespace taxopt
