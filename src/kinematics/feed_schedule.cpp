#include "taxopt/kinematics/feed_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace taxopt {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// One joint's same-direction acceleration constraint at a point: |p| and |q| are the joint's
/// displacements in the segments before and after, accel its limit (margin applied).
struct Turn {
  double p, q, accel;
  std::uint8_t joint;
};

/// Largest rate after a point for rate `w` before it, for one joint (the file comment's phi):
/// the root above the constant-velocity ray of |q| u - |p| w = (A/2)(1/w + 1/u), with w
/// raised to w* = sqrt(A / 2|p|) where that bound is least.
double rate_after(const Turn& t, double w) {
  const double w_star = std::sqrt(t.accel / (2.0 * t.p));
  const double x = std::max(w, w_star);
  const double b = t.p * x + t.accel / (2.0 * x);
  return (b + std::sqrt(b * b + 2.0 * t.q * t.accel)) / (2.0 * t.q);
}

/// The same with the segments exchanged (psi): largest rate before a point for rate `u`
/// after it.
double rate_before(const Turn& t, double u) {
  return rate_after(Turn{t.q, t.p, t.accel, t.joint}, u);
}

/// A rate cap with what sets it.
struct Cap {
  double rate = kInf;
  FeedBound bound = FeedBound::Programmed;
  Joint joint = Joint::X;
  void lower(double r, FeedBound b, Joint j) {
    if (r < rate) rate = r, bound = b, joint = j;
  }
};

}  // namespace

const char* to_string(Joint joint) {
  static const char* const names[kJointCount] = {"X", "Y", "Z", "tilt", "C"};
  return names[static_cast<std::size_t>(joint)];
}

std::string joint_name(Joint joint, char tilt_letter) {
  return joint == Joint::Tilt ? std::string(1, tilt_letter) : std::string(to_string(joint));
}

double FeedSchedule::total_time_s() const {
  double t = 0.0;
  for (double s : time_s) t += s;
  return t;
}

namespace {

/// One chain's schedule (schedule_feed): the segments that move, their single caps and the
/// same-direction turns between them, the sweeps that make neighbouring rates agree, and the
/// uniform fallback where the sweeps do not converge.
class FeedScheduler {
 public:
  FeedScheduler(const FeedChain& chain, const JointLimits& limits, const ScheduleOptions& options)
      : chain_(chain), limits_(limits), options_(options), keep_(1.0 - options.margin) {}

  FeedSchedule run() {
    const std::size_t n = chain_.joints.size();
    if (n == 0 || chain_.min_time_s.size() + 1 != n) {
      throw std::invalid_argument("schedule_feed: need n joint positions and n - 1 segment times");
    }
    out_.time_s.assign(n - 1, 0.0);
    out_.bound.assign(n - 1, FeedBound::Programmed);
    out_.bound_joint.assign(n - 1, Joint::X);
    moving_segments();
    if (seg_.empty()) return out_;
    single_caps();
    sweep();
    for (std::size_t k = 0; k < seg_.size(); ++k) {
      // A segment at its programmed feed takes exactly its time (1 / (1 / t) may not be t).
      out_.time_s[seg_[k]] = std::max(1.0 / u_[k], chain_.min_time_s[seg_[k]]);
      out_.bound[seg_[k]] = cap_[k].bound;
      out_.bound_joint[seg_[k]] = cap_[k].joint;
    }
    if (!out_.converged) uniform_fallback();
    return out_;
  }

 private:
  /// The segments that move a joint; the others take no time and are skipped.
  void moving_segments() {
    for (std::size_t i = 0; i + 1 < chain_.joints.size(); ++i) {
      JointPosition d;
      bool moves = false;
      for (std::size_t j = 0; j < kJointCount; ++j) {
        d[j] = chain_.joints[i + 1][j] - chain_.joints[i][j];
        if (!std::isfinite(d[j])) {
          throw std::invalid_argument("schedule_feed: joint position not finite at point " +
                                      std::to_string(i + 1));
        }
        moves = moves || d[j] != 0.0;
      }
      if (!moves) continue;
      if (!(chain_.min_time_s[i] > 0.0) || !std::isfinite(chain_.min_time_s[i])) {
        throw std::invalid_argument("schedule_feed: segment " + std::to_string(i) +
                                    " moves but has no positive time at the programmed feed");
      }
      seg_.push_back(i);
      dq_.push_back(d);
    }
  }

  /// |dq| u <= A / (2u): the joint reaches (or sheds) its velocity within half the segment.
  double own_half_time(std::size_t k, std::size_t j) const {
    return std::sqrt(limits_[j].max_accel_per_s2 * keep_ / (2.0 * std::abs(dq_[k][j])));
  }

