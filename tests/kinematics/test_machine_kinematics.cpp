#include <catch2/catch.hpp>
#include <random>

#include "taxopt/kinematics/machine_kinematics.hpp"

using namespace taxopt;

namespace {

Vec3d random_axis(std::mt19937& rng, double min_z = -1.0) {
  std::normal_distribution<double> n(0.0, 1.0);
  for (;;) {
    Vec3d v(n(rng), n(rng), n(rng));
    v.normalize();
    if (v.z() >= min_z) return v;
  }
}

MachineKinematicsd machine_with_sense(int sa, int sc, TiltAxis tilt = TiltAxis::X) {
  MachineKinematicsd m = default_machine_kinematics();
  m.tilt.sense = sa;
  m.c.sense = sc;
  m.tilt_about = tilt;
  return m;
}

// The kinematics every property below holds for: the A/C and the B/C table-table (one
// template per kinematics: forward after inverse on both branches, the pole, the machine-mode
// round trip; the planner's winding in test_pose_planner.cpp).
constexpr TiltAxis kTilts[] = {TiltAxis::X, TiltAxis::Y};

}  // namespace

TEST_CASE("kinematics: forward is eq. 14", "[kinematics]") {
  const MachineKinematicsd m = default_machine_kinematics();
  const double a = deg_to_rad(30.0), c = deg_to_rad(40.0);
  const Vec3d v = m.forward({a, c});
  CHECK(v.x() == Approx(std::sin(a) * std::sin(c)));
  CHECK(v.y() == Approx(-std::sin(a) * std::cos(c)));
  CHECK(v.z() == Approx(std::cos(a)));
}

TEST_CASE("kinematics: inverse undoes forward on both branches and every sense", "[kinematics]") {
  std::mt19937 rng(20201);
  for (int sa : {1, -1}) {
    for (int sc : {1, -1}) {
      for (TiltAxis tilt : kTilts) {
        const MachineKinematicsd m = machine_with_sense(sa, sc, tilt);
        INFO("tilt " << m.tilt_letter() << ", senses " << sa << ", " << sc);
        for (int k = 0; k < 2000; ++k) {
          const Vec3d v = random_axis(rng);
          const auto both = m.inverse(v);
          for (const Posed& p : both) {
            REQUIRE((m.forward(p) - v).norm() < 1e-12);
            REQUIRE(p.c_rad > -Constants<double>::pi() - 1e-12);
            REQUIRE(p.c_rad <= Constants<double>::pi() + 1e-12);
          }
          // Branch [0] has s_A A >= 0, branch [1] s_A A <= 0.
          REQUIRE(sa * both[0].tilt_rad >= 0.0);
          REQUIRE(sa * both[1].tilt_rad <= 0.0);
        }
        // The pole: A = 0 on both branches, and every C gives the same axis.
        const auto pole = m.inverse(Vec3d::UnitZ());
        CHECK(pole[0].tilt_rad == 0.0);
        CHECK(pole[1].tilt_rad == 0.0);
        for (double c : {-3.0, -1.0, 0.5, 2.9}) CHECK(m.at_pole(m.forward(Posed{0.0, c})));
        CHECK_FALSE(m.at_pole(m.forward(Posed{1e-5, 0.3})));
      }
    }
  }
}

TEST_CASE("kinematics: forward of any pose comes back through the inverse", "[kinematics]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ua(-2.0, 2.0), uc(-10.0, 10.0);
  for (TiltAxis tilt : kTilts) {
    const MachineKinematicsd m = machine_with_sense(1, 1, tilt);
    INFO("tilt " << m.tilt_letter());
    for (int k = 0; k < 2000; ++k) {
      const Posed p{ua(rng), uc(rng)};
      const Vec3d v = m.forward(p);
      bool matched = false;
      for (const Posed& q : m.inverse(v)) {
        const bool same_a = std::abs(q.tilt_rad - p.tilt_rad) < 1e-9;
        const bool same_c =
            std::abs(wrap_pi(q.c_rad - p.c_rad)) < 1e-9 || std::abs(std::sin(p.tilt_rad)) < 1e-9;
        matched = matched || (same_a && same_c);
      }
      REQUIRE(matched);
    }
  }
}

