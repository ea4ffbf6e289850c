#include "taxopt/cspace/tool_model.hpp"

#include <algorithm>

#include "taxopt/core/error.hpp"

namespace taxopt {

double ToolModel::reach_mm() const {
  double r = ball_radius_mm;
  for (const auto& b : bodies) r = std::max(r, std::hypot(b.radius_mm, b.end_mm));
  return r;
}

ToolModel ToolModel::ball_end(const Tool& tool, const ToolOverrides& o) {
  const double R = o.ball_radius_mm.value_or(tool.ball_radius_mm());
  if (!(R > 0.0)) throw InputError("the collision check needs a ball-end mill (ball radius > 0)");
  const double d = 2.0 * R;
  const double flute =
      o.flute_length_mm.value_or(tool.flute_length_mm > 0.0 ? tool.flute_length_mm : 4.0 * d);
  const double gauge = o.gauge_length_mm.value_or(std::max(flute, 10.0 * d));
  const double shank = o.shank_radius_mm.value_or(R);
  if (!(flute > R)) throw InputError("flute length must exceed the ball radius");
  if (!(gauge >= flute)) throw InputError("gauge length must be at least the flute length");
  if (!(shank > 0.0)) throw InputError("shank radius must be positive");
  ToolModel m;
  m.ball_radius_mm = R;
  m.bodies.push_back({R, 0.0, flute - R});
  if (gauge > flute) m.bodies.push_back({shank, flute - R, gauge - R});
  if (o.holder_radius_mm) {
    const double hr = *o.holder_radius_mm;
    const double hl = o.holder_length_mm.value_or(40.0);
    if (!(hr >= shank)) throw InputError("holder radius must be at least the shank radius");
    if (!(hl > 0.0)) throw InputError("holder length must be positive");
    m.bodies.push_back({hr, gauge - R, gauge - R + hl});
  } else if (o.holder_length_mm) {
    throw InputError("--holder-length needs --holder-radius");
  }
  return m;
}

}  // namespace taxopt
