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
  static const char* const names[kJointCount] = {"X", "Y", "Z", "A", "C"};
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

FeedSchedule schedule_feed(const FeedChain& chain, const JointLimits& limits,
                           const ScheduleOptions& options) {
  const std::size_t n = chain.joints.size();
  if (n == 0 || chain.min_time_s.size() + 1 != n) {
    throw std::invalid_argument("schedule_feed: need n joint positions and n - 1 segment times");
  }
  const double keep = 1.0 - options.margin;
  FeedSchedule out;
  out.time_s.assign(n - 1, 0.0);
  out.bound.assign(n - 1, FeedBound::Programmed);
  out.bound_joint.assign(n - 1, Joint::X);

  // The segments that move a joint; the others take no time and are skipped.
  std::vector<std::size_t> seg;
  std::vector<JointPosition> dq;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    JointPosition d;
    bool moves = false;
    for (std::size_t j = 0; j < kJointCount; ++j) {
      d[j] = chain.joints[i + 1][j] - chain.joints[i][j];
      if (!std::isfinite(d[j])) {
        throw std::invalid_argument("schedule_feed: joint position not finite at point " +
                                    std::to_string(i + 1));
      }
      moves = moves || d[j] != 0.0;
    }
    if (!moves) continue;
    if (!(chain.min_time_s[i] > 0.0) || !std::isfinite(chain.min_time_s[i])) {
      throw std::invalid_argument("schedule_feed: segment " + std::to_string(i) +
                                  " moves but has no positive time at the programmed feed");
    }
    seg.push_back(i);
    dq.push_back(d);
  }
  const std::size_t m = seg.size();
  if (m == 0) return out;

  // Caps of single segments: programmed feed, velocity limits, and the acceleration bounds
  // of rests, reversals, starts and stops (p q <= 0). Same-direction turns are kept per point.
  std::vector<Cap> cap(m);
  std::vector<std::size_t> turn_begin(m + 1, 0);
  std::vector<Turn> turns;
  const auto own_half_time = [&](std::size_t k, std::size_t j) {
    // |dq| u <= A / (2u): the joint reaches (or sheds) its velocity within half the segment.
    return std::sqrt(limits[j].max_accel_per_s2 * keep / (2.0 * std::abs(dq[k][j])));
  };
  for (std::size_t k = 0; k < m; ++k) {
    cap[k].lower(1.0 / chain.min_time_s[seg[k]], FeedBound::Programmed, Joint::X);
    turn_begin[k] = turns.size();
    for (std::size_t j = 0; j < kJointCount; ++j) {
      const Joint joint = static_cast<Joint>(j);
      const double d = std::abs(dq[k][j]);
      if (d == 0.0) continue;
      if (limits[j].max_velocity_per_s > 0.0) {
        cap[k].lower(limits[j].max_velocity_per_s * keep / d, FeedBound::Velocity, joint);
      }
      if (!(limits[j].max_accel_per_s2 > 0.0)) continue;
      const bool first = k == 0, last = k + 1 == m;
      if ((first && chain.start_at_rest) || (last && chain.end_at_rest)) {
        cap[k].lower(own_half_time(k, j), FeedBound::Acceleration, joint);
      }
    }
    if (k == 0) continue;
    // The point between segments k - 1 and k.
    for (std::size_t j = 0; j < kJointCount; ++j) {
      if (!(limits[j].max_accel_per_s2 > 0.0)) continue;
      const Joint joint = static_cast<Joint>(j);
      const double p = dq[k - 1][j], q = dq[k][j];
      if (p * q > 0.0) {
        turns.push_back(Turn{std::abs(p), std::abs(q), limits[j].max_accel_per_s2 * keep,
                             static_cast<std::uint8_t>(j)});
        continue;
      }
      if (p != 0.0) cap[k - 1].lower(own_half_time(k - 1, j), FeedBound::Acceleration, joint);
      if (q != 0.0) cap[k].lower(own_half_time(k, j), FeedBound::Acceleration, joint);
    }
  }
  turn_begin[m] = turns.size();
  // turns of the point before segment k: [turn_begin[k], turn_begin[k + 1]) for k >= 1.

  std::vector<double> u(m);
  for (std::size_t k = 0; k < m; ++k) u[k] = cap[k].rate;
  const auto lower = [&](std::size_t k, double r, Joint joint) {
    if (r < u[k]) {
      u[k] = r;
      cap[k].bound = FeedBound::Acceleration;
      cap[k].joint = joint;
      return true;
    }
    return false;
  };
  const auto psi = [&](std::size_t k, Joint& joint) {  // bound on u[k-1] from u[k]
    double r = kInf;
    for (std::size_t t = turn_begin[k]; t < turn_begin[k + 1]; ++t) {
      const double x = rate_before(turns[t], u[k]);
      if (x < r) r = x, joint = static_cast<Joint>(turns[t].joint);
    }
    return r;
  };
  const auto phi = [&](std::size_t k, Joint& joint) {  // bound on u[k] from u[k-1]
    double r = kInf;
    for (std::size_t t = turn_begin[k]; t < turn_begin[k + 1]; ++t) {
      const double x = rate_after(turns[t], u[k - 1]);
      if (x < r) r = x, joint = static_cast<Joint>(turns[t].joint);
    }
    return r;
  };
  out.converged = false;
  while (out.sweeps < options.max_sweeps) {
    ++out.sweeps;
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
      ok = u[k - 1] <= psi(k, joint) * (1.0 + 1e-12);
    }
    if (ok) {
      out.converged = true;
      break;
    }
  }
  for (std::size_t k = 0; k < m; ++k) {
    // A segment at its programmed feed takes exactly its time (1 / (1 / t) may not be t).
    out.time_s[seg[k]] = std::max(1.0 / u[k], chain.min_time_s[seg[k]]);
    out.bound[seg[k]] = cap[k].bound;
    out.bound_joint[seg[k]] = cap[k].joint;
  }
  if (!out.converged) {
    // Feasible fallback: slow the whole chain uniformly until the exact model holds
    // (velocities scale with the factor, accelerations with its square).
    const JointRates r =
        joint_rates(chain.joints, out.time_s, chain.start_at_rest, chain.end_at_rest);
    double slow = 1.0;
    for (std::size_t j = 0; j < kJointCount; ++j) {
      if (limits[j].max_velocity_per_s > 0.0 && r.max_velocity_per_s[j] > 0.0) {
        slow = std::min(slow, limits[j].max_velocity_per_s * keep / r.max_velocity_per_s[j]);
      }
      if (limits[j].max_accel_per_s2 > 0.0 && r.max_accel_per_s2[j] > 0.0) {
        slow = std::min(slow, std::sqrt(limits[j].max_accel_per_s2 * keep / r.max_accel_per_s2[j]));
      }
    }
    for (double& t : out.time_s) t /= slow;
  }
  return out;
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
