#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "taxopt/kinematics/feed_schedule.hpp"

using namespace taxopt;

namespace {

JointLimits uniform_limits(double v_mm, double a_mm, double v_deg, double tilt_deg) {
  JointLimits l;
  for (int j = 0; j < 3; ++j) l[j] = {v_mm, a_mm, 0.0};
  for (int j = 3; j < 5; ++j) l[j] = {v_deg, tilt_deg, 0.0};
  return l;
}

/// Independent of the library: the largest velocity and acceleration ratio to the limits of
/// a chain run with times t (the eq. 16-18 model with rests at both ends), straight from the
/// definitions.
double worst_ratio(const FeedChain& c, const std::vector<double>& t, const JointLimits& l) {
  double worst = 0.0;
  std::vector<std::array<double, 5>> w;  // velocities of moving segments, rests around them
  std::vector<double> dt;
  w.push_back({});
  dt.push_back(0.0);
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] == 0.0) continue;
    std::array<double, 5> v{};
    for (int j = 0; j < 5; ++j) {
      v[j] = (c.joints[i + 1][j] - c.joints[i][j]) / t[i];
      if (l[j].max_velocity_per_s > 0)
        worst = std::max(worst, std::abs(v[j]) / l[j].max_velocity_per_s);
    }
    w.push_back(v);
    dt.push_back(t[i]);
  }
  w.push_back({});
  dt.push_back(0.0);
  for (std::size_t k = 1; k < w.size(); ++k) {
    for (int j = 0; j < 5; ++j) {
      const double a = (w[k][j] - w[k - 1][j]) / ((dt[k] + dt[k - 1]) / 2.0);
      if (l[j].max_accel_per_s2 > 0) worst = std::max(worst, std::abs(a) / l[j].max_accel_per_s2);
    }
  }
  return worst;
}

/// A random chain: a smooth walk in the five joints with noise and the odd reversal.
FeedChain random_chain(std::mt19937& rng, std::size_t n, double flip = 0.9) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  FeedChain c;
  JointPosition q{}, dir{};
  for (auto& d : dir) d = u(rng);
  for (std::size_t i = 0; i < n; ++i) {
    c.joints.push_back(q);
    for (std::size_t j = 0; j < 5; ++j) {
      dir[j] += 0.3 * u(rng);
      if (u(rng) > flip) dir[j] = -dir[j];
      q[j] += (j < 3 ? 0.2 : 0.5) * dir[j];
    }
    if (i + 1 < n) c.min_time_s.push_back(0.005 + 0.02 * (u(rng) + 1.0));
  }
  return c;
}

