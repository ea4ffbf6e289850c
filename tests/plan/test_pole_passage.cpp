#include <catch2/catch.hpp>

#include "plan/pole_passage.hpp"
#include "support.hpp"
#include "taxopt/kinematics/pose_planner.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// A pass of axes whose tilt about y grows by `rate_deg_mm` per mm along x while the tilt
/// about x stays `offset_deg`: the axis passes the pole at about `offset_deg`. Points every
/// `step_mm` over [-half_mm, half_mm].
struct Pass {
  std::vector<Vec3d> axes;
  std::vector<double> segment_mm, feed_mm_min;
};

Pass grazing_pass(double offset_deg, double rate_deg_mm = 1.0, double half_mm = 30.0,
                  double step_mm = 0.25) {
  Pass p;
  for (double s = -half_mm; s <= half_mm + 1e-9; s += step_mm) {
    p.axes.push_back(
        Vec3d(std::tan(deg_to_rad(rate_deg_mm * s)), std::tan(deg_to_rad(offset_deg)), 1.0)
            .normalized());
    if (s > -half_mm) {
      p.segment_mm.push_back(step_mm);
      p.feed_mm_min.push_back(1000.0);
    }
  }
  return p;
}

std::vector<Posed> poses_of(const MachineKinematicsd& m, const std::vector<Vec3d>& axes) {
  std::vector<bool> rapid_into(axes.size(), false);
  rapid_into[0] = true;
  const PosePlan plan = plan_poses(m, axes, rapid_into);
  REQUIRE(plan.ok());
  return plan.poses;
}

const AxisTest any_axis = [](std::size_t, const Vec3d&) { return true; };

}  // namespace

TEST_CASE("pole passage: a pass grazing the pole turns C slowly, each axis within 2|A| of its own",
          "[plan][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  for (double offset : {0.3, 1.0, 2.5}) {
    INFO("offset " << offset << " deg");
    const Pass p = grazing_pass(offset);
    const std::vector<Posed> poses = poses_of(m, p.axes);
    const PolePassage r =
        smooth_pole_passages(m, p.axes, poses, p.segment_mm, p.feed_mm_min, any_axis);
    INFO("peak omega " << r.omega_before_deg_s << " -> " << r.omega_after_deg_s << " deg/s, a "
                       << r.accel_before_deg_s2 << " -> " << r.accel_after_deg_s2
                       << " deg/s^2, rho " << r.radius_deg);
    REQUIRE(r.stretches >= 1);
    CHECK(r.omega_after_deg_s <= 0.5 * r.omega_before_deg_s);
    CHECK(r.accel_after_deg_s2 <= 0.5 * r.accel_before_deg_s2);
    REQUIRE(r.axes.size() == p.axes.size());
    std::vector<std::size_t> changed;
    for (std::size_t i = 0; i < p.axes.size(); ++i) {
      // A is kept; the axis turns by at most 2|A| (on the circle of constant A).
      CHECK(r.poses[i].tilt_rad == poses[i].tilt_rad);
      CHECK(angle_between(r.axes[i], p.axes[i]) <= 2.0 * std::abs(poses[i].tilt_rad) + 1e-12);
      CHECK(angle_between(r.axes[i], m.forward(r.poses[i])) < 1e-12);
      if (r.poses[i].c_rad != poses[i].c_rad) {
        changed.push_back(i);
        CHECK(std::abs(poses[i].tilt_rad) < deg_to_rad(r.radius_deg));
      } else {
        CHECK(r.axes[i] == p.axes[i]);  // untouched points keep their axis bit for bit
      }
    }
    // Inside a stretch C is linear in arc length, or a cubic (the Hermite shape): with equal
    // steps its second, or fourth, differences vanish.
    REQUIRE(changed.size() >= 5);
    const int order = r.hermite ? 4 : 2;
    for (std::size_t j = 0; j + order < changed.size(); ++j) {
      if (changed[j + order] != changed[j] + order) continue;  // not inside one stretch
      std::vector<double> d;
      for (int k = 0; k <= order; ++k) d.push_back(r.poses[changed[j] + k].c_rad);
      for (int o = 0; o < order; ++o) {
        for (std::size_t k = 0; k + 1 < d.size() - o; ++k) d[k] = d[k + 1] - d[k];
      }
      CHECK(d[0] == Approx(0.0).margin(1e-9));
    }
  }
}

