#include "taxopt/plan/global_optimiser.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>

#include "plan/candidate_paths.hpp"
#include "plan/held_axis.hpp"
#include "taxopt/kinematics/metrics.hpp"

namespace taxopt {
namespace {

using detail::kRadToDeg;
using Value = detail::RotaryValue;
using detail::less;
using detail::scalar;

/// Accelerations (deg/s^2) of A and C at every point of poses with continuous C (eq. 16-18,
/// metrics.hpp; 0 at the ends).
void accelerations(const std::vector<Posed>& poses, const std::vector<double>& t,
                   std::vector<double>& aa, std::vector<double>& ac) {
  std::vector<double> tilt_deg, c_deg;
  for (const Posed& p : poses) {
    tilt_deg.push_back(rad_to_deg(p.tilt_rad));
    c_deg.push_back(rad_to_deg(p.c_rad));
  }
  RotaryKinematics k = rotary_kinematics_from_times(tilt_deg, c_deg, t);
  aa = std::move(k.accel_tilt_deg_s2);
  ac = std::move(k.accel_c_deg_s2);
}

Value value_of(const std::vector<Posed>& poses, const std::vector<double>& t, double jerk_weight) {
  std::vector<double> aa, ac;
  accelerations(poses, t, aa, ac);
  Value v;
  for (std::size_t i = 0; i < aa.size(); ++i) {
    const double sq = aa[i] * aa[i] + ac[i] * ac[i];
    v.peak_sq = std::max(v.peak_sq, sq);
    v.sum_sq += sq;
  }
  if (jerk_weight > 0.0) {
    for (std::size_t i = 1; i + 2 < aa.size(); ++i) {
      const double ja = (aa[i + 1] - aa[i]) / t[i], jc = (ac[i + 1] - ac[i]) / t[i];
      v.sum_sq += jerk_weight * (ja * ja + jc * jc);
    }
  }
  return v;
}

/// Sparse rows of the accelerations as linear functions of one coordinate (rad -> deg/s^2),
/// weighted by `row_weight` (per interior point), and of the jerks: M, so that the objective
/// of one coordinate is |M x|^2.
Eigen::SparseMatrix<double> second_difference(const std::vector<double>& t,
                                              const std::vector<double>& row_weight,
                                              double jerk_weight) {
  const std::size_t n = t.size() + 1;
  std::vector<Eigen::Triplet<double>> entries;
  const auto acc_row = [&](std::size_t i, double scale, long row) {
    const double c = scale * kRadToDeg * 2.0 / (t[i - 1] + t[i]);
    entries.emplace_back(row, static_cast<long>(i - 1), c / t[i - 1]);
    entries.emplace_back(row, static_cast<long>(i), -c / t[i - 1] - c / t[i]);
    entries.emplace_back(row, static_cast<long>(i + 1), c / t[i]);
  };
  long row = 0;
  for (std::size_t i = 1; i + 1 < n; ++i) acc_row(i, std::sqrt(row_weight[i]), row++);
  if (jerk_weight > 0.0) {
    const double s = std::sqrt(jerk_weight);
    for (std::size_t i = 1; i + 2 < n; ++i) {
      acc_row(i + 1, s / t[i], row);
      acc_row(i, -s / t[i], row);
      ++row;
    }
  }
  Eigen::SparseMatrix<double> m(row, static_cast<long>(n));
  m.setFromTriplets(entries.begin(), entries.end());
  return m;
}

/// The candidate poses of point i for the programme (C in (-pi, pi] for a continuous C, else
/// every turn within its range); the warm start's pose first.
std::vector<Posed> candidates_at(const MachineKinematicsd& machine, std::size_t i,
                                 const Posed& warm, const std::vector<Posed>& extra,
                                 const std::vector<Vec3d>& grid_axes, bool both_branches,
                                 const AxisTest& acceptable) {
  std::vector<Posed> out;
  const auto add = [&](Posed p) {
    if (!machine.tilt.contains(p.tilt_rad)) return;
    const auto push = [&](const Posed& q) {
      for (const Posed& o : out) {
        if (std::abs(o.tilt_rad - q.tilt_rad) < 1e-9 &&
            std::abs(wrap_pi(o.c_rad - q.c_rad)) < 1e-9) {
          return;
        }
      }
      if (out.size() < 255) out.push_back(q);
    };
    if (machine.c.continuous) {
      p.c_rad = wrap_pi(p.c_rad);
      push(p);
      return;
    }
    const double two_pi = Constants<double>::two_pi();
    for (int turn = -2; turn <= 2; ++turn) {
      const Posed q{p.tilt_rad, wrap_pi(p.c_rad) + turn * two_pi};
      if (machine.c.contains(q.c_rad)) push(q);
    }
  };
  add(warm);
  for (const Posed& p : extra) add(p);
  const bool warm_positive = warm.tilt_rad >= 0.0;
  for (const Vec3d& axis : grid_axes) {
    if (!acceptable(i, axis)) continue;
    if (machine.at_pole(axis)) {
      add(Posed{0.0, warm.c_rad});
      continue;
    }
    for (const Posed& p : machine.inverse(axis)) {
      if (both_branches || (p.tilt_rad >= 0.0) == warm_positive) add(p);
    }
  }
  return out;
}

}  // namespace

const char* to_string(GlobalObjective objective) {
  switch (objective) {
    case GlobalObjective::Peak: return "peak";
    case GlobalObjective::Time: return "time";
    case GlobalObjective::SumSquares: break;
  }
  return "sum-squares";
}

double rotary_objective(const std::vector<Posed>& poses, const std::vector<double>& segment_time_s,
                        GlobalObjective objective, double jerk_weight_s2) {
  if (segment_time_s.size() + 1 != poses.size() && !poses.empty()) {
    throw std::invalid_argument("rotary_objective: n poses need n - 1 segment times");
  }
  if (objective == GlobalObjective::Time) {
    throw std::invalid_argument("rotary_objective: the time objective needs the joints");
  }
  return scalar(value_of(poses, segment_time_s, jerk_weight_s2), objective);
}

namespace {

FeedSchedule pass_schedule(const std::vector<JointPosition>& joints,
                           const std::vector<double>& programmed_time_s,
                           const JointLimits& limits) {
  FeedChain chain;
  chain.joints = joints;
  chain.min_time_s = programmed_time_s;
  for (double& ti : chain.min_time_s) ti = std::max(ti, 1e-9);
  return schedule_feed(chain, limits);
}

}  // namespace

double pass_time_s(const std::vector<JointPosition>& joints,
                   const std::vector<double>& programmed_time_s, const JointLimits& limits) {
  if (joints.size() < 2) return 0.0;
  return pass_schedule(joints, programmed_time_s, limits).total_time_s();
}

namespace {

/// A sparse LDL^T that keeps its analysis (the fill-reducing ordering and the elimination tree)
/// while the matrices it factors keep one pattern, as the refinement's do: the same factors
/// as a new SimplicialLDLT each time, without the ordering's cost.
class SparseLdlt {
 public:
  bool factor(const Eigen::SparseMatrix<double>& a) {
    if (!same_pattern(a)) {
      ldlt_.analyzePattern(a);
      rows_ = a.rows();
      outer_.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
      inner_.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
    }
    ldlt_.factorize(a);
    return ldlt_.info() == Eigen::Success;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const { return ldlt_.solve(b); }

 private:
  bool same_pattern(const Eigen::SparseMatrix<double>& a) const {
    return a.isCompressed() && a.rows() == rows_ &&
           static_cast<std::size_t>(a.nonZeros()) == inner_.size() &&
           std::equal(outer_.begin(), outer_.end(), a.outerIndexPtr()) &&
           std::equal(inner_.begin(), inner_.end(), a.innerIndexPtr());
  }

  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  long rows_ = -1;
  std::vector<int> outer_, inner_;
};

/// One pass's plan (plan_pass_global): the programme over coarse candidates, the pyramid of
/// finer caps, the continuous refinement, and for the time objective the fastest start and
/// rounds at the scheduled times.
class GlobalPassPlanner {
 public:
  GlobalPassPlanner(const MachineKinematicsd& machine, const GlobalPassProblem& problem,
                    const AxisTest& acceptable, const GlobalOptions& options)
      : machine_(machine),
        problem_(problem),
        acceptable_(acceptable),
        options_(options),
        n_(problem.warm_start.size()),
        timed_(options.objective == GlobalObjective::Time) {}

