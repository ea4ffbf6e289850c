// --method global on every pass, and the turns between passes spread over the rapids in the air
// (plan_rooms.hpp).
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

/// --method global (global_optimiser.hpp) on every feed pass of `op`, from the paper's axes in
/// `out` (the warm start), in parallel over passes. The points between passes then follow the
/// new pass ends; a guard gives a pass back the paper's axes (or `reference`'s) where its peak
/// a would rise or its moves would hit the part. With `time` (--objective time) the passes get
/// their joints, programmed times and alternatives from it.
void refine_global(const Operationd& op, const std::vector<ContactPoint>& contacts,
                   double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                   const Machine& machine, const BlockTiming& timing,
                   const PosePlanOptions& pose_options, const GlobalOptions& options,
                   OptimisedOperation& out, detail::StageProgress& progress,
                   const TimeContext* time, const GuardReference* reference) {
  const std::size_t n = op.points.size();
  const std::vector<IndexRange> passes = feed_passes(op);
  const PosePlan warm = plan_poses(machine.rotary, out.axes, rapid_into_of(op), {}, pose_options);
  if (!warm.ok()) {
    for (std::size_t q = 0; q < passes.size(); ++q) progress.advance();
    return;
  }
  const GuardReference paper{out.axes, {}};
  const Acceptance acceptable_at{op,
                                 contacts,
                                 ball_radius_mm,
                                 model,
                                 tool,
                                 machine.rotary,
                                 deg_to_rad(options.max_deviation_deg)};
  // Each pass's cut: from the first to the last contact of the pass (all of it without a part).
  // The points in the air before and after keep the axis of the nearest contact, as with the
  // paper method: the tool comes down and leaves along the axis it cuts with.
  const auto plan_pass = [&](std::size_t, const IndexRange& whole) -> std::optional<PassAxes> {
    const IndexRange pass = contact_span(contacts, whole);
    if (pass.size() < 3) return std::nullopt;
    GlobalPassProblem problem;
    std::vector<double> tilt_deg, c_deg;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      problem.input_axes.push_back(op.points[i].axis);
      problem.warm_start.push_back(warm.poses[i]);
      tilt_deg.push_back(rad_to_deg(warm.poses[i].tilt_rad));
      c_deg.push_back(rad_to_deg(warm.poses[i].c_rad));
    }
    // The program's own timing with the warm start's tips (move_times_s: the report's and the
    // guard's); a move too short to time gets a floor (it would divide).
    problem.segment_time_s =
        move_times_s(op, ball_radius_mm, machine.rotary, warm.poses, timing, pass);
    for (double& t : problem.segment_time_s) t = std::max(t, 1e-6);
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at.in_cone(pass.begin + j, axis);
    };
    if (time) {
      // The machine's joints of a pose (the schedule's, whatever the G-code mode): the tip
      // under the fixed ball centre, carried by the table.
      problem.joints_at = [&op, &machine, ball_radius_mm, b = pass.begin](std::size_t j,
                                                                          const Posed& pose) {
        const Vec3d tip =
            tip_for_axis(op.points[b + j], ball_radius_mm, machine.rotary.forward(pose));
        const Vec3d xyz = machine.rotary.to_machine_mm(tip, pose);
        return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.tilt_rad),
                             rad_to_deg(pose.c_rad)};
      };
      problem.programmed_time_s = slice(time->programmed_s, pass.begin + 1, pass.end);
      problem.limits = time->limits;
      for (const std::vector<Posed>& alt : time->alternatives) {
        std::vector<Posed> poses = slice(alt, pass.begin, pass.end);
        bool ok = true;
        for (std::size_t j = 0; ok && j < poses.size(); ++j) {
          ok = machine.rotary.tilt.contains(poses[j].tilt_rad) &&
               acceptable(j, machine.rotary.forward(poses[j]));
        }
        if (ok) problem.alternatives.push_back(std::move(poses));
      }
    }
    std::optional<GlobalPassPlan> plan =
        plan_pass_global(machine.rotary, problem, acceptable, options);
    if (!plan) return std::nullopt;
    return PassAxes{pass, std::move(plan->axes), std::move(plan->poses)};
  };
  out.preferred.assign(n, std::nullopt);
  plan_passes(op, contacts, acceptable_at, out, progress, plan_pass,
              [&](std::size_t, const PassAxes&) { ++out.global_passes; });
  out.global_guard = guard_passes(op, contacts, ball_radius_mm, model, tool, machine, timing,
                                  pose_options, out, reference ? reference : &paper);
}

