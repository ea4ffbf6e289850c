#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

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

TEST_CASE("types: wrap_pi is the fmod formula to the bit, with or without the call", "[core]") {
  // The formula wrap_pi had before its shortcut for |a + pi| < 2 pi.
  const auto by_fmod = [](double a) {
    double r = std::fmod(a + Constants<double>::pi(), Constants<double>::two_pi());
    if (r <= 0.0) r += Constants<double>::two_pi();
    return r - Constants<double>::pi();
  };
  const double pi = Constants<double>::pi(), two_pi = Constants<double>::two_pi();
  std::vector<double> angles = {0.0,      -0.0,      pi,     -pi,     two_pi, -two_pi,
                                3.0 * pi, -3.0 * pi, 1e-300, -1e-300, 1e6,    -1e6};
  for (double a : {pi, -pi, pi - two_pi, -pi - two_pi, two_pi - pi}) {
    angles.push_back(std::nextafter(a, 10.0));
    angles.push_back(std::nextafter(a, -10.0));
  }
  for (int k = -2000; k <= 2000; ++k) angles.push_back(k * 0.00731 * pi);
  for (double a : angles) {
    INFO("angle " << a);
    const double got = wrap_pi(a), want = by_fmod(a);
    CHECK(std::memcmp(&got, &want, sizeof got) == 0);
  }
  CHECK(std::isnan(wrap_pi(std::numeric_limits<double>::quiet_NaN())));
}

TEST_CASE("types: angle_between is accurate for tiny and straight angles", "[core]") {
  const Vec3d z = Vec3d::UnitZ();
  const Vec3d tiny = Eigen::AngleAxisd(1e-9, Vec3d::UnitX()) * z;
  CHECK(angle_between(z, tiny) == Approx(1e-9).epsilon(1e-6));
  CHECK(angle_between(z, Vec3d(-z)) == Approx(Constants<double>::pi()));
}