  GlobalPassPlan run() {
    check_problem();
    plan_.poses = problem_.warm_start;
    plan_.objective_warm = plan_.objective_dp = objective_of(plan_.poses);
    if (n_ < 3) return finish();
    const std::vector<Posed> dp = programme();
    if (!timed_) {
      const std::vector<double>& t = problem_.segment_time_s;
      const Value current = value_of(plan_.poses, t, options_.jerk_weight_s2);
      const Value dp_full = value_of(dp, t, options_.jerk_weight_s2);
      const Peaks bound = peaks_of(plan_.poses, t);
      const auto within = [&](const std::vector<Posed>& poses) {
        return allowed_plan(poses, t, bound);
      };
      if (less(dp_full, current, options_.objective) && within(dp)) plan_.poses = dp;
      if (const auto low = low_passed_plan(t, bound)) {
        if (less(value_of(*low, t, options_.jerk_weight_s2),
                 value_of(plan_.poses, t, options_.jerk_weight_s2), options_.objective)) {
          plan_.poses = *low;
        }
      }
      plan_.iterations = refine(t, options_.objective, options_.max_iterations,
                                problem_.keep_peaks || problem_.admissible ? within : Admissible{});
      return finish();
    }
    fastest(dp);
    return finish();
  }

 private:
  void check_problem() const {
    const GlobalPassProblem& problem = problem_;
    const std::size_t n = n_;
    if (problem.input_axes.size() != n || (n > 0 && problem.segment_time_s.size() + 1 != n)) {
      throw std::invalid_argument("plan_pass_global: n axes, n poses and n - 1 times are needed");
    }
    for (double ti : problem.segment_time_s) {
      if (!(ti > 0.0) || !std::isfinite(ti)) {
        throw std::invalid_argument("plan_pass_global: segment times must be positive");
      }
    }
    if (!timed_) return;
    if (!problem.joints_at || (n > 0 && problem.programmed_time_s.size() + 1 != n)) {
      throw std::invalid_argument(
          "plan_pass_global: the time objective needs the joints and n - 1 programmed times");
    }
    for (const auto& alt : problem.alternatives) {
      if (alt.size() != n) {
        throw std::invalid_argument("plan_pass_global: an alternative needs n poses");
      }
    }
  }

