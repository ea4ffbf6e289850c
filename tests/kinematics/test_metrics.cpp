#include <catch2/catch.hpp>

#include "taxopt/kinematics/metrics.hpp"

using namespace taxopt;

TEST_CASE("metrics: eq. 16-18 against a hand computation", "[kinematics][metrics]") {
  // v = 60 mm/min = 1 mm/s; L = 1, 2, 1 mm.
  const std::vector<double> a = {0.0, 1.0, 5.0, 5.0};
  const std::vector<double> c = {0.0, 0.0, 3.0, 7.0};
  const std::vector<double> len = {1.0, 2.0, 1.0};
  const std::vector<double> feed = {60.0, 60.0, 60.0};
  const RotaryKinematics k = rotary_kinematics(a, c, len, feed);
  // omega_i = v (theta_{i+1} - theta_i) / L_i
  CHECK(k.omega_tilt_deg_s[0] == Approx(1.0));
  CHECK(k.omega_tilt_deg_s[1] == Approx(2.0));
  CHECK(k.omega_c_deg_s[1] == Approx(1.5));
  CHECK(k.omega_c_deg_s[2] == Approx(4.0));
  CHECK(k.omega_deg_s[1] == Approx(2.5));  // sqrt(2^2 + 1.5^2)
  CHECK(k.omega_deg_s[3] == 0.0);
  // a_i = 2 v (omega_i - omega_{i-1}) / (L_{i-1} + L_i)  (erratum of eq. 18: L, not T)
  CHECK(k.accel_tilt_deg_s2[1] == Approx(2.0 * (2.0 - 1.0) / 3.0));
  CHECK(k.accel_c_deg_s2[1] == Approx(2.0 * (1.5 - 0.0) / 3.0));
  CHECK(k.accel_tilt_deg_s2[2] == Approx(2.0 * (0.0 - 2.0) / 3.0));
  CHECK(k.accel_c_deg_s2[2] == Approx(2.0 * (4.0 - 1.5) / 3.0));
  CHECK(k.accel_deg_s2[2] == Approx(std::hypot(4.0 / 3.0, 5.0 / 3.0)));
  CHECK(k.accel_deg_s2[0] == 0.0);
  CHECK(k.accel_deg_s2[3] == 0.0);

  RotarySummary s;
  accumulate(s, k, c);
  CHECK(s.max_omega_deg_s == Approx(4.0));
  CHECK(s.accel_samples == 2);
  CHECK(s.rms_accel_deg_s2 == Approx(std::sqrt((k.accel_deg_s2[1] * k.accel_deg_s2[1] +
                                                k.accel_deg_s2[2] * k.accel_deg_s2[2]) /
                                               2.0)));
  CHECK(s.omega_samples == 3);
  CHECK(s.rms_omega_deg_s == Approx(std::sqrt((k.omega_deg_s[0] * k.omega_deg_s[0] +
                                               k.omega_deg_s[1] * k.omega_deg_s[1] +
                                               k.omega_deg_s[2] * k.omega_deg_s[2]) /
                                              3.0)));
  CHECK(s.c_jumps == 0);
}

TEST_CASE("metrics: the paper's feed in mm/min gives deg/s", "[kinematics][metrics]") {
  // 250 mm/min over 0.5 mm segments turning 1 deg each: omega = 250/60 / 0.5 = 8.333 deg/s.
  const RotaryKinematics k = rotary_kinematics({0, 1, 2}, {180, 180, 180}, {0.5, 0.5}, {250, 250});
  CHECK(k.omega_deg_s[0] == Approx(250.0 / 60.0 / 0.5));
  CHECK(k.accel_deg_s2[1] == Approx(0.0).margin(1e-9));
}

TEST_CASE("metrics: C jumps over 90 deg are counted", "[kinematics][metrics]") {
  const std::vector<double> c = {0, 10, 110, 100, -100};
  const RotaryKinematics k = rotary_kinematics({0, 0, 0, 0, 0}, c, {1, 1, 1, 1}, {60, 60, 60, 60});
  RotarySummary s;
  accumulate(s, k, c);
  CHECK(s.c_jumps == 2);
}

TEST_CASE("metrics: a rotation on the spot takes the G94 rotary time", "[kinematics][metrics]") {
  const auto t = segment_times_s({0.0}, {120.0}, {0.0, 6.0}, {0.0, 8.0});
  CHECK(t[0] == Approx(10.0 / 2.0));  // 10 deg at 120 deg/min
}
