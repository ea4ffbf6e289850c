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
/// `check`, for axes `axes` posed as `poses` (tips from the fixed ball centres); `machine` as
/// the path is run (machine mode with linearisation runs the straight tip line: pass TCP).
/// Nothing hits without a model.
std::vector<char> points_and_moves_hit(const Operationd& op,
                                       const std::vector<ContactPoint>& contacts,
                                       double ball_radius_mm, const PartCheck* model,
                                       const ToolModel* tool, const Machine& machine,
                                       const std::vector<Vec3d>& axes,
                                       const std::vector<Posed>& poses,
                                       const std::vector<char>& check) {
  const std::size_t n = op.points.size();
  std::vector<char> hit(n, 0);
  if (!model || !tool) return hit;
  std::vector<Vec3d> xyz;
  std::vector<double> a, c;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d tip = tip_for_axis(op.points[i], ball_radius_mm, axes[i]);
    xyz.push_back(written_xyz_mm(machine, tip, poses[i]));
    a.push_back(rad_to_deg(poses[i].tilt_rad));
    c.push_back(rad_to_deg(poses[i].c_rad));
  }
  std::vector<ContactPoint> air(n);  // no contacts known: treat every move as in the air
  for (std::size_t i :
       colliding_moves(*model, *tool, machine, xyz, a, c, contacts.empty() ? air : contacts,
                       nullptr, nullptr, &check)) {
    hit[i] = 1;
  }
  for (std::size_t i : colliding_points(*model, *tool, op, axes, contacts, nullptr, &check)) {
    hit[i] = 1;
  }
  return hit;
}

