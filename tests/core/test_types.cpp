#include <catch2/catch.hpp>

#include "taxopt/core/types.hpp"

using namespace taxopt;

TEMPLATE_TEST_CASE("types: degree and radian conversions invert each other", "[core]", float,
                   double) {
  for (TestType d :
       {TestType(-720), TestType(-180), TestType(0), TestType(33.3), TestType(359.9)}) {
    CHECK(rad_to_deg(deg_to_rad(d)) == Approx(d).epsilon(Constants<TestType>::unit_tolerance()));
  }
  CHECK(deg_to_rad(TestType(180)) == Approx(Constants<TestType>::pi()));
}

TEST_CASE("types: wrap_pi maps into -pi < a <= pi", "[core]") {
  const double pi = Constants<double>::pi();
  CHECK(wrap_pi(pi) == Approx(pi));
  CHECK(wrap_pi(-pi) == Approx(pi));
  CHECK(wrap_pi(3 * pi + 0.1) == Approx(-pi + 0.1));
  CHECK(wrap_pi(-0.25) == Approx(-0.25));
  CHECK(wrap_pi(7.0 * 2 * pi + 0.5) == Approx(0.5));
}

TEST_CASE("types: angle_between is accurate for tiny and straight angles", "[core]") {
  const Vec3d z = Vec3d::UnitZ();
  const Vec3d tiny = Eigen::AngleAxisd(1e-9, Vec3d::UnitX()) * z;
  CHECK(angle_between(z, tiny) == Approx(1e-9).epsilon(1e-6));
  CHECK(angle_between(z, Vec3d(-z)) == Approx(Constants<double>::pi()));
}
