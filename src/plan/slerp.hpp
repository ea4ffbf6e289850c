#pragma once
/// @file Tool axes on the unit sphere: spherical linear interpolation with the arc-length
/// parameter of the paper (eq. 36-41, with the erratum of eq. 41), and the exponential and
/// logarithm maps the joint smoothing works in.

#include <cmath>
#include <stdexcept>
#include <vector>

#include "taxopt/core/types.hpp"

namespace taxopt {

/// Spherical linear interpolation between unit axes: the point at fraction `lambda` of the
/// great-circle arc from `ve` to `vf` (eq. 39, 41 corrected):
///   V = sin((1 - lambda) thQ) / sin thQ * Ve + sin(lambda thQ) / sin thQ * Vf,
///   thQ = acos(Ve . Vf).
/// The printed eq. 41 swaps the two coefficients and drops thQ from the second; this is the
/// solution of eq. 38. For thQ below 1e-9 rad the (normalised) chord is used, the limit of
/// the formula. @throws std::invalid_argument when ve and vf are (nearly) opposite: the arc
/// is then not unique.
template <class S>
Vec3<S> slerp(const Vec3<S>& ve, const Vec3<S>& vf, S lambda) {
  const S theta = angle_between(ve, vf);
  if (theta > Constants<S>::pi() - S(1e-6)) {
    throw std::invalid_argument("slerp: opposite axes have no unique arc between them");
  }
  if (theta < S(1e-9)) {
    return ((S(1) - lambda) * ve + lambda * vf).normalized();
  }
  const S s = std::sin(theta);
  return (std::sin((S(1) - lambda) * theta) / s) * ve + (std::sin(lambda * theta) / s) * vf;
}

/// The axes of an interval [e, f] by arc-length slerp (eq. 40-41): point i gets
/// lambda_i = (L_e + ... + L_{i-1}) / (L_e + ... + L_{f-1}), so equal arc lengths get equal
/// angular steps and the angular rate per unit of path is constant.
/// @param segment_mm lengths L of the f - e segments (non-negative; a zero total gives
///                   equal steps)
/// @return f - e + 1 unit axes, the first `ve` and the last `vf`
template <class S>
std::vector<Vec3<S>> arc_length_slerp(const Vec3<S>& ve, const Vec3<S>& vf,
                                      const std::vector<S>& segment_mm) {
  S total = S(0);
  for (S l : segment_mm) total += l;
  const std::size_t n = segment_mm.size();
  std::vector<Vec3<S>> out;
  out.reserve(n + 1);
  out.push_back(ve);
  S walked = S(0);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    walked += segment_mm[i];
    const S lambda = total > S(0) ? walked / total : S(i + 1) / S(n);
    out.push_back(slerp(ve, vf, lambda));
  }
  if (n > 0) out.push_back(vf);
  return out;
}

/// Logarithm map of the unit sphere at `p`: the tangent vector at p pointing along the great
/// circle towards q, of length the angle between them (rad). Precondition: q is not -p.
template <class S>
Vec3<S> sphere_log(const Vec3<S>& p, const Vec3<S>& q) {
  const Vec3<S> perp = q - q.dot(p) * p;
  const S n = perp.norm();
  if (n < S(1e-15)) return Vec3<S>::Zero();
  return angle_between(p, q) * (perp / n);
}

/// Exponential map of the unit sphere at `p`: the point reached by walking |u| rad from p
/// along the great circle in direction u (u tangent at p).
template <class S>
Vec3<S> sphere_exp(const Vec3<S>& p, const Vec3<S>& u) {
  const S t = u.norm();
  if (t < S(1e-15)) return p;
  return (std::cos(t) * p + std::sin(t) * (u / t)).normalized();
}

}  // namespace taxopt
