#include "taxopt/plan/paper_optimiser.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <optional>

#include "plan/cap_order.hpp"
#include "plan/paper_single.hpp"
#include "plan/slerp.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt {

Vec3d tangent_towards(const Vec3d& centre, const Vec3d& along) {
  const Vec3d across = along - along.dot(centre) * centre;
  if (across.norm() > 1e-9) return across.normalized();
  const Vec3d seed = std::abs(centre.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY();
  return centre.cross(seed).normalized();
}

std::vector<Vec3d> cap_grid(const Vec3d& centre, double radius_rad, double step_rad,
                            const Vec3d& along) {
  return detail::CapPattern(radius_rad, step_rad).axes(centre, along);
}

namespace {

/// The pattern search's eight directions: cos and sin of 2 pi d / 8, worked out once.
struct EightDirections {
  double cos[8], sin[8];
  EightDirections() {
    for (int d = 0; d < 8; ++d) {
      const double phi = Constants<double>::two_pi() * d / 8;
      cos[d] = std::cos(phi);
      sin[d] = std::sin(phi);
    }
  }
};
const EightDirections kEight;

/// The state of one pass while it is being planned.
class PassPlanner {
 public:
  PassPlanner(const PassProblem& problem, const AxisTest& is_free, const PaperOptions& options)
      : p_(problem),
        is_free_(is_free),
        opt_(options),
        n_(problem.input_axes.size()),
        pattern_(deg_to_rad(options.max_deviation_deg), deg_to_rad(options.grid_deg)) {
    arc_.assign(n_, 0.0);
    for (std::size_t i = 1; i < n_; ++i) arc_[i] = arc_[i - 1] + p_.segment_mm[i - 1];
    const double length = n_ ? arc_.back() : 0.0;
    pull_ = opt_.pull_weight / std::max(length, 1e-6);
    max_dev_rad_ = deg_to_rad(opt_.max_deviation_deg);
    step_rad_ = deg_to_rad(opt_.grid_deg);
  }

  /// `single` (when given and a resettle round would run) receives the plan as it stands
  /// before the resettle rounds: the paper's single repair, what plan_pass_paper with no
  /// resettle rounds returns.
  PassPlan run(std::optional<PassPlan>* single = nullptr) {
    PassPlan plan;
    if (n_ == 0) return plan;
    const CurveShape<double> shape = segment_curve(p_.curve_mm, p_.up, opt_.segmenter);
    plan.segmenter_keys = shape.keys;
    keys_ = shape.keys;
    key_axes_.clear();
    for (std::size_t k : keys_) {
      const std::optional<Vec3d> v = nearest_free(k);
      if (!v) no_free_.push_back(k);
      key_axes_.push_back(v.value_or(p_.input_axes[k]));
    }
    optimise_keys();
    axes_.assign(p_.input_axes.begin(), p_.input_axes.end());
    for (std::size_t k = 0; k + 1 < keys_.size(); ++k) fill(k);
    plan.repairs = repair();
    if (single && opt_.resettle_rounds > 0 && plan.repairs > 0) {
      const std::vector<Vec3d> axes = axes_;
      *single = finished(plan);
      axes_ = axes;
    }
    // PaperOptions::resettle_rounds: the keys set again with the repair keys among them.
    for (int round = 0; round < opt_.resettle_rounds && plan.repairs > 0; ++round) {
      if (!optimise_keys()) break;
      for (std::size_t k = 0; k + 1 < keys_.size(); ++k) fill(k);
      plan.repairs += repair();
    }
    return finished(plan);
  }

 private:
  /// The plan with its joints smoothed (which writes axes_), its axes, keys and no-free points.
  PassPlan finished(PassPlan plan) {
    if (opt_.joint_smoothing) smooth_joints(plan);
    plan.axes = axes_;
    plan.keys = keys_;
    std::sort(no_free_.begin(), no_free_.end());
    no_free_.erase(std::unique(no_free_.begin(), no_free_.end()), no_free_.end());
    plan.no_free_axis = no_free_;
    return plan;
  }

 private:
  bool acceptable(std::size_t i, const Vec3d& v) const {
    return angle_between(v, p_.input_axes[i]) <= max_dev_rad_ + 1e-12 && is_free_(i, v);
  }

  /// The cap grid of a key point, made once per point (keys are asked again on every sweep).
  struct Cap {
    std::vector<Vec3d> axes;
  };
  const Cap& cap_at(std::size_t i) const {
    auto it = caps_.find(i);
    if (it == caps_.end()) {
      it = caps_.emplace(i, Cap{pattern_.axes(p_.input_axes[i], input_turn(i))}).first;
    }
    return it->second;
  }

  /// The way the input axes turn at point i (their central difference).
  Vec3d input_turn(std::size_t i) const {
    const std::size_t n = p_.input_axes.size();
    return p_.input_axes[std::min(i + 1, n - 1)] - p_.input_axes[i > 0 ? i - 1 : 0];
  }

  /// The pull of axis v at point i towards its input axis.
  double pull_term(std::size_t i, const Vec3d& v) const {
    const double dev = angle_between(v, p_.input_axes[i]);
    return pull_ * dev * dev;
  }

  /// The input axis if free, else the free candidate nearest to it.
  std::optional<Vec3d> nearest_free(std::size_t i) const {
    for (const Vec3d& v : cap_at(i).axes) {
      if (acceptable(i, v)) return v;
    }
    return std::nullopt;
  }

  /// The bending energy terms of the key polygon that involve key j at axis v, with what does
  /// not depend on v worked out once (the keys' lengths and spans,
  /// the rates that do not touch key j), the same operations in the same order per v: a key's
  /// whole cap of candidates is priced with it (it was a third of a run).
  class Bending {
   public:
    Bending(const PassPlanner& planner, std::size_t j) : key_axes_(planner.key_axes_), j_(j) {
      const std::vector<std::size_t>& keys = planner.keys_;
      const std::vector<double>& arc = planner.arc_;
      const std::size_t m = keys.size();
      const auto len = [&](std::size_t t) {
        return std::max(arc[keys[t + 1]] - arc[keys[t]], 1e-9);
      };
      for (std::size_t t = (j > 0 ? j - 1 : 0); t <= j + 1 && t + 1 < m; ++t) {
        if (t == 0) continue;
        terms_[count_] = {t, std::max(0.5 * (arc[keys[t + 1]] - arc[keys[t - 1]]), 1e-9)};
        ++count_;
      }
      // rate(t) for t = j - 2 .. j + 1 where it exists: fixed unless t is j - 1 or j.
      for (std::size_t t = (j >= 2 ? j - 2 : 0); t <= j + 1 && t + 1 < m; ++t) {
        len_[t + 2 - j] = len(t);
        if (t + 1 != j && t != j)
          rate_[t + 2 - j] = Vec3d((key_axes_[t + 1] - key_axes_[t]) / len(t));
      }
    }
    double operator()(const Vec3d& v) const {
      Vec3d rate[4];
      for (int s = 0; s < 4; ++s) rate[s] = rate_[s];
      if (j_ >= 1) rate[1] = Vec3d((v - key_axes_[j_ - 1]) / len_[1]);
      if (j_ + 1 < key_axes_.size()) rate[2] = Vec3d((key_axes_[j_ + 1] - v) / len_[2]);
      double e = 0.0;
      for (int k = 0; k < count_; ++k) {
        const std::size_t t = terms_[k].t;
        e += (rate[t + 2 - j_] - rate[t + 1 - j_]).squaredNorm() / terms_[k].span;
      }
      return e;
    }

    /// operator()(v) for unit v as constant + gradient.v (each term's square expanded with
    /// |v|^2 = 1), and the size of the expanded terms, which bounds the rounding of both forms.
    struct Linear {
      double constant = 0.0, scale = 0.0;
      Vec3d gradient = Vec3d::Zero();
    };
    Linear linear() const {
      // rate(j - 2 + s) = a[s] v + b[s].
      double a[4] = {0.0, 0.0, 0.0, 0.0};
      Vec3d b[4] = {rate_[0], rate_[1], rate_[2], rate_[3]};
      if (j_ >= 1) a[1] = 1.0 / len_[1], b[1] = -key_axes_[j_ - 1] / len_[1];
      if (j_ + 1 < key_axes_.size()) a[2] = -1.0 / len_[2], b[2] = key_axes_[j_ + 1] / len_[2];
      Linear out;
      for (int k = 0; k < count_; ++k) {
        const std::size_t s = terms_[k].t + 2 - j_;
        const double da = a[s] - a[s - 1];
        const Vec3d db = b[s] - b[s - 1];
        const double span = terms_[k].span;
        out.constant += (da * da + db.squaredNorm()) / span;
        out.gradient += (2.0 * da / span) * db;
        out.scale += (std::abs(da) + db.norm()) * (std::abs(da) + db.norm()) / span;
      }
      return out;
    }

   private:
    struct Term {
      std::size_t t = 0;
      double span = 0.0;
    };
    const std::vector<Vec3d>& key_axes_;
    std::size_t j_;
    Term terms_[3];
    int count_ = 0;
    // Index s holds rate(j - 2 + s), s = 0 .. 3.
    Vec3d rate_[4] = {Vec3d::Zero(), Vec3d::Zero(), Vec3d::Zero(), Vec3d::Zero()};
    double len_[4] = {1.0, 1.0, 1.0, 1.0};
  };

  /// The best acceptable axis for key j with the others fixed: the cap grid by cost, then a
  /// pattern search down to grid / 8. Empty when no candidate is acceptable.
  std::optional<Vec3d> best_key_axis(std::size_t j) const {
    const std::size_t i = keys_[j];
    const Cap& cap = cap_at(i);
    const std::vector<Vec3d>& cands = cap.axes;
    const Bending bending_at(*this, j);
    // Candidates by (cost, index), cheapest first, as the first acceptable one ends the search
    // (usually among the first few): priced by bending's linear form and the ring's angle, the
    // exact cost worked out only where it decides (1e-9 of the terms' size: rounding is 1e-14).
    const Bending::Linear linear = bending_at.linear();
    std::vector<double> approx(cands.size());
    for (std::size_t c = 0; c < cands.size(); ++c) {
      approx[c] = linear.constant + linear.gradient.dot(cands[c]) +
                  pull_ * pattern_.rho(c) * pattern_.rho(c);
    }
    const double tolerance =
        1e-9 * (linear.scale + std::abs(linear.constant) + pull_ * max_dev_rad_ * max_dev_rad_);
    detail::CandidateOrder order(std::move(approx), tolerance, [&](std::size_t c) {
      return bending_at(cands[c]) + pull_term(i, cands[c]);
    });
    std::optional<Vec3d> best;
    double best_cost = 0.0;
    // The current axis competes too: a sweep never makes a key worse.
    const double current_cost = bending_at(key_axes_[j]) + pull_term(i, key_axes_[j]);
    const bool current_ok = acceptable(i, key_axes_[j]);
    while (const auto next = order.next()) {
      const auto [cost, c] = *next;
      if (current_ok && cost >= current_cost) break;
      if (acceptable(i, cands[c])) {
        best = cands[c];
        best_cost = cost;
        break;
      }
    }
    if (!best && current_ok) best = key_axes_[j], best_cost = current_cost;
    if (!best) return best;
    // Pattern search in the tangent plane of the best axis.
    for (double step = 0.5 * step_rad_; step > step_rad_ / 8.5; step *= 0.5) {
      for (int round = 0; round < 8; ++round) {
        const Vec3d b = *best;
        const Vec3d e1 = tangent_towards(b, input_turn(i)), e2 = b.cross(e1);
        bool improved = false;
        for (int d = 0; d < 8; ++d) {
          const Vec3d v = sphere_exp(b, Vec3d(step * (kEight.cos[d] * e1 + kEight.sin[d] * e2)));
          const double cost = bending_at(v) + pull_term(i, v);
          if (cost < best_cost - 1e-15 && acceptable(i, v)) {
            best = v;
            best_cost = cost;
            improved = true;
          }
        }
        if (!improved) break;
      }
    }
    return best;
  }

  /// Sweeps over the keys until none moves.
  /// Returns whether any key moved.
  bool optimise_keys() {
    bool any = false;
    dirty_.resize(keys_.size(), 1);
    for (int sweep = 0; sweep < opt_.max_sweeps; ++sweep) {
      bool moved = false;
      std::vector<char> next(keys_.size(), 0);
      for (std::size_t j = 0; j < keys_.size(); ++j) {
        if (!dirty_[j]) continue;
        const std::optional<Vec3d> v = best_key_axis(j);
        if (!v) continue;
        if (angle_between(*v, key_axes_[j]) > 1e-9) {
          moved = true;
          mark(next, j);
        }
        key_axes_[j] = *v;
      }
      dirty_ = std::move(next);
      any = any || moved;
      if (!moved) break;
    }
    return any;
  }

  /// Keys whose cost a move of key j changes (bending reaches two keys either side), marked.
  static void mark(std::vector<char>& dirty, std::size_t j) {
    for (std::size_t t = j >= 2 ? j - 2 : 0; t <= j + 2 && t < dirty.size(); ++t) dirty[t] = 1;
  }

  /// Arc-length slerp over the interval from key k to key k + 1.
  void fill(std::size_t k) {
    const std::size_t e = keys_[k], f = keys_[k + 1];
    const std::vector<double> len(p_.segment_mm.begin() + static_cast<long>(e),
                                  p_.segment_mm.begin() + static_cast<long>(f));
    // Keys that (nearly) oppose each other have no unique great circle between them (an input
    // that turns the tool over within a pass, as real NX output does): the interval keeps its
    // input axes there; repair() then splits it where those are not acceptable.
    if (angle_between(key_axes_[k], key_axes_[k + 1]) > Constants<double>::pi() - 1e-3) {
      for (std::size_t i = e + 1; i < f; ++i) axes_[i] = p_.input_axes[i];
      axes_[e] = key_axes_[k];
      axes_[f] = key_axes_[k + 1];
      return;
    }
    const std::vector<Vec3d> v = arc_length_slerp(key_axes_[k], key_axes_[k + 1], len);
    std::copy(v.begin(), v.end(), axes_.begin() + static_cast<long>(e));
  }

  /// Points strictly inside the interval from key k to key k + 1 whose axis is not acceptable.
  std::vector<std::size_t> bad_points(std::size_t k) const {
    return detail::parallel_select(keys_[k] + 1, keys_[k + 1],
                                   [&](std::size_t i) { return !acceptable(i, axes_[i]); });
  }

  /// Splits intervals at unacceptable interpolated axes until every axis is acceptable or a
  /// key. Returns the number of keys added.
  std::size_t repair() {
    std::size_t added = 0;
    std::vector<std::size_t> todo(keys_.size() > 1 ? keys_.size() - 1 : 0);
    std::iota(todo.begin(), todo.end(), std::size_t(0));
    // Work from the last interval back so that inserting keys does not shift pending ones.
    std::sort(todo.rbegin(), todo.rend());
    while (!todo.empty()) {
      const std::size_t k = todo.back();
      todo.pop_back();
      const std::vector<std::size_t> bad = bad_points(k);
      if (bad.empty()) continue;
      std::size_t worst = bad.front();
      double worst_dev = -1.0;
      for (std::size_t i : bad) {
        const double dev = angle_between(axes_[i], p_.input_axes[i]);
        if (dev > worst_dev) worst = i, worst_dev = dev;
      }
      keys_.insert(keys_.begin() + static_cast<long>(k + 1), worst);
      key_axes_.insert(key_axes_.begin() + static_cast<long>(k + 1), axes_[worst]);
      dirty_.insert(dirty_.begin() + static_cast<long>(k + 1), 1);
      mark(dirty_, k + 1);
      const std::optional<Vec3d> v = best_key_axis(k + 1);
      if (!v) {
        no_free_.push_back(worst);
        key_axes_[k + 1] = p_.input_axes[worst];
      } else {
        key_axes_[k + 1] = *v;
      }
      ++added;
      fill(k);
      fill(k + 1);
      // Pending intervals after k moved one place up; k and k + 1 are checked again.
      for (std::size_t& t : todo) {
        if (t > k) ++t;
      }
      todo.push_back(k + 1);
      todo.push_back(k);
    }
    return added;
  }

  /// Parabolic blends at the interior keys (see the header).
  void smooth_joints(PassPlan& plan) {
    if (keys_.size() < 3) return;
    const std::size_t joints = keys_.size() - 2;
    std::vector<char> smoothed(joints, 0);
    detail::parallel_for(std::size_t(0), joints, [&](std::size_t q) {
      const std::size_t j = q + 1;
      const std::size_t ia = keys_[j - 1], ik = keys_[j], ib = keys_[j + 1];
      const Vec3d vk = key_axes_[j];
      const double left = arc_[ik] - arc_[ia], right = arc_[ib] - arc_[ik];
      if (!(left > 0.0) || !(right > 0.0)) return;
      const Vec3d w_left = -sphere_log(vk, key_axes_[j - 1]) / left;
      const Vec3d w_right = sphere_log(vk, key_axes_[j + 1]) / right;
      const Vec3d dw = w_right - w_left;
      if (dw.norm() * std::min(left, right) < 1e-12) {
        smoothed[q] = 1;
        return;
      }
      double d = 0.5 * std::min(left, right);
      for (int attempt = 0; attempt < 5; ++attempt, d *= 0.5) {
        std::vector<std::pair<std::size_t, Vec3d>> blend;
        bool ok = true;
        for (std::size_t i = ia + 1; i < ib && ok; ++i) {
          const double s = arc_[i] - arc_[ik];
          if (std::abs(s) >= d) continue;
          const Vec3d u = w_left * s + dw * ((s + d) * (s + d) / (4.0 * d));
          const Vec3d v = sphere_exp<double>(vk, u);
          ok = acceptable(i, v);
          blend.emplace_back(i, v);
        }
        if (!ok) continue;
        for (const auto& [i, v] : blend) axes_[i] = v;
        smoothed[q] = 1;
        return;
      }
    });
    for (char s : smoothed) (s ? plan.smoothed_joints : plan.sharp_joints) += 1;
  }

  const PassProblem& p_;
  const AxisTest& is_free_;
  const PaperOptions& opt_;
  std::size_t n_;
  std::vector<double> arc_;
  double pull_ = 0.0, max_dev_rad_ = 0.0, step_rad_ = 0.0;
  std::vector<std::size_t> keys_;
  /// Keys optimise_keys must look at again: every key at first, then those next to a key that
  /// moved or was added (a key whose neighbours stand still would find its own axis again).
  std::vector<char> dirty_;
  std::vector<Vec3d> key_axes_;
  std::vector<Vec3d> axes_;
  std::vector<std::size_t> no_free_;
  detail::CapPattern pattern_;
  mutable std::map<std::size_t, Cap> caps_;
};

}  // namespace

namespace {

void check_problem(const PassProblem& problem, const PaperOptions& options) {
  const std::size_t n = problem.input_axes.size();
  if (problem.curve_mm.size() != n || (n > 0 && problem.segment_mm.size() != n - 1)) {
    throw std::invalid_argument("plan_pass_paper: curve, axes and segments do not match");
  }
  if (!(options.grid_deg > 0.0) || !(options.max_deviation_deg >= 0.0)) {
    throw std::invalid_argument("plan_pass_paper: grid must be positive, deviation not negative");
  }
}

}  // namespace

PassPlan plan_pass_paper(const PassProblem& problem, const AxisTest& is_free,
                         const PaperOptions& options) {
  check_problem(problem, options);
  return PassPlanner(problem, is_free, options).run();
}

namespace detail {

PassPlan plan_pass_paper(const PassProblem& problem, const AxisTest& is_free,
                         const PaperOptions& options, std::optional<PassPlan>& single) {
  check_problem(problem, options);
  single.reset();
  return PassPlanner(problem, is_free, options).run(&single);
}

}  // namespace detail

}  // namespace taxopt