  /// Caps of single segments: programmed feed, velocity limits, and the acceleration bounds
  /// of rests, reversals, starts and stops (p q <= 0). Same-direction turns are kept per point:
  /// those of the point before segment k are [turn_begin_[k], turn_begin_[k + 1]) for k >= 1.
  void single_caps() {
    const std::size_t m = seg_.size();
    cap_.assign(m, Cap{});
    turn_begin_.assign(m + 1, 0);
    for (std::size_t k = 0; k < m; ++k) {
      cap_[k].lower(1.0 / chain_.min_time_s[seg_[k]], FeedBound::Programmed, Joint::X);
      turn_begin_[k] = turns_.size();
      for (std::size_t j = 0; j < kJointCount; ++j) {
        const Joint joint = static_cast<Joint>(j);
        const double d = std::abs(dq_[k][j]);
        if (d == 0.0) continue;
        if (limits_[j].max_velocity_per_s > 0.0) {
          cap_[k].lower(limits_[j].max_velocity_per_s * keep_ / d, FeedBound::Velocity, joint);
        }
        if (!(limits_[j].max_accel_per_s2 > 0.0)) continue;
        const bool first = k == 0, last = k + 1 == m;
        if ((first && chain_.start_at_rest) || (last && chain_.end_at_rest)) {
          cap_[k].lower(own_half_time(k, j), FeedBound::Acceleration, joint);
        }
      }
      if (k > 0) point_caps(k);
    }
    turn_begin_[m] = turns_.size();
  }

  /// The point between segments k - 1 and k.
  void point_caps(std::size_t k) {
    for (std::size_t j = 0; j < kJointCount; ++j) {
      if (!(limits_[j].max_accel_per_s2 > 0.0)) continue;
      const Joint joint = static_cast<Joint>(j);
      const double p = dq_[k - 1][j], q = dq_[k][j];
      if (p * q > 0.0) {
        turns_.push_back(Turn{std::abs(p), std::abs(q), limits_[j].max_accel_per_s2 * keep_,
                              static_cast<std::uint8_t>(j)});
        continue;
      }
      if (p != 0.0) cap_[k - 1].lower(own_half_time(k - 1, j), FeedBound::Acceleration, joint);
      if (q != 0.0) cap_[k].lower(own_half_time(k, j), FeedBound::Acceleration, joint);
    }
  }

  bool lower(std::size_t k, double r, Joint joint) {
    if (r < u_[k]) {
      u_[k] = r;
      cap_[k].bound = FeedBound::Acceleration;
      cap_[k].joint = joint;
      return true;
    }
    return false;
  }
  /// The bound on u[k-1] from u[k].
  double psi(std::size_t k, Joint& joint) const {
    double r = kInf;
    for (std::size_t t = turn_begin_[k]; t < turn_begin_[k + 1]; ++t) {
      const double x = rate_before(turns_[t], u_[k]);
      if (x < r) r = x, joint = static_cast<Joint>(turns_[t].joint);
    }
    return r;
  }
  /// The bound on u[k] from u[k-1].
  double phi(std::size_t k, Joint& joint) const {
    double r = kInf;
    for (std::size_t t = turn_begin_[k]; t < turn_begin_[k + 1]; ++t) {
      const double x = rate_after(turns_[t], u_[k - 1]);
      if (x < r) r = x, joint = static_cast<Joint>(turns_[t].joint);
    }
    return r;
  }

  /// Backward and forward sweeps until every turn's bound holds both ways.
  void sweep() {
    const std::size_t m = seg_.size();
    u_.resize(m);
    for (std::size_t k = 0; k < m; ++k) u_[k] = cap_[k].rate;
    out_.converged = false;
    while (out_.sweeps < options_.max_sweeps) {
      ++out_.sweeps;
      Joint joint = Joint::X;
      for (std::size_t k = m - 1; k >= 1; --k) {
        const double r = psi(k, joint);
        lower(k - 1, r, joint);
      }
      for (std::size_t k = 1; k < m; ++k) {
        const double r = phi(k, joint);
        lower(k, r, joint);
      }
      // Every phi holds after the forward sweep; done when every psi holds too.
      bool ok = true;
      for (std::size_t k = 1; k < m && ok; ++k) {
        ok = u_[k - 1] <= psi(k, joint) * (1.0 + 1e-12);
      }
      if (ok) {
        out_.converged = true;
        break;
      }
    }
  }

