#include <catch2/catch.hpp>
#include <random>

#include "plan/slerp.hpp"
#include "taxopt/plan/paper_optimiser.hpp"

using namespace taxopt;

namespace {

/// A pass along x over z = a sin(k x): contact points, normals tilted by `tilt_rad` towards
/// the feed, equal steps.
PassProblem sine_pass(double a, double wavelength, double tilt_rad, double step = 0.5,
                      double length = 80.0) {
  PassProblem p;
  const double k = 2.0 * Constants<double>::pi() / wavelength;
  for (double x = 0.0; x <= length + 1e-9; x += step) {
    p.curve_mm.emplace_back(x, 0.0, a * std::sin(k * x));
    const Vec3d n = Vec3d(-a * k * std::cos(k * x), 0.0, 1.0).normalized();
    const Vec3d t = Vec3d(1.0, 0.0, a * k * std::cos(k * x)).normalized();
    p.input_axes.push_back((std::cos(tilt_rad) * n + std::sin(tilt_rad) * t).normalized());
  }
  for (std::size_t i = 0; i + 1 < p.curve_mm.size(); ++i) {
    p.segment_mm.push_back((p.curve_mm[i + 1] - p.curve_mm[i]).norm());
  }
  return p;
}

/// Rate of turn of the axes per mm on each segment (vectors, chord approximation).
std::vector<Vec3d> rates(const std::vector<Vec3d>& axes, const std::vector<double>& len) {
  std::vector<Vec3d> w;
  for (std::size_t i = 0; i + 1 < axes.size(); ++i) w.push_back((axes[i + 1] - axes[i]) / len[i]);
  return w;
}

double max_rate_change(const std::vector<Vec3d>& w) {
  double m = 0.0;
  for (std::size_t i = 0; i + 1 < w.size(); ++i) m = std::max(m, (w[i + 1] - w[i]).norm());
  return m;
}

}  // namespace

TEST_CASE("paper optimiser: the cap grid covers the cone evenly", "[plan][paper]") {
  const Vec3d c = Vec3d(0.3, -0.2, 0.9).normalized();
  const double r = deg_to_rad(30.0), step = deg_to_rad(2.0);
  const std::vector<Vec3d> g = cap_grid(c, r, step);
  CHECK((g.front() - c).norm() < 1e-15);
  const double cap_area = 2.0 * Constants<double>::pi() * (1.0 - std::cos(r));
  CHECK(static_cast<double>(g.size()) == Approx(cap_area / (step * step)).epsilon(0.15));
  for (const Vec3d& v : g) {
    CHECK(std::abs(v.norm() - 1.0) < 1e-12);
    CHECK(angle_between(v, c) <= r + 1e-12);
  }
  // Every axis of the cone has a grid point within one step.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int t = 0; t < 200; ++t) {
    const double rho = r * std::sqrt(u(rng)), phi = 6.283185307 * u(rng);
    const Vec3d e1 = c.cross(Vec3d::UnitX()).normalized(), e2 = c.cross(e1);
    const Vec3d v = std::cos(rho) * c + std::sin(rho) * (std::cos(phi) * e1 + std::sin(phi) * e2);
    double best = 10.0;
    for (const Vec3d& q : g) best = std::min(best, angle_between(v, q));
    CHECK(best <= step);
  }
}

TEST_CASE("paper optimiser: no output axis outside its free space", "[plan][paper]") {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int t = 0; t < 8; ++t) {
    const PassProblem p = sine_pass(4.0 + 8.0 * u(rng), 25.0 + 30.0 * u(rng), deg_to_rad(5.0));
    // An obstacle: axes within 20 deg of a random direction above the part are blocked at the
    // points of one stretch of the pass, and the machine reaches 100 deg from +Z at most.
    const Vec3d blocked = Vec3d(u(rng) - 0.5, 0.4 * (u(rng) - 0.5), 0.8).normalized();
    const std::size_t from = static_cast<std::size_t>(u(rng) * 100), to = from + 40;
    const AxisTest test = [&](std::size_t i, const Vec3d& v) {
      if (v.z() < std::cos(deg_to_rad(100.0))) return false;
      return !(i >= from && i < to && angle_between(v, blocked) < deg_to_rad(20.0));
    };
    PaperOptions opt;
    const PassPlan plan = plan_pass_paper(p, test, opt);
    INFO("trial " << t);
    REQUIRE(plan.axes.size() == p.input_axes.size());
    for (std::size_t i = 0; i < plan.axes.size(); ++i) {
      INFO("point " << i);
      CHECK(std::abs(plan.axes[i].norm() - 1.0) < 1e-12);
      CHECK(rad_to_deg(angle_between(plan.axes[i], p.input_axes[i])) <= 30.0 + 1e-9);
      CHECK(test(i, plan.axes[i]));
    }
    CHECK(plan.no_free_axis.empty());
    CHECK(plan.keys.front() == 0);
    CHECK(plan.keys.back() == p.input_axes.size() - 1);
  }
}

