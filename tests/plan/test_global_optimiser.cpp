#include <catch2/catch.hpp>
#include <random>

#include "taxopt/kinematics/pose_planner.hpp"
#include "taxopt/plan/global_optimiser.hpp"

using namespace taxopt;

namespace {

/// Poses of a candidate sequence with C made continuous (each step the nearest turn), as the
/// machine would run them.
std::vector<Posed> unwrapped(std::vector<Posed> poses) {
  for (std::size_t i = 1; i < poses.size(); ++i) {
    poses[i].c_rad = poses[i - 1].c_rad + wrap_pi(poses[i].c_rad - poses[i - 1].c_rad);
  }
  return poses;
}

/// The least objective over every sequence of candidates, by enumeration.
double brute_force(const std::vector<std::vector<Posed>>& cand, const std::vector<double>& t,
                   GlobalObjective objective, bool wrap) {
  const std::size_t n = cand.size();
  std::vector<std::size_t> idx(n, 0);
  double best = std::numeric_limits<double>::infinity();
  while (true) {
    std::vector<Posed> p;
    for (std::size_t i = 0; i < n; ++i) p.push_back(cand[i][idx[i]]);
    best = std::min(best, rotary_objective(wrap ? unwrapped(p) : p, t, objective));
    std::size_t i = 0;
    while (i < n && ++idx[i] == cand[i].size()) idx[i++] = 0;
    if (i == n) break;
  }
  return best;
}

/// A pass whose axis tilts about y by `rate_deg_mm` per mm while its tilt about x stays
/// `offset_deg` (it passes the pole at about that distance), points every 0.5 mm.
std::vector<Vec3d> grazing_axes(double offset_deg, double half_mm, double rate_deg_mm = 1.0) {
  std::vector<Vec3d> axes;
  for (double s = -half_mm; s <= half_mm + 1e-9; s += 0.5) {
    axes.push_back(
        Vec3d(std::tan(deg_to_rad(rate_deg_mm * s)), std::tan(deg_to_rad(offset_deg)), 1.0)
            .normalized());
  }
  return axes;
}

}  // namespace

TEST_CASE("global: the programme finds the best sequence of candidates, as enumeration does",
          "[plan][global]") {
  std::mt19937 rng(61);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t n = 3 + trial % 4;  // 3 .. 6 points
    std::vector<std::vector<Posed>> cand(n);
    std::vector<double> t;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = 1 + static_cast<std::size_t>(u(rng) * 4.0);  // 1 .. 4 candidates
      for (std::size_t j = 0; j < k; ++j) {
        cand[i].push_back(
            Posed{deg_to_rad(-60.0 + 120.0 * u(rng)), deg_to_rad(-180.0 + 360.0 * u(rng))});
      }
      if (i > 0) t.push_back(0.05 + u(rng));
    }
    for (GlobalObjective objective : {GlobalObjective::SumSquares, GlobalObjective::Peak}) {
      for (bool wrap : {true, false}) {
        INFO("trial " << trial << ", " << to_string(objective) << (wrap ? ", C wrapped" : ""));
        double value = -1.0;
        const std::vector<std::size_t> seq =
            best_candidate_sequence(cand, t, objective, &value, wrap);
        REQUIRE(seq.size() == n);
        std::vector<Posed> chosen;
        for (std::size_t i = 0; i < n; ++i) {
          REQUIRE(seq[i] < cand[i].size());
          chosen.push_back(cand[i][seq[i]]);
        }
        const double own = rotary_objective(wrap ? unwrapped(chosen) : chosen, t, objective);
        const double best = brute_force(cand, t, objective, wrap);
        CHECK(own == Approx(best).epsilon(1e-9).margin(1e-9));
        CHECK(value == Approx(best).epsilon(1e-9).margin(1e-9));
        ++compared;
      }
    }
  }
  CHECK(compared == 160);
}

TEST_CASE("global: the objective is eq. 16-18's acceleration, squared and summed or peaked",
          "[plan][global]") {
  // A at 0, 1, 3 deg and C fixed, segments of 0.5 s: omega 2 and 4 deg/s, a = 2 / 0.5 = 4.
  const std::vector<Posed> p = {Posed{0.0, 0.0}, Posed{deg_to_rad(1.0), 0.0},
                                Posed{deg_to_rad(3.0), 0.0}};
  CHECK(rotary_objective(p, {0.5, 0.5}, GlobalObjective::SumSquares) == Approx(16.0));
  CHECK(rotary_objective(p, {0.5, 0.5}, GlobalObjective::Peak) == Approx(4.0));
  CHECK_THROWS_AS(rotary_objective(p, {0.5}, GlobalObjective::Peak), std::invalid_argument);
}

