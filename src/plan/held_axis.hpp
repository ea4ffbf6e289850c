#pragma once
/// @file The global method with one rotary axis held where the input holds it still
/// (GlobalPassProblem::hold_tilt, hold_c; docs/global-method.md, step 3b): the other axis's
/// candidates, its series low-passed in time, the snap back to the warm start.
///
/// The series x_i at times tau_0 = 0, tau_{i+1} = tau_i + t_i is read as the piecewise-linear
/// x(tau), held at its end values outside the pass, and averaged over a window of `width_s`
/// at each tau_i, twice (a triangle of twice the width). Each discrete rate of the result,
/// (y_{i+1} - y_i) / t_i, is an average of secant slopes of x, so of its rates and of zero:
/// never above the input's peak rate, where a sum-of-squares step, smoothing the acceleration,
/// can turn the axis faster than the input into a corner. The window is centred on tau_i, or
/// lies ahead of it (the axis turns before the input does, never after: a tool led into its
/// travel keeps at least its lead) or behind it.

#include <cstddef>
#include <functional>
#include <vector>

#include "taxopt/kinematics/machine_kinematics.hpp"
#include "taxopt/kinematics/metrics.hpp"

namespace taxopt {

/// Where the window lies: [tau - w/2, tau + w/2], [tau, tau + w] or [tau - w, tau].
enum class Window { Centred, Ahead, Behind };

/// x low-passed over `width_s` (> 0) as the file comment says; `t` the n - 1 positive segment
/// times of the n values of x, s.
std::vector<double> low_passed(const std::vector<double>& x, const std::vector<double>& t,
                               double width_s, Window window = Window::Centred);

namespace detail {

/// The rotary rates of poses (radians) over segment times `t` (s), summarised per axis
/// (accumulate).
RotarySummary rate_summary(const std::vector<Posed>& poses, const std::vector<double>& t);

/// One pass with one axis held at the warm start's values and the other free.
class HeldAxis {
 public:
  /// Whether pose p is feasible at point i (the machine's ranges, the acceptability test).
  using Feasible = std::function<bool(std::size_t, const Posed&)>;
  /// `hold_tilt`: the tilt held and C free; else C held and the tilt free.
  HeldAxis(bool hold_tilt, const std::vector<Posed>& warm, Feasible feasible)
      : hold_tilt_(hold_tilt), warm_(warm), feasible_(std::move(feasible)) {}

  /// The candidates of point i: `centre` first, then the free axis stepped either side of it
  /// so that the tool axis turns about `step` rad a step (a step of C turns it sin|tilt| times
  /// as far), out to `radius`, where feasible (255 at most); `extra` where it holds the same
  /// axis.
  std::vector<Posed> candidates(std::size_t i, const Posed& centre, double radius_rad,
                                double step_rad, const std::vector<Posed>& extra) const;
  /// The free axis low-passed (low_passed) at widths from the pass's duration down by halves to
  /// two of its shortest segments, each window, each pose moved only as far toward its filtered
  /// value as is feasible (all the way, else the farthest of six halvings, else not at all).
  std::vector<std::vector<Posed>> low_passed_plans(const std::vector<double>& t) const;
  /// `plan` with its turns off the warm start below 1e-5 rad taken back: no written word
  /// would show them, and the point would count as changed where the program keeps its input
  /// axis (the filter's tails).
  std::vector<Posed> snapped(const std::vector<Posed>& plan) const;

 private:
  double& free_of(Posed& p) const { return hold_tilt_ ? p.c_rad : p.tilt_rad; }
  std::vector<Posed> clipped(const std::vector<double>& y) const;

  bool hold_tilt_;
  const std::vector<Posed>& warm_;
  Feasible feasible_;
};

}  // namespace detail

}  // namespace taxopt
