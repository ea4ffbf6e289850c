#include "taxopt/core/toolpath.hpp"

#include <cmath>

namespace taxopt {

const char* to_string(LengthUnit unit) { return unit == LengthUnit::Inch ? "in" : "mm"; }

bool Tool::is_ball() const {
  return diameter_mm > 0.0 &&
         std::abs(corner_radius_mm - 0.5 * diameter_mm) <= 1e-6 * std::max(1.0, diameter_mm);
}

std::size_t point_count(const Toolpath& toolpath) {
  std::size_t n = 0;
  for (const auto& op : toolpath.operations) n += op.points.size();
  return n;
}

}  // namespace taxopt
