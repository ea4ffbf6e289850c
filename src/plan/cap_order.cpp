// A key's cap of candidates for the paper optimiser (cap_order.hpp).
#include "plan/cap_order.hpp"

#include <algorithm>
#include <cmath>

#include "taxopt/plan/paper_optimiser.hpp"

namespace taxopt::detail {

CapPattern::CapPattern(double radius_rad, double step_rad) {
  rho_ = {0.0};
  cos_rho_ = {1.0};
  sin_rho_ = {0.0};
  cos_phi_ = {1.0};
  sin_phi_ = {0.0};
  const int rings = static_cast<int>(std::floor(radius_rad / step_rad + 1e-9));
  for (int r = 1; r <= rings; ++r) {
    const double rho = r * step_rad;
    const int m = std::max(
        1, static_cast<int>(std::ceil(Constants<double>::two_pi() * std::sin(rho) / step_rad)));
    for (int t = 0; t < m; ++t) {
      const double phi = Constants<double>::two_pi() * t / m;
      rho_.push_back(rho);
      cos_rho_.push_back(std::cos(rho));
      sin_rho_.push_back(std::sin(rho));
      cos_phi_.push_back(std::cos(phi));
      sin_phi_.push_back(std::sin(phi));
    }
  }
}

std::vector<Vec3d> CapPattern::axes(const Vec3d& centre, const Vec3d& along) const {
  // An orthonormal pair across the centre, the first along the axes' own turn: a grid in
  // the world's frame gave the sine's paper plan 14.2 deg/s^2 in place and 24.3 turned 30 deg
  // about Z (its keys off the path's great circle, through the pole).
  const Vec3d e1 = tangent_towards(centre, along);
  const Vec3d e2 = centre.cross(e1);
  std::vector<Vec3d> out;
  out.reserve(rho_.size());
  out.push_back(centre);
  for (std::size_t c = 1; c < rho_.size(); ++c) {
    out.push_back(cos_rho_[c] * centre + sin_rho_[c] * (cos_phi_[c] * e1 + sin_phi_[c] * e2));
  }
  return out;
}

CandidateOrder::CandidateOrder(std::vector<double> approx, double tolerance,
                               std::function<double(std::size_t)> exact)
    : approx_(std::move(approx)),
      tolerance_(tolerance),
      exact_(std::move(exact)),
      cost_(approx_.size(), 0.0),
      taken_(approx_.size(), 0),
      priced_(approx_.size(), 0) {}

std::optional<std::pair<double, std::size_t>> CandidateOrder::next() {
  if (heaped_ || lazy_left_ == 0) return next_in_heap();
  --lazy_left_;
  const std::size_t n = approx_.size();
  double least = 0.0;
  bool any = false;
  for (std::size_t c = 0; c < n; ++c) {
    if (taken_[c]) continue;
    if (!any || approx_[c] < least) least = approx_[c];
    any = true;
  }
  if (!any) return std::nullopt;
  // Any candidate beyond least + 2 tolerance costs more than the least one's exact cost.
  std::optional<std::pair<double, std::size_t>> best;
  for (std::size_t c = 0; c < n; ++c) {
    if (taken_[c] || approx_[c] > least + 2.0 * tolerance_) continue;
    if (!priced_[c]) cost_[c] = exact_(c), priced_[c] = 1;
    const std::pair<double, std::size_t> here{cost_[c], c};
    if (!best || here < *best) best = here;
  }
  taken_[best->second] = 1;
  return best;
}

std::optional<std::pair<double, std::size_t>> CandidateOrder::next_in_heap() {
  const auto later = std::greater<std::pair<double, std::size_t>>();
  if (!heaped_) {
    for (std::size_t c = 0; c < approx_.size(); ++c) {
      if (taken_[c]) continue;
      heap_.emplace_back(priced_[c] ? cost_[c] : exact_(c), c);
    }
    std::make_heap(heap_.begin(), heap_.end(), later);
    heaped_ = true;
  }
  if (heap_.empty()) return std::nullopt;
  std::pop_heap(heap_.begin(), heap_.end(), later);
  const std::pair<double, std::size_t> top = heap_.back();
  heap_.pop_back();
  return top;
}

}  // namespace taxopt::detail
