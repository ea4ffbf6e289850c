// The guard that gives a pass back its reference axes where the method would raise its peak or hit
// the part (plan_rooms.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/plan_rooms.hpp"
#include "pipeline/stages.hpp"
#include "plan/air_turn.hpp"
#include "plan/pole_passage.hpp"
#include "plan/stretch_guard.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {

/// Points of `op` (and the moves into them) whose tool hits the part, among those marked in
/// `check`, for axes `axes` posed as `poses` (tips from the fixed ball centres), the moves as
/// `posted_machine` runs them: in machine mode with linearisation the tip runs the straight
/// line, as in TCP mode. Nothing hits without a model.
std::vector<char> points_and_moves_hit(const OperationPlanInputs& in,
                                       const std::vector<Vec3d>& axes,
                                       const std::vector<Posed>& poses,
                                       const std::vector<char>& check) {
  const Operationd& op = in.op;
  const std::vector<ContactPoint>& contacts = in.contacts;
  const std::size_t n = op.points.size();
  std::vector<char> hit(n, 0);
  if (!in.model || !in.tool) return hit;
  const PartCheck& model = *in.model;
  const ToolModel& tool = *in.tool;
  Machine machine = in.machine;
  if (machine.gcode.program.linearise_tolerance_mm > 0.0) machine.gcode.mode = GcodeMode::Tcp;
  std::vector<Vec3d> xyz;
  std::vector<double> a, c;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d tip = tip_for_axis(op.points[i], in.ball_radius_mm, axes[i]);
    xyz.push_back(written_xyz_mm(machine, tip, poses[i]));
    a.push_back(rad_to_deg(poses[i].tilt_rad));
    c.push_back(rad_to_deg(poses[i].c_rad));
  }
  // No progress to report (the sweeps run inside a stage's item), but the job's stop looked
  // at with every point and move.
  const StopSource none;
  detail::StageProgress watch(3 * n, in.stop ? *in.stop : none);
  std::vector<ContactPoint> air(n);  // no contacts known: treat every move as in the air
  for (std::size_t i :
       colliding_moves(model, tool, machine, xyz, a, c, contacts.empty() ? air : contacts, &watch,
                       nullptr, &check, in.bounds)) {
    hit[i] = 1;
  }
  for (std::size_t i : colliding_points(model, tool, op, axes, contacts, &watch, &check)) {
    hit[i] = 1;
  }
  // Where the input's flutes clear the part, an axis other than the input's must clear it too.
  std::vector<char> strict(n, 0);
  bool any_strict = false;
  for (std::size_t i = 0; i < n; ++i) {
    strict[i] = check[i] && !hit[i] && in.held_to_input(i) &&
                angle_between(axes[i], op.points[i].axis) > 1e-12;
    any_strict = any_strict || strict[i];
  }
  if (any_strict) {
    for (std::size_t i :
         colliding_points(model, *in.strict_tool, op, axes, contacts, &watch, &strict)) {
      hit[i] = 1;
    }
  }
  return hit;
}

// (plan_rooms.hpp)
/// The largest share of its machine limit any rotary axis reaches: of the peaks of a (`rms`
/// false) or of the RMS of a (true). The limits are the machine's effective ones (its own,
/// else the defaults), so that a B far slower than its C weighs as the machine feels it.
double worst_accel_share(const RotarySummary& s, const JointLimits& limits, bool rms) {
  const double tilt_limit = limits[static_cast<std::size_t>(Joint::Tilt)].max_accel_per_s2;
  const double c_limit = limits[static_cast<std::size_t>(Joint::C)].max_accel_per_s2;
  const double tilt = rms ? s.tilt.rms_accel_deg_s2 : s.tilt.max_accel_deg_s2;
  const double c = rms ? s.c.rms_accel_deg_s2 : s.c.max_accel_deg_s2;
  return std::max(tilt / tilt_limit, c / c_limit);
}

// (plan_rooms.hpp)
PassRates pass_rates(const OperationPlanInputs& in, const IndexRange& pass,
                     const std::vector<Posed>& poses) {
  std::vector<double> a, c;
  for (std::size_t i = pass.begin; i < pass.end; ++i) {
    a.push_back(rad_to_deg(poses[i].tilt_rad));
    c.push_back(rad_to_deg(poses[i].c_rad));
  }
  PassRates r{
      rotary_kinematics_from_times(
          a, c, move_times_s(in.op, in.ball_radius_mm, in.machine.rotary, poses, in.timing, pass)),
      {}};
  accumulate(r.summary, r.k, c);
  return r;
}

