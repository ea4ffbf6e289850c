#pragma once
/// @file The guard after an optimiser, per stretch rather than per pass.
///
/// An optimiser's axes can be worse than the input's somewhere in a pass: the machine's moves
/// between two points sweep the tool through the part (the optimiser checks points, not moves:
/// near the pole A = 0 a small turn of the axis is a large turn of C), or a local turn raises
/// the pass's peak omega or a above the input's. Keeping the input axes over the whole pass
/// throws away every improvement elsewhere in it (two removable C flips stay because a third
/// stretch is hard). So the pass keeps its input axes over the stretches where the optimised
/// ones are worse, and only there.
///
/// Each kept stretch joins the optimised axes on either side by a blend of b points: point k
/// away from the stretch (k = 1..b) takes slerp(optimised, input, s(w)), w = (b + 1 - k) /
/// (b + 1), s(w) = 3 w^2 - 2 w^3 (smoothstep: no jump of the axis or of its rate of turn at
/// either end of the blend). The blended axis lies on the great circle between the optimised
/// and the input axis, so it is within any cone about the input that holds the optimised one.
///
/// Rounds: the caller judges the candidate axes of the passes still open (`evaluate`); a point
/// judged worse outside every stretch starts a stretch of its own; one inside a stretch's
/// reach (the stretch, its blends and the point next to them) doubles its blend when the rate
/// is the trouble (a join too sharp), and widens the stretch to the point when it hits (a
/// longer blend would not move the tool out of the part). Stretches whose blends meet merge;
/// one whose blend would leave the pass reaches the pass's end. A pass covered by its stretch,
/// or still worse after the last round, or good at every point but with no gain on the input
/// (StretchVerdicts::gains), keeps its input axes whole: a method never turns the axes where
/// nothing improves. A pass the guard
/// leaves optimised, even in part, was judged good as a whole in its last round.
///
/// Serial and deterministic; the evaluation may run in parallel.

#include <cstddef>
#include <functional>
#include <vector>

#include "taxopt/core/toolpath.hpp"
#include "taxopt/core/types.hpp"

namespace taxopt {

/// Why a point kept its input axis.
enum class KeptWhy : unsigned char {
  None,       ///< optimised
  Collision,  ///< the optimised axes' points or moves hit the part
  PeakRate,   ///< the optimised axes raised the pass's peak rate
  Join,       ///< blended between kept and optimised axes (neither one)
  NoGain      ///< the optimised axes were no better over the pass: turning them gains nothing
};

/// The caller's verdict on one point of a candidate.
enum class PointVerdict : unsigned char { Good, RaisesRate, Hits };

/// Options of guard_stretches.
struct StretchGuardOptions {
  /// Blend length of a new stretch, points on each side.
  std::size_t first_blend = 4;
  /// Rounds of evaluation before a pass still worse keeps its input axes whole.
  std::size_t rounds = 10;
};

/// Outcome of guard_stretches.
struct StretchGuardResult {
  /// The axes afterwards: optimised, input, or blended between them.
  std::vector<Vec3d> axes;
  /// Per point why it kept its input axis (KeptWhy::None where optimised).
  std::vector<KeptWhy> why;
  /// Passes kept whole; stretches kept within passes that stay optimised elsewhere.
  std::size_t whole_passes = 0, stretches = 0;
  /// Points kept by why, and points blended.
  std::size_t points_hit = 0, points_rate = 0, points_blended = 0, points_no_gain = 0;
};

/// The caller's verdicts on a candidate.
struct StretchVerdicts {
  /// Per point of the operation (Good outside the passes asked about). The verdict on point i
  /// covers the move into i and the rates at i.
  std::vector<PointVerdict> points;
  /// Per pass asked about: the candidate gains on the input over the pass (the caller says
  /// what gains). A pass with no gain keeps its input whole: axes turned, or a mix of input and
  /// optimised axes, no better than the input are not worth the turn or the joins.
  std::vector<char> gains;
};

/// Judges a candidate: `axes` and `why` of the whole operation, the points with `check[i]`
/// set (the points of the passes still open).
using StretchEvaluation =
    std::function<StretchVerdicts(const std::vector<Vec3d>& axes, const std::vector<KeptWhy>& why,
                                  const std::vector<char>& check)>;

/// The guard: `optimised` and `input` are the axes of the whole operation (unit vectors);
/// `guarded[q]` says whether pass q is guarded at all (not when its input is itself unsafe:
/// it keeps its optimised axes). Passes are disjoint and ascending.
StretchGuardResult guard_stretches(const std::vector<IndexRange>& passes,
                                   const std::vector<char>& guarded,
                                   const std::vector<Vec3d>& optimised,
                                   const std::vector<Vec3d>& input,
                                   const StretchEvaluation& evaluate,
                                   const StretchGuardOptions& options = {});

}  // namespace taxopt
