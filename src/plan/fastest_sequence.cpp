// --objective time's dynamic programme: the candidate poses whose scheduled pass is the
// fastest (global_optimiser.hpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "plan/candidate_paths.hpp"
#include "taxopt/kinematics/metrics.hpp"
#include "taxopt/plan/global_optimiser.hpp"

namespace taxopt {
namespace {

using detail::kRadToDeg;

/// The time objective's surrogate: the share of a segment's stretch charged to each of its
/// ends (docs/global-method.md measures the choice).
constexpr double kStretchShare = 0.5;

using detail::kTie;

}  // namespace

namespace {

/// The dynamic programme of fastest_candidate_sequence: its states are the pairs of
/// candidates of a segment, its cost a surrogate of the scheduled time.
class FastestSequence {
 public:
  FastestSequence(const std::vector<std::vector<Posed>>& candidates,
                  const std::vector<std::vector<JointPosition>>& joints,
                  const std::vector<double>& programmed_time_s,
                  const std::vector<double>& segment_time_s, const JointLimits& limits, bool wrap_c)
      : candidates_(candidates),
        joints_(joints),
        programmed_time_s_(programmed_time_s),
        t_(segment_time_s),
        wrap_c_(wrap_c) {
    // Velocity limits with the schedule's margin; reciprocal acceleration limits (0: none).
    for (std::size_t j = 0; j < kJointCount; ++j) {
      v_max_[j] = limits[j].max_velocity_per_s * (1.0 - ScheduleOptions{}.margin);
      inv_a_[j] = limits[j].max_accel_per_s2 > 0.0
                      ? 1.0 / (limits[j].max_accel_per_s2 * (1.0 - ScheduleOptions{}.margin))
                      : 0.0;
    }
  }

  std::vector<std::size_t> run(double* surrogate_s) {
    const std::size_t n = candidates_.size();
    std::vector<Pair> seg0, seg1;
    pairs(0, seg0);
    std::vector<Cost> cost(seg0.size());
    for (std::size_t st = 0; st < seg0.size(); ++st) {
      cost[st].time_s = seg0[st].tau + point_extra(nullptr, &seg0[st]);
    }
    std::vector<std::vector<std::uint8_t>> back(n);
    for (std::size_t i = 1; i + 1 < n; ++i) {
      pairs(i, seg1);
      step(i, seg0, seg1, cost, back[i + 1]);
      seg0.swap(seg1);
    }
    // The stop at the end (the states are the last segment's pairs, in the same order).
    for (std::size_t st = 0; st < cost.size(); ++st) {
      cost[st].time_s += point_extra(&seg0[st], nullptr);
    }
    std::size_t best = 0;
    for (std::size_t st = 1; st < cost.size(); ++st) {
      if (better(cost[st], cost[best])) best = st;
    }
    if (surrogate_s) *surrogate_s = cost[best].time_s;
    return detail::backtrack(candidates_, back, best);
  }

 private:
  /// A pair of candidates of segment i: its surrogate time, the joint velocities at that
  /// time, and the rotary rates (rad/s) at the metrics' time for the tie-breaker. `quiet`:
  /// every joint could start or stop within half the segment's time (2 |w_j| / tau <= A_j);
  /// between two quiet segments no acceleration binds (the change of velocity is at most the
  /// sum of the two, within the mean time), so a point between them adds nothing.
  struct Pair {
    double tau;
    std::array<double, kJointCount> w;
    double wa, wc;
    bool quiet;
  };
  struct Cost {
    double time_s = 0.0, sum_sq = 0.0;
  };

  static bool better(const Cost& x, const Cost& y) {
    if (x.time_s < y.time_s * (1.0 - 1e-9)) return true;
    if (x.time_s > y.time_s * (1.0 + 1e-9)) return false;
    return x.sum_sq < y.sum_sq * (1.0 - kTie) - 1e-300;
  }

  /// Every pair of candidates of segment i, the first point's candidate major.
  void pairs(std::size_t i, std::vector<Pair>& out) const {
    constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
    const auto& p = candidates_[i];
    const auto& q = candidates_[i + 1];
    out.resize(p.size() * q.size());
    for (std::size_t r = 0; r < p.size(); ++r) {
      for (std::size_t s = 0; s < q.size(); ++s) {
        Pair& e = out[r * q.size() + s];
        std::array<double, kJointCount> dq{};
        double tau = std::max(programmed_time_s_[i], 1e-9);
        for (std::size_t j = 0; j < kJointCount; ++j) {
          dq[j] = joints_[i + 1][s][j] - joints_[i][r][j];
          if (j == kC && wrap_c_) dq[j] = std::remainder(dq[j], 360.0);
          if (v_max_[j] > 0.0) tau = std::max(tau, std::abs(dq[j]) / v_max_[j]);
        }
        e.tau = tau;
        double fastest = 0.0;  // largest |w_j| / A_j
        for (std::size_t j = 0; j < kJointCount; ++j) {
          e.w[j] = dq[j] / tau;
          fastest = std::max(fastest, std::abs(e.w[j]) * inv_a_[j]);
        }
        e.quiet = 2.0 * fastest <= tau;
        e.wa = (q[s].tilt_rad - p[r].tilt_rad) / t_[i];
        const double step = q[s].c_rad - p[r].c_rad;
        e.wc = (wrap_c_ ? wrap_pi(step) : step) / t_[i];
      }
    }
  }