TEST_CASE(
    "global: from a feasible start it never leaves the free space and never ends worse; near "
    "the pole it lowers the acceleration",
    "[plan][global][pole]") {
  const ACMachined m = default_ac_machine();
  // A forbidden cone of 12 deg about a direction near the path (an obstacle in C-space), the
  // 30 deg deviation cone around each input axis.
  const Vec3d obstacle = Vec3d(0.25, 0.3, 1.0).normalized();
  for (double offset : {0.5, 2.0, 6.0}) {
    for (GlobalObjective objective : {GlobalObjective::SumSquares, GlobalObjective::Peak}) {
      INFO("offset " << offset << " deg, " << to_string(objective));
      const std::vector<Vec3d> input = grazing_axes(offset, 20.0);
      const std::size_t n = input.size();
      const AxisTest free = [&](std::size_t i, const Vec3d& axis) {
        return angle_between(axis, input[i]) <= deg_to_rad(30.0) + 1e-12 &&
               angle_between(axis, obstacle) > deg_to_rad(12.0);
      };
      // The warm start: the input axes where free, else pushed out of the obstacle.
      std::vector<Vec3d> start = input;
      for (std::size_t i = 0; i < n; ++i) {
        if (free(i, start[i])) continue;
        const Vec3d away = (start[i] - obstacle).normalized();
        const Vec3d side = (obstacle + std::tan(deg_to_rad(13.0)) * away).normalized();
        start[i] = side;
        REQUIRE(free(i, start[i]));
      }
      std::vector<bool> rapid_into(n, false);
      rapid_into[0] = true;
      const PosePlan warm = plan_poses(m, start, rapid_into);
      REQUIRE(warm.ok());
      GlobalPassProblem problem;
      problem.input_axes = input;
      problem.warm_start = warm.poses;
      problem.segment_time_s.assign(n - 1, 0.5 / (1000.0 / 60.0));  // 0.5 mm at 1000 mm/min
      GlobalOptions options;
      options.objective = objective;
      const GlobalPassPlan plan = plan_pass_global(m, problem, free, options);
      REQUIRE(plan.poses.size() == n);
      INFO("objective " << plan.objective_warm << " -> programme " << plan.objective_dp << " -> "
                        << plan.objective << " after " << plan.iterations << " steps, up to "
                        << plan.max_candidates << " candidates a point");
      for (std::size_t i = 0; i < n; ++i) {
        CHECK(free(i, plan.axes[i]));
        CHECK((plan.axes[i] - m.forward(plan.poses[i])).norm() < 1e-12);
        CHECK(m.a.contains(plan.poses[i].a_rad));
        if (i > 0) CHECK(std::abs(plan.poses[i].c_rad - plan.poses[i - 1].c_rad) < 3.2);
      }
      CHECK(plan.objective <= plan.objective_warm);
      CHECK(plan.objective ==
            Approx(rotary_objective(plan.poses, problem.segment_time_s, objective)));
      // Grazing the pole the input turns C fast; the machine-space optimum does not.
      if (offset < 3.0) CHECK(plan.objective <= 0.1 * plan.objective_warm);
    }
  }
}

TEST_CASE("global: warm-started from its own result it stays where it is or improves",
          "[plan][global]") {
  const ACMachined m = default_ac_machine();
  const std::vector<Vec3d> input = grazing_axes(1.0, 15.0);
  const std::size_t n = input.size();
  const AxisTest cone = [&](std::size_t i, const Vec3d& axis) {
    return angle_between(axis, input[i]) <= deg_to_rad(20.0) + 1e-12;
  };
  std::vector<bool> rapid_into(n, false);
  rapid_into[0] = true;
  GlobalPassProblem problem;
  problem.input_axes = input;
  problem.warm_start = plan_poses(m, input, rapid_into).poses;
  problem.segment_time_s.assign(n - 1, 0.03);
  GlobalOptions options;
  options.max_deviation_deg = 20.0;
  const GlobalPassPlan first = plan_pass_global(m, problem, cone, options);
  problem.warm_start = first.poses;
  const GlobalPassPlan second = plan_pass_global(m, problem, cone, options);
  CHECK(second.objective <= first.objective);
  CHECK(second.objective_warm == Approx(first.objective));
  // Deterministic: the same problem gives the same poses.
  const GlobalPassPlan again = plan_pass_global(m, problem, cone, options);
  for (std::size_t i = 0; i < n; ++i) {
    CHECK(again.poses[i].a_rad == second.poses[i].a_rad);
    CHECK(again.poses[i].c_rad == second.poses[i].c_rad);
  }
}

TEST_CASE("global: bad problems are refused", "[plan][global][bad-input]") {
  const ACMachined m = default_ac_machine();
  const AxisTest any = [](std::size_t, const Vec3d&) { return true; };
  GlobalPassProblem p;
  p.input_axes = {Vec3d::UnitZ(), Vec3d::UnitZ(), Vec3d::UnitZ()};
  p.warm_start = {Posed{}, Posed{}, Posed{}};
  p.segment_time_s = {0.1};
  CHECK_THROWS_AS(plan_pass_global(m, p, any), std::invalid_argument);
  p.segment_time_s = {0.1, 0.0};
  CHECK_THROWS_AS(plan_pass_global(m, p, any), std::invalid_argument);
  CHECK_THROWS_AS(best_candidate_sequence({{}, {Posed{}}}, {0.1}, GlobalObjective::Peak, nullptr),
                  std::invalid_argument);
}