TEST_CASE("kinematics: the paper's first axis has the A <= 0 solution of its table",
          "[kinematics][paper]") {
  const MachineKinematicsd m = default_machine_kinematics();
  const auto both = m.inverse(Vec3d(0, -0.3281, 0.9447).normalized());
  CHECK(rad_to_deg(both[1].tilt_rad) == Approx(-19.1507).margin(0.01));
  CHECK(std::abs(rad_to_deg(both[1].c_rad)) == Approx(180.0).margin(1e-9));
  CHECK(rad_to_deg(both[0].tilt_rad) == Approx(19.1507).margin(0.01));
  CHECK(rad_to_deg(both[0].c_rad) == Approx(0.0).margin(1e-9));
}

TEST_CASE("kinematics: sense -1 mirrors A and C and keeps the tool axis", "[kinematics]") {
  std::mt19937 rng(99);
  const MachineKinematicsd pos = machine_with_sense(1, 1), neg = machine_with_sense(-1, -1);
  for (int k = 0; k < 500; ++k) {
    const Vec3d v = random_axis(rng, 0.0);
    const auto p = pos.inverse(v), q = neg.inverse(v);
    for (int b = 0; b < 2; ++b) {
      CHECK(q[b].tilt_rad == Approx(-p[b].tilt_rad).margin(1e-12));
      CHECK(std::abs(wrap_pi(q[b].c_rad + p[b].c_rad)) < 1e-12);
      CHECK((neg.forward(q[b]) - v).norm() < 1e-12);
    }
  }
  // LinuxCNC xyzac-trt turns the other way: its axis is (sin A sin C, sin A cos C, cos A).
  const double a = 0.3, c = 1.1;
  CHECK((neg.forward({a, c}) -
         Vec3d(std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)))
            .norm() < 1e-12);
}

TEST_CASE("kinematics: machine mode puts the tool axis on the machine's +Z", "[kinematics]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int sa : {1, -1}) {
    for (TiltAxis tilt : kTilts) {
      MachineKinematicsd m = machine_with_sense(sa, sa, tilt);
      INFO("tilt " << m.tilt_letter() << ", sense " << sa);
      const bool b = tilt == TiltAxis::Y;
      m.c_axis_point_mm = Vec3d(u(rng), u(rng), 0.0);
      m.tilt_axis_point_mm = b ? Vec3d(u(rng), 0.0, u(rng)) : Vec3d(0.0, u(rng), u(rng));
      for (int k = 0; k < 300; ++k) {
        const Vec3d v = random_axis(rng, 0.0);
        const Posed pose = m.inverse(v)[static_cast<std::size_t>(k % 2)];
        const Vec3d p(u(rng), u(rng), u(rng));
        const Vec3d pm = m.to_machine_mm(p, pose);
        // The joint move from the tip to a point along the axis is along +Z.
        const Vec3d up = m.to_machine_mm(p + 10.0 * v, pose) - pm;
        REQUIRE((up - Vec3d(0, 0, 10.0)).norm() < 1e-9);
        REQUIRE((m.from_machine_mm(pm, pose) - p).norm() < 1e-9);
        // A point on both rotary axes does not move.
        const Vec3d fixed =
            b ? Vec3d(m.tilt_axis_point_mm.x(), m.c_axis_point_mm.y(), m.tilt_axis_point_mm.z())
              : Vec3d(m.c_axis_point_mm.x(), m.tilt_axis_point_mm.y(), m.tilt_axis_point_mm.z());
        if (std::abs(pose.c_rad) < 1e-12)
          REQUIRE((m.to_machine_mm(fixed, pose) - fixed).norm() < 1e-9);
      }
    }
  }
}

TEST_CASE("kinematics: the machine-mode formula of CLI.md, written out", "[kinematics]") {
  MachineKinematicsd m = default_machine_kinematics();
  m.c_axis_point_mm = Vec3d(5, -3, 0);
  m.tilt_axis_point_mm = Vec3d(0, 2, -7);
  const Posed pose{deg_to_rad(-35.0), deg_to_rad(120.0)};
  const Vec3d pw(12, 4, 9);
  const Mat3d rz = Eigen::AngleAxisd(-pose.c_rad, Vec3d::UnitZ()).toRotationMatrix();
  const Mat3d rx = Eigen::AngleAxisd(-pose.tilt_rad, Vec3d::UnitX()).toRotationMatrix();
  const Vec3d expect =
      rx * (rz * (pw - m.c_axis_point_mm) + m.c_axis_point_mm - m.tilt_axis_point_mm) +
      m.tilt_axis_point_mm;
  CHECK((m.to_machine_mm(pw, pose) - expect).norm() < 1e-12);
}
