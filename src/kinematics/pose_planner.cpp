#include "taxopt/kinematics/pose_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "kinematics/pose_planning.hpp"
#include "util/progress.hpp"

namespace taxopt {
namespace {

/// Costs closer than this (rad) are equal: rounding must not decide a branch.
constexpr double kTie = 1e-9;

struct Candidate {
  Posed pose;
  /// 1: the caller's preferred pose, 2: its mirror (-A, C + 180 deg); 0: neither.
  int side = 0;
};

/// Candidate poses of a non-pole axis within the machine's ranges. With a continuous C the
/// winding is left to the unwrapping after the programme (nearest turn is always optimal);
/// with a bounded C every turn within the range is a candidate.
/// `wind_free`: a bounded C's turns are left to the unwrapping too (PosePlanner::run).
std::vector<Candidate> candidates(const MachineKinematicsd& m, const Vec3d& axis, bool wind_free) {
  std::vector<Candidate> out;
  for (const Posed& p : m.inverse(axis)) {
    if (!m.tilt.contains(p.tilt_rad)) continue;
    if (m.c.continuous || wind_free) {
      out.push_back({p});
      continue;
    }
    const double two_pi = Constants<double>::two_pi();
    const double k_lo = std::ceil((m.c.min_rad - 1e-9 - p.c_rad) / two_pi);
    const double k_hi = std::floor((m.c.max_rad + 1e-9 - p.c_rad) / two_pi);
    // Where turns cost the same, the programme keeps the first: the turn nearest C = 0, not
    // the end of a range of many turns (LinuxCNC's sample gives C +-36000 deg).
    const std::size_t first = out.size();
    for (double k = k_lo; k <= k_hi; k += 1.0) {
      Posed q = p;
      q.c_rad = p.c_rad + k * two_pi;
      out.push_back({q});
    }
    std::stable_sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
                     [](const Candidate& x, const Candidate& y) {
                       return std::abs(x.pose.c_rad) < std::abs(y.pose.c_rad) - 1e-12;
                     });
  }
  return out;
}

/// One plan: the candidates of every point, the dynamic programme over the key points (those
/// off the pole, and pole points the caller gave a pose), the points on the pole between them.
class PosePlanner {
 public:
  PosePlanner(const MachineKinematicsd& m, const std::vector<Vec3d>& axes,
              const std::vector<bool>& rapid_into, const std::optional<Posed>& start,
              const PosePlanOptions& options, const std::vector<std::optional<Posed>>& preferred,
              const StopSource* stop)
      : m_(m),
        axes_(axes),
        rapid_into_(rapid_into),
        start_(start),
        options_(options),
        preferred_(preferred),
        stop_(stop) {}

  PosePlan run() {
    if (!m_.c.continuous) {
      // Every turn of a bounded C within its range is a candidate, and the programme's work
      // grows with the square of their number: on LinuxCNC's samples (C +-36000 deg, 200
      // turns a side) 143,840 points took minutes a plan. Planned first with the turns left
      // to the unwrapping, as a continuous C is: every path's cost there is no more than its
      // cost on the bounded C, so where that plan stays within the range it is the bounded
      // plan's optimum too; else the programme over every turn.
      wind_free_ = true;
      PosePlan free = attempt();
      if (!free.ok() || within_c_range(free)) return free;
      wind_free_ = false;
    }
    return attempt();
  }

 private:
  /// Whether every pose's C lies within the bounded C's range.
  bool within_c_range(const PosePlan& p) const {
    return std::all_of(p.poses.begin(), p.poses.end(), [&](const Posed& q) {
      return q.c_rad >= m_.c.min_rad - 1e-9 && q.c_rad <= m_.c.max_rad + 1e-9;
    });
  }
  /// The turns of C are the unwrapping's, not the programme's (a continuous C, or a bounded
  /// one planned free of its range).
  bool unwrapped_c() const { return m_.c.continuous || wind_free_; }

