#pragma once
/// @file Tensor-product B-spline surface of any degree (bicubic by default) with clamped knot
/// vectors, so that CAD-like free-form parts can be represented (Piegl & Tiller, The NURBS
/// Book, algorithms A2.1 and A2.3).

#include <stdexcept>
#include <vector>

#include "taxopt/geometry/surface.hpp"

namespace taxopt {

template <class S>
class BSplineSurface {
 public:
  /// @param control control points, row-major: control[i * nv + j], i along u, j along v
  /// @param nu, nv   control points along u and v (> degree)
  /// @param degree   degree in both directions (3: bicubic)
  /// Knots are clamped and uniform on [0, 1]. @throws std::invalid_argument
  BSplineSurface(std::vector<Vec3<S>> control, int nu, int nv, int degree = 3)
      : ctrl_(std::move(control)), nu_(nu), nv_(nv), p_(degree) {
    if (degree < 1 || nu <= degree || nv <= degree ||
        ctrl_.size() != static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv)) {
      throw std::invalid_argument("BSplineSurface: need nu, nv > degree >= 1 and nu*nv points");
    }
    ku_ = clamped_knots(nu);
    kv_ = clamped_knots(nv);
  }

  S u_min() const { return S(0); }
  S u_max() const { return S(1); }
  S v_min() const { return S(0); }
  S v_max() const { return S(1); }

  SurfaceJet<S> jet(S u, S v) const {
    std::vector<S> nu_ders[3], nv_ders[3];
    const int su = span(ku_, nu_, u), sv = span(kv_, nv_, v);
    basis_ders(ku_, su, u, nu_ders);
    basis_ders(kv_, sv, v, nv_ders);
    Vec3<S> d[3][3];
    for (auto& row : d) {
      for (auto& x : row) x.setZero();
    }
    for (int a = 0; a <= p_; ++a) {
      for (int b = 0; b <= p_; ++b) {
        const Vec3<S>& c = ctrl_[static_cast<std::size_t>((su - p_ + a) * nv_ + (sv - p_ + b))];
        for (int k = 0; k < 3; ++k) {
          for (int l = 0; k + l < 3; ++l) {
            d[k][l] += nu_ders[k][static_cast<std::size_t>(a)] *
                       nv_ders[l][static_cast<std::size_t>(b)] * c;
          }
        }
      }
    }
    return SurfaceJet<S>{d[0][0], d[1][0], d[0][1], d[2][0], d[1][1], d[0][2]};
  }

 private:
  std::vector<S> clamped_knots(int n) const {
    std::vector<S> k;
    const int inner = n - p_ - 1;
    for (int i = 0; i <= p_; ++i) k.push_back(S(0));
    for (int i = 1; i <= inner; ++i) k.push_back(S(i) / S(inner + 1));
    for (int i = 0; i <= p_; ++i) k.push_back(S(1));
    return k;
  }

  /// Knot span index of t (A2.1).
  int span(const std::vector<S>& k, int n, S t) const {
    if (t >= k[static_cast<std::size_t>(n)]) return n - 1;
    if (t <= k[static_cast<std::size_t>(p_)]) return p_;
    int lo = p_, hi = n;
    int mid = (lo + hi) / 2;
    while (t < k[static_cast<std::size_t>(mid)] || t >= k[static_cast<std::size_t>(mid + 1)]) {
      if (t < k[static_cast<std::size_t>(mid)]) {
        hi = mid;
      } else {
        lo = mid;
      }
      mid = (lo + hi) / 2;
    }
    return mid;
  }

  /// Non-zero basis functions and their first two derivatives at t (A2.3).
  void basis_ders(const std::vector<S>& k, int i, S t, std::vector<S> (&ders)[3]) const {
    const int p = p_;
    const auto K = [&](int idx) { return k[static_cast<std::size_t>(idx)]; };
    std::vector<std::vector<S>> ndu(static_cast<std::size_t>(p + 1),
                                    std::vector<S>(static_cast<std::size_t>(p + 1)));
    std::vector<S> left(static_cast<std::size_t>(p + 1)), right(static_cast<std::size_t>(p + 1));
    ndu[0][0] = S(1);
    for (int j = 1; j <= p; ++j) {
      left[static_cast<std::size_t>(j)] = t - K(i + 1 - j);
      right[static_cast<std::size_t>(j)] = K(i + j) - t;
      S saved = S(0);
      for (int r = 0; r < j; ++r) {
        ndu[static_cast<std::size_t>(j)][static_cast<std::size_t>(r)] =
            right[static_cast<std::size_t>(r + 1)] + left[static_cast<std::size_t>(j - r)];
        const S temp = ndu[static_cast<std::size_t>(r)][static_cast<std::size_t>(j - 1)] /
                       ndu[static_cast<std::size_t>(j)][static_cast<std::size_t>(r)];
        ndu[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)] =
            saved + right[static_cast<std::size_t>(r + 1)] * temp;
        saved = left[static_cast<std::size_t>(j - r)] * temp;
      }
      ndu[static_cast<std::size_t>(j)][static_cast<std::size_t>(j)] = saved;
    }
    for (auto& d : ders) d.assign(static_cast<std::size_t>(p + 1), S(0));
    for (int j = 0; j <= p; ++j)
      ders[0][static_cast<std::size_t>(j)] =
          ndu[static_cast<std::size_t>(j)][static_cast<std::size_t>(p)];
    std::vector<std::vector<S>> a(2, std::vector<S>(static_cast<std::size_t>(p + 1)));
    const int n = std::min(2, p);
    for (int r = 0; r <= p; ++r) {
      int s1 = 0, s2 = 1;
      a[0][0] = S(1);
      for (int kk = 1; kk <= n; ++kk) {
        S d = S(0);
        const int rk = r - kk, pk = p - kk;
        auto at = [](std::vector<std::vector<S>>& m, int x, int y) -> S& {
          return m[static_cast<std::size_t>(x)][static_cast<std::size_t>(y)];
        };
        if (r >= kk) {
          at(a, s2, 0) = at(a, s1, 0) / at(ndu, pk + 1, rk);
          d = at(a, s2, 0) * at(ndu, rk, pk);
        }
        const int j1 = rk >= -1 ? 1 : -rk;
        const int j2 = (r - 1 <= pk) ? kk - 1 : p - r;
        for (int j = j1; j <= j2; ++j) {
          at(a, s2, j) = (at(a, s1, j) - at(a, s1, j - 1)) / at(ndu, pk + 1, rk + j);
          d += at(a, s2, j) * at(ndu, rk + j, pk);
        }
        if (r <= pk) {
          at(a, s2, kk) = -at(a, s1, kk - 1) / at(ndu, pk + 1, r);
          d += at(a, s2, kk) * at(ndu, r, pk);
        }
        ders[kk][static_cast<std::size_t>(r)] = d;
        std::swap(s1, s2);
      }
    }
    S factor = S(p);
    for (int kk = 1; kk <= n; ++kk) {
      for (auto& x : ders[kk]) x *= factor;
      factor *= S(p - kk);
    }
  }

  std::vector<Vec3<S>> ctrl_;
  int nu_, nv_, p_;
  std::vector<S> ku_, kv_;
};
using BSplineSurfaced = BSplineSurface<double>;

}  // namespace taxopt
