#include "taxopt/core/toolpath.hpp"

#include <cmath>

namespace taxopt {

const char* to_string(LengthUnit unit) { return unit == LengthUnit::Inch ? "in" : "mm"; }

Tool Tool::ball_end_mill(double diameter_mm, double flute_length_mm) {
  Tool t;
  t.diameter_mm = diameter_mm;
  t.corner_radius_mm = 0.5 * diameter_mm;
  t.flute_length_mm = flute_length_mm;
  return t;
}

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
