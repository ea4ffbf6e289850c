#include <catch2/catch.hpp>
#include <random>

#include "taxopt/kinematics/pose_planner.hpp"

using namespace taxopt;

namespace {

std::vector<bool> feeds(std::size_t n) {
  std::vector<bool> r(n, false);
  r[0] = true;
  return r;
}

double max_c_step_deg(const std::vector<Posed>& poses) {
  double m = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    m = std::max(m, std::abs(rad_to_deg(poses[i].c_rad - poses[i - 1].c_rad)));
  }
  return m;
}

void require_axes(const MachineKinematicsd& m, const std::vector<Posed>& poses,
                  const std::vector<Vec3d>& axes) {
  for (std::size_t i = 0; i < axes.size(); ++i) {
    REQUIRE((m.forward(poses[i]) - axes[i]).norm() < 1e-9);
    REQUIRE(m.tilt.contains(poses[i].tilt_rad));
    REQUIRE(m.c.contains(poses[i].c_rad));
  }
}

// The kinematics every planner property holds for: the A/C table-table and the B/C one. B/C at
// (t, c) gives the axis A/C gives at (t, c + 90 deg), so a path written for A/C, turned a
// quarter about Z, asks the B/C machine for the same poses: the tests below check the same
// poses of both.
std::vector<MachineKinematicsd> both_kinematics(const MachineKinematicsd& ac) {
  MachineKinematicsd bc = ac;
  bc.tilt_about = TiltAxis::Y;
  return {ac, bc};
}

std::vector<Vec3d> for_machine(const MachineKinematicsd& m, std::vector<Vec3d> axes) {
  if (m.tilt_about == TiltAxis::Y) {
    for (Vec3d& v : axes) v = Eigen::AngleAxisd(Constants<double>::pi() / 2, Vec3d::UnitZ()) * v;
  }
  return axes;
}

}  // namespace

TEST_CASE("planner: the paper's eight axes give its eight (A, C) with A from -110 to 30 deg",
          "[kinematics][paper]") {
  MachineKinematicsd m = default_machine_kinematics();
  m.tilt.min_rad = deg_to_rad(-110.0);
  m.tilt.max_rad = deg_to_rad(30.0);
  const double ij[8][2] = {{-0.3281, 0.9447}, {-0.6063, 0.7952}, {-0.7259, 0.6878},
                           {-0.7870, 0.6169}, {-0.8267, 0.5626}, {-0.8500, 0.5268},
                           {-0.8679, 0.4968}, {-0.8804, 0.4742}};
  const double tilt_deg[8] = {-19.1507, -37.3222, -46.5477, -51.9082,
                              -55.7644, -58.2102, -60.2138, -61.6904};
  std::vector<Vec3d> axes;
  for (const auto& v : ij) axes.push_back(Vec3d(0, v[0], v[1]).normalized());
  const PosePlan plan = plan_poses(m, axes, feeds(8));
  REQUIRE(plan.ok());
  for (int i = 0; i < 8; ++i) {
    CHECK(rad_to_deg(plan.poses[i].tilt_rad) == Approx(tilt_deg[i]).margin(0.01));
    CHECK(std::abs(rad_to_deg(plan.poses[i].c_rad)) == Approx(180.0).margin(0.01));
  }
}

TEST_CASE("planner: crossing the pole A = 0 flips A's sign, C does not jump, A/C and B/C",
          "[kinematics][bc]") {
  for (const MachineKinematicsd& m : both_kinematics(default_machine_kinematics())) {
    INFO("tilt " << m.tilt_letter());
    std::vector<Vec3d> axes;
    for (int i = -10; i <= 10; ++i) {
      axes.push_back(Eigen::AngleAxisd(deg_to_rad(3.0 * i), Vec3d::UnitY()) * Vec3d::UnitZ());
    }
    axes = for_machine(m, axes);
    const PosePlan plan = plan_poses(m, axes, feeds(axes.size()));
    REQUIRE(plan.ok());
    require_axes(m, plan.poses, axes);
    CHECK(max_c_step_deg(plan.poses) < 1e-9);
    CHECK(plan.poses.front().tilt_rad * plan.poses.back().tilt_rad < 0.0);
    CHECK(plan.poses[10].tilt_rad == 0.0);
  }
}