  /// One plan from scratch (the candidates, the programme, the pole runs).
  PosePlan attempt() {
    const std::size_t n = axes_.size();
    cand_.assign(n, {});
    keys_.clear();
    plan_ = PosePlan{};
    plan_.poses.assign(n, Posed{});
    if (n == 0) return plan_;
    for (std::size_t i = 0; i < n; ++i) {
      detail::look_at_stop(stop_, i, detail::kPointStride);
      if (!candidates_at(i)) return plan_;
    }
    if (!keys_.empty()) choose_keys();
    fill_pole_runs();
    return plan_;
  }

  const std::optional<Posed>& preferred_at(std::size_t i) const {
    static const std::optional<Posed> none;
    return preferred_.empty() ? none : preferred_[i];
  }
  // Points on the pole that the caller gave a pose keep its C, as key points.
  bool free_pole(std::size_t i) const { return m_.at_pole(axes_[i]) && !preferred_at(i); }

  /// Point i's candidate poses (a key point), or none (on the pole); false with the plan's
  /// failure where it has no pose within the ranges.
  bool candidates_at(std::size_t i) {
    const MachineKinematicsd& m = m_;
    const std::vector<Vec3d>& axes = axes_;
    std::vector<std::vector<Candidate>>& cand = cand_;
    std::vector<std::size_t>& keys = keys_;
    PosePlan& plan = plan_;
    if (m.at_pole(axes[i]) && preferred_at(i) && m.tilt.contains(0.0)) {
      const double c = preferred_at(i)->c_rad;
      cand[i] = {Candidate{Posed{0.0, c}, 1},
                 Candidate{Posed{0.0, c + Constants<double>::pi()}, 2}};
      keys.push_back(i);
      return true;
    }
    if (m.at_pole(axes[i])) {
      if (!m.tilt.contains(0.0)) {
        plan.status = PosePlan::Status::OutOfLimits;
        plan.failed_index = i;
        const std::string t(1, m.tilt_letter());
        plan.message = "axis on the pole needs " + t + " = 0, outside the " + t + " range";
        return false;
      }
      return true;
    }
    cand[i] = candidates(m, axes[i], wind_free_);
    if (const std::optional<Posed>& want = preferred_at(i)) {
      // The caller's pose and its mirror (the whole pass mirrored has the same rates: which
      // one is left to the travel to and from the neighbouring passes), where the machine has
      // them; on a bounded C every turn of the caller's C within the range, the programme
      // choosing the winding (tests/controller: the global method's first table turn went to C-720,
      // two turns from home, on LinuxCNC's sample with C in +-36000 deg).
      std::vector<Candidate> kept;
      for (Candidate c : cand[i]) {
        const double dc = wrap_pi(c.pose.c_rad - want->c_rad);
        const double dm = wrap_pi(c.pose.c_rad - want->c_rad - Constants<double>::pi());
        if (std::abs(c.pose.tilt_rad - want->tilt_rad) < 1e-6 && std::abs(dc) < 1e-6) {
          c.side = 1;
          kept.push_back(c);
        } else if (m.c.continuous && std::abs(c.pose.tilt_rad + want->tilt_rad) < 1e-6 &&
                   std::abs(dm) < 1e-6) {
          c.side = 2;
          kept.push_back(c);
        }
      }
      if (!kept.empty()) cand[i] = std::move(kept);
    }
    if (cand[i].empty()) {
      plan.status = PosePlan::Status::OutOfLimits;
      plan.failed_index = i;
      const auto both = m.inverse(axes[i]);
      std::ostringstream os;
      os << "no pose within the axis ranges: " << m.tilt_letter() << " would be "
         << rad_to_deg(both[0].tilt_rad) << " or " << rad_to_deg(both[1].tilt_rad) << " deg";
      if (!m.c.continuous) {
        os << ", C " << rad_to_deg(both[0].c_rad) << " or " << rad_to_deg(both[1].c_rad)
           << " deg (plus turns)";
      }
      plan.message = os.str();
      return false;
    }
    keys.push_back(i);
    return true;
  }