  /// The time objective: the pass's schedule at the machine's limits.
  std::vector<JointPosition> joints_of(const std::vector<Posed>& poses) const {
    std::vector<JointPosition> q(n_);
    for (std::size_t i = 0; i < n_; ++i) q[i] = problem_.joints_at(i, poses[i]);
    return q;
  }
  double time_of(const std::vector<Posed>& poses) const {
    return pass_time_s(joints_of(poses), problem_.programmed_time_s, problem_.limits);
  }
  double objective_of(const std::vector<Posed>& poses) const {
    return timed_ ? time_of(poses)
                  : rotary_objective(poses, problem_.segment_time_s, options_.objective,
                                     options_.jerk_weight_s2);
  }
  GlobalPassPlan finish() {
    snap_to_warm();
    plan_.axes.clear();
    for (const Posed& p : plan_.poses) plan_.axes.push_back(machine_.forward(p));
    plan_.objective = objective_of(plan_.poses);
    return plan_;
  }

  /// (1) The programme over coarse candidates, then (1b) the pyramid: caps around the answer
  /// at half the spacing, on its branch; a level is kept only when it lowers the objective.
  std::vector<Posed> programme() {
    const std::size_t n = n_;
    const double radius = deg_to_rad(options_.max_deviation_deg);
    const double step = deg_to_rad(std::max(options_.candidate_step_deg, 1.0));
    // Both branches only where the pass comes within reach of the pole.
    bool near_pole = false;
    for (const Posed& p : problem_.warm_start) {
      near_pole = near_pole || std::abs(p.tilt_rad) <= 2.0 * radius + step;
    }
    cand_.assign(n, {});
    std::vector<Posed> extra;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3d turn =
          problem_.input_axes[std::min(i + 1, n - 1)] - problem_.input_axes[i > 0 ? i - 1 : 0];
      std::vector<Vec3d> grid = cap_grid(problem_.input_axes[i], radius, step, turn);
      extra.clear();
      if (timed_) {
        for (const auto& alt : problem_.alternatives) extra.push_back(alt[i]);
      }
      cand_[i] = held() ? held_candidates(i, problem_.warm_start[i], radius, step / 2.0, extra)
                        : candidates_at(machine_, i, problem_.warm_start[i], extra, grid, near_pole,
                                        acceptable_);
      plan_.max_candidates = std::max(plan_.max_candidates, cand_[i].size());
    }
    std::vector<std::size_t> seq;
    if (timed_) {
      std::vector<std::vector<JointPosition>> joints(n);
      for (std::size_t i = 0; i < n; ++i) {
        for (const Posed& p : cand_[i]) joints[i].push_back(problem_.joints_at(i, p));
      }
      seq = fastest_candidate_sequence(cand_, joints, problem_.programmed_time_s,
                                       problem_.segment_time_s, problem_.limits, nullptr,
                                       machine_.c.continuous);
    } else {
      seq = best_candidate_sequence(cand_, problem_.segment_time_s, options_.objective, nullptr,
                                    machine_.c.continuous);
    }
    std::vector<Posed> dp = poses_of(seq);
    plan_.objective_pyramid = objective_of(dp);
    if (!timed_) plan_.objective_dp = plan_.objective_pyramid;
    if (!timed_ && options_.fine_step_deg > 0.0) {
      const double fine = deg_to_rad(std::max(options_.fine_step_deg, 0.25));
      for (double s = step / 2.0; s >= fine * (1.0 - 1e-9); s /= 2.0) {
        for (std::size_t i = 0; i < n; ++i) {
          if (held()) {
            cand_[i] = held_candidates(i, dp[i], 2.0 * s, s, {});
          } else {
            const std::vector<Vec3d> grid = cap_grid(machine_.forward(dp[i]), 2.0 * s, s);
            cand_[i] = candidates_at(machine_, i, dp[i], {}, grid, false, acceptable_);
          }
          plan_.max_candidates = std::max(plan_.max_candidates, cand_[i].size());
        }
        std::vector<Posed> finer = poses_of(best_candidate_sequence(
            cand_, problem_.segment_time_s, options_.objective, nullptr, machine_.c.continuous));
        const double value = objective_of(finer);
        ++plan_.pyramid_levels;
        if (value < plan_.objective_pyramid) dp = std::move(finer), plan_.objective_pyramid = value;
      }
    }
    return dp;
  }