  /// What a point adds: the least uniform stretch of its segments that meets the schedule's
  /// inner set there (feed_schedule.hpp: the change of velocity within the mean time where a
  /// joint keeps its direction; where it reverses, starts or stops, each side within half its
  /// own time), at kStretchShare of its time (each segment has two ends). `before` null: the
  /// start from rest; `after` null: the stop.
  double point_extra(const Pair* before, const Pair* after) const {
    double both = 0.0, side_before = 0.0, side_after = 0.0;  // largest |a_j| / A_j
    const double h = 0.5 * ((before ? before->tau : 0.0) + (after ? after->tau : 0.0));
    for (std::size_t j = 0; j < kJointCount; ++j) {
      if (inv_a_[j] == 0.0) continue;
      const double wb = before ? before->w[j] : 0.0, wa = after ? after->w[j] : 0.0;
      if (wb * wa > 0.0) {
        both = std::max(both, std::abs(wa - wb) * inv_a_[j] / h);
      } else {
        if (before)
          side_before = std::max(side_before, 2.0 * std::abs(wb) * inv_a_[j] / before->tau);
        if (after) side_after = std::max(side_after, 2.0 * std::abs(wa) * inv_a_[j] / after->tau);
      }
    }
    double extra = 0.0;
    if (both > 1.0) extra += (std::sqrt(both) - 1.0) * 2.0 * h;
    if (side_before > 1.0) extra += (std::sqrt(side_before) - 1.0) * before->tau;
    if (side_after > 1.0) extra += (std::sqrt(side_after) - 1.0) * after->tau;
    return kStretchShare * extra;
  }

  /// Point i: every pair (s, u) of segment i reached from the best pair (r, s) of segment
  /// i - 1; `back` keeps that r.
  void step(std::size_t i, const std::vector<Pair>& seg0, const std::vector<Pair>& seg1,
            std::vector<Cost>& cost, std::vector<std::uint8_t>& back) const {
    const std::size_t kp = candidates_[i - 1].size(), k = candidates_[i].size(),
                      kn = candidates_[i + 1].size();
    const double c = kRadToDeg * 2.0 / (t_[i - 1] + t_[i]);
    std::vector<Cost> next(k * kn);
    back.assign(k * kn, 0);
    for (std::size_t s = 0; s < k; ++s) {
      for (std::size_t u = 0; u < kn; ++u) {
        const Pair& after = seg1[s * kn + u];
        Cost best{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
        std::uint8_t arg = 0;
        for (std::size_t r = 0; r < kp; ++r) {
          const Pair& before = seg0[r * k + s];
          const double extra = before.quiet && after.quiet ? 0.0 : point_extra(&before, &after);
          const double da = c * (after.wa - before.wa), dc = c * (after.wc - before.wc);
          const Cost& was = cost[r * k + s];
          const Cost v{was.time_s + after.tau + extra, was.sum_sq + da * da + dc * dc};
          if (better(v, best)) best = v, arg = static_cast<std::uint8_t>(r);
        }
        next[s * kn + u] = best;
        back[s * kn + u] = arg;
      }
    }
    cost.swap(next);
  }

  const std::vector<std::vector<Posed>>& candidates_;
  const std::vector<std::vector<JointPosition>>& joints_;
  const std::vector<double>& programmed_time_s_;
  const std::vector<double>& t_;
  const bool wrap_c_;
  std::array<double, kJointCount> v_max_{}, inv_a_{};
};

}  // namespace

std::vector<std::size_t> fastest_candidate_sequence(
    const std::vector<std::vector<Posed>>& candidates,
    const std::vector<std::vector<JointPosition>>& joints,
    const std::vector<double>& programmed_time_s, const std::vector<double>& segment_time_s,
    const JointLimits& limits, double* surrogate_s, bool wrap_c) {
  const std::size_t n = candidates.size();
  if (n == 0) return {};
  if (segment_time_s.size() + 1 != n || programmed_time_s.size() + 1 != n || joints.size() != n) {
    throw std::invalid_argument(
        "fastest_candidate_sequence: n points need n joint sets and n - 1 segment times");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (candidates[i].empty() || candidates[i].size() > 255 ||
        joints[i].size() != candidates[i].size()) {
      throw std::invalid_argument(
          "fastest_candidate_sequence: 1 to 255 candidates per point, each with its joints");
    }
  }
  if (n <= 2) {
    if (surrogate_s) *surrogate_s = 0.0;
    return std::vector<std::size_t>(n, 0);
  }
  return FastestSequence(candidates, joints, programmed_time_s, segment_time_s, limits, wrap_c)
      .run(surrogate_s);
}

}  // namespace taxopt