  double dc(double c0, double c1) const {
    return unwrapped_c() ? std::abs(wrap_pi(c1 - c0)) : std::abs(c1 - c0);
  }
  /// The heaviest move between two key points.
  double weight(std::size_t from, std::size_t to) const {
    double w = 0.0;
    for (std::size_t k = from + 1; k <= to; ++k) {
      w = std::max(w, rapid_into_[k] ? options_.rapid_weight : 1.0);
    }
    return w;
  }
  /// Travel between two key points `steps` moves apart (steps > 1: pole points between them,
  /// where A passes through 0 and C is spread evenly over the steps).
  double travel(const Posed& p, const Posed& q, std::size_t steps) const {
    const double da =
        steps > 1 ? std::abs(p.tilt_rad) + std::abs(q.tilt_rad) : std::abs(q.tilt_rad - p.tilt_rad);
    const double c = dc(p.c_rad, q.c_rad);
    const double jump = c / static_cast<double>(steps) > options_.c_jump_threshold_rad
                            ? options_.c_jump_penalty_rad
                            : 0.0;
    return da + options_.c_weight * c + jump;
  }

  /// The dynamic programme over the key points, then the continuous C's winding.
  void choose_keys() {
    const std::vector<std::vector<Candidate>>& cand = cand_;
    const std::vector<std::size_t>& keys = keys_;
    const std::vector<bool>& rapid_into = rapid_into_;
    const std::optional<Posed>& start = start_;
    const PosePlanOptions& options = options_;
    PosePlan& plan = plan_;
    // Forward pass of the dynamic programme over the key points.
    std::vector<std::vector<double>> cost(keys.size());
    std::vector<std::vector<int>> from(keys.size());
    {
      const auto& c0 = cand[keys[0]];
      cost[0].assign(c0.size(), 0.0);
      from[0].assign(c0.size(), -1);
      if (start) {
        for (std::size_t s = 0; s < c0.size(); ++s) {
          cost[0][s] = options.rapid_weight * travel(*start, c0[s].pose, keys[0] + 1);
        }
      }
    }
    for (std::size_t k = 1; k < keys.size(); ++k) {
      // Every turn of a bounded C is a candidate here: some 10^5 steps a key point.
      detail::look_at_stop(stop_, k, 64);
      const auto& prev = cand[keys[k - 1]];
      const auto& cur = cand[keys[k]];
      const double w = weight(keys[k - 1], keys[k]);
      const std::size_t steps = keys[k] - keys[k - 1];
      cost[k].assign(cur.size(), std::numeric_limits<double>::infinity());
      from[k].assign(cur.size(), -1);
      for (std::size_t s = 0; s < cur.size(); ++s) {
        for (std::size_t r = 0; r < prev.size(); ++r) {
          // Between two preferred points the sides must agree: a pass is mirrored whole.
          if (prev[r].side != 0 && cur[s].side != 0 && prev[r].side != cur[s].side &&
              !rapid_into[keys[k]]) {
            continue;
          }
          const double c = cost[k - 1][r] + w * travel(prev[r].pose, cur[s].pose, steps);
          // Ties (within rounding) keep the earlier candidate: the a >= 0 branch of the
          // geometry first, whatever the axes' senses, so mirrored machines mirror.
          if (c < cost[k][s] - kTie) {
            cost[k][s] = c;
            from[k][s] = static_cast<int>(r);
          }
        }
      }
    }
    // Backtrack.
    std::size_t best = 0;
    for (std::size_t s = 1; s < cost.back().size(); ++s) {
      if (cost.back()[s] < cost.back()[best] - kTie) best = s;
    }
    int s = static_cast<int>(best);
    for (std::size_t k = keys.size(); k-- > 0;) {
      plan.poses[keys[k]] = cand[keys[k]][static_cast<std::size_t>(s)].pose;
      s = from[k][static_cast<std::size_t>(s)];
    }
    // Continuous C: take the turn nearest to the previous key point (the first from `start`,
    // else from home, C = 0). A half turn either way is a tie: turned negative, as the
    // production NX post for the Haas UMC-750 turns it (tests/test_program.cpp: it turns -180 deg
    // where taxopt turned +180, and every C after differed by a whole turn). A bounded C
    // planned free of its range turns such a tie towards C = 0, as the programme over its
    // turns keeps the candidate nearest C = 0: else every pass over the pole turned it half a
    // turn further the same way (the 143,840-point sine left C +-36000 deg on LinuxCNC's sample).
    if (unwrapped_c()) {
      const double pi = Constants<double>::pi();
      double prev_c = start ? start->c_rad : 0.0;
      for (std::size_t k : keys) {
        double turn = wrap_pi(plan.poses[k].c_rad - prev_c);
        if (std::abs(turn - pi) < kTie) turn = m_.c.continuous || prev_c >= 0.0 ? -pi : pi;
        plan.poses[k].c_rad = prev_c + turn;
        prev_c = plan.poses[k].c_rad;
      }
    }
  }

