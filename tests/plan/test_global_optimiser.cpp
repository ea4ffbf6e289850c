#include <array>
#include <catch2/catch.hpp>
#include <cmath>
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

/// A pass grazing the pole beside an obstacle in C-space: its input axes, the acceptable set
/// (a forbidden cone of 12 deg about a direction near the path, the 30 deg deviation cone
/// around each input axis), and a feasible start (the input axes where free, else pushed out
/// of the obstacle).
struct BesideObstacle {
  std::vector<Vec3d> input, start;
  AxisTest free;
};

BesideObstacle beside_obstacle(double offset_deg, double half_mm) {
  BesideObstacle c;
  c.input = grazing_axes(offset_deg, half_mm);
  const Vec3d obstacle = Vec3d(0.25, 0.3, 1.0).normalized();
  c.free = [input = c.input, obstacle](std::size_t i, const Vec3d& axis) {
    return angle_between(axis, input[i]) <= deg_to_rad(30.0) + 1e-12 &&
           angle_between(axis, obstacle) > deg_to_rad(12.0);
  };
  c.start = c.input;
  for (std::size_t i = 0; i < c.start.size(); ++i) {
    if (c.free(i, c.start[i])) continue;
    const Vec3d away = (c.start[i] - obstacle).normalized();
    c.start[i] = (obstacle + std::tan(deg_to_rad(13.0)) * away).normalized();
  }
  return c;
}

/// A pass problem: the input axes, the machine's poses of `start` as the warm start (the pass
/// entered by a rapid), every segment `segment_s` long.
GlobalPassProblem pass_problem(const MachineKinematicsd& m, const std::vector<Vec3d>& input,
                               const std::vector<Vec3d>& start, double segment_s) {
  std::vector<bool> rapid_into(input.size(), false);
  rapid_into[0] = true;
  GlobalPassProblem problem;
  problem.input_axes = input;
  problem.warm_start = plan_poses(m, start, rapid_into).poses;
  problem.segment_time_s.assign(input.size() - 1, segment_s);
  return problem;
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

namespace {

/// The sum-of-squares programme as the file comment states it, one state and one predecessor
/// at a time: the first predecessor of the least value (ties within 1e-12 keep the earlier).
std::vector<std::size_t> reference_sum_squares(const std::vector<std::vector<Posed>>& cand,
                                               const std::vector<double>& t, double& value) {
  const std::size_t n = cand.size();
  const double deg = 180.0 / Constants<double>::pi();
  const auto rate = [&](std::size_t i, std::size_t r, std::size_t s) {
    return std::array<double, 2>{(cand[i + 1][s].tilt_rad - cand[i][r].tilt_rad) / t[i],
                                 wrap_pi(cand[i + 1][s].c_rad - cand[i][r].c_rad) / t[i]};
  };
  std::vector<std::vector<double>> cost(n);
  std::vector<std::vector<std::size_t>> back(n);
  cost[1].assign(cand[0].size() * cand[1].size(), 0.0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const std::size_t kp = cand[i - 1].size(), k = cand[i].size(), kn = cand[i + 1].size();
    const double c = deg * 2.0 / (t[i - 1] + t[i]);
    cost[i + 1].assign(k * kn, 0.0);
    back[i + 1].assign(k * kn, 0);
    for (std::size_t s = 0; s < k; ++s) {
      for (std::size_t u = 0; u < kn; ++u) {
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t r = 0; r < kp; ++r) {
          const auto before = rate(i - 1, r, s), after = rate(i, s, u);
          const double da = c * (after[0] - before[0]), dc = c * (after[1] - before[1]);
          const double v = cost[i][r * k + s] + (da * da + dc * dc);
          if (v < best * (1.0 - 1e-12) - 1e-300) best = v, back[i + 1][s * kn + u] = r;
        }
        cost[i + 1][s * kn + u] = best;
      }
    }
  }
  std::size_t state = 0;
  for (std::size_t st = 1; st < cost[n - 1].size(); ++st) {
    if (cost[n - 1][st] < cost[n - 1][state] * (1.0 - 1e-12) - 1e-300) state = st;
  }
  value = cost[n - 1][state];
  std::vector<std::size_t> seq(n);
  seq[n - 1] = state % cand[n - 1].size();
  seq[n - 2] = state / cand[n - 1].size();
  for (std::size_t i = n - 1; i >= 2; --i) {
    seq[i - 2] = back[i][seq[i - 1] * cand[i].size() + seq[i]];
  }
  return seq;
}

}  // namespace

