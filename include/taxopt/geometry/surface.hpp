#pragma once
/// @file Parametric surfaces S(u, v) (paper eq. 1-2) and their differential geometry.
///
/// A surface type provides, templated on the scalar S:
///   `SurfaceJet<S> jet(S u, S v) const`  -- point and first and second derivatives
///   `S u_min() const, u_max(), v_min(), v_max()` -- the parameter domain
/// Everything else (normal, principal curvatures) is computed from the jet by the free
/// functions below, so a new surface only implements jet().
///
/// Curvature sign: normal curvature k > 0 means the surface bends towards its normal N
/// (eq. 2, S_u x S_v), i.e. it is concave seen from the tool, which sits on the N side.
/// The local gouge check (eq. 19) fails where a concave radius 1/k is smaller than R.

#include <array>
#include <cmath>

#include "taxopt/core/types.hpp"

namespace taxopt {

/// Point and derivatives of a surface at (u, v).
template <class S>
struct SurfaceJet {
  Vec3<S> p, su, sv, suu, suv, svv;
};

/// Principal curvatures k1 >= k2 (1/mm, sign as above) with their unit directions.
template <class S>
struct PrincipalCurvatures {
  S k1 = S(0), k2 = S(0);
  Vec3<S> d1 = Vec3<S>::UnitX(), d2 = Vec3<S>::UnitY();
};

/// Unit normal (eq. 2) of a jet.
template <class S>
Vec3<S> unit_normal(const SurfaceJet<S>& j) {
  return j.su.cross(j.sv).normalized();
}

/// Principal curvatures and directions from the first and second fundamental forms.
template <class S>
PrincipalCurvatures<S> principal_curvatures(const SurfaceJet<S>& j) {
  const Vec3<S> n = unit_normal(j);
  const S E = j.su.dot(j.su), F = j.su.dot(j.sv), G = j.sv.dot(j.sv);
  const S L = j.suu.dot(n), M = j.suv.dot(n), N = j.svv.dot(n);
  // Shape operator W = I^-1 II in the (su, sv) basis; its eigenvalues are the curvatures.
  Eigen::Matrix<S, 2, 2> I, II;
  I << E, F, F, G;
  II << L, M, M, N;
  const Eigen::Matrix<S, 2, 2> W = I.inverse() * II;
  const S tr = W.trace(), det = W.determinant();
  const S disc = std::sqrt(std::max(S(0), tr * tr / S(4) - det));
  PrincipalCurvatures<S> pc;
  pc.k1 = tr / S(2) + disc;
  pc.k2 = tr / S(2) - disc;
  // Eigenvector of W for k1 in parameter space, mapped to 3-D.
  Eigen::Matrix<S, 2, 1> e;
  if (std::abs(W(0, 1)) > std::abs(W(1, 0)) && std::abs(W(0, 1)) > S(1e-14)) {
    e << W(0, 1), pc.k1 - W(0, 0);
  } else if (std::abs(W(1, 0)) > S(1e-14)) {
    e << pc.k1 - W(1, 1), W(1, 0);
  } else {
    e << (W(0, 0) >= W(1, 1) ? S(1) : S(0)), (W(0, 0) >= W(1, 1) ? S(0) : S(1));
  }
  Vec3<S> d1 = (e(0) * j.su + e(1) * j.sv);
  d1 = (d1 - d1.dot(n) * n).normalized();
  pc.d1 = d1;
  pc.d2 = n.cross(d1);
  return pc;
}

/// Normal curvature of a jet in the tangent direction t (unit, tangent): Euler's formula.
template <class S>
S normal_curvature(const PrincipalCurvatures<S>& pc, const Vec3<S>& t) {
  const S c = pc.d1.dot(t), s = pc.d2.dot(t);
  return pc.k1 * c * c + pc.k2 * s * s;
}

/// The parameter domain of a surface over x in [x0, x1], y in [y0, y1] (u = x, v = y): by
/// default the paper's 20 x 80 mm.
template <class S>
struct XYDomain {
  S x0_mm = S(0), x1_mm = S(20), y0_mm = S(0), y1_mm = S(80);