  /// The programme's sequence as poses with a continuous C, on the warm start's turn of C at
  /// the first point (the programme works modulo a turn).
  std::vector<Posed> poses_of(const std::vector<std::size_t>& chosen) const {
    std::vector<Posed> out(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      out[i] = cand_[i][chosen[i]];
      if (i > 0 && machine_.c.continuous) {
        out[i].c_rad = out[i - 1].c_rad + wrap_pi(out[i].c_rad - out[i - 1].c_rad);
      }
    }
    if (machine_.c.continuous) {
      const double shift = problem_.warm_start[0].c_rad - out[0].c_rad;
      const double turns = std::round(shift / Constants<double>::two_pi());
      for (Posed& p : out) p.c_rad += turns * Constants<double>::two_pi();
    }
    return out;
  }

  bool held() const { return problem_.hold_tilt || problem_.hold_c; }

  using Admissible = GlobalPassProblem::Admissible;
  using Peaks = RotarySummary;
  static Peaks peaks_of(const std::vector<Posed>& poses, const std::vector<double>& t) {
    return detail::rate_summary(poses, t);
  }

  /// The pass with its held axis (held() and not both).
  detail::HeldAxis held_axis() const {
    return detail::HeldAxis(problem_.hold_tilt, problem_.warm_start,
                            [this](std::size_t i, const Posed& p) { return feasible(i, p); });
  }

  /// The candidates of point i with an axis held (HeldAxis::candidates; only `centre` when both
  /// are).
  std::vector<Posed> held_candidates(std::size_t i, const Posed& centre, double radius, double step,
                                     const std::vector<Posed>& extra) const {
    if (problem_.hold_tilt && problem_.hold_c) return {centre};
    return held_axis().candidates(i, centre, radius, step, extra);
  }

  /// With an axis held, the plan's turns too small to write taken back (HeldAxis::snapped)
  /// where it stays allowed.
  void snap_to_warm() {
    if (!held() || plan_.poses.size() != n_) return;
    const std::vector<Posed> snapped = held_axis().snapped(plan_.poses);
    const std::vector<double>& t = problem_.segment_time_s;
    if (allowed_plan(snapped, t, peaks_of(problem_.warm_start, t))) plan_.poses = snapped;
  }