TEST_CASE("global: the sum-of-squares programme keeps the rule's choice on ties and near-ties",
          "[plan][global]") {
  // Many candidates (the programme's vectorised step), some repeated exactly or within a few
  // ulps (ties its shortcut must hand to the rule's scan), some far apart (no tie).
  std::mt19937 rng(65);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int repeats = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const std::size_t n = 4 + static_cast<std::size_t>(u(rng) * 30.0);
    std::vector<std::vector<Posed>> cand(n);
    std::vector<double> t;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = 1 + static_cast<std::size_t>(u(rng) * 24.0);
      for (std::size_t j = 0; j < k; ++j) {
        const double pick = u(rng);
        if (j > 0 && pick < 0.3) {
          Posed again = cand[i][static_cast<std::size_t>(u(rng) * static_cast<double>(j))];
          if (pick < 0.1) again.tilt_rad = std::nextafter(again.tilt_rad, 10.0);
          cand[i].push_back(again);
          ++repeats;
        } else {
          cand[i].push_back(
              Posed{deg_to_rad(-40.0 + 80.0 * u(rng)), deg_to_rad(-180.0 + 360.0 * u(rng))});
        }
      }
      if (i > 0) t.push_back(trial % 3 == 0 ? 0.1 : 0.01 + u(rng));
    }
    if (trial % 5 == 0) {
      // Every point the same candidates: the zero-acceleration plans tie exactly.
      for (std::size_t i = 1; i < n; ++i) cand[i] = cand[0];
    }
    INFO("trial " << trial);
    double value = -1.0, want_value = -2.0;
    const std::vector<std::size_t> seq =
        best_candidate_sequence(cand, t, GlobalObjective::SumSquares, &value, true);
    CHECK(seq == reference_sum_squares(cand, t, want_value));
    CHECK(value == want_value);
  }
  CHECK(repeats > 100);
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
    "global: from a feasible start it never leaves the free space and never ends worse -- near "
    "the pole it lowers the acceleration",
    "[plan][global][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  for (double offset : {0.5, 2.0, 6.0}) {
    for (GlobalObjective objective : {GlobalObjective::SumSquares, GlobalObjective::Peak}) {
      INFO("offset " << offset << " deg, " << to_string(objective));
      const BesideObstacle c = beside_obstacle(offset, 20.0);
      const std::vector<Vec3d>& input = c.input;
      const std::vector<Vec3d>& start = c.start;
      const AxisTest& free = c.free;
      const std::size_t n = input.size();
      for (std::size_t i = 0; i < n; ++i) REQUIRE(free(i, start[i]));
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
        CHECK(m.tilt.contains(plan.poses[i].tilt_rad));
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
  const MachineKinematicsd m = default_machine_kinematics();
  const std::vector<Vec3d> input = grazing_axes(1.0, 15.0);
  const std::size_t n = input.size();
  const AxisTest cone = [&](std::size_t i, const Vec3d& axis) {
    return angle_between(axis, input[i]) <= deg_to_rad(20.0) + 1e-12;
  };
  GlobalPassProblem problem = pass_problem(m, input, input, 0.03);
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
    CHECK(again.poses[i].tilt_rad == second.poses[i].tilt_rad);
    CHECK(again.poses[i].c_rad == second.poses[i].c_rad);
  }
}