  S u_min() const { return x0_mm; }
  S u_max() const { return x1_mm; }
  S v_min() const { return y0_mm; }
  S v_max() const { return y1_mm; }
};

/// The demo part: a sine wave along y, constant along x, with a crest at y = 0:
/// z = height_mm * cos(2 pi y / wavelength_mm), u = x, v = y (documented in data/README.md).
/// With the defaults (10 mm, 40 mm) the normal leans up to atan(2 pi 10 / 40) = 57.5 deg off
/// vertical (62.5 deg with the 5 deg tilt, the paper's largest 62 deg) and the tightest radius
/// is 40^2 / (4 pi^2 10) = 4.05 mm, above the 3 mm ball: no local gouge.
template <class S>
struct SineSurface : XYDomain<S> {
  S height_mm = S(10);
  S wavelength_mm = S(40);

  SurfaceJet<S> jet(S u, S v) const {
    const S w = Constants<S>::two_pi() / wavelength_mm;
    const S s = std::sin(w * v), c = std::cos(w * v);
    SurfaceJet<S> j;
    j.p = Vec3<S>(u, v, height_mm * c);
    j.su = Vec3<S>(1, 0, 0);
    j.sv = Vec3<S>(0, 1, -height_mm * w * s);
    j.suu = Vec3<S>::Zero();
    j.suv = Vec3<S>::Zero();
    j.svv = Vec3<S>(0, 0, -height_mm * w * w * c);
    return j;
  }
};
using SineSurfaced = SineSurface<double>;

/// A plane through `origin` spanned by unit directions `du`, `dv`, over [0, size] x [0, size].
template <class S>
struct Plane {
  Vec3<S> origin = Vec3<S>::Zero();
  Vec3<S> du = Vec3<S>::UnitX(), dv = Vec3<S>::UnitY();
  S u_size_mm = S(100), v_size_mm = S(100);

  S u_min() const { return S(0); }
  S u_max() const { return u_size_mm; }
  S v_min() const { return S(0); }
  S v_max() const { return v_size_mm; }

  SurfaceJet<S> jet(S u, S v) const {
    SurfaceJet<S> j;
    j.p = origin + u * du + v * dv;
    j.su = du;
    j.sv = dv;
    j.suu = j.suv = j.svv = Vec3<S>::Zero();
    return j;
  }
};
using Planed = Plane<double>;

/// A heightfield z = f(x, y) over [x0, x1] x [y0, y1], u = x, v = y, from f and its first and
/// second partial derivatives (`Field::at(x, y)` returns f, fx, fy, fxx, fxy, fyy).
template <class S, class Field>
struct HeightfieldSurface : XYDomain<S> {
  Field field;

  SurfaceJet<S> jet(S u, S v) const {
    const std::array<S, 6> f = field.at(u, v);
    SurfaceJet<S> j;
    j.p = Vec3<S>(u, v, f[0]);
    j.su = Vec3<S>(1, 0, f[1]);
    j.sv = Vec3<S>(0, 1, f[2]);
    j.suu = Vec3<S>(0, 0, f[3]);
    j.suv = Vec3<S>(0, 0, f[4]);
    j.svv = Vec3<S>(0, 0, f[5]);
    return j;
  }
};

/// A round bump: z = h exp(-r^2 / (2 sigma^2)), r the distance from (cx, cy). Its concave ring
/// (r = sqrt(3) sigma) bends by at most 0.45 h / sigma^2 (a 22 mm radius for h = sigma = 10).
template <class S>
struct BumpField {
  S height_mm = S(10), sigma_mm = S(10), cx_mm = S(10), cy_mm = S(40);
  std::array<S, 6> at(S x, S y) const {
    const S dx = x - cx_mm, dy = y - cy_mm, s2 = sigma_mm * sigma_mm;
    const S z = height_mm * std::exp(-(dx * dx + dy * dy) / (S(2) * s2));
    return {z,
            -z * dx / s2,
            -z * dy / s2,
            z * (dx * dx / s2 - S(1)) / s2,
            z * dx * dy / (s2 * s2),
            z * (dy * dy / s2 - S(1)) / s2};
  }
};

/// A saddle: z = h ((x - cx)^2 / a^2 - (y - cy)^2 / b^2) / 2, concave across x (radius about
/// a^2 / h), convex along y.
template <class S>
struct SaddleField {
  S height_mm = S(10), a_mm = S(10), b_mm = S(40), cx_mm = S(10), cy_mm = S(40);
  std::array<S, 6> at(S x, S y) const {
    const S dx = x - cx_mm, dy = y - cy_mm, a2 = a_mm * a_mm, b2 = b_mm * b_mm;
    return {height_mm * (dx * dx / a2 - dy * dy / b2) / S(2),
            height_mm * dx / a2,
            -height_mm * dy / b2,
            height_mm / a2,
            S(0),
            -height_mm / b2};
  }
};

}  // namespace taxopt