TEST_CASE("planner: passing close to the pole does not swing C, A/C and B/C", "[kinematics][bc]") {
  for (const MachineKinematicsd& m : both_kinematics(default_machine_kinematics())) {
    INFO("tilt " << m.tilt_letter());
    for (double offset_deg : {0.001, 0.05, 0.5}) {
      std::vector<Vec3d> axes;
      for (int i = -20; i <= 20; ++i) {
        const Vec3d v =
            Eigen::AngleAxisd(deg_to_rad(2.0 * i), Vec3d::UnitY()) *
            (Eigen::AngleAxisd(deg_to_rad(offset_deg), Vec3d::UnitX()) * Vec3d::UnitZ());
        axes.push_back(v);
      }
      axes = for_machine(m, axes);
      const PosePlan plan = plan_poses(m, axes, feeds(axes.size()));
      REQUIRE(plan.ok());
      require_axes(m, plan.poses, axes);
      CHECK(max_c_step_deg(plan.poses) < 90.0);
    }
  }
}

TEST_CASE("planner: C unwinds past +-180 deg on a continuous axis, A/C and B/C",
          "[kinematics][bc]") {
  for (const MachineKinematicsd& m : both_kinematics(default_machine_kinematics())) {
    INFO("tilt " << m.tilt_letter());
    std::vector<Vec3d> axes;
    for (int i = 0; i <= 3 * 72; ++i) {  // three full turns of the azimuth, 5 deg a step
      const double phi = deg_to_rad(5.0 * i);
      axes.push_back(
          Vec3d(std::sin(0.5) * std::cos(phi), std::sin(0.5) * std::sin(phi), std::cos(0.5)));
    }
    axes = for_machine(m, axes);
    const PosePlan plan = plan_poses(m, axes, feeds(axes.size()));
    REQUIRE(plan.ok());
    require_axes(m, plan.poses, axes);
    CHECK(max_c_step_deg(plan.poses) == Approx(5.0).margin(1e-9));
    CHECK(std::abs(rad_to_deg(plan.poses.back().c_rad - plan.poses.front().c_rad)) ==
          Approx(1080.0).margin(1e-6));
  }
}

TEST_CASE("planner: a bounded C stays in range and turns back where it must, A/C and B/C",
          "[kinematics][bc]") {
  MachineKinematicsd bounded = default_machine_kinematics();
  bounded.c.continuous = false;
  bounded.c.min_rad = deg_to_rad(-200.0);
  bounded.c.max_rad = deg_to_rad(200.0);
  for (const MachineKinematicsd& m : both_kinematics(bounded)) {
    INFO("tilt " << m.tilt_letter());
    std::vector<Vec3d> axes;
    for (int i = 0; i <= 144; ++i) {  // two turns
      const double phi = deg_to_rad(5.0 * i);
      axes.push_back(
          Vec3d(std::sin(0.5) * std::cos(phi), std::sin(0.5) * std::sin(phi), std::cos(0.5)));
    }
    axes = for_machine(m, axes);
    const PosePlan plan = plan_poses(m, axes, feeds(axes.size()));
    REQUIRE(plan.ok());
    require_axes(m, plan.poses, axes);
  }
}

TEST_CASE("planner: an axis out of the tilt range is reported at its index, by its letter",
          "[kinematics][bc]") {
  MachineKinematicsd narrow = default_machine_kinematics();
  narrow.tilt.min_rad = deg_to_rad(-30.0);
  narrow.tilt.max_rad = deg_to_rad(30.0);
  for (const MachineKinematicsd& m : both_kinematics(narrow)) {
    const std::vector<Vec3d> axes =
        for_machine(m, {Vec3d::UnitZ(), Vec3d(0, -std::sin(0.3), std::cos(0.3)),
                        Vec3d(0, -std::sin(0.9), std::cos(0.9))});
    const PosePlan plan = plan_poses(m, axes, feeds(3));
    CHECK_FALSE(plan.ok());
    CHECK(plan.failed_index == 2);
    CHECK_THAT(plan.message, Catch::Contains(std::string(1, m.tilt_letter()) + " would be"));
  }
}

