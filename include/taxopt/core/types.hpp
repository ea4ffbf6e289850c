#pragma once
/// @file Eigen aliases, scalar constants and the one place where degrees become radians.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace taxopt {

template <class S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using Mat3 = Eigen::Matrix<S, 3, 3>;
using Vec3d = Vec3<double>;
using Mat3d = Mat3<double>;

/// Numeric constants and tolerances per scalar type (never #define).
template <class S>
struct Constants {
  static constexpr S pi() { return S(3.14159265358979323846264338327950288); }
  static constexpr S two_pi() { return S(2) * pi(); }
  static constexpr S epsilon() { return std::numeric_limits<S>::epsilon(); }
  /// Tolerance for geometric comparisons of unit vectors (|v| - 1, angles in rad).
  static constexpr S unit_tolerance() { return std::sqrt(epsilon()) * S(10); }
};

/// Millimetres per inch (exact, by definition).
inline constexpr double kMmPerInch = 25.4;
/// Coordinates beyond any machine (1e6 mm = 1 km) are a broken input, not a part or a program
/// (past it a mesh's face areas and normals overflow): the CL and mesh readers (on a file's own
/// numbers, whatever its unit) and the library's checks of values built in code refuse them.
inline constexpr double kMaxCoordinateMm = 1e6;

/// Degrees to radians. Angles are radians inside taxopt; this and rad_to_deg are the
/// only conversions, used at I/O boundaries.
template <class S>
constexpr S deg_to_rad(S angle_deg) {
  return angle_deg * (Constants<S>::pi() / S(180));
}
/// Radians to degrees.
template <class S>
constexpr S rad_to_deg(S angle_rad) {
  return angle_rad * (S(180) / Constants<S>::pi());
}

/// Wraps an angle to (-pi, pi].
template <class S>
S wrap_pi(S angle_rad) {
  // fmod(x, 2 pi) is x itself for |x| < 2 pi (exactly): the usual case, without the call.
  const S x = angle_rad + Constants<S>::pi();
  using std::abs;
  S a = abs(x) < Constants<S>::two_pi() ? x : S(std::fmod(x, Constants<S>::two_pi()));
  if (a <= S(0)) a += Constants<S>::two_pi();
  return a - Constants<S>::pi();
}

/// Angle between two unit vectors in radians, accurate also for tiny angles.
template <class S>
S angle_between(const Vec3<S>& a, const Vec3<S>& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace taxopt
