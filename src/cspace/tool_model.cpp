#include "taxopt/cspace/tool_model.hpp"

#include <algorithm>
#include <cmath>

#include "taxopt/core/error.hpp"

namespace taxopt {

double ToolModel::reach_mm() const {
  double r = ball_radius_mm;
  for (const auto& b : bodies) r = std::max(r, std::hypot(b.radius_mm, b.end_mm));
  return r;
}

namespace {

/// The holder of the overrides, from `face_mm` (the gauge length, measured from the model's
/// reference point) up by its length (default 40 mm): the last body.
void add_holder(ToolModel& m, const ToolOverrides& o, double shank_mm, double face_mm) {
  if (o.holder_radius_mm) {
    const double hr = *o.holder_radius_mm;
    const double hl = o.holder_length_mm.value_or(40.0);
    if (!(hr >= shank_mm)) throw InputError("holder radius must be at least the shank radius");
    if (!(hl > 0.0)) throw InputError("holder length must be positive");
    m.holder_body = static_cast<int>(m.bodies.size());
    m.bodies.push_back({hr, face_mm, face_mm + hl});
  } else if (o.holder_length_mm) {
    throw InputError(
        "a holder length needs a holder radius (ToolOverrides::holder_radius_mm, or the machine "
        "file's [holder] radius_mm)");
  }
}

/// The gauge length where no option gives one: the CL file's (LOADTL LENGTH), else the longer
/// of the flutes and 10 diameters.
double default_gauge_mm(const Tool& tool, double flute_mm, double diameter_mm) {
  return tool.gauge_length_mm > 0.0 ? tool.gauge_length_mm : std::max(flute_mm, 10.0 * diameter_mm);
}

/// Refuses a gauge length shorter than the flutes, naming where it came from.
void check_gauge(const Tool& tool, const ToolOverrides& o, double gauge_mm, double flute_mm) {
  if (gauge_mm >= flute_mm) return;
  throw InputError(!o.gauge_length_mm && tool.gauge_length_mm > 0.0
                       ? "the CL file's tool length (LOADTL LENGTH) is shorter than the flute "
                         "length: give the gauge length (--gauge-length, or the machine file's "
                         "holder.gauge_length_mm)"
                       : "gauge length must be at least the flute length");
}

}  // namespace

ToolModel ToolModel::ball_end(const Tool& tool, const ToolOverrides& o) {
  const double R = o.ball_radius_mm.value_or(tool.ball_radius_mm());
  if (!(R > 0.0)) throw InputError("the collision check needs a ball-end mill (ball radius > 0)");
  const double d = 2.0 * R;
  const double flute =
      o.flute_length_mm.value_or(tool.flute_length_mm > 0.0 ? tool.flute_length_mm : 4.0 * d);
  const double gauge = o.gauge_length_mm.value_or(default_gauge_mm(tool, flute, d));
  const double shank = o.shank_radius_mm.value_or(R);
  if (!(flute > R)) throw InputError("flute length must exceed the ball radius");
  check_gauge(tool, o, gauge, flute);
  if (!(shank > 0.0)) throw InputError("shank radius must be positive");
  ToolModel m;
  m.ball_radius_mm = R;
  if (tool.taper_rad > 0.0) {
    // A tapered ball: the cone tangent to the ball has the radius R / cos(b) + s tan(b) at s
    // above the ball centre. Steps of cylinders each enclose the cone over their span (the
    // radius at its top), at most 0.02 mm over it, 64 at the most (then a 64th of its rise).
    const double t = std::tan(tool.taper_rad);
    const double length = flute - R;
    const int steps = std::clamp(static_cast<int>(std::ceil(length * t / 0.02)), 1, 64);
    for (int k = 0; k < steps; ++k) {
      const double s0 = length * k / steps, s1 = length * (k + 1) / steps;
      m.bodies.push_back({R / std::cos(tool.taper_rad) + s1 * t, s0, s1});
    }
    m.flute_bodies = steps;
    const double top = R / std::cos(tool.taper_rad) + length * t;
    if (!o.shank_radius_mm && gauge > flute) m.bodies.push_back({top, flute - R, gauge - R});
    if (o.shank_radius_mm && gauge > flute) m.bodies.push_back({shank, flute - R, gauge - R});
    if (o.holder_radius_mm && !(*o.holder_radius_mm >= m.bodies.back().radius_mm)) {
      throw InputError("holder radius must be at least the tapered flutes' top radius");
    }
  } else {
    m.bodies.push_back({R, 0.0, flute - R});
    if (gauge > flute) m.bodies.push_back({shank, flute - R, gauge - R});
  }
  add_holder(m, o, shank, gauge - R);
  return m;
}

ToolModel ToolModel::shank_and_holder(const Tool& tool, const ToolOverrides& o) {
  const double D = tool.diameter_mm;
  if (!(D > 0.0)) throw InputError("the shank and holder check needs the tool's diameter");
  const double r = std::clamp(tool.corner_radius_mm, 0.0, 0.5 * D);
  const double flute =
      o.flute_length_mm.value_or(tool.flute_length_mm > 0.0 ? tool.flute_length_mm : 4.0 * D);
  const double gauge = o.gauge_length_mm.value_or(default_gauge_mm(tool, flute, D));
  const double shank = o.shank_radius_mm.value_or(0.5 * D);
  if (!(flute > r)) throw InputError("flute length must exceed the corner radius");
  check_gauge(tool, o, gauge, flute);
  if (!(shank > 0.0)) throw InputError("shank radius must be positive");
  ToolModel m;
  m.ball_radius_mm = r;
  m.flute_bodies = 0;
  if (gauge > flute) m.bodies.push_back({shank, flute - r, gauge - r});
  add_holder(m, o, shank, gauge - r);
  return m;
}

ToolModel ToolModel::judged(const ToolMargins& margins) const {
  ToolModel m = *this;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    ToolBody& b = m.bodies[i];
    if (static_cast<int>(i) < flute_bodies) {
      b.radius_mm = std::max(0.5 * ball_radius_mm, b.radius_mm - margins.flute_tolerance_mm);
    } else if (static_cast<int>(i) == holder_body) {
      b.radius_mm += margins.holder_clearance_mm;
      // Towards the tip too (its face), but not below where the shank starts.
      const double floor_mm = i > 0 ? bodies[i - 1].start_mm : 0.0;
      b.start_mm = std::max(floor_mm, b.start_mm - margins.holder_clearance_mm);
    } else {
      b.radius_mm += margins.shank_clearance_mm;
    }
  }
  return m;
}

}  // namespace taxopt