TEST_CASE("planner: a branch change goes where the move is a rapid, A/C and B/C",
          "[kinematics][bc]") {
  // Pass 1 reachable only with A > 0, pass 2 only with A < 0 (A range [-100, 100], tilts of
  // 60 deg towards opposite sides with C limited to [-10, 10]).
  MachineKinematicsd bounded = default_machine_kinematics();
  bounded.c.continuous = false;
  bounded.c.min_rad = deg_to_rad(-10.0);
  bounded.c.max_rad = deg_to_rad(10.0);
  for (const MachineKinematicsd& m : both_kinematics(bounded)) {
    INFO("tilt " << m.tilt_letter());
    const Vec3d left(0, -std::sin(1.0), std::cos(1.0)), right(0, std::sin(1.0), std::cos(1.0));
    const std::vector<Vec3d> axes = for_machine(m, {left, left, left, right, right, right});
    std::vector<bool> rapid = {true, false, false, true, false, false};
    const PosePlan plan = plan_poses(m, axes, rapid);
    REQUIRE(plan.ok());
    require_axes(m, plan.poses, axes);
    CHECK(plan.poses[0].tilt_rad > 0.0);
    CHECK(plan.poses[5].tilt_rad < 0.0);
  }
}

TEST_CASE("planner: a 3-axis path stays at A = 0 with C held", "[kinematics]") {
  const std::vector<Vec3d> axes(5, Vec3d::UnitZ());
  const PosePlan plan = plan_poses(default_machine_kinematics(), axes, feeds(5), Posed{0.0, 1.25});
  REQUIRE(plan.ok());
  for (const auto& p : plan.poses) {
    CHECK(p.tilt_rad == 0.0);
    CHECK(p.c_rad == 1.25);
  }
}

TEST_CASE("planner: random smooth paths never jump C by 90 deg, A/C and B/C", "[kinematics][bc]") {
  std::mt19937 rng(4242);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const MachineKinematicsd& m : both_kinematics(default_machine_kinematics())) {
    INFO("tilt " << m.tilt_letter());
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<Vec3d> axes;
      Vec3d v = Vec3d(0.3 * n(rng), 0.3 * n(rng), 1.0).normalized();
      for (int i = 0; i < 100; ++i) {
        // Steps of at most ~3 deg, staying in the upper hemisphere.
        Vec3d w = (v + 0.05 * Vec3d(n(rng), n(rng), n(rng))).normalized();
        if (w.z() < 0.2) w = (w + Vec3d(0, 0, 0.5)).normalized();
        if (angle_between(v, w) > deg_to_rad(8.0)) w = v;
        v = w;
        axes.push_back(v);
      }
      const PosePlan plan = plan_poses(m, axes, feeds(axes.size()));
      REQUIRE(plan.ok());
      require_axes(m, plan.poses, axes);
      REQUIRE(max_c_step_deg(plan.poses) <= 90.0);
    }
  }
}

