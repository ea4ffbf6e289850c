#pragma once
/// @file The segmenter of the paper (section 3.2, eq. 22-27, figs. 12, 16-17): a pass's
/// contact-point curve cut into convex and concave intervals at its inflection points, with a
/// key point added at the extreme point of a strongly asymmetric interval.
///
/// The curve is read as a height f over a running abscissa, as in the paper: f is the height
/// along `up` (the paper's z; taxopt uses the pass's mean input axis), the abscissa is the
/// arc length of the curve. Where the curve is a graph over the horizontal, arc length and
/// the paper's horizontal distance give f' and f'' of the same sign (d/ds = cos(slope) d/dx),
/// hence the same extreme and inflection points; unlike horizontal distance, arc length stays
/// defined where the curve climbs a vertical wall.
///
/// Errata of eq. 27: the printed second difference (z_{i+1} - 2 z_i + z_{i-1}) / (h_{i-1} h_i)
/// is only right for equal steps; with unequal steps it is non-zero on a straight slope and
/// its sign flips with the step pattern. taxopt uses the non-uniform second difference
///   f''_i = 2 (f'_{i+1/2} - f'_{i-1/2}) / (h_{i-1} + h_i),  f'_{i+1/2} = (z_{i+1} - z_i) / h_i.
///
//// Noise: a sign of f'' counts only where |f''| exceeds max(noise_floor_per_mm,
/// noise_fraction * max |f''| of the pass, the coordinate noise bound of `resolution_mm`); between
/// two counted signs of opposite sign the inflection point is the point nearest the middle (by arc
/// length) of the stretch between them. A flat or noisy stretch therefore gives one inflection at
/// most, never a shower.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "taxopt/core/types.hpp"

namespace taxopt {

/// Options of segment_curve.
struct SegmenterOptions {
  /// |f''| below this fraction of the pass's largest |f''| counts as zero (no sign).
  double noise_fraction = 0.1;
  /// ... and below this absolute value, 1/mm (a radius of curvature above 1000 mm is flat).
  double noise_floor_per_mm = 1e-3;
  /// Noise of the point coordinates, mm (the decimals of the CL file, the facets of a mesh):
  /// at point i, |f''| below 4 resolution / (h_{i-1} h_i), the most such noise can make of the
  /// second difference, counts as zero; likewise a slope below 2 resolution / h.
  double resolution_mm = 5e-4;
  /// An interval whose extreme point splits it into arcs whose ratio exceeds this gets a key
  /// point at the extreme point (figs. 16-17).
  double asymmetry_ratio = 2.0;
};

/// What the segmenter found on one pass. Indices are into the input points.
template <class S>
struct CurveShape {
  /// Arc length of each point from the first, mm.
  std::vector<S> arc_mm;
  /// f'' at each point (0 at the ends and at repeated points), 1/mm.
  std::vector<S> f2_per_mm;
  /// Points where f' changes sign, beyond the noise (local maxima and minima of f).
  std::vector<std::size_t> extremes;
  /// Points where f'' changes sign, beyond the noise.
  std::vector<std::size_t> inflections;
  /// Key points, ascending, unique: the first and last point, the inflection points and the
  /// extreme points of strongly asymmetric intervals. Consecutive keys bound the intervals.
  std::vector<std::size_t> keys;
};

/// Segments the curve `points_mm` (one pass, in order) seen with height along unit `up`.
template <class S>
CurveShape<S> segment_curve(const std::vector<Vec3<S>>& points_mm,
                            const typename std::vector<Vec3<S>>::value_type& up,
                            const SegmenterOptions& options = {}) {
  CurveShape<S> out;
  const std::size_t n = points_mm.size();
  out.arc_mm.assign(n, S(0));
  out.f2_per_mm.assign(n, S(0));
  if (n == 0) return out;
  for (std::size_t i = 1; i < n; ++i) {
    out.arc_mm[i] = out.arc_mm[i - 1] + (points_mm[i] - points_mm[i - 1]).norm();
  }
  // Distinct points only: a repeated point has no slope of its own.
  const S min_step = S(1e-9);
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < n; ++i) {
    if (at.empty() || out.arc_mm[i] - out.arc_mm[at.back()] > min_step) at.push_back(i);
  }
  const std::size_t m = at.size();
  std::vector<S> f1(m > 0 ? m - 1 : 0);  // f' on the segment from at[k] to at[k+1]
  for (std::size_t k = 0; k + 1 < m; ++k) {
    const S h = out.arc_mm[at[k + 1]] - out.arc_mm[at[k]];
    f1[k] = (points_mm[at[k + 1]] - points_mm[at[k]]).dot(up) / h;
  }
  S f2_max = S(0);
  for (std::size_t k = 1; k + 1 < m; ++k) {
    const S h0 = out.arc_mm[at[k]] - out.arc_mm[at[k - 1]];
    const S h1 = out.arc_mm[at[k + 1]] - out.arc_mm[at[k]];
    const S f2 = S(2) * (f1[k] - f1[k - 1]) / (h0 + h1);
    out.f2_per_mm[at[k]] = f2;
    f2_max = std::max(f2_max, std::abs(f2));
  }
  const S threshold = std::max(S(options.noise_floor_per_mm), S(options.noise_fraction) * f2_max);

