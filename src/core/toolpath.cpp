#include "taxopt/core/toolpath.hpp"

#include <cmath>

namespace taxopt {

const char* to_string(LengthUnit unit) { return unit == LengthUnit::Inch ? "in" : "mm"; }

const char* to_string(ClDialect dialect) {
  switch (dialect) {
    case ClDialect::SiemensNx: return "siemens-nx";
    case ClDialect::MakinoFfcam: return "makino-ffcam";
    case ClDialect::Catia: return "catia-v5";
    case ClDialect::SolidworksCam: return "solidworks-cam";
    case ClDialect::Creo: return "creo";
    case ClDialect::Generic: break;
  }
  return "generic-apt";
}

const char* to_string(ArcDirection direction) {
  switch (direction) {
    case ArcDirection::Clockwise: return "cw";
    case ArcDirection::CounterClockwise: return "ccw";
    case ArcDirection::Auto: break;
  }
  return "auto";
}

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