TEST_CASE(
    "global: the pyramid's finer caps never make the programme's answer worse, stay in the "
    "free space, and beside obstacles lower it",
    "[plan][global][pyramid]") {
  // Passes grazing the pole with a forbidden cone placed at random beside them: the coarse
  // caps (15 deg) see the free space only in big steps.
  const MachineKinematicsd m = default_machine_kinematics();
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int lowered = 0, trials = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const std::vector<Vec3d> input = grazing_axes(3.0 + 4.0 * u(rng), 12.0, 1.5);
    const Vec3d obstacle = Vec3d(0.3 * u(rng), 0.3 * u(rng), 1.0).normalized();
    const double obstacle_rad = deg_to_rad(8.0 + 4.0 * u(rng));
    const AxisTest free = [&](std::size_t i, const Vec3d& axis) {
      return angle_between(axis, input[i]) <= deg_to_rad(30.0) + 1e-12 &&
             angle_between(axis, obstacle) > obstacle_rad;
    };
    const std::size_t n = input.size();
    std::vector<Vec3d> start = input;
    for (std::size_t i = 0; i < n; ++i) {
      if (free(i, start[i])) continue;
      const Vec3d away = (start[i] - obstacle).normalized();
      start[i] = (obstacle + std::tan(obstacle_rad + deg_to_rad(1.0)) * away).normalized();
    }
    bool feasible = true;
    for (std::size_t i = 0; i < n; ++i) feasible = feasible && free(i, start[i]);
    if (!feasible) continue;
    const GlobalPassProblem problem = pass_problem(m, input, start, 0.05);
    GlobalOptions coarse;
    coarse.fine_step_deg = 0.0;
    GlobalOptions fine;
    fine.fine_step_deg = 2.0;
    const GlobalPassPlan a = plan_pass_global(m, problem, free, coarse);
    const GlobalPassPlan b = plan_pass_global(m, problem, free, fine);
    INFO("trial " << trial << ": coarse programme " << b.objective_dp << ", pyramid "
                  << b.objective_pyramid << ", after refinement " << a.objective << " / "
                  << b.objective);
    CHECK(a.pyramid_levels == 0);
    CHECK(b.pyramid_levels == 2);  // 7.5 and 3.75 deg; 1.875 is below the 2 deg asked
    CHECK(b.objective_dp == Approx(a.objective_dp));
    CHECK(b.objective_pyramid <= b.objective_dp);
    for (std::size_t i = 0; i < n; ++i) REQUIRE(free(i, b.axes[i]));
    ++trials;
    lowered += b.objective_pyramid < 0.9 * b.objective_dp;
  }
  CHECK(trials >= 6);
  CHECK(lowered >= 2);  // beside some obstacles the finer caps find a much smoother way
}