  // Inflections: sign changes of f'' between counted (above-threshold) points.
  std::size_t last = 0;
  int last_sign = 0;
  for (std::size_t k = 1; k + 1 < m; ++k) {
    const S f2 = out.f2_per_mm[at[k]];
    const S h0 = out.arc_mm[at[k]] - out.arc_mm[at[k - 1]];
    const S h1 = out.arc_mm[at[k + 1]] - out.arc_mm[at[k]];
    const S tau = std::max(threshold, S(4 * options.resolution_mm) / (h0 * h1));
    const int sign = f2 > tau ? 1 : (f2 < -tau ? -1 : 0);
    if (sign == 0) continue;
    if (last_sign != 0 && sign != last_sign) {
      const S mid = S(0.5) * (out.arc_mm[at[last]] + out.arc_mm[at[k]]);
      std::size_t best = at[last];
      for (std::size_t j = last; j <= k; ++j) {
        if (std::abs(out.arc_mm[at[j]] - mid) < std::abs(out.arc_mm[best] - mid)) best = at[j];
      }
      out.inflections.push_back(best);
    }
    last = k;
    last_sign = sign;
  }

  // Extremes: sign changes of f' beyond a slope noise of threshold * step (a slope that
  // small is what the counted curvature could build over one step).
  int last_slope = 0;
  std::size_t last_slope_k = 0;
  for (std::size_t k = 0; k + 1 < m; ++k) {
    const S h = out.arc_mm[at[k + 1]] - out.arc_mm[at[k]];
    const S eps = std::max(threshold * h, S(2 * options.resolution_mm) / h);
    const int sign = f1[k] > eps ? 1 : (f1[k] < -eps ? -1 : 0);
    if (sign == 0) continue;
    if (last_slope != 0 && sign != last_slope) {
      // The extreme is the highest (lowest) point between the two slopes.
      std::size_t best = at[last_slope_k + 1];
      for (std::size_t j = last_slope_k + 1; j <= k; ++j) {
        const S z = points_mm[at[j]].dot(up), zb = points_mm[best].dot(up);
        if (last_slope > 0 ? z > zb : z < zb) best = at[j];
      }
      out.extremes.push_back(best);
    }
    last_slope = sign;
    last_slope_k = k;
  }

  // Keys: ends and inflections; then the extreme of an asymmetric interval.
  std::vector<std::size_t> keys = {0};
  for (std::size_t i : out.inflections) {
    if (i > keys.back() && i + 1 < n) keys.push_back(i);
  }
  if (n > 1) keys.push_back(n - 1);
  std::vector<std::size_t> with_extremes;
  for (std::size_t k = 0; k + 1 < keys.size(); ++k) {
    with_extremes.push_back(keys[k]);
    const std::size_t e = keys[k], f = keys[k + 1];
    for (std::size_t x : out.extremes) {
      if (x <= e || x >= f) continue;
      const S left = out.arc_mm[x] - out.arc_mm[e], right = out.arc_mm[f] - out.arc_mm[x];
      const S ratio = std::max(left, right) / std::max(std::min(left, right), min_step);
      if (ratio > S(options.asymmetry_ratio)) with_extremes.push_back(x);
      break;  // one extreme per interval: f'' keeps its sign inside
    }
  }
  with_extremes.push_back(keys.back());
  with_extremes.erase(std::unique(with_extremes.begin(), with_extremes.end()), with_extremes.end());
  out.keys = std::move(with_extremes);
  return out;
}

}  // namespace taxopt