  /// Feasible fallback: slow the whole chain uniformly until the exact model holds
  /// (velocities scale with the factor, accelerations with its square).
  void uniform_fallback() {
    const JointRates r =
        joint_rates(chain_.joints, out_.time_s, chain_.start_at_rest, chain_.end_at_rest);
    double slow = 1.0;
    for (std::size_t j = 0; j < kJointCount; ++j) {
      if (limits_[j].max_velocity_per_s > 0.0 && r.max_velocity_per_s[j] > 0.0) {
        slow = std::min(slow, limits_[j].max_velocity_per_s * keep_ / r.max_velocity_per_s[j]);
      }
      if (limits_[j].max_accel_per_s2 > 0.0 && r.max_accel_per_s2[j] > 0.0) {
        slow =
            std::min(slow, std::sqrt(limits_[j].max_accel_per_s2 * keep_ / r.max_accel_per_s2[j]));
      }
    }
    for (double& t : out_.time_s) t /= slow;
  }

  const FeedChain& chain_;
  const JointLimits& limits_;
  const ScheduleOptions& options_;
  const double keep_;
  FeedSchedule out_;
  std::vector<std::size_t> seg_;
  std::vector<JointPosition> dq_;
  std::vector<Cap> cap_;
  std::vector<std::size_t> turn_begin_;
  std::vector<Turn> turns_;
  std::vector<double> u_;
};

}  // namespace

FeedSchedule schedule_feed(const FeedChain& chain, const JointLimits& limits,
                           const ScheduleOptions& options) {
  return FeedScheduler(chain, limits, options).run();
}

JointRates joint_rates(const std::vector<JointPosition>& joints, const std::vector<double>& time_s,
                       bool start_at_rest, bool end_at_rest) {
  if (joints.empty() || time_s.size() + 1 != joints.size()) {
    throw std::invalid_argument("joint_rates: need n joint positions and n - 1 segment times");
  }
  JointRates r;
  // Moving segments in order: their index, time and velocities; rests are zero-time
  // segments at rest.
  struct Seg {
    std::size_t begin_point;
    double t;
    JointPosition w;
  };
  std::vector<Seg> segs;
  if (start_at_rest) segs.push_back(Seg{0, 0.0, {}});
  bool any = false;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    if (!(time_s[i] > 0.0)) continue;
    Seg s{i, time_s[i], {}};
    for (std::size_t j = 0; j < kJointCount; ++j) {
      s.w[j] = (joints[i + 1][j] - joints[i][j]) / time_s[i];
      const double v = std::abs(s.w[j]);
      if (v > r.max_velocity_per_s[j]) r.max_velocity_per_s[j] = v, r.velocity_at[j] = i;
    }
    if (!any && start_at_rest) segs.front().begin_point = i;
    segs.push_back(s);
    any = true;
  }
  if (!any) return r;
  if (end_at_rest) segs.push_back(Seg{segs.back().begin_point + 1, 0.0, {}});
  // Acceleration at the point between consecutive segments, and jerk between those points.
  std::array<double, kJointCount> prev_a{};
  double prev_span = 0.0;
  for (std::size_t k = 1; k < segs.size(); ++k) {
    const Seg &a = segs[k - 1], &b = segs[k];
    const double span = 0.5 * (a.t + b.t);
    if (!(span > 0.0)) continue;
    // The point between them: b's first point (a rest at the end sits after a's last).
    const std::size_t at = b.t > 0.0 ? b.begin_point : a.begin_point + 1;
    for (std::size_t j = 0; j < kJointCount; ++j) {
      const double acc = (b.w[j] - a.w[j]) / span;
      if (std::abs(acc) > r.max_accel_per_s2[j])
        r.max_accel_per_s2[j] = std::abs(acc), r.accel_at[j] = at;
      if (k > 1) {
        // Accelerations hold over [mid a, mid b]; their centres are (prev_span + span) / 2 apart.
        const double jerk = std::abs(acc - prev_a[j]) / (0.5 * (prev_span + span));
        if (jerk > r.max_jerk_per_s3[j]) r.max_jerk_per_s3[j] = jerk, r.jerk_at[j] = at;
      }
      prev_a[j] = acc;
    }
    prev_span = span;
  }
  return r;
}

double rapid_time_s(const JointPosition& from, const JointPosition& to, const JointLimits& limits) {
  double t = 0.0;
  for (std::size_t j = 0; j < kJointCount; ++j) {
    const double d = std::abs(to[j] - from[j]);
    const double v = limits[j].max_velocity_per_s, a = limits[j].max_accel_per_s2;
    double tj = 0.0;
    if (d == 0.0) {
      tj = 0.0;
    } else if (v > 0.0 && a > 0.0) {
      tj = d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a);
    } else if (v > 0.0) {
      tj = d / v;
    } else if (a > 0.0) {
      tj = 2.0 * std::sqrt(d / a);
    }
    t = std::max(t, tj);
  }
  return t;
}

}  // namespace taxopt
