// The global method with a rotary axis held where the input holds it still (issue 59: a chamfer
// round a block at a constant tilt kept its input's C a of 4,843 deg/s^2, since every free plan
// moved the still tilt): the low-pass filter of the free axis against analytic values and its
// promise (no rate above the input's peak), and the held plan on a corner.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "plan/held_axis.hpp"
#include "taxopt/kinematics/pose_planner.hpp"
#include "taxopt/plan/global_optimiser.hpp"

using namespace taxopt;

namespace {

double peak_rate(const std::vector<double>& x, const std::vector<double>& t) {
  double peak = 0.0;
  for (std::size_t i = 0; i + 1 < x.size(); ++i)
    peak = std::max(peak, std::abs(x[i + 1] - x[i]) / t[i]);
  return peak;
}

double peak_accel(const std::vector<double>& x, const std::vector<double>& t) {
  double peak = 0.0;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {
    const double a =
        ((x[i + 1] - x[i]) / t[i] - (x[i] - x[i - 1]) / t[i - 1]) / (0.5 * (t[i] + t[i - 1]));
    peak = std::max(peak, std::abs(a));
  }
  return peak;
}

/// C of a chamfer round a corner: still, a quarter turn over `turn` points, still again.
std::vector<double> corner(std::size_t before, std::size_t turn, std::size_t after) {
  std::vector<double> c;
  for (std::size_t i = 0; i < before; ++i) c.push_back(0.0);
  for (std::size_t i = 1; i <= turn; ++i) {
    c.push_back(0.5 * M_PI * static_cast<double>(i) / static_cast<double>(turn));
  }
  for (std::size_t i = 0; i < after; ++i) c.push_back(0.5 * M_PI);
  return c;
}

}  // namespace

TEST_CASE("low pass: a ramp comes back where the window is centred and a window ahead of it",
          "[plan][global][held]") {
  // x = 2 tau over 0 .. 10 s in steps of 0.1 s; far from the ends (held outside) the centred
  // double box of width 0.6 s gives x back, the window ahead x + 2 * 0.6 (each box: half ahead).
  std::vector<double> x, t(100, 0.1);
  for (int i = 0; i <= 100; ++i) x.push_back(0.2 * i);
  const std::vector<double> centred = low_passed(x, t, 0.6, Window::Centred);
  const std::vector<double> ahead = low_passed(x, t, 0.6, Window::Ahead);
  const std::vector<double> behind = low_passed(x, t, 0.6, Window::Behind);
  for (int i = 20; i <= 80; ++i) {
    CHECK(centred[i] == Approx(x[i]).margin(1e-12));
    CHECK(ahead[i] == Approx(x[i] + 2.0 * 0.6).margin(1e-12));
    CHECK(behind[i] == Approx(x[i] - 2.0 * 0.6).margin(1e-12));
  }
  // Held at its ends outside the pass: a constant series stays itself.
  const std::vector<double> flat(101, 1.25);
  for (double v : low_passed(flat, t, 3.0, Window::Ahead)) CHECK(v == Approx(1.25).margin(1e-12));
}

TEST_CASE("low pass: no rate of the result above the input's peak, any window, width and times",
          "[plan][global][held]") {
  std::mt19937 rng(59);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = 3 + trial % 60;
    std::vector<double> x{0.0}, t;
    for (std::size_t i = 1; i < n; ++i) {
      t.push_back(0.01 + u(rng));
      x.push_back(x.back() + (u(rng) < 0.3 ? 0.0 : 4.0 * (u(rng) - 0.3)));
    }
    const double width = 0.02 + 5.0 * u(rng);
    for (Window w : {Window::Centred, Window::Ahead, Window::Behind}) {
      const std::vector<double> y = low_passed(x, t, width, w);
      CHECK(peak_rate(y, t) <= peak_rate(x, t) * (1.0 + 1e-9) + 1e-12);
    }
  }
}

TEST_CASE("low pass: a corner's turn spread out, its peak acceleration a small part of the input's",
          "[plan][global][held]") {
  const std::vector<double> c = corner(30, 6, 30);
  const std::vector<double> t(c.size() - 1, 0.05);
  const std::vector<double> y = low_passed(c, t, 0.8, Window::Centred);
  CHECK(peak_accel(y, t) < 0.1 * peak_accel(c, t));
  CHECK(peak_rate(y, t) < peak_rate(c, t));
}

TEST_CASE(
    "global, tilt held: round a corner at a constant tilt the plan keeps every tilt as it was, "
    "turns C no faster than the input and smooths its acceleration, and where C may only lead it "
    "leads",
    "[plan][global][held]") {
  const MachineKinematicsd m = default_machine_kinematics();
  const std::vector<double> c = corner(30, 6, 30);
  std::vector<Vec3d> input;
  const double tilt = 45.0 * M_PI / 180.0;
  for (double ci : c) input.push_back(m.forward(Posed{tilt, ci}));
  std::vector<bool> rapid_into(input.size(), false);
  rapid_into[0] = true;
  GlobalPassProblem problem;
  problem.input_axes = input;
  problem.warm_start = plan_poses(m, input, rapid_into).poses;
  problem.segment_time_s.assign(input.size() - 1, 0.05);
  problem.hold_tilt = problem.keep_peaks = true;
  GlobalOptions options;
  options.max_deviation_deg = 20.0;
  std::vector<double> input_c;
  for (const Posed& p : problem.warm_start) input_c.push_back(p.c_rad);
  const AxisTest cone = [&](std::size_t i, const Vec3d& axis) {
    return angle_between(axis, input[i]) <= deg_to_rad(20.0) + 1e-12;
  };
  // C may not fall behind the input's (a tool led into its travel keeps its lead).
  const AxisTest leads = [&](std::size_t i, const Vec3d& axis) {
    if (!cone(i, axis)) return false;
    const Posed p = m.inverse(axis).front();
    return std::abs(p.tilt_rad - tilt) > 1e-6 ||
           wrap_pi(p.c_rad - input_c[i]) >= -1e-9;  // the other branch: not this test's
  };
  for (const AxisTest* test : {&cone, &leads}) {
    const GlobalPassPlan plan = plan_pass_global(m, problem, *test, options);
    std::vector<double> plan_c;
    for (std::size_t i = 0; i < plan.poses.size(); ++i) {
      CHECK(plan.poses[i].tilt_rad == problem.warm_start[i].tilt_rad);
      CHECK((*test)(i, m.forward(plan.poses[i])));
      plan_c.push_back(plan.poses[i].c_rad);
    }
    const std::vector<double>& t = problem.segment_time_s;
    CHECK(peak_rate(plan_c, t) <= peak_rate(input_c, t) * (1.0 + 1e-9));
    CHECK(peak_accel(plan_c, t) < 0.5 * peak_accel(input_c, t));
  }
  // A caller's test that refuses every change keeps the warm start.
  problem.admissible = [&](const std::vector<Posed>& poses) {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      if (poses[i].c_rad != problem.warm_start[i].c_rad) return false;
    }
    return true;
  };
  const GlobalPassPlan kept = plan_pass_global(m, problem, cone, options);
  for (std::size_t i = 0; i < kept.poses.size(); ++i) {
    CHECK(kept.poses[i].c_rad == problem.warm_start[i].c_rad);
  }
}