TEST_CASE("pole passage: a stretch whose new axes are not acceptable keeps its axes",
          "[plan][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  const Pass p = grazing_pass(1.0);
  const std::vector<Posed> poses = poses_of(m, p.axes);
  // Acceptable only where the axis has not moved: no stretch can change.
  const AxisTest only_input = [&](std::size_t i, const Vec3d& v) {
    return angle_between(v, p.axes[i]) < 1e-9;
  };
  const PolePassage r =
      smooth_pole_passages(m, p.axes, poses, p.segment_mm, p.feed_mm_min, only_input);
  CHECK(r.stretches == 0);
  CHECK(r.radius_deg == 0.0);
  CHECK(r.axes == p.axes);
  CHECK(r.omega_after_deg_s == r.omega_before_deg_s);
}

TEST_CASE("pole passage: far from the pole and straight through it nothing changes",
          "[plan][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  SECTION("far: the axis stays 20 deg or more from the pole") {
    const Pass p = grazing_pass(20.0);
    const std::vector<Posed> poses = poses_of(m, p.axes);
    const PolePassage r =
        smooth_pole_passages(m, p.axes, poses, p.segment_mm, p.feed_mm_min, any_axis);
    CHECK(r.stretches == 0);
    CHECK(r.axes == p.axes);
  }
  SECTION("through: A changes sign, C stands still; nothing to gain, nothing made worse") {
    const Pass p = grazing_pass(0.0);
    const std::vector<Posed> poses = poses_of(m, p.axes);
    const PolePassage r =
        smooth_pole_passages(m, p.axes, poses, p.segment_mm, p.feed_mm_min, any_axis);
    CHECK(r.omega_after_deg_s <= r.omega_before_deg_s);
    CHECK(r.accel_after_deg_s2 <= r.accel_before_deg_s2);
    for (std::size_t i = 0; i < p.axes.size(); ++i) {
      CHECK(angle_between(r.axes[i], p.axes[i]) < 1e-9);
    }
  }
}

TEST_CASE("pole passage: a stretch at the end of a pass holds C at its one neighbour",
          "[plan][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  Pass p = grazing_pass(1.0);
  // Keep the first half only: the pass ends next to the pole.
  const std::size_t n = p.axes.size() / 2 + 2;
  p.axes.resize(n);
  p.segment_mm.resize(n - 1);
  p.feed_mm_min.resize(n - 1);
  const std::vector<Posed> poses = poses_of(m, p.axes);
  const PolePassage r =
      smooth_pole_passages(m, p.axes, poses, p.segment_mm, p.feed_mm_min, any_axis);
  REQUIRE(r.stretches == 1);
  const double c_end = r.poses.back().c_rad;
  std::size_t first = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (r.poses[i].c_rad != poses[i].c_rad) first = std::min(first, i);
  }
  REQUIRE(first < n);
  REQUIRE(first > 0);
  CHECK(c_end == poses[first - 1].c_rad);
  CHECK(r.omega_after_deg_s < r.omega_before_deg_s);
}

TEST_CASE("pole passage: sizes that do not match are refused", "[plan][pole]") {
  const MachineKinematicsd m = default_machine_kinematics();
  const Pass p = grazing_pass(1.0);
  const std::vector<Posed> poses = poses_of(m, p.axes);
  std::vector<double> short_feed(p.feed_mm_min.begin(), p.feed_mm_min.end() - 1);
  CHECK_THROWS_AS(smooth_pole_passages(m, p.axes, poses, p.segment_mm, short_feed, any_axis),
                  std::invalid_argument);
}