/// The turn of the rotary axes between two passes (made in one move by carry_between_passes)
/// spread over the rapids of the chain in the air (air_turn.hpp), where that makes the chain
/// faster and every new pose and move is acceptable: within the cone of its point's input
/// axis, within the machine's ranges and, with a part, free (points and swept moves). The ball
/// centres stay where the CAM system put them.
void spread_turns_in_air(const Operationd& op, const std::vector<ContactPoint>& contacts,
                         double ball_radius_mm, const PartCheck* model, const ToolModel& tool,
                         const Machine& machine, double max_deviation_rad, PostedOperation& po) {
  const std::size_t n = op.points.size();
  if (n < 3 || po.poses.size() != n) return;
  const JointLimits limits = effective_limits(machine);
  // The point as the machine's joints reach it (what the schedule times: in TCP mode too the
  // linear joints follow the turning table), and as the G-code writes it.
  const auto tip_at = [&](std::size_t i, const Posed& pose) {
    return tip_for_axis(op.points[i], ball_radius_mm, machine.rotary.forward(pose));
  };
  const auto joints_at = [&](std::size_t i, const Posed& pose) {
    const Vec3d xyz = machine.rotary.to_machine_mm(tip_at(i, pose), pose);
    return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.tilt_rad),
                         rad_to_deg(pose.c_rad)};
  };
  // A chain's time: its rapids on their trapezoids, its feed moves at their feed.
  // `chain[k]` is the pose of point a - 1 + k (k = 0 .. b - a + 1).
  const auto chain_time = [&](std::size_t a, std::size_t b, const std::vector<Posed>& chain) {
    double t = 0.0;
    for (std::size_t j = a; j <= b; ++j) {
      const JointPosition from = joints_at(j - 1, chain[j - a]),
                          to = joints_at(j, chain[j - a + 1]);
      if (op.points[j].motion == Motion::Rapid) {
        t += rapid_time_s(from, to, limits);
      } else if (po.points[j].feed_mm_per_min > 0.0) {
        t += 60.0 * Vec3d(to[0] - from[0], to[1] - from[1], to[2] - from[2]).norm() /
             po.points[j].feed_mm_per_min;
      }
    }
    return t;
  };
  std::vector<char> in_pass(n, 0);
  for (const IndexRange& pass : feed_passes(op)) {
    std::fill(in_pass.begin() + static_cast<long>(pass.begin),
              in_pass.begin() + static_cast<long>(pass.end), 1);
  }
  std::vector<Posed> trial = po.poses;
  std::vector<std::pair<std::size_t, std::size_t>> changed;  // chains [a, b) taken
  for (std::size_t a = 1; a < n;) {
    if (in_pass[a]) {
      ++a;
      continue;
    }
    std::size_t b = a;
    while (b < n && !in_pass[b]) ++b;
    const std::size_t first = a;
    a = b;
    if (b == n) break;  // after the last pass: nothing to turn to
    // Moves first .. b; the turn from the pose before the chain to the pose after it. Only
    // chains whose turn is made by rapids now (a feed move in the air keeps its axis).
    const Posed from = po.poses[first - 1], to = po.poses[b];
    bool rapid_turn = true;
    std::vector<double> linear_s, now;  // per move: its time without the turn, its share now
    std::vector<bool> rapid;
    const double turn_rad = std::abs(to.tilt_rad - from.tilt_rad) + std::abs(to.c_rad - from.c_rad);
    for (std::size_t j = first; j <= b; ++j) {
      const double turned = std::abs(po.poses[j].tilt_rad - po.poses[j - 1].tilt_rad) +
                            std::abs(po.poses[j].c_rad - po.poses[j - 1].c_rad);
      rapid.push_back(op.points[j].motion == Motion::Rapid);
      if (turned > 1e-12 && !rapid.back()) rapid_turn = false;
      now.push_back(turn_rad > 0.0 ? turned / turn_rad : 0.0);
      JointPosition p = joints_at(j - 1, po.poses[j - 1]), q = joints_at(j, po.poses[j]);
      q[3] = p[3];
      q[4] = p[4];
      linear_s.push_back(rapid.back() ? rapid_time_s(p, q, limits) : 0.0);
    }
    if (!rapid_turn || turn_rad < 1e-9) continue;
    // The chain's poses for per-move shares of the turn, and their time.
    const std::vector<Posed> current(po.poses.begin() + static_cast<long>(first - 1),
                                     po.poses.begin() + static_cast<long>(b + 1));
    const auto poses_for = [&](const std::vector<double>& share) {
      std::vector<Posed> cand = current;
      double f = 0.0;
      for (std::size_t j = first; j < b; ++j) {
        f += share[j - first];
        cand[j - first + 1] = Posed{from.tilt_rad + f * (to.tilt_rad - from.tilt_rad),
                                    from.c_rad + f * (to.c_rad - from.c_rad)};
      }
      return cand;
    };
    std::vector<std::vector<double>> starts = {now};
    const std::vector<double> by_capacity =
        spread_turn(linear_s, rapid, rad_to_deg(to.tilt_rad - from.tilt_rad),
                    rad_to_deg(to.c_rad - from.c_rad), limits);
    if (!by_capacity.empty()) starts.push_back(by_capacity);
    const std::vector<double> share = best_turn_shares(
        starts, rapid,
        [&](const std::vector<double>& sh) { return chain_time(first, b, poses_for(sh)); });
    const std::vector<Posed> cand = poses_for(share);
    bool ok = true;
    for (std::size_t j = first; j < b && ok; ++j) {
      const Posed& pose = cand[j - first + 1];
      ok = angle_between(machine.rotary.forward(pose), op.points[j].axis) <=
               max_deviation_rad + 1e-12 &&
           machine.rotary.tilt.contains(pose.tilt_rad) &&
           (machine.rotary.c.continuous || machine.rotary.c.contains(pose.c_rad));
    }
    if (!ok || chain_time(first, b, cand) >= chain_time(first, b, current) - 1e-6) continue;
    std::copy(cand.begin() + 1, cand.end() - 1, trial.begin() + static_cast<long>(first));
    changed.emplace_back(first, b);
  }
  if (changed.empty()) return;
  // The new poses and the moves into and out of them must be free; a chain with any hit keeps
  // its turn where it was.
  if (model) {
    std::vector<char> check_point(n, 0), check_move(n, 0);
    for (const auto& [first, b] : changed) {
      std::fill(check_point.begin() + static_cast<long>(first),
                check_point.begin() + static_cast<long>(b), 1);
      std::fill(check_move.begin() + static_cast<long>(first),
                check_move.begin() + static_cast<long>(b) + 1, 1);
    }
    std::vector<Vec3d> axes, xyz;
    std::vector<double> tilt_deg, c_deg;
    for (std::size_t i = 0; i < n; ++i) {
      axes.push_back(machine.rotary.forward(trial[i]));
      const Vec3d tip = tip_at(i, trial[i]);
      xyz.push_back(written_xyz_mm(machine, tip, trial[i]));
      tilt_deg.push_back(rad_to_deg(trial[i].tilt_rad));
      c_deg.push_back(rad_to_deg(trial[i].c_rad));
    }
    std::vector<ContactPoint> air(n);  // no contacts known: every point in the air
    const std::vector<ContactPoint>& state = contacts.empty() ? air : contacts;
    std::vector<char> hit(n, 0);
    for (std::size_t i : colliding_points(*model, tool, op, axes, state, nullptr, &check_point)) {
      hit[i] = 1;
    }
    for (std::size_t i : colliding_moves(*model, tool, machine, xyz, tilt_deg, c_deg, state,
                                         nullptr, nullptr, &check_move)) {
      hit[i] = 1;
    }
    for (const auto& [first, b] : changed) {
      if (std::any_of(hit.begin() + static_cast<long>(first),
                      hit.begin() + static_cast<long>(b) + 1, [](char h) { return h != 0; })) {
        std::copy(po.poses.begin() + static_cast<long>(first),
                  po.poses.begin() + static_cast<long>(b),
                  trial.begin() + static_cast<long>(first));
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (trial[i].tilt_rad == po.poses[i].tilt_rad && trial[i].c_rad == po.poses[i].c_rad) continue;
    po.points[i].axis = machine.rotary.forward(trial[i]);
    po.points[i].tip_mm = tip_for_axis(op.points[i], ball_radius_mm, po.points[i].axis);
  }
  po.poses = std::move(trial);
}

}  // namespace taxopt::pipeline