TEST_CASE("paper optimiser: a point with no free axis in its cone is reported, not hidden",
          "[plan][paper]") {
  const PassProblem p = sine_pass(5.0, 40.0, 0.0);
  const AxisTest test = [](std::size_t i, const Vec3d&) { return i != 37; };
  const PassPlan plan = plan_pass_paper(p, test, PaperOptions{});
  CHECK(plan.no_free_axis == std::vector<std::size_t>{37});
  CHECK((plan.axes[37] - p.input_axes[37]).norm() < 1e-15);
  for (std::size_t i = 0; i < plan.axes.size(); ++i) {
    if (i != 37) CHECK(test(i, plan.axes[i]));
  }
}

TEST_CASE("paper optimiser: a flat pass keeps its input axes", "[plan][paper]") {
  PassProblem p;
  const Vec3d axis = Vec3d(0.1, -0.05, 1.0).normalized();
  for (int i = 0; i <= 60; ++i) {
    p.curve_mm.emplace_back(0.5 * i, 2.0, 1.0);
    p.input_axes.push_back(axis);
    if (i > 0) p.segment_mm.push_back(0.5);
  }
  const PassPlan plan = plan_pass_paper(
      p, [](std::size_t, const Vec3d&) { return true; }, PaperOptions{});
  for (const Vec3d& v : plan.axes) CHECK(angle_between(v, axis) < 1e-9);
  CHECK(plan.intervals() == 1);
}

TEST_CASE("paper optimiser: joint smoothing leaves the rate of turn continuous", "[plan][paper]") {
  // Input axes that already are the slerp between alternating key axes at the inflection
  // points of a sine: the rate of turn is constant in each interval and reverses at the keys.
  // A strong pull keeps the keys where they are, so only the joints change.
  PassProblem p = sine_pass(6.0, 40.0, 0.0);
  const std::size_t n = p.input_axes.size();
  const std::vector<std::size_t> corners = {0, 40, 80, 120, 160};  // x = 0, 20, 40, 60, 80 mm
  REQUIRE(corners.back() == n - 1);
  for (std::size_t c = 0; c + 1 < corners.size(); ++c) {
    const double lean = deg_to_rad(c % 2 == 0 ? 10.0 : -10.0);
    const Vec3d from = Vec3d(std::sin(lean), 0.0, std::cos(lean));
    const Vec3d to = Vec3d(-std::sin(lean), 0.0, std::cos(lean));
    const std::vector<double> len(p.segment_mm.begin() + static_cast<long>(corners[c]),
                                  p.segment_mm.begin() + static_cast<long>(corners[c + 1]));
    const std::vector<Vec3d> v = arc_length_slerp(from, to, len);
    std::copy(v.begin(), v.end(), p.input_axes.begin() + static_cast<long>(corners[c]));
  }
  const AxisTest all = [](std::size_t, const Vec3d&) { return true; };
  PaperOptions sharp_opt;
  sharp_opt.pull_weight = 1e9;
  sharp_opt.joint_smoothing = false;
  PaperOptions smooth_opt = sharp_opt;
  smooth_opt.joint_smoothing = true;
  const PassPlan sharp = plan_pass_paper(p, all, sharp_opt);
  const PassPlan smooth = plan_pass_paper(p, all, smooth_opt);
  REQUIRE(smooth.keys.size() == 5);
  CHECK(smooth.smoothed_joints == 3);
  CHECK(smooth.sharp_joints == 0);
  const double jump_sharp = max_rate_change(rates(sharp.axes, p.segment_mm));
  const double jump_smooth = max_rate_change(rates(smooth.axes, p.segment_mm));
  INFO("largest change of the rate between segments: sharp " << jump_sharp << ", smoothed "
                                                             << jump_smooth << " rad/mm");
  // The reversal is spread evenly over the blend window (2 d = 20 mm = 40 segments here): what
  // was one jump becomes 40 steps of 1/40 of it (within the chord approximation of the rates).
  CHECK(jump_smooth < 0.05 * jump_sharp);
  // Within the blend the rate changes linearly with the path: a constant change per mm.
  const std::vector<Vec3d> w = rates(smooth.axes, p.segment_mm);
  const auto accel = [&](std::size_t i) {
    return (w[i + 1] - w[i]).norm() / (0.5 * (p.segment_mm[i] + p.segment_mm[i + 1]));
  };
  for (std::size_t i = 62; i < 98; ++i) CHECK(accel(i) == Approx(accel(80)).epsilon(0.05));
}

TEST_CASE("paper optimiser: on a sine the peak rate and its change fall", "[plan][paper]") {
  const PassProblem p = sine_pass(10.0, 40.0, deg_to_rad(5.0));
  const PassPlan plan = plan_pass_paper(
      p, [](std::size_t, const Vec3d&) { return true; }, PaperOptions{});
  const auto peak = [](const std::vector<Vec3d>& w) {
    double m = 0.0;
    for (const Vec3d& x : w) m = std::max(m, x.norm());
    return m;
  };
  const std::vector<Vec3d> before = rates(p.input_axes, p.segment_mm);
  const std::vector<Vec3d> after = rates(plan.axes, p.segment_mm);
  CHECK(peak(after) < 0.6 * peak(before));
  CHECK(max_rate_change(after) < 0.6 * max_rate_change(before));
}