namespace {

/// The time objective's surrogate written out on its own (docs/global-method.md): per segment
/// the least time at the programmed time and the velocity limits; per point (the ends too,
/// from and to rest) half of the least uniform stretch of its segments that meets the
/// schedule's inner set there: a joint that keeps its direction changes velocity within the
/// mean time, one that reverses, starts or stops does so on each side within half that side's
/// time. C steps wrapped to half a turn.
double surrogate_time(const std::vector<JointPosition>& q, const std::vector<double>& programmed,
                      const JointLimits& lim) {
  const std::size_t n = q.size();
  // Segments 0 .. n - 2, with a zero-length, zero-time one before and after (the rests).
  std::vector<double> tau(n + 1, 0.0);
  std::vector<std::array<double, 5>> dq(n + 1, std::array<double, 5>{});
  for (std::size_t i = 0; i + 1 < n; ++i) {
    tau[i + 1] = programmed[i];
    for (std::size_t j = 0; j < 5; ++j) {
      double d = q[i + 1][j] - q[i][j];
      if (j == 4) d = std::remainder(d, 360.0);
      dq[i + 1][j] = d;
      const double v = lim[j].max_velocity_per_s * (1.0 - 1e-5);
      if (v > 0.0) tau[i + 1] = std::max(tau[i + 1], std::abs(d) / v);
    }
  }
  double total = 0.0;
  for (double t : tau) total += t;
  for (std::size_t i = 1; i <= n; ++i) {  // point i - 1, between segments i - 1 and i
    double both = 0.0, side[2] = {0.0, 0.0};
    const double h = (tau[i - 1] + tau[i]) / 2.0;
    for (std::size_t j = 0; j < 5; ++j) {
      const double a = lim[j].max_accel_per_s2 * (1.0 - 1e-5);
      if (!(a > 0.0)) continue;
      const double w0 = tau[i - 1] > 0 ? dq[i - 1][j] / tau[i - 1] : 0.0;
      const double w1 = tau[i] > 0 ? dq[i][j] / tau[i] : 0.0;
      if (w0 * w1 > 0.0) {
        both = std::max(both, std::abs(w1 - w0) / h / a);
      } else {
        if (tau[i - 1] > 0) side[0] = std::max(side[0], 2.0 * std::abs(w0) / tau[i - 1] / a);
        if (tau[i] > 0) side[1] = std::max(side[1], 2.0 * std::abs(w1) / tau[i] / a);
      }
    }
    if (both > 1.0) total += 0.5 * (std::sqrt(both) - 1.0) * 2.0 * h;
    if (side[0] > 1.0) total += 0.5 * (std::sqrt(side[0]) - 1.0) * tau[i - 1];
    if (side[1] > 1.0) total += 0.5 * (std::sqrt(side[1]) - 1.0) * tau[i];
  }
  return total;
}

/// Joints of a made-up machine for the tests: the table carries point i (on a line along x)
/// by C about z and A about x, as a table-table does; X Y Z in mm, A C in degrees.
JointPosition made_up_joints(std::size_t i, const Posed& p) {
  const double x = -10.0 + 0.5 * static_cast<double>(i), y = 20.0;
  const double xc = std::cos(p.c_rad) * x + std::sin(p.c_rad) * y;
  const double yc = -std::sin(p.c_rad) * x + std::cos(p.c_rad) * y;
  return {xc, std::cos(p.tilt_rad) * yc, -std::sin(p.tilt_rad) * yc, rad_to_deg(p.tilt_rad),
          rad_to_deg(p.c_rad)};
}

/// 20 deg/s on A and C, with `rotary_accel` deg/s^2; X Y Z 100 mm/s and 1000 mm/s^2.
JointLimits slow_rotary_limits(double rotary_accel = 40.0) {
  JointLimits lim{};
  for (std::size_t j = 0; j < 3; ++j) lim[j] = {100.0, 1000.0, 0.0};
  lim[3] = {20.0, rotary_accel, 0.0};
  lim[4] = {20.0, rotary_accel, 0.0};
  return lim;
}

}  // namespace