/// For one joint turning the same way, |p| then |q|: the largest rate after the point for rate
/// x before it, on the accelerating side, by bisection of the exact constraint
/// |q| u - |p| x <= (A/2)(1/x + 1/u) (not the library's closed form).
double largest_rate_after(double p, double q, double a, double x) {
  double lo = p * x / q, hi = lo + 1.0;
  const auto ok = [&](double u) { return q * u - p * x <= a / 2.0 * (1.0 / x + 1.0 / u); };
  while (ok(hi)) hi *= 2.0;
  for (int it = 0; it < 100; ++it) (ok(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
  return lo;
}

/// Brute force: the least total time over a fine geometric grid of segment rates, by dynamic
/// programming, under the exact eq. 16-18 constraints or (`inner`) the scheduler's inner set.
double brute_force_time(const FeedChain& c, const JointLimits& l, int levels, bool inner) {
  const std::size_t m = c.min_time_s.size();
  std::vector<std::vector<double>> rates(m);
  for (std::size_t k = 0; k < m; ++k) {
    const double top = 1.0 / c.min_time_s[k];
    for (int g = 0; g <= levels; ++g) rates[k].push_back(top * std::pow(1e-3, double(g) / levels));
  }
  const auto d = [&](std::size_t k, int j) { return c.joints[k + 1][j] - c.joints[k][j]; };
  const auto unary = [&](std::size_t k, double u) {
    for (int j = 0; j < 5; ++j) {
      if (l[j].max_velocity_per_s > 0 && std::abs(d(k, j)) * u > l[j].max_velocity_per_s)
        return false;
      const bool rest = k == 0 || k + 1 == m;
      // From or to rest: |w| <= A t / 2.
      if (rest && l[j].max_accel_per_s2 > 0 &&
          std::abs(d(k, j)) * u > l[j].max_accel_per_s2 / (2 * u))
        return false;
    }
    return true;
  };
  // The file comment's inner set at the point before segment k, from its definition: turning
  // the same way, the accelerating bound with the rate before raised to w* = sqrt(A / 2|p|)
  // and the braking bound likewise; otherwise each side within half its own time. Bounds
  // per grid rate, computed once: bound_after[k][h][j] caps u given w = rates[k-1][h].
  const auto bounds = [&](std::size_t k, bool after) {
    const std::size_t from = after ? k - 1 : k;
    std::vector<std::array<double, 5>> b(rates[from].size());
    for (std::size_t h = 0; h < rates[from].size(); ++h) {
      for (int j = 0; j < 5; ++j) {
        const double a = l[j].max_accel_per_s2, p = d(k - 1, j), q = d(k, j);
        double cap = std::numeric_limits<double>::infinity();
        if (a > 0 && p * q > 0) {
          const double x_abs = after ? std::abs(p) : std::abs(q),
                       y_abs = after ? std::abs(q) : std::abs(p);
          cap = largest_rate_after(x_abs, y_abs, a,
                                   std::max(rates[from][h], std::sqrt(a / (2 * x_abs))));
        }
        b[h][j] = cap;
      }
    }
    return b;
  };
  const auto inner_ok = [&](std::size_t k, double w, double u, const std::array<double, 5>& cap_u,
                            const std::array<double, 5>& cap_w) {
    for (int j = 0; j < 5; ++j) {
      const double a = l[j].max_accel_per_s2, p = d(k - 1, j), q = d(k, j);
      if (!(a > 0)) continue;
      if (p * q > 0) {
        if (u > cap_u[j] * (1 + 1e-9) || w > cap_w[j] * (1 + 1e-9)) return false;
      } else if (std::abs(p) * w * w > a / 2 || std::abs(q) * u * u > a / 2) {
        return false;
      }
    }
    return true;
  };
  const auto exact_ok = [&](std::size_t k, double w, double u) {
    for (int j = 0; j < 5; ++j) {
      const double a = l[j].max_accel_per_s2;
      if (!(a > 0)) continue;
      const double dv = std::abs(d(k, j) * u - d(k - 1, j) * w);
      if (dv > a * (1.0 / w + 1.0 / u) / 2.0) return false;
    }
    return true;
  };
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> cost(rates[0].size(), inf);
  for (std::size_t g = 0; g < rates[0].size(); ++g) {
    if (unary(0, rates[0][g])) cost[g] = 1.0 / rates[0][g];
  }
  for (std::size_t k = 1; k < m; ++k) {
    std::vector<double> next(rates[k].size(), inf);
    std::vector<std::array<double, 5>> cap_after, cap_before;
    if (inner) cap_after = bounds(k, true), cap_before = bounds(k, false);
    for (std::size_t g = 0; g < rates[k].size(); ++g) {
      const double u = rates[k][g];
      if (!unary(k, u)) continue;
      for (std::size_t h = 0; h < rates[k - 1].size(); ++h) {
        const double w = rates[k - 1][h];
        if (cost[h] == inf) continue;
        if (inner ? inner_ok(k, w, u, cap_after[h], cap_before[g]) : exact_ok(k, w, u)) {
          next[g] = std::min(next[g], cost[h] + 1.0 / u);
        }
      }
    }
    cost = next;
  }
  return *std::min_element(cost.begin(), cost.end());
}

}  // namespace

TEST_CASE("feed schedule: a straight line with fixed axes runs at the programmed feed",
          "[kinematics][feed]") {
  FeedChain c;
  for (int i = 0; i <= 100; ++i) c.joints.push_back({double(i), 2.0, -3.0, 10.0, 45.0});
  c.min_time_s.assign(100, 0.06);  // 1 mm at 1000 mm/min
  const FeedSchedule s = schedule_feed(c, uniform_limits(500, 3000, 150, 1000));
  CHECK(s.converged);
  CHECK(s.total_time_s() == Approx(6.0).epsilon(1e-12));
  for (std::size_t i = 0; i < 100; ++i) CHECK(s.bound[i] == FeedBound::Programmed);
}

TEST_CASE("feed schedule: one rotary move with an acceleration limit takes the trapezoid's time",
          "[kinematics][feed]") {
  for (const auto& [v_deg_s, a_deg_s2, expected_s] :
       {std::tuple<double, double, double>{100.0, 500.0, 90.0 / 100.0 + 100.0 / 500.0},
        {1000.0, 500.0, 2.0 * std::sqrt(90.0 / 500.0)}}) {
    INFO("limits " << v_deg_s << " deg/s, " << a_deg_s2 << " deg/s^2");
    FeedChain c;
    const int n = 4000;
    for (int i = 0; i <= n; ++i) c.joints.push_back({0.0, 0.0, 0.0, 0.0, 90.0 * i / n});
    c.min_time_s.assign(n, 1e-6);  // the programmed feed never binds
    const FeedSchedule s = schedule_feed(c, uniform_limits(500, 3000, v_deg_s, a_deg_s2));
    CHECK(s.converged);
    CHECK(s.total_time_s() == Approx(expected_s).epsilon(0.005));
    // Accelerating, cruising (when the velocity limit is reached) and braking.
    CHECK(s.bound.front() == FeedBound::Acceleration);
    CHECK(s.bound.back() == FeedBound::Acceleration);
    CHECK((s.bound[n / 2] == FeedBound::Velocity) == (v_deg_s < 200.0));
  }
}

TEST_CASE("feed schedule: random chains respect every limit and the programmed feed",
          "[kinematics][feed]") {
  std::mt19937 rng(20261123);
  for (int trial = 0; trial < 50; ++trial) {
    const FeedChain c = random_chain(rng, 200);
    const JointLimits l = uniform_limits(40, 400, 60, 300);
    const FeedSchedule s = schedule_feed(c, l);
    INFO("trial " << trial << ", sweeps " << s.sweeps);
    CHECK(s.converged);
    CHECK(worst_ratio(c, s.time_s, l) <= 1.0);
    for (std::size_t i = 0; i < s.time_s.size(); ++i) CHECK(s.time_s[i] >= c.min_time_s[i]);
    const JointRates r = joint_rates(c.joints, s.time_s);
    for (int j = 0; j < 5; ++j) {
      CHECK(r.max_velocity_per_s[j] <= l[j].max_velocity_per_s);
      CHECK(r.max_accel_per_s2[j] <= l[j].max_accel_per_s2);
    }
  }
}

TEST_CASE("feed schedule: no schedule of the inner set is faster (brute force on a fine grid)",
          "[kinematics][feed]") {
  std::mt19937 rng(7);
  double worst_inner = 0.0, worst_exact = 0.0, sum_exact = 0.0;
  const int trials = 40;
  for (int trial = 0; trial < trials; ++trial) {
    const FeedChain c = random_chain(rng, 5);
    const JointLimits l = uniform_limits(40, 400, 60, 300);
    const FeedSchedule s = schedule_feed(c, l);
    const double inner = brute_force_time(c, l, 400, true);
    const double exact = brute_force_time(c, l, 400, false);
    INFO("trial " << trial << ": schedule " << s.total_time_s() << " s, brute force " << inner
                  << " s (inner set), " << exact << " s (exact model)");
    // The grid's brute force is feasible, so the greatest element is at least as fast (up to
    // the scheduler's margin of 1e-5 on the limits).
    REQUIRE(std::isfinite(inner));
    CHECK(s.total_time_s() <= inner * (1.0 + 1e-4));
    // ... and the grid, 1.7 % a level, comes within a level of it.
    CHECK(inner <= s.total_time_s() * 1.02);
    // The exact model admits crawl and reversal trade-offs the lattice gives up: bounded.
    CHECK(s.total_time_s() <= exact * 1.10);
    worst_inner = std::max(worst_inner, s.total_time_s() / inner - 1.0);
    worst_exact = std::max(worst_exact, s.total_time_s() / exact - 1.0);
    sum_exact += s.total_time_s() / exact - 1.0;
  }
  WARN("schedule vs brute force: inner set worst "
       << worst_inner << ", exact model worst " << worst_exact << ", mean " << sum_exact / trials);
}
