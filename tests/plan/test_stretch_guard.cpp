// The guard per stretch (plan/stretch_guard.hpp) on synthetic passes whose verdicts are known:
// a pass keeps its input axes only where the optimised ones are worse, joins them smoothly on
// the great circle, and falls back to the whole pass when nothing else makes it good.
#include <catch2/catch.hpp>
#include <cmath>

#include "plan/stretch_guard.hpp"

using namespace taxopt;

namespace {

/// n input axes leaning along a gentle arc, and optimised axes turned 10 deg from each.
struct Case {
  std::vector<Vec3d> input, optimised;
};

Case make_case(std::size_t n) {
  Case c;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = deg_to_rad(20.0 * static_cast<double>(i) / static_cast<double>(n));
    const Vec3d in(std::sin(t), 0.0, std::cos(t));
    c.input.push_back(in);
    const double d = deg_to_rad(10.0);
    c.optimised.push_back((std::cos(d) * in + std::sin(d) * Vec3d::UnitY()).normalized());
  }
  return c;
}

bool same(const Vec3d& a, const Vec3d& b) { return angle_between(a, b) < 1e-12; }

/// A rate-like measure of the axes: the second difference of their angle from the input, deg.
double second_difference_deg(const std::vector<Vec3d>& axes, const std::vector<Vec3d>& input,
                             std::size_t i) {
  const auto th = [&](std::size_t k) { return rad_to_deg(angle_between(axes[k], input[k])); };
  return std::abs(th(i - 1) - 2.0 * th(i) + th(i + 1));
}

}  // namespace

TEST_CASE("stretch guard: a pass keeps its input axes only where the optimised ones hit",
          "[plan][guard]") {
  const Case c = make_case(100);
  const std::vector<IndexRange> passes = {{0, 100}};
  // The optimised axes of points 40..45 hit the part; every other axis is free.
  std::size_t calls = 0;
  const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                         const std::vector<KeptWhy>& why,
                                         const std::vector<char>& check) {
    ++calls;
    StretchVerdicts out{std::vector<PointVerdict>(axes.size(), PointVerdict::Good), {1, 1}};
    auto& v = out.points;
    for (std::size_t i = 40; i <= 45; ++i) {
      REQUIRE(check[i]);
      if (!same(axes[i], c.input[i])) v[i] = PointVerdict::Hits;
      (void)why;
    }
    return out;
  };
  const StretchGuardResult r = guard_stretches(passes, {1}, c.optimised, c.input, evaluate);
  CHECK(calls == 2);  // the optimised axes, then the candidate that is good
  CHECK(r.whole_passes == 0);
  CHECK(r.stretches == 1);
  CHECK(r.points_hit == 6);
  CHECK(r.points_rate == 0);
  CHECK(r.points_blended == 8);  // 4 on each side
  for (std::size_t i = 0; i < 100; ++i) {
    INFO("point " << i);
    if (i >= 40 && i <= 45) {
      CHECK(r.why[i] == KeptWhy::Collision);
      CHECK(same(r.axes[i], c.input[i]));
    } else if ((i >= 36 && i < 40) || (i > 45 && i <= 49)) {
      CHECK(r.why[i] == KeptWhy::Join);
      // On the great circle between the optimised and the input axis: within the cone.
      const double to_in = angle_between(r.axes[i], c.input[i]);
      const double to_opt = angle_between(r.axes[i], c.optimised[i]);
      CHECK(to_in + to_opt == Approx(angle_between(c.input[i], c.optimised[i])).margin(1e-9));
      CHECK(to_in > 1e-6);
      CHECK(to_opt > 1e-6);
      CHECK(std::abs(r.axes[i].norm() - 1.0) < 1e-12);
    } else {
      CHECK(r.why[i] == KeptWhy::None);
      CHECK(same(r.axes[i], c.optimised[i]));
    }
  }
  // The blend's weights rise towards the stretch: closer points are nearer the input.
  for (std::size_t i = 36; i < 39; ++i) {
    CHECK(angle_between(r.axes[i + 1], c.input[i + 1]) < angle_between(r.axes[i], c.input[i]));
  }
}

TEST_CASE("stretch guard: a join too sharp for the pass's peak rate gets a longer blend",
          "[plan][guard]") {
  const Case c = make_case(120);
  const std::vector<IndexRange> passes = {{0, 120}};
  // Points 58..62 raise the rate while optimised; and any point whose second difference of
  // deviation exceeds 1 deg raises the pass's peak (a 10 deg join over 4 points makes about
  // 10 * 6 / 25 = 2.4 deg; over 8 points about 0.74).
  const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                         const std::vector<KeptWhy>&,
                                         const std::vector<char>& check) {
    StretchVerdicts out{std::vector<PointVerdict>(axes.size(), PointVerdict::Good), {1, 1}};
    auto& v = out.points;
    for (std::size_t i = 1; i + 1 < axes.size(); ++i) {
      if (!check[i]) continue;
      if (second_difference_deg(axes, c.input, i) > 1.0) v[i] = PointVerdict::RaisesRate;
    }
    for (std::size_t i = 58; i <= 62; ++i) {
      if (!same(axes[i], c.input[i])) v[i] = PointVerdict::RaisesRate;
    }
    return out;
  };
  const StretchGuardResult r = guard_stretches(passes, {1}, c.optimised, c.input, evaluate);
  CHECK(r.whole_passes == 0);
  CHECK(r.stretches == 1);
  CHECK(r.points_rate == 5);
  CHECK(r.points_blended == 16);  // doubled once: 8 on each side
  double peak = 0.0;
  for (std::size_t i = 1; i + 1 < 120; ++i)
    peak = std::max(peak, second_difference_deg(r.axes, c.input, i));
  CHECK(peak <= 1.0);
  CHECK(same(r.axes[0], c.optimised[0]));
  CHECK(same(r.axes[119], c.optimised[119]));
}