namespace {

/// A pass gains on its reference when its worst axis's peak a falls by more than this share,
/// or the worst axis's RMS a by more than kRmsGain: below that the axes would turn for an
/// improvement the machine cannot feel (and the rounding of the written words can undo).
constexpr double kPeakGain = 1e-3;
constexpr double kRmsGain = 1e-2;

/// The guard of an operation's passes (guard_passes): the reference's poses (the input's
/// unless given), which passes it guards (those whose reference is free), the input's peaks per
/// axis that bound every guarded pass, and the verdict on a candidate's points that
/// guard_stretches asks for.
class PassGuard {
 public:
  PassGuard(const OperationPlanInputs& in, const GuardReference* reference)
      : in_(in),
        n_(in.op.points.size()),
        rapid_into_(rapid_into_of(in.op)),
        passes_(feed_passes(in.op)),
        limits_(effective_limits(in.machine)) {
    for (const CLPointd& p : in.op.points) input_axes_.push_back(p.axis);
    ref_axes_ = input_axes_;
    if (reference) {
      ref_axes_ = reference->axes;
      ref_preferred_ = reference->preferred;
      judge_gain_ = reference->judge_gain;
    }
    reference_is_input_ = !reference;
  }

  StretchGuardResult run(OptimisedOperation& out) {
    const PosePlan ref_plan = plan_poses(in_.machine.rotary, ref_axes_, rapid_into_, {},
                                         in_.pose_options, ref_preferred_);
    // Without a reference of its own the reference is the input: its plan is the input's.
    const PosePlan input_plan = reference_is_input_ ? ref_plan
                                                    : plan_poses(in_.machine.rotary, input_axes_,
                                                                 rapid_into_, {}, in_.pose_options);
    if (!ref_plan.ok() || !input_plan.ok()) {
      return {out.axes, std::vector<KeptWhy>(n_, KeptWhy::None)};
    }
    const std::vector<char> ref_hit =
        moves_hit(ref_axes_, ref_plan.poses, std::vector<char>(n_, 1));
    // Where the input hits the part its rates promise nothing: a pass guarded against another
    // method's safe axes may then turn each axis as fast as those do (below).
    const std::vector<char> input_hit =
        reference_is_input_ ? ref_hit
                            : moves_hit(input_axes_, input_plan.poses, std::vector<char>(n_, 1));
    std::vector<char> guarded(passes_.size(), 0);
    before_.assign(passes_.size(), {});
    bound_.assign(passes_.size(), {});
    for (std::size_t q = 0; q < passes_.size(); ++q) {
      const IndexRange& pass = passes_[q];
      bool ref_safe = true;
      for (std::size_t i = pass.begin; i < pass.end; ++i) ref_safe = ref_safe && !ref_hit[i];
      if (!ref_safe || pass.size() == 0) continue;
      guarded[q] = 1;
      before_[q] = rates(pass, ref_plan.poses).summary;
      // The promise is the input's, per axis, whatever the reference, where the input is safe;
      // where it is not, each axis may turn as fast as the higher of the input and the
      // reference do (the demo's input holds C still and hits the part; the paper's free plan
      // turns C).
      bool input_safe = true;
      for (std::size_t i = pass.begin; i < pass.end; ++i) input_safe = input_safe && !input_hit[i];
      bound_[q] = reference_is_input_ ? before_[q] : rates(pass, input_plan.poses).summary;
      if (!reference_is_input_ && !input_safe) {
        raise_to(bound_[q].tilt, before_[q].tilt);
        raise_to(bound_[q].c, before_[q].c);
      }
    }
    opt_preferred_ = out.preferred;
    const StretchEvaluation evaluate =
        [this](const std::vector<Vec3d>& axes, const std::vector<KeptWhy>& why,
               const std::vector<char>& check) { return verdicts(axes, why, check); };
    StretchGuardResult guard = guard_stretches(passes_, guarded, out.axes, ref_axes_, evaluate);
    out.axes = guard.axes;
    if (!out.preferred.empty()) out.preferred = preferred_of(guard.why);
    // The points between passes were carried from the method's pass ends: where the guard gave
    // a pass end back its reference axis, the points in the air next to it take theirs back too
    // (the tool does not turn in the air for a pass that kept its axes).
    carry_between_passes(in_.op, passes_, [&](std::size_t to, std::size_t from) {
      if (angle_between(out.axes[from], ref_axes_[from]) > 1e-12) return;
      out.axes[to] = ref_axes_[to];
      if (!out.preferred.empty()) {
        out.preferred[to] = ref_preferred_.empty() ? std::nullopt : ref_preferred_[to];
      }
    });
    return guard;
  }

 private:
  std::vector<char> moves_hit(const std::vector<Vec3d>& axes, const std::vector<Posed>& poses,
                              const std::vector<char>& check) const {
    return points_and_moves_hit(in_, axes, poses, check);
  }

  /// `bound`'s peaks raised to `other`'s where those are higher.
  static void raise_to(AxisPeaks& bound, const AxisPeaks& other) {
    bound.max_omega_deg_s = std::max(bound.max_omega_deg_s, other.max_omega_deg_s);
    bound.max_accel_deg_s2 = std::max(bound.max_accel_deg_s2, other.max_accel_deg_s2);
  }

