#pragma once
/// @file The paper's tool-axis optimiser (section 3.2-3.3, eq. 28-41, figs. 13-19) for one pass:
/// segment the contact-point curve, choose key axes inside the free space, fill each interval
/// by arc-length slerp, repair where an interpolated axis is not free, smooth the joints.
///
/// What the paper leaves open, and what taxopt does (docs/method.md has the reasoning):
/// - **Key axes.** The objective (eq. 28) is the sum of squared angular-velocity changes.
///   Between keys the slerp turns the axis at a constant rate per unit of path, so all of the
///   change happens at the keys: with keys V_k at arc positions s_k and the key rates
///   w_k = (V_{k+1} - V_k) / (s_{k+1} - s_k), the objective over the keys is
///   E = sum_k |w_k - w_{k-1}|^2 / ((s_{k+1} - s_{k-1}) / 2),
///   the discrete bending energy of the key polygon. Each key is chosen, in turn, as the free
///   axis (within the deviation cone of its input axis) that minimises E plus a small pull
///   towards its input axis, mu * angle^2 with mu = pull_weight / (pass length), which breaks
///   ties on flat passes in favour of the CAM system's axes. The candidates are a cap grid of
///   spacing `grid_deg` around the input axis, refined by pattern search to grid_deg / 8;
///   sweeps over the keys repeat until no key moves (at most `max_sweeps`).
/// - **Repair.** An interpolated axis that is not free splits its interval: the offending
///   point whose axis lies farthest from its input axis becomes a key, chosen like the others
///   with its neighbours fixed, and the two new intervals are filled again. Each repair adds a
///   key, so the loop ends.
/// - **Joint smoothing (fig. 19).** At an interior key the rate jumps from w_L to w_R. In the
///   tangent plane of the key axis (logarithm map, where both neighbouring arcs are straight
///   lines through the origin) the corner is replaced by a parabolic blend over
///   s in [s_k - d, s_k + d]: u(s) = w_L (s - s_k) + (w_R - w_L) (s - s_k + d)^2 / (4 d), which
///   meets both arcs with their rates, so the rate is continuous and its change is spread
///   evenly over 2d of path. d is half the shorter neighbouring interval (windows never
///   overlap); where a blended axis is not free, d is halved (up to 4 times), else the joint
///   is left sharp.

#include <cstddef>
#include <functional>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/types.hpp"
#include "taxopt/plan/segmenter.hpp"

namespace taxopt {

/// Whether `axis` (unit) is acceptable at point `index` of the pass: within the deviation
/// cone, reachable by the machine, collision-free. Called from several threads at once.
using AxisTest = std::function<bool(std::size_t index, const Vec3d& axis)>;

/// Options of plan_pass_paper.
struct PaperOptions {
  /// Largest angle between an output axis and its input axis, deg (the cone of candidates).
  double max_deviation_deg = 30.0;
  /// Spacing of the key-axis candidates, deg (the C-space cell size).
  double grid_deg = 2.0;
  SegmenterOptions segmenter;
  /// Weight of the pull of a key towards its input axis (see the file comment).
  double pull_weight = 0.05;
  /// Largest number of sweeps over the keys.
  int max_sweeps = 12;
  /// Smooth the joints between intervals (fig. 19).
  bool joint_smoothing = true;
  /// After the repair, set the keys again with the repair keys among them, fill and repair
  /// anew (at most this many rounds; 0: the paper's single repair). A repair key is placed
  /// with its neighbours fixed: where the free set has a hole the interpolation must pass (the
  /// cap round the normal that JobOptions::min_tilt_deg keeps clear), the keys around it then follow it.
  int resettle_rounds = 0;
};

/// One pass as the optimiser sees it.
struct PassProblem {
  /// The contact-point curve the segmenter reads (n points), mm.
  std::vector<Vec3d> curve_mm;
  /// The input tool axes (n, unit).
  std::vector<Vec3d> input_axes;
  /// Path length L_i from point i to point i + 1 (n - 1), mm: the lengths of eq. 40.
  std::vector<double> segment_mm;
  /// Height direction of the segmenter (unit).
  Vec3d up = Vec3d::UnitZ();
};

/// The optimised axes of a pass and how they came about.
struct PassPlan {
  std::vector<Vec3d> axes;
  /// Key points of the segmenter (ends, inflections, asymmetric extremes).
  std::vector<std::size_t> segmenter_keys;
  /// Key points in the end (segmenter keys plus repairs), ascending.
  std::vector<std::size_t> keys;
  std::size_t repairs = 0;
  /// Interior joints smoothed (with a window of any width) and left sharp.
  std::size_t smoothed_joints = 0, sharp_joints = 0;
  /// Points where no acceptable axis exists within the cone: their input axis is kept, and
  /// the caller must report them (the output is then not safe).
  std::vector<std::size_t> no_free_axis;
  /// Intervals (keys - 1).
  std::size_t intervals() const { return keys.empty() ? 0 : keys.size() - 1; }
};

/// Plans the axes of one pass. Deterministic: the same input gives the same axes whatever
/// the thread count (`is_free` may be called in parallel; its answers must not depend on
/// the order of calls).
TAXOPT_API PassPlan plan_pass_paper(const PassProblem& problem, const AxisTest& is_free,
                                    const PaperOptions& options = {});

/// Unit axes on a cap around unit `centre`: rings at multiples of `step_rad` up to
/// `radius_rad`, each with points about `step_rad` apart; the centre first, rings outwards.
/// Each ring starts in the direction of `along` (its part across the centre: give the way the
/// axes turn there, so that the grid turns with the part and a path through the pole keeps
/// candidates on its own great circle); where that is nil, in a direction fixed by the
/// world's X or Y axis.
TAXOPT_API std::vector<Vec3d> cap_grid(const Vec3d& centre, double radius_rad, double step_rad,
                                       const Vec3d& along = Vec3d::Zero());

/// The tangent direction at `centre` in which `along` points (unit, across the centre), else a
/// fixed one from the world's X or Y axis: the frame of cap_grid and of a pattern search.
TAXOPT_API Vec3d tangent_towards(const Vec3d& centre, const Vec3d& along);

}  // namespace taxopt
