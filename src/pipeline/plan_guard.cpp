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
  std::vector<ContactPoint> air(n);  // no contacts known: treat every move as in the air
  for (std::size_t i :
       colliding_moves(model, tool, machine, xyz, a, c, contacts.empty() ? air : contacts, nullptr,
                       nullptr, &check)) {
    hit[i] = 1;
  }
  for (std::size_t i : colliding_points(model, tool, op, axes, contacts, nullptr, &check)) {
    hit[i] = 1;
  }
  return hit;
}

namespace {

/// The rates of a pass for poses of the whole operation (eq. 16-18), with their peaks and the
/// sum of squares of a over the interior points (metrics' accumulate).
struct PassRates {
  RotaryKinematics k;
  RotarySummary summary;
  double mean_sq_accel() const {
    return summary.accel_samples ? summary.sum_sq_accel / static_cast<double>(summary.accel_samples)
                                 : 0.0;
  }
};

/// The guard of an operation's passes (guard_passes): the reference's poses (the input's
/// unless given), which passes it guards (those whose reference is free), and the verdict on a
/// candidate's points that guard_stretches asks for.
class PassGuard {
 public:
  PassGuard(const OperationPlanInputs& in, const GuardReference* reference)
      : reference_(reference),
        in_(in),
        n_(in.op.points.size()),
        rapid_into_(rapid_into_of(in.op)),
        passes_(feed_passes(in.op)) {
    for (const CLPointd& p : in.op.points) in_axes_.push_back(p.axis);
    if (reference) {
      in_axes_ = reference->axes;
      in_preferred_ = reference->preferred;
    }
  }

  StretchGuardResult run(OptimisedOperation& out) {
    const PosePlan in_plan =
        plan_poses(in_.machine.rotary, in_axes_, rapid_into_, {}, in_.pose_options, in_preferred_);
    if (!in_plan.ok()) return {out.axes, std::vector<KeptWhy>(n_, KeptWhy::None)};
    const std::vector<char> in_hit = moves_hit(in_axes_, in_plan.poses, std::vector<char>(n_, 1));
    std::vector<char> guarded(passes_.size(), 0);
    before_.assign(passes_.size(), {});
    for (std::size_t q = 0; q < passes_.size(); ++q) {
      const IndexRange& pass = passes_[q];
      bool input_safe = true;
      for (std::size_t i = pass.begin; i < pass.end; ++i) input_safe = input_safe && !in_hit[i];
      if (!input_safe || pass.size() == 0) continue;
      guarded[q] = 1;
      before_[q] = rates(pass, in_plan.poses);
    }
    opt_preferred_ = out.preferred;
    const StretchEvaluation evaluate =
        [this](const std::vector<Vec3d>& axes, const std::vector<KeptWhy>& why,
               const std::vector<char>& check) { return verdicts(axes, why, check); };
    StretchGuardResult guard = guard_stretches(passes_, guarded, out.axes, in_axes_, evaluate);
    out.axes = guard.axes;
    if (!out.preferred.empty()) out.preferred = preferred_of(guard.why);
    return guard;
  }

 private:
  std::vector<char> moves_hit(const std::vector<Vec3d>& axes, const std::vector<Posed>& poses,
                              const std::vector<char>& check) const {
    return points_and_moves_hit(in_, axes, poses, check);
  }

  PassRates rates(const IndexRange& pass, const std::vector<Posed>& poses) const {
    std::vector<double> a, c;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      a.push_back(rad_to_deg(poses[i].tilt_rad));
      c.push_back(rad_to_deg(poses[i].c_rad));
    }
    PassRates r{
        rotary_kinematics_from_times(
            a, c,
            move_times_s(in_.op, in_.ball_radius_mm, in_.machine.rotary, poses, in_.timing, pass)),
        {}};
    accumulate(r.summary, r.k, c);
    return r;
  }

  /// The preferred poses of a candidate: the optimiser's where optimised, the reference's
  /// where kept, none on a join.
  std::vector<std::optional<Posed>> preferred_of(const std::vector<KeptWhy>& why) const {
    std::vector<std::optional<Posed>> preferred = opt_preferred_;
    for (std::size_t i = 0; i < preferred.size() && i < why.size(); ++i) {
      if (why[i] == KeptWhy::Join) preferred[i] = std::nullopt;
      if (why[i] == KeptWhy::Collision || why[i] == KeptWhy::PeakRate) {
        preferred[i] = in_preferred_.empty() ? std::nullopt : in_preferred_[i];
      }
    }
    return preferred;
  }

  /// A candidate's points: those whose points or moves hit, those that raise their guarded
  /// pass's peak omega or a above the reference's; and the passes whose rates it improves.
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

  /// Pass q's points judged (see verdicts); true when the pass gains.
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
    constexpr double kRel = 1.0 + 1e-9;
    const bool rates_count = !reference_ || reference_->rates;
    for (std::size_t j = 0; rates_count && j < pass.size(); ++j) {
      if (!reference_ && k.omega_deg_s[j] > before_[q].summary.max_omega_deg_s * kRel) {
        raises(j, j + 1);
      }
      if (k.accel_deg_s2[j] > before_[q].summary.max_accel_deg_s2 * kRel) {
        raises(j ? j - 1 : 0, j + 1);
      }
    }
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      if (hit[i]) verdict[i] = PointVerdict::Hits;
    }
    return !rates_count ||
           after.summary.max_accel_deg_s2 * kRel < before_[q].summary.max_accel_deg_s2 ||
           after.mean_sq_accel() * kRel < before_[q].mean_sq_accel();
  }

  const GuardReference* reference_;
  const OperationPlanInputs in_;
  const std::size_t n_;
  const std::vector<bool> rapid_into_;
  const std::vector<IndexRange> passes_;
  std::vector<Vec3d> in_axes_;
  std::vector<std::optional<Posed>> in_preferred_;
  std::vector<std::optional<Posed>> opt_preferred_;
  std::vector<PassRates> before_;
};

}  // namespace

StretchGuardResult guard_passes(const OperationPlanInputs& in, OptimisedOperation& out,
                                const GuardReference* reference) {
  return PassGuard(in, reference).run(out);
}

}  // namespace taxopt::pipeline