TEST_CASE(
    "planner: a bounded C of many turns plans as a continuous C where the path stays within "
    "its range, and within a narrow range it turns back, A/C and B/C",
    "[kinematics][bc]") {
  // LinuxCNC's samples bound C at +-36000 deg: every turn a candidate made the programme's
  // work grow with the square of 200 turns a side (minutes on 143,840 points). Where the
  // plan with C free of its range stays within it, it is the bounded plan's optimum.
  std::mt19937 rng(977);
  std::normal_distribution<double> n(0.0, 1.0);
  MachineKinematicsd wide = default_machine_kinematics();
  wide.c.continuous = false;
  wide.c.min_rad = deg_to_rad(-36000.0);
  wide.c.max_rad = deg_to_rad(36000.0);
  MachineKinematicsd narrow = wide;
  narrow.c.min_rad = deg_to_rad(-100.0);
  narrow.c.max_rad = deg_to_rad(100.0);
  const std::vector<MachineKinematicsd> kins = both_kinematics(default_machine_kinematics());
  const std::vector<MachineKinematicsd> wides = both_kinematics(wide);
  const std::vector<MachineKinematicsd> narrows = both_kinematics(narrow);
  int turned_back = 0;
  for (std::size_t k = 0; k < kins.size(); ++k) {
    INFO("tilt " << kins[k].tilt_letter());
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<Vec3d> axes;
      std::vector<bool> rapid(1, true);
      const double turns = 0.5 * n(rng);  // the azimuth winds up to a turn or two
      for (int i = 0; i < 200; ++i) {
        const double phi = 2.0 * Constants<double>::pi() * turns * i / 200.0 + 0.02 * n(rng);
        const double tilt = 0.4 + 0.1 * std::sin(i / 17.0);
        axes.emplace_back(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi),
                          std::cos(tilt));
        if (i > 0) rapid.push_back(i % 50 == 0);  // passes: a branch may change between them
      }
      const std::optional<Posed> start =
          trial % 2 ? std::optional<Posed>(Posed{deg_to_rad(10.0), deg_to_rad(400.0)})
                    : std::nullopt;
      const PosePlan free = plan_poses(kins[k], axes, rapid, start);
      const PosePlan bounded = plan_poses(wides[k], axes, rapid, start);
      REQUIRE(free.ok());
      REQUIRE(bounded.ok());
      require_axes(wides[k], bounded.poses, axes);
      for (std::size_t i = 0; i < axes.size(); ++i) {
        INFO("point " << i);
        CHECK(bounded.poses[i].tilt_rad == Approx(free.poses[i].tilt_rad).margin(1e-12));
        CHECK(bounded.poses[i].c_rad == Approx(free.poses[i].c_rad).margin(1e-12));
      }
      // Within +-100 deg: every pose in range, the axes kept.
      const PosePlan tight = plan_poses(narrows[k], axes, rapid, std::nullopt);
      if (!tight.ok()) continue;
      require_axes(narrows[k], tight.poses, axes);
      bool differs = false;
      for (std::size_t i = 0; i < axes.size(); ++i) {
        differs |= std::abs(tight.poses[i].c_rad - free.poses[i].c_rad) > 1e-9;
      }
      turned_back += differs;
    }
  }
  CHECK(turned_back > 0);  // the narrow range is not the free plan everywhere
}

TEST_CASE(
    "planner: on a bounded C of many turns a half turn over the pole turns back towards C = 0, "
    "not on round the same way pass after pass",
    "[kinematics]") {
  // A tilt range almost one-sided (LinuxCNC's xyzac-trt: A in [-100, 50] deg): a pass
  // through the pole keeps A's side and turns C half a turn. Unwrapped with every such tie
  // turned negative, 40 passes left C 14,400 deg from home (the 143,840-point sine: -36181 deg, out
  // of the sample's +-36000, so the plan fell back to the programme over every turn).
  MachineKinematicsd m = default_machine_kinematics();
  m.tilt.min_rad = deg_to_rad(-100.0);
  m.tilt.max_rad = deg_to_rad(5.0);
  m.c.continuous = false;
  m.c.min_rad = deg_to_rad(-36000.0);
  m.c.max_rad = deg_to_rad(36000.0);
  std::vector<Vec3d> axes;
  std::vector<bool> rapid;
  for (int pass = 0; pass < 40; ++pass) {
    for (int i = 0; i <= 20; ++i) {
      const double t = deg_to_rad(-30.0 + 3.0 * i);  // through the pole, along Y
      axes.emplace_back(0.0, std::sin(t), std::cos(t));
      rapid.push_back(i == 0);
    }
  }
  const PosePlan plan = plan_poses(m, axes, rapid);
  REQUIRE(plan.ok());
  require_axes(m, plan.poses, axes);
  double widest = 0.0;
  for (const Posed& p : plan.poses) widest = std::max(widest, std::abs(rad_to_deg(p.c_rad)));
  CHECK(widest <= 180.0 + 1e-6);
  CHECK(max_c_step_deg(plan.poses) <= 180.0 + 1e-6);
}