  /// Points on the pole: A = 0, C interpolated between the neighbouring key points (held at
  /// the ends of the sequence), so that C never jumps where it does not move the axis.
  void fill_pole_runs() {
    const std::size_t n = axes_.size();
    const std::optional<Posed>& start = start_;
    PosePlan& plan = plan_;
    std::size_t i = 0;
    while (i < n) {
      if (!free_pole(i)) {
        ++i;
        continue;
      }
      std::size_t e = i;
      while (e < n && free_pole(e)) ++e;
      const bool has_before = i > 0, has_after = e < n;
      const double c_before =
          has_before ? plan.poses[i - 1].c_rad
                     : (has_after ? plan.poses[e].c_rad : (start ? start->c_rad : 0.0));
      const double c_after = has_after ? plan.poses[e].c_rad : c_before;
      for (std::size_t k = i; k < e; ++k) {
        const double t = (has_before && has_after)
                             ? static_cast<double>(k - i + 1) / static_cast<double>(e - i + 1)
                             : 0.0;
        plan.poses[k] = Posed{0.0, c_before + t * (c_after - c_before)};
      }
      i = e;
    }
  }

  const MachineKinematicsd& m_;
  const std::vector<Vec3d>& axes_;
  const std::vector<bool>& rapid_into_;
  const std::optional<Posed>& start_;
  const PosePlanOptions& options_;
  const std::vector<std::optional<Posed>>& preferred_;
  const StopSource* stop_;
  std::vector<std::vector<Candidate>> cand_;
  std::vector<std::size_t> keys_;  // points off the pole (and preferred pole points), in order
  PosePlan plan_;
  bool wind_free_ = false;  // a bounded C planned with its turns left to the unwrapping
};

}  // namespace

PosePlan plan_poses(const MachineKinematicsd& m, const std::vector<Vec3d>& axes,
                    const std::vector<bool>& rapid_into, const std::optional<Posed>& start,
                    const PosePlanOptions& options,
                    const std::vector<std::optional<Posed>>& preferred) {
  return detail::plan_poses(m, axes, rapid_into, start, options, preferred, nullptr);
}

PosePlan detail::plan_poses(const MachineKinematicsd& m, const std::vector<Vec3d>& axes,
                            const std::vector<bool>& rapid_into, const std::optional<Posed>& start,
                            const PosePlanOptions& options,
                            const std::vector<std::optional<Posed>>& preferred,
                            const StopSource* stop) {
  if (rapid_into.size() != axes.size()) {
    throw std::invalid_argument("plan_poses: rapid_into and axes differ in size");
  }
  if (!preferred.empty() && preferred.size() != axes.size()) {
    throw std::invalid_argument("plan_poses: preferred and axes differ in size");
  }
  return PosePlanner(m, axes, rapid_into, start, options, preferred, stop).run();
}

}  // namespace taxopt