  /// A plan the problem allows: within the warm start's peaks (`bound`, at times t) where it
  /// keeps them, and passing the caller's test where it gives one.
  bool allowed_plan(const std::vector<Posed>& poses, const std::vector<double>& t,
                    const Peaks& bound) const {
    // 1e-12: a still axis's round-off, no more
    return (!problem_.keep_peaks || peaks_within(peaks_of(poses, t), bound, 1e-12, 1e-12)) &&
           (!problem_.admissible || problem_.admissible(poses));
  }

  /// With one axis held: of the other's low-passed plans (HeldAxis::low_passed_plans: its rate
  /// never above the warm start's peak), the allowed one of the lowest objective; empty when
  /// none is.
  std::optional<std::vector<Posed>> low_passed_plan(const std::vector<double>& t,
                                                    const Peaks& bound) const {
    if (!held() || (problem_.hold_tilt && problem_.hold_c)) return std::nullopt;
    std::optional<std::vector<Posed>> best;
    double best_value = 0.0;
    for (std::vector<Posed>& poses : held_axis().low_passed_plans(t)) {
      if (!allowed_plan(poses, t, bound)) continue;
      const double value = objective_of(poses);
      if (!best || value < best_value) best = std::move(poses), best_value = value;
    }
    return best;
  }

  bool feasible(std::size_t i, const Posed& p) const {
    if (!machine_.tilt.contains(p.tilt_rad)) return false;
    if (!machine_.c.continuous && !machine_.c.contains(p.c_rad)) return false;
    return acceptable_(i, machine_.forward(p));
  }

  /// The damped Gauss-Newton step of both coordinates from `plan_.poses`: (H + lambda diag) d =
  /// -H x, with a floor on the damping of 1e-9 of H's mean diagonal. False where it fails.
  bool damped_step(const Eigen::SparseMatrix<double>& h, double lambda, SparseLdlt& ldlt,
                   Eigen::VectorXd& da, Eigen::VectorXd& dc) const {
    const long n = static_cast<long>(n_);
    Eigen::VectorXd xa(n), xc(n);
    for (long i = 0; i < n; ++i) {
      xa[i] = plan_.poses[static_cast<std::size_t>(i)].tilt_rad;
      xc[i] = plan_.poses[static_cast<std::size_t>(i)].c_rad;
    }
    Eigen::SparseMatrix<double> lhs = h;
    double mean_diag = 0.0;
    for (long i = 0; i < h.rows(); ++i) mean_diag += h.coeff(i, i);
    mean_diag /= static_cast<double>(h.rows());
    for (long i = 0; i < h.rows(); ++i) {
      lhs.coeffRef(i, i) += lambda * (h.coeff(i, i) + 1e-9 * mean_diag + 1e-300);
    }
    if (!ldlt.factor(lhs)) return false;
    da = ldlt.solve(-(h * xa));
    dc = ldlt.solve(-(h * xc));
    return da.allFinite() && dc.allFinite();
  }