  PassRates rates(const IndexRange& pass, const std::vector<Posed>& poses) const {
    return pass_rates(in_, pass, poses);
  }

  /// The preferred poses of a candidate: the optimiser's where optimised, the reference's
  /// where kept, none on a join.
  std::vector<std::optional<Posed>> preferred_of(const std::vector<KeptWhy>& why) const {
    std::vector<std::optional<Posed>> preferred = opt_preferred_;
    for (std::size_t i = 0; i < preferred.size() && i < why.size(); ++i) {
      if (why[i] == KeptWhy::Join) preferred[i] = std::nullopt;
      if (why[i] == KeptWhy::Collision || why[i] == KeptWhy::PeakRate ||
          why[i] == KeptWhy::NoGain) {
        preferred[i] = ref_preferred_.empty() ? std::nullopt : ref_preferred_[i];
      }
    }
    return preferred;
  }

  /// A candidate's points: those whose points or moves hit, those that raise an axis's omega or
  /// a above the input's peak over their guarded pass; and the passes where it gains on the
  /// reference.
  StretchVerdicts verdicts(const std::vector<Vec3d>& axes, const std::vector<KeptWhy>& why,
                           const std::vector<char>& check) const {
    StretchVerdicts out{std::vector<PointVerdict>(n_, PointVerdict::Good),
                        std::vector<char>(passes_.size(), 0)};
    const PosePlan plan =
        plan_poses(in_.machine.rotary, axes, rapid_into_, {}, in_.pose_options, preferred_of(why));
    if (!plan.ok()) {
      for (std::size_t i = 0; i < n_; ++i) {
        if (check[i]) out.points[i] = PointVerdict::Hits;
      }
      return out;
    }
    const std::vector<char> hit = moves_hit(axes, plan.poses, check);
    for (std::size_t q = 0; q < passes_.size(); ++q) {
      const IndexRange& pass = passes_[q];
      if (pass.size() == 0 || !check[pass.begin]) continue;
      out.gains[q] = pass_verdicts(q, plan.poses, hit, out.points);
    }
    return out;
  }

  /// Pass q's points judged (see verdicts), each rotary axis on its own; true when the pass
  /// gains on its reference.
  bool pass_verdicts(std::size_t q, const std::vector<Posed>& poses, const std::vector<char>& hit,
                     std::vector<PointVerdict>& verdict) const {
    const IndexRange& pass = passes_[q];
    const PassRates after = rates(pass, poses);
    const RotaryKinematics& k = after.k;
    // omega_j belongs to the segment j -> j + 1, a_j to the points j - 1, j, j + 1.
    const auto raises = [&](std::size_t lo, std::size_t hi) {
      for (std::size_t j = lo; j <= hi && j < pass.size(); ++j) {
        if (verdict[pass.begin + j] == PointVerdict::Good)
          verdict[pass.begin + j] = PointVerdict::RaisesRate;
      }
    };
    const AxisPeaks& tilt = bound_[q].tilt;
    const AxisPeaks& c = bound_[q].c;
    for (std::size_t j = 0; j < pass.size(); ++j) {
      if (rate_above(k.omega_tilt_deg_s[j], tilt.max_omega_deg_s, kStillOmegaDegS) ||
          rate_above(k.omega_c_deg_s[j], c.max_omega_deg_s, kStillOmegaDegS)) {
        raises(j, j + 1);
      }
      if (rate_above(k.accel_tilt_deg_s2[j], tilt.max_accel_deg_s2, kStillAccelDegS2) ||
          rate_above(k.accel_c_deg_s2[j], c.max_accel_deg_s2, kStillAccelDegS2)) {
        raises(j ? j - 1 : 0, j + 1);
      }
    }
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      if (hit[i]) verdict[i] = PointVerdict::Hits;
    }
    if (!judge_gain_) return true;
    return worst_accel_share(after.summary, limits_, false) <
               worst_accel_share(before_[q], limits_, false) * (1.0 - kPeakGain) ||
           worst_accel_share(after.summary, limits_, true) <
               worst_accel_share(before_[q], limits_, true) * (1.0 - kRmsGain);
  }

  const OperationPlanInputs in_;
  const std::size_t n_;
  const std::vector<bool> rapid_into_;
  const std::vector<IndexRange> passes_;
  const JointLimits limits_;
  std::vector<Vec3d> input_axes_, ref_axes_;
  std::vector<std::optional<Posed>> ref_preferred_;
  std::vector<std::optional<Posed>> opt_preferred_;
  bool judge_gain_ = true;
  bool reference_is_input_ = true;
  /// Per pass: the reference's rates (what a candidate must gain on) and the input's (what no
  /// axis may exceed).
  std::vector<RotarySummary> before_, bound_;
};

}  // namespace

StretchGuardResult guard_passes(const OperationPlanInputs& in, OptimisedOperation& out,
                                const GuardReference* reference) {
  return PassGuard(in, reference).run(out);
}

}  // namespace taxopt::pipeline