TEST_CASE("global, objective time: the programme minimises the surrogate time, as enumeration does",
          "[plan][global][time]") {
  std::mt19937 rng(67);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // Accelerations low enough that the points' term matters as much as the segments'.
  const JointLimits lim = slow_rotary_limits(2.0);
  int binding = 0, accel_binding = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t n = 3 + trial % 4;  // 3 .. 6 points
    std::vector<std::vector<Posed>> cand(n);
    std::vector<std::vector<JointPosition>> joints(n);
    std::vector<double> t, programmed;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = 1 + static_cast<std::size_t>(u(rng) * 4.0);
      for (std::size_t j = 0; j < k; ++j) {
        cand[i].push_back(
            Posed{deg_to_rad(-30.0 + 60.0 * u(rng)), deg_to_rad(-180.0 + 360.0 * u(rng))});
        joints[i].push_back(made_up_joints(i, cand[i].back()));
      }
      if (i > 0) t.push_back(0.05 + u(rng)), programmed.push_back(0.1 + 2.0 * u(rng));
    }
    INFO("trial " << trial);
    double value = -1.0;
    const std::vector<std::size_t> seq =
        fastest_candidate_sequence(cand, joints, programmed, t, lim, &value);
    REQUIRE(seq.size() == n);
    std::vector<JointPosition> chosen;
    for (std::size_t i = 0; i < n; ++i) {
      REQUIRE(seq[i] < cand[i].size());
      chosen.push_back(joints[i][seq[i]]);
    }
    CHECK(value == Approx(surrogate_time(chosen, programmed, lim)).epsilon(1e-9));
    // Enumeration.
    std::vector<std::size_t> idx(n, 0);
    double best = std::numeric_limits<double>::infinity(), programmed_sum = 0.0;
    for (double p : programmed) programmed_sum += p;
    while (true) {
      std::vector<JointPosition> q;
      for (std::size_t i = 0; i < n; ++i) q.push_back(joints[i][idx[i]]);
      best = std::min(best, surrogate_time(q, programmed, lim));
      std::size_t i = 0;
      while (i < n && ++idx[i] == cand[i].size()) idx[i++] = 0;
      if (i == n) break;
    }
    CHECK(value <= best * (1.0 + 1e-9));
    if (best > programmed_sum * 1.01) ++binding;
    JointLimits velocity_only = lim;
    for (JointLimit& l : velocity_only) l.max_accel_per_s2 = 0.0;
    if (value > surrogate_time(chosen, programmed, velocity_only) * 1.01) ++accel_binding;
  }
  // The limits shape most of these problems, the accelerations many.
  CHECK(binding > 30);
  CHECK(accel_binding > 15);
}

TEST_CASE(
    "global, objective time: the surrogate's choice, timed by the schedule, comes close to the "
    "best sequence by the schedule itself",
    "[plan][global][time]") {
  // How close the tractable surrogate gets to the true objective over the same candidates
  // (docs/global-method.md quotes these numbers): enumeration timed by schedule_feed.
  std::mt19937 rng(71);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst_gap = 0.0, sum_gap = 0.0;
  int trials = 0, exact = 0;
  for (double accel : {40.0, 2.0}) {
    const JointLimits lim = slow_rotary_limits(accel);
    for (int trial = 0; trial < 60; ++trial) {
      const std::size_t n = 4 + trial % 3;  // 4 .. 6 points
      std::vector<std::vector<Posed>> cand(n);
      std::vector<std::vector<JointPosition>> joints(n);
      std::vector<double> t, programmed;
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = 2 + static_cast<std::size_t>(u(rng) * 3.0);
        // Candidates near a common path, as a cone's are: C within +-40 deg of a drift.
        for (std::size_t j = 0; j < k; ++j) {
          cand[i].push_back(
              Posed{deg_to_rad(-20.0 + 40.0 * u(rng)),
                    deg_to_rad(15.0 * static_cast<double>(i) - 40.0 + 80.0 * u(rng))});
          joints[i].push_back(made_up_joints(i, cand[i].back()));
        }
        if (i > 0) t.push_back(0.05 + u(rng)), programmed.push_back(0.2 + u(rng));
      }
      const auto timed = [&](const std::vector<std::size_t>& idx) {
        std::vector<JointPosition> q;
        std::vector<Posed> p;
        for (std::size_t i = 0; i < n; ++i) p.push_back(cand[i][idx[i]]);
        p = unwrapped(p);
        for (std::size_t i = 0; i < n; ++i) q.push_back(made_up_joints(i, p[i]));
        return pass_time_s(q, programmed, lim);
      };
      const double chosen =
          timed(fastest_candidate_sequence(cand, joints, programmed, t, lim, nullptr));
      std::vector<std::size_t> idx(n, 0);
      double best = std::numeric_limits<double>::infinity();
      while (true) {
        best = std::min(best, timed(idx));
        std::size_t i = 0;
        while (i < n && ++idx[i] == cand[i].size()) idx[i++] = 0;
        if (i == n) break;
      }
      const double gap = chosen / best - 1.0;
      REQUIRE(gap >= -1e-9);
      worst_gap = std::max(worst_gap, gap);
      sum_gap += gap;
      exact += gap < 1e-9;
      ++trials;
    }
  }
  WARN("surrogate vs schedule over " << trials << " problems: " << exact << " exact, mean gap "
                                     << 100.0 * sum_gap / trials << " %, worst "
                                     << 100.0 * worst_gap << " %");
  CHECK(sum_gap / trials < 0.05);
  CHECK(worst_gap < 0.5);
}