  /// (2) Continuous refinement from `plan_.poses`, minimising `obj` at segment times `tt`; a
  /// step is taken only where `admissible` (if given) accepts it. Returns the steps taken.
  int refine(const std::vector<double>& tt, GlobalObjective obj, int budget,
             const Admissible& admissible) {
    const std::size_t n = n_;
    const double wj = options_.jerk_weight_s2;
    const GlobalOptions& options = options_;
    GlobalPassPlan& plan = plan_;
    Value current = value_of(plan.poses, tt, wj);
    std::vector<double> row_weight(n, 1.0);
    double lambda = 1e-3;
    int rejected = 0, taken = 0;
    Eigen::SparseMatrix<double> h;
    SparseLdlt ldlt;
    while (taken < budget && rejected < 12) {
      if (obj == GlobalObjective::Peak) {
        std::vector<double> aa, ac;
        accelerations(plan.poses, tt, aa, ac);
        const double peak = std::sqrt(current.peak_sq);
        for (std::size_t i = 0; i < n; ++i) {
          const double r = peak > 0.0 ? std::hypot(aa[i], ac[i]) / peak : 1.0;
          row_weight[i] = std::max(std::pow(r, 6.0), 1e-6);
        }
      }
      // The normal matrix changes only with the weights (the peak objective's).
      if (h.rows() == 0 || obj == GlobalObjective::Peak) {
        const Eigen::SparseMatrix<double> m = second_difference(tt, row_weight, wj);
        h = (m.transpose() * m).pruned();
      }
      Eigen::VectorXd da, dc;
      if (!damped_step(h, lambda, ldlt, da, dc)) break;
      std::vector<Posed> trial = plan.poses;
      for (std::size_t i = 0; i < n; ++i) {
        const double sa = problem_.hold_tilt ? 0.0 : da[static_cast<long>(i)];
        const double sc = problem_.hold_c ? 0.0 : dc[static_cast<long>(i)];
        if (std::abs(sa) + std::abs(sc) < 1e-12) continue;
        double f = 1.0;
        for (int b = 0; b <= options.bisection_steps; ++b, f *= 0.5) {
          const Posed p{plan.poses[i].tilt_rad + f * sa, plan.poses[i].c_rad + f * sc};
          if (feasible(i, p)) {
            trial[i] = p;
            break;
          }
        }
      }
      const Value v = value_of(trial, tt, wj);
      if (less(v, current, obj) &&
          (obj == GlobalObjective::Peak || v.sum_sq < current.sum_sq * (1.0 - 1e-9)) &&
          (!admissible || admissible(trial))) {
        plan.poses = std::move(trial);
        current = v;
        ++taken;
        lambda = std::max(lambda * 0.3, 1e-6);
        rejected = 0;
      } else {
        lambda *= 10.0;
        ++rejected;
      }
    }
    return taken;
  }

  /// The time objective: the fastest of the starts by the schedule itself (the warm start
  /// first, so ties keep it), then the sum of squares lowered at the scheduled times, a step
  /// taken only where the schedule does not get slower; the times follow the poses (rounds).
  void fastest(const std::vector<Posed>& dp) {
    const std::vector<double>& t = problem_.segment_time_s;
    const Peaks warm_peaks = peaks_of(problem_.warm_start, t);
    const auto allowed = [&](const std::vector<Posed>& poses) {
      return allowed_plan(poses, t, warm_peaks);
    };
    double best_s = plan_.objective_warm;
    for (const auto& alt : problem_.alternatives) {
      const double alt_s = time_of(alt);
      if (alt_s < best_s * (1.0 - 1e-9) && allowed(alt)) plan_.poses = alt, best_s = alt_s;
    }
    plan_.objective_dp = time_of(dp);
    if (plan_.objective_dp < best_s * (1.0 - 1e-9) && allowed(dp)) {
      plan_.poses = dp, best_s = plan_.objective_dp;
    }
    if (const auto low = low_passed_plan(t, warm_peaks)) {
      const double low_s = time_of(*low);
      if (low_s < best_s * (1.0 - 1e-9)) plan_.poses = *low, best_s = low_s;
    }
    for (int round = 0; round < 3 && plan_.iterations < options_.max_iterations; ++round) {
      FeedSchedule schedule =
          pass_schedule(joints_of(plan_.poses), problem_.programmed_time_s, problem_.limits);
      for (double& ti : schedule.time_s) ti = std::max(ti, 1e-6);
      const int taken =
          refine(schedule.time_s, GlobalObjective::SumSquares,
                 options_.max_iterations - plan_.iterations, [&](const std::vector<Posed>& trial) {
                   if (!allowed(trial)) return false;
                   const double trial_s = time_of(trial);
                   if (trial_s > best_s * (1.0 + 1e-12)) return false;
                   best_s = trial_s;
                   return true;
                 });
      plan_.iterations += taken;
      if (taken == 0) break;
    }
  }

  const MachineKinematicsd& machine_;
  const GlobalPassProblem& problem_;
  const AxisTest& acceptable_;
  const GlobalOptions& options_;
  const std::size_t n_;
  const bool timed_;
  std::vector<std::vector<Posed>> cand_;
  GlobalPassPlan plan_;
};

}  // namespace

GlobalPassPlan plan_pass_global(const MachineKinematicsd& machine, const GlobalPassProblem& problem,
                                const AxisTest& acceptable, const GlobalOptions& options) {
  return GlobalPassPlanner(machine, problem, acceptable, options).run();
}

}  // namespace taxopt
