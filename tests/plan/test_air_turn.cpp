// The turn between passes spread over the rapids in the air (air_turn.hpp): the reach of a
// rest-to-rest move against the rapid timing, the capacities, and the search over shares.
#include <catch2/catch.hpp>
#include <random>

#include "plan/air_turn.hpp"

using namespace taxopt;

TEST_CASE("air turn: a rapid of time T carries exactly the turn it reaches in T", "[air_turn]") {
  // rest_to_rest_reach inverts rapid_time_s for one joint, on both sides of the trapezoid's
  // corner (d = v^2 / a).
  JointLimits limits{};
  limits[static_cast<std::size_t>(Joint::Tilt)] = {20.0, 40.0, 0.0};
  for (double d : {0.5, 5.0, 10.0, 33.0, 180.0}) {
    JointPosition from{}, to{};
    to[static_cast<std::size_t>(Joint::Tilt)] = d;
    const double t = rapid_time_s(from, to, limits);
    INFO("d " << d << " t " << t);
    CHECK(rest_to_rest_reach(t, limits[static_cast<std::size_t>(Joint::Tilt)]) ==
          Approx(d).epsilon(1e-12));
  }
  CHECK(rest_to_rest_reach(0.0, limits[3]) == 0.0);
  CHECK(std::isinf(rest_to_rest_reach(1.0, JointLimit{})));
}

TEST_CASE("air turn: shares by capacity hide a turn the rapids can carry", "[air_turn]") {
  JointLimits limits{};
  limits[static_cast<std::size_t>(Joint::Tilt)] = {150.0, 1000.0, 0.0};
  limits[static_cast<std::size_t>(Joint::C)] = {240.0, 1500.0, 0.0};
  // Retract, rise, traverse, descent (rapids) and a plunge at feed.
  const std::vector<double> linear = {0.12, 0.06, 0.33, 0.06, 2.4};
  const std::vector<bool> rapid = {true, true, true, true, false};
  // Capacities: 3.6, 0.9, 27 and 0.9 deg of A (32.4 in all) for a turn of 30 deg.
  const std::vector<double> share = spread_turn(linear, rapid, 30.0, 0.0, limits);
  REQUIRE(share.size() == linear.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < share.size(); ++k) {
    sum += share[k];
    if (!rapid[k]) CHECK(share[k] == 0.0);
  }
  CHECK(sum == Approx(1.0));
  // Each rapid's part of the turn takes no longer than its own linear time (the capacities add
  // up to more than the turn here), and the longest move carries the most.
  for (std::size_t k = 0; k < 4; ++k) {
    JointPosition from{}, to{};
    to[static_cast<std::size_t>(Joint::Tilt)] = 30.0 * share[k];
    CHECK(rapid_time_s(from, to, limits) <= linear[k] * (1.0 + 1e-9));
  }
  CHECK(share[2] > share[0]);
  CHECK(share[0] > share[1]);
  // No rapid, or no turn: nothing to spread.
  CHECK(spread_turn(linear, std::vector<bool>(5, false), 33.0, 0.0, limits).empty());
  CHECK(spread_turn(linear, rapid, 0.0, 0.0, limits).empty());
}

TEST_CASE(
    "air turn: the search over shares is never slower than its starts and finds the "
    "least time of a chain",
    "[air_turn]") {
  // A chain of three rapids whose time is sum_k max(L_k, T(s_k)): the least time puts the turn
  // where the linear times can hide it.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0.05, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> linear = {u(rng), u(rng), u(rng)};
    const double turn_s = 0.5 * (linear[0] + linear[1] + linear[2]) * u(rng) * 2.0;
    const auto time_of = [&](const std::vector<double>& s) {
      double t = 0.0;
      for (std::size_t k = 0; k < 3; ++k) t += std::max(linear[k], s[k] * turn_s);
      return t;
    };
    const std::vector<bool> may = {true, true, true};
    const std::vector<double> one = {1.0, 0.0, 0.0};
    const std::vector<double> best = best_turn_shares({one}, may, time_of);
    REQUIRE(best.size() == 3);
    CHECK(best[0] + best[1] + best[2] == Approx(1.0));
    CHECK(time_of(best) <= time_of(one) + 1e-12);
    // The least time: the linear times where the turn fits behind them, else the turn itself.
    const double least = std::max(linear[0] + linear[1] + linear[2], turn_s);
    CHECK(time_of(best) <= least + turn_s / 128.0);
  }
  // A move that may not turn keeps its share at 0.
  const auto slow_middle = [](const std::vector<double>& s) { return s[0] + 2.0 * s[2]; };
  const std::vector<double> r =
      best_turn_shares({{0.0, 0.0, 1.0}}, {true, false, true}, slow_middle);
  CHECK(r[1] == 0.0);
  CHECK(r[0] == Approx(1.0));
}