TEST_CASE(
    "global, objective time: the pass's schedule is never slower than its starts, stays in the "
    "free space, and near the pole on slow rotary axes it is much faster",
    "[plan][global][time][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  const JointLimits lim = slow_rotary_limits();
  for (double offset : {0.5, 2.0, 6.0}) {
    INFO("offset " << offset << " deg");
    const BesideObstacle c = beside_obstacle(offset, 10.0);
    const std::vector<Vec3d>& input = c.input;
    const std::vector<Vec3d>& start = c.start;
    const AxisTest& free = c.free;
    const std::size_t n = input.size();
    GlobalPassProblem problem = pass_problem(m, input, start, 0.5 / (1000.0 / 60.0));
    problem.programmed_time_s = problem.segment_time_s;
    problem.joints_at = made_up_joints;
    problem.limits = lim;
    // The sum-squares plan as an alternative, as run_job gives it.
    GlobalOptions options;
    problem.alternatives.push_back(plan_pass_global(m, problem, free, options).poses);
    options.objective = GlobalObjective::Time;
    const GlobalPassPlan plan = plan_pass_global(m, problem, free, options);
    REQUIRE(plan.poses.size() == n);
    const auto time_of = [&](const std::vector<Posed>& poses) {
      std::vector<JointPosition> q;
      for (std::size_t i = 0; i < n; ++i) q.push_back(made_up_joints(i, poses[i]));
      return pass_time_s(q, problem.programmed_time_s, lim);
    };
    INFO("time " << plan.objective_warm << " s (warm), " << time_of(problem.alternatives[0])
                 << " s (sum-squares), programme " << plan.objective_dp << " s -> "
                 << plan.objective << " s");
    for (std::size_t i = 0; i < n; ++i) {
      CHECK(free(i, plan.axes[i]));
      CHECK(m.tilt.contains(plan.poses[i].tilt_rad));
    }
    CHECK(plan.objective == Approx(time_of(plan.poses)).epsilon(1e-12));
    CHECK(plan.objective <= plan.objective_warm * (1.0 + 1e-9));
    CHECK(plan.objective <= time_of(problem.alternatives[0]) * (1.0 + 1e-9));
    if (offset < 3.0) CHECK(plan.objective <= 0.5 * plan.objective_warm);
    // Deterministic.
    const GlobalPassPlan again = plan_pass_global(m, problem, free, options);
    for (std::size_t i = 0; i < n; ++i) CHECK(again.poses[i].c_rad == plan.poses[i].c_rad);
  }
}

TEST_CASE("global: bad problems are refused", "[plan][global][bad-input]") {
  const MachineKinematicsd m = default_machine_kinematics();
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
  // The time objective needs the joints and the programmed times.
  GlobalOptions timed;
  timed.objective = GlobalObjective::Time;
  p.segment_time_s = {0.1, 0.1};
  CHECK_THROWS_AS(plan_pass_global(m, p, any, timed), std::invalid_argument);
  p.joints_at = made_up_joints;
  CHECK_THROWS_AS(plan_pass_global(m, p, any, timed), std::invalid_argument);
  p.programmed_time_s = {0.1, 0.1};
  CHECK_NOTHROW(plan_pass_global(m, p, any, timed));
  CHECK_THROWS_AS(rotary_objective(p.warm_start, p.segment_time_s, GlobalObjective::Time),
                  std::invalid_argument);
}
