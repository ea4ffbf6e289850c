#include <catch2/catch.hpp>
#include <random>

#include "plan/slerp.hpp"

using namespace taxopt;

namespace {

template <class S>
Vec3<S> random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3d(g(rng), g(rng), g(rng)).normalized().template cast<S>();
}

}  // namespace

TEMPLATE_TEST_CASE("slerp: unit length, endpoints, on the great circle", "[plan][slerp]", float,
                   double) {
  using S = TestType;
  const S tol = Constants<S>::unit_tolerance() * S(10);
  std::mt19937 rng(11);
  for (int t = 0; t < 200; ++t) {
    const Vec3<S> ve = random_unit<S>(rng), vf = random_unit<S>(rng);
    if (angle_between(ve, vf) > S(3.0)) continue;
    CHECK((slerp(ve, vf, S(0)) - ve).norm() < tol);
    CHECK((slerp(ve, vf, S(1)) - vf).norm() < tol);
    const Vec3<S> plane = ve.cross(vf).normalized();
    for (S lambda : {S(0.1), S(0.37), S(0.5), S(0.9)}) {
      const Vec3<S> v = slerp(ve, vf, lambda);
      CHECK(std::abs(v.norm() - S(1)) < tol);
      CHECK(std::abs(v.dot(plane)) < tol);
      // The angle from Ve is the fraction lambda of the whole arc (the printed eq. 41 would
      // give 1 - lambda and lose the arc: see the erratum in slerp.hpp).
      CHECK(angle_between(ve, v) ==
            Approx(lambda * angle_between(ve, vf)).margin(static_cast<double>(tol)));
    }
  }
}

TEMPLATE_TEST_CASE("slerp: equal lengths give equal angular steps, unequal ones proportional steps",
                   "[plan][slerp]", float, double) {
  using S = TestType;
  const S tol = Constants<S>::unit_tolerance() * S(10);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> len(0.05, 2.0);
  for (int t = 0; t < 50; ++t) {
    const Vec3<S> ve = random_unit<S>(rng), vf = random_unit<S>(rng);
    if (angle_between(ve, vf) > S(3.0)) continue;
    const S theta = angle_between(ve, vf);
    const std::vector<S> equal(7, S(0.5));
    const std::vector<Vec3<S>> a = arc_length_slerp(ve, vf, equal);
    REQUIRE(a.size() == 8);
    CHECK((a.front() - ve).norm() < tol);
    CHECK((a.back() - vf).norm() < tol);
    for (std::size_t i = 0; i + 1 < a.size(); ++i) {
      CHECK(angle_between(a[i], a[i + 1]) == Approx(theta / 7).margin(static_cast<double>(tol)));
    }
    std::vector<S> uneven;
    S total = S(0);
    for (int i = 0; i < 9; ++i) total += uneven.emplace_back(static_cast<S>(len(rng)));
    const std::vector<Vec3<S>> b = arc_length_slerp(ve, vf, uneven);
    for (std::size_t i = 0; i + 1 < b.size(); ++i) {
      CHECK(angle_between(b[i], b[i + 1]) ==
            Approx(theta * uneven[i] / total).margin(static_cast<double>(tol)));
    }
  }
}

TEST_CASE("slerp: coincident axes stay put, opposite axes are refused", "[plan][slerp]") {
  const Vec3d v = Vec3d(0.2, -0.3, 0.9).normalized();
  CHECK((slerp(v, v, 0.4) - v).norm() < 1e-15);
  CHECK_THROWS_AS(slerp(v, Vec3d(-v), 0.5), std::invalid_argument);
}

TEST_CASE("slerp: the logarithm and exponential maps undo each other", "[plan][slerp]") {
  std::mt19937 rng(13);
  for (int t = 0; t < 100; ++t) {
    const Vec3d p = random_unit<double>(rng), q = random_unit<double>(rng);
    if (angle_between(p, q) > 3.0) continue;
    const Vec3d u = sphere_log(p, q);
    CHECK(std::abs(u.dot(p)) < 1e-12);
    CHECK(u.norm() == Approx(angle_between(p, q)).margin(1e-12));
    CHECK((sphere_exp(p, u) - q).norm() < 1e-12);
  }
}