StretchGuardResult guard_passes(const Operationd& op, const std::vector<ContactPoint>& contacts,
                                double ball_radius_mm, const PartCheck* model,
                                const ToolModel* tool, const Machine& machine,
                                const BlockTiming& timing, const PosePlanOptions& pose_options,
                                OptimisedOperation& out, const GuardReference* reference) {
  const std::size_t n = op.points.size();
  const std::vector<bool> rapid_into = rapid_into_of(op);
  std::vector<Vec3d> in_axes;
  for (const CLPointd& p : op.points) in_axes.push_back(p.axis);
  if (reference) in_axes = reference->axes;
  const std::vector<std::optional<Posed>> in_preferred =
      reference ? reference->preferred : std::vector<std::optional<Posed>>{};
  const PosePlan in_plan =
      plan_poses(machine.rotary, in_axes, rapid_into, {}, pose_options, in_preferred);
  if (!in_plan.ok()) return {out.axes, std::vector<KeptWhy>(n, KeptWhy::None)};
  // In machine mode with linearisation the tip runs the straight line as in TCP mode.
  Machine path_machine = machine;
  if (machine.gcode.program.linearise_tolerance_mm > 0.0) path_machine.gcode.mode = GcodeMode::Tcp;
  const auto moves_hit = [&](const std::vector<Vec3d>& axes, const std::vector<Posed>& poses,
                             const std::vector<char>& check) {
    return points_and_moves_hit(op, contacts, ball_radius_mm, model, tool, path_machine, axes,
                                poses, check);
  };
  const std::vector<IndexRange> passes = feed_passes(op);
  const std::vector<char> in_hit = moves_hit(in_axes, in_plan.poses, std::vector<char>(n, 1));
  // The rates of a pass for poses of the whole operation (eq. 16-18), with their peaks and the
  // sum of squares of a over the interior points (metrics' accumulate).
  struct PassRates {
    RotaryKinematics k;
    RotarySummary summary;
    double mean_sq_accel() const {
      return summary.accel_samples
                 ? summary.sum_sq_accel / static_cast<double>(summary.accel_samples)
                 : 0.0;
    }
  };
  const auto rates = [&](const IndexRange& pass, const std::vector<Posed>& poses) {
    std::vector<double> a, c;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      a.push_back(rad_to_deg(poses[i].tilt_rad));
      c.push_back(rad_to_deg(poses[i].c_rad));
    }
    PassRates r{rotary_kinematics_from_times(
                    a, c, move_times_s(op, ball_radius_mm, machine.rotary, poses, timing, pass)),
                {}};
    accumulate(r.summary, r.k, c);
    return r;
  };
  std::vector<char> guarded(passes.size(), 0);
  std::vector<PassRates> before(passes.size());
  for (std::size_t q = 0; q < passes.size(); ++q) {
    const IndexRange& pass = passes[q];
    bool input_safe = true;
    for (std::size_t i = pass.begin; i < pass.end; ++i) input_safe = input_safe && !in_hit[i];
    if (!input_safe || pass.size() == 0) continue;
    guarded[q] = 1;
    before[q] = rates(pass, in_plan.poses);
  }
  const std::vector<std::optional<Posed>> opt_preferred = out.preferred;
  // The preferred poses of a candidate: the optimiser's where optimised, the reference's where
  // kept, none on a join.
  const auto preferred_of = [&](const std::vector<KeptWhy>& why) {
    std::vector<std::optional<Posed>> preferred = opt_preferred;
    for (std::size_t i = 0; i < preferred.size() && i < why.size(); ++i) {
      if (why[i] == KeptWhy::Join) preferred[i] = std::nullopt;
      if (why[i] == KeptWhy::Collision || why[i] == KeptWhy::PeakRate) {
        preferred[i] = in_preferred.empty() ? std::nullopt : in_preferred[i];
      }
    }
    return preferred;
  };
  const StretchEvaluation evaluate = [&](const std::vector<Vec3d>& axes,
                                         const std::vector<KeptWhy>& why,
                                         const std::vector<char>& check) {
    StretchVerdicts out_verdicts{std::vector<PointVerdict>(n, PointVerdict::Good),
                                 std::vector<char>(passes.size(), 0)};
    std::vector<PointVerdict>& verdict = out_verdicts.points;
    const PosePlan plan =
        plan_poses(machine.rotary, axes, rapid_into, {}, pose_options, preferred_of(why));
    if (!plan.ok()) {
      for (std::size_t i = 0; i < n; ++i) {
        if (check[i]) verdict[i] = PointVerdict::Hits;
      }
      return out_verdicts;
    }
    const std::vector<char> hit = moves_hit(axes, plan.poses, check);
    for (std::size_t q = 0; q < passes.size(); ++q) {
      const IndexRange& pass = passes[q];
      if (pass.size() == 0 || !check[pass.begin]) continue;
      const PassRates after = rates(pass, plan.poses);
      const RotaryKinematics& k = after.k;
      // omega_j belongs to the segment j -> j + 1, a_j to the points j - 1, j, j + 1.
      const auto raises = [&](std::size_t lo, std::size_t hi) {
        for (std::size_t j = lo; j <= hi && j < pass.size(); ++j) {
          if (verdict[pass.begin + j] == PointVerdict::Good)
            verdict[pass.begin + j] = PointVerdict::RaisesRate;
        }
      };
      constexpr double kRel = 1.0 + 1e-9;
      const bool rates_count = !reference || reference->rates;
      for (std::size_t j = 0; rates_count && j < pass.size(); ++j) {
        if (!reference && k.omega_deg_s[j] > before[q].summary.max_omega_deg_s * kRel) {
          raises(j, j + 1);
        }
        if (k.accel_deg_s2[j] > before[q].summary.max_accel_deg_s2 * kRel) {
          raises(j ? j - 1 : 0, j + 1);
        }
      }
      for (std::size_t i = pass.begin; i < pass.end; ++i) {
        if (hit[i]) verdict[i] = PointVerdict::Hits;
      }
      out_verdicts.gains[q] =
          !rates_count ||
          after.summary.max_accel_deg_s2 * kRel < before[q].summary.max_accel_deg_s2 ||
          after.mean_sq_accel() * kRel < before[q].mean_sq_accel();
    }
    return out_verdicts;
  };
  StretchGuardResult guard = guard_stretches(passes, guarded, out.axes, in_axes, evaluate);
  out.axes = guard.axes;
  if (!out.preferred.empty()) out.preferred = preferred_of(guard.why);
  return guard;
}

}  // namespace taxopt::pipeline
