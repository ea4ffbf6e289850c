#pragma once
/// @file What lets the paper optimiser price a key's cap of candidates quickly and still take
/// them in exactly the order it always did (paper_optimiser.cpp): the cap's pattern worked out
/// once per pass, and the candidates in (cost, index) order without the exact cost of each.

#include <cstddef>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "taxopt/core/types.hpp"

namespace taxopt::detail {

/// The rings of cap_grid: per candidate (the centre first) its angle from the centre and the
/// cosines and sines cap_grid takes, so that a cap is made with no trigonometry and the very
/// same arithmetic.
class CapPattern {
 public:
  CapPattern(double radius_rad, double step_rad);
  /// cap_grid(centre, radius_rad, step_rad, along), bit for bit.
  std::vector<Vec3d> axes(const Vec3d& centre, const Vec3d& along) const;
  /// Candidate c's angle from the centre, rad.
  double rho(std::size_t c) const { return rho_[c]; }
  std::size_t size() const { return rho_.size(); }

 private:
  std::vector<double> rho_, cos_rho_, sin_rho_, cos_phi_, sin_phi_;
};

/// Candidates in ascending (exact cost, index) order, the exact cost worked out only where it
/// can decide: `approx` is within `tolerance` of each exact cost, so the next candidate is among
/// those whose approximation lies within 2 tolerance of the least left. After a few, the rest
/// are priced exactly and heaped (a key whose cheapest candidates are all blocked).
class CandidateOrder {
 public:
  CandidateOrder(std::vector<double> approx, double tolerance,
                 std::function<double(std::size_t)> exact);
  /// The next candidate and its exact cost, none when every one was taken.
  std::optional<std::pair<double, std::size_t>> next();

 private:
  std::optional<std::pair<double, std::size_t>> next_in_heap();

  std::vector<double> approx_;
  double tolerance_;
  std::function<double(std::size_t)> exact_;
  std::vector<double> cost_;
  std::vector<char> taken_, priced_;
  std::vector<std::pair<double, std::size_t>> heap_;
  int lazy_left_ = 8;
  bool heaped_ = false;
};

}  // namespace taxopt::detail
