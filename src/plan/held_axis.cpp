#include "plan/held_axis.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "taxopt/kinematics/metrics.hpp"

namespace taxopt {

namespace {

/// One box average of the piecewise-linear x(tau) over [tau_i + lo, tau_i + hi] at each tau_i,
/// from its integral F(u) (x held at its end values outside [0, T]).
std::vector<double> box(const std::vector<double>& x, const std::vector<double>& tau, double lo,
                        double hi) {
  const std::size_t n = x.size();
  std::vector<double> prefix(n, 0.0);  // integral of x from 0 to tau_i
  for (std::size_t i = 1; i < n; ++i) {
    prefix[i] = prefix[i - 1] + 0.5 * (x[i - 1] + x[i]) * (tau[i] - tau[i - 1]);
  }
  const double end = tau.back();
  const auto integral = [&](double u) {
    if (u <= 0.0) return x.front() * u;
    if (u >= end) return prefix.back() + x.back() * (u - end);
    const std::size_t j =
        static_cast<std::size_t>(std::upper_bound(tau.begin(), tau.end(), u) - tau.begin()) - 1;
    const double s = u - tau[j], slope = (x[j + 1] - x[j]) / (tau[j + 1] - tau[j]);
    return prefix[j] + x[j] * s + 0.5 * slope * s * s;
  };
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) {
    y[i] = (integral(tau[i] + hi) - integral(tau[i] + lo)) / (hi - lo);
  }
  return y;
}

}  // namespace

std::vector<double> low_passed(const std::vector<double>& x, const std::vector<double>& t,
                               double width_s, Window window) {
  if (x.size() < 2 || t.size() + 1 != x.size() || !(width_s > 0.0)) return x;
  std::vector<double> tau(x.size(), 0.0);
  for (std::size_t i = 1; i < x.size(); ++i) tau[i] = tau[i - 1] + t[i - 1];
  const double lo = window == Window::Centred ? -0.5 * width_s
                    : window == Window::Ahead ? 0.0
                                              : -width_s;
  return box(box(x, tau, lo, lo + width_s), tau, lo, lo + width_s);
}

namespace detail {

RotarySummary rate_summary(const std::vector<Posed>& poses, const std::vector<double>& t) {
  std::vector<double> tilt_deg, c_deg;
  for (const Posed& p : poses) {
    tilt_deg.push_back(rad_to_deg(p.tilt_rad));
    c_deg.push_back(rad_to_deg(p.c_rad));
  }
  RotarySummary out;
  accumulate(out, rotary_kinematics_from_times(tilt_deg, c_deg, t), c_deg);
  return out;
}

std::vector<Posed> HeldAxis::candidates(std::size_t i, const Posed& centre, double radius_rad,
                                        double step_rad, const std::vector<Posed>& extra) const {
  std::vector<Posed> out{centre};
  const auto held = [&](const Posed& p) { return hold_tilt_ ? p.tilt_rad : p.c_rad; };
  for (const Posed& p : extra) {
    if (std::abs(held(p) - held(centre)) < 1e-12 && feasible_(i, p)) out.push_back(p);
  }
  const double reach = hold_tilt_ ? std::sin(std::abs(centre.tilt_rad)) : 1.0;
  if (reach < 1e-3) return out;  // at the pole C turns no axis
  const int steps = static_cast<int>(std::ceil(radius_rad / step_rad - 1e-9));
  for (int k = -steps; k <= steps && out.size() < 255; ++k) {
    if (k == 0) continue;
    Posed p = centre;
    free_of(p) += k * step_rad / reach;
    if (feasible_(i, p)) out.push_back(p);
  }
  return out;
}

std::vector<std::vector<Posed>> HeldAxis::low_passed_plans(const std::vector<double>& t) const {
  std::vector<std::vector<Posed>> out;
  if (t.empty()) return out;
  std::vector<double> x;
  for (Posed p : warm_) x.push_back(free_of(p));
  double total = 0.0, shortest = t.front();
  for (double ti : t) total += ti, shortest = std::min(shortest, ti);
  for (Window window : {Window::Ahead, Window::Behind, Window::Centred}) {
    for (double width = total; width >= 2.0 * shortest; width /= 2.0) {
      out.push_back(clipped(low_passed(x, t, width, window)));
    }
  }
  return out;
}

std::vector<Posed> HeldAxis::clipped(const std::vector<double>& y) const {
  std::vector<Posed> poses = warm_;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    double& free = free_of(poses[i]);
    const double from = free;
    for (double f = 1.0; f > 0.01; f *= 0.5) {
      free = from + f * (y[i] - from);
      if (feasible_(i, poses[i])) break;
      free = from;
    }
  }
  return poses;
}

std::vector<Posed> HeldAxis::snapped(const std::vector<Posed>& plan) const {
  constexpr double kSnapRad = 1e-5;
  std::vector<Posed> out = plan;
  for (std::size_t i = 0; i < out.size() && i < warm_.size(); ++i) {
    if (std::abs(out[i].tilt_rad - warm_[i].tilt_rad) < kSnapRad &&
        std::abs(out[i].c_rad - warm_[i].c_rad) < kSnapRad) {
      out[i] = warm_[i];
    }
  }
  return out;
}

}  // namespace detail

}  // namespace taxopt