TEST_CASE("stretch guard: a pass bad everywhere, or still bad after the rounds, is kept whole",
          "[plan][guard]") {
  const Case c = make_case(50);
  const std::vector<IndexRange> passes = {{0, 20}, {20, 50}};
  SECTION("bad everywhere") {
    const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                           const std::vector<KeptWhy>&,
                                           const std::vector<char>& check) {
      StretchVerdicts out{std::vector<PointVerdict>(axes.size(), PointVerdict::Good), {1, 1}};
      auto& v = out.points;
      for (std::size_t i = 20; i < 50; ++i) {
        if (check[i] && !same(axes[i], c.input[i])) v[i] = PointVerdict::RaisesRate;
      }
      return out;
    };
    const StretchGuardResult r = guard_stretches(passes, {1, 1}, c.optimised, c.input, evaluate);
    CHECK(r.whole_passes == 1);
    CHECK(r.stretches == 0);
    CHECK(r.points_rate == 30);
    for (std::size_t i = 0; i < 20; ++i) CHECK(same(r.axes[i], c.optimised[i]));
    for (std::size_t i = 20; i < 50; ++i) CHECK(same(r.axes[i], c.input[i]));
  }
  SECTION("every join hits: rounds run out") {
    std::size_t rounds = 0;
    const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                           const std::vector<KeptWhy>& why,
                                           const std::vector<char>& check) {
      ++rounds;
      StretchVerdicts out{std::vector<PointVerdict>(axes.size(), PointVerdict::Good), {1, 1}};
      auto& v = out.points;
      if (check[25] && !same(axes[25], c.input[25])) v[25] = PointVerdict::RaisesRate;
      for (std::size_t i = 0; i < axes.size(); ++i) {
        if (check[i] && why[i] == KeptWhy::Join) v[i] = PointVerdict::RaisesRate;
      }
      return out;
    };
    StretchGuardOptions options;
    options.first_blend = 1;
    options.rounds = 3;
    const StretchGuardResult r =
        guard_stretches(passes, {0, 1}, c.optimised, c.input, evaluate, options);
    CHECK(rounds == 3);
    CHECK(r.whole_passes == 1);
    for (std::size_t i = 20; i < 50; ++i) CHECK(r.why[i] == KeptWhy::PeakRate);
  }
}

TEST_CASE(
    "stretch guard: an unguarded pass is never judged or changed -- a stretch near a pass "
    "end reaches the end",
    "[plan][guard]") {
  const Case c = make_case(60);
  const std::vector<IndexRange> passes = {{0, 30}, {30, 60}};
  const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                         const std::vector<KeptWhy>&,
                                         const std::vector<char>& check) {
    for (std::size_t i = 0; i < 30; ++i) REQUIRE_FALSE(check[i]);
    StretchVerdicts out{std::vector<PointVerdict>(axes.size(), PointVerdict::Good), {1, 1}};
    auto& v = out.points;
    if (!same(axes[57], c.input[57])) v[57] = PointVerdict::Hits;
    v[10] = PointVerdict::Hits;  // never asked: the first pass is not guarded
    return out;
  };
  const StretchGuardResult r = guard_stretches(passes, {0, 1}, c.optimised, c.input, evaluate);
  for (std::size_t i = 0; i < 30; ++i) CHECK(same(r.axes[i], c.optimised[i]));
  // Point 57's blend would need 4 points after it; the stretch reaches the pass's end instead.
  for (std::size_t i = 57; i < 60; ++i) CHECK(r.why[i] == KeptWhy::Collision);
  for (std::size_t i = 53; i < 57; ++i) CHECK(r.why[i] == KeptWhy::Join);
  CHECK(r.why[52] == KeptWhy::None);
  CHECK(r.stretches == 1);
  CHECK(r.whole_passes == 0);
}

TEST_CASE(
    "stretch guard: a pass with no gain on the input keeps the input whole, with kept stretches "
    "or without -- a method never turns the axes where nothing improves",
    "[plan][guard]") {
  const Case c = make_case(150);
  const std::vector<IndexRange> passes = {{0, 50}, {50, 100}, {100, 150}};
  // Points 20..22 of the first pass hit while optimised; the second and third passes are good
  // at every point. Only the third gains on its input.
  std::size_t calls = 0;
  const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                         const std::vector<KeptWhy>&, const std::vector<char>&) {
    ++calls;
    StretchVerdicts out{std::vector<PointVerdict>(axes.size(), PointVerdict::Good), {0, 0, 1}};
    for (std::size_t i = 20; i <= 22; ++i) {
      if (!same(axes[i], c.input[i])) out.points[i] = PointVerdict::Hits;
    }
    return out;
  };
  const StretchGuardResult r = guard_stretches(passes, {1, 1, 1}, c.optimised, c.input, evaluate);
  CHECK(calls == 2);
  CHECK(r.whole_passes == 2);
  CHECK(r.stretches == 0);
  CHECK(r.points_hit == 50);
  CHECK(r.points_no_gain == 50);
  for (std::size_t i = 0; i < 100; ++i) CHECK(same(r.axes[i], c.input[i]));
  for (std::size_t i = 50; i < 100; ++i) CHECK(r.why[i] == KeptWhy::NoGain);
  for (std::size_t i = 100; i < 150; ++i) CHECK(same(r.axes[i], c.optimised[i]));
}
