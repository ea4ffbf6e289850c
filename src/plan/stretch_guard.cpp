#include "plan/stretch_guard.hpp"

#include <algorithm>

#include "plan/slerp.hpp"

namespace taxopt {
namespace {

enum class State { Open, Settled, Whole };

/// A stretch [begin, end) kept, with b blend points on each side.
struct Stretch {
  std::size_t begin = 0, end = 0, blend = 0;
  bool hit = false;
  /// Kept because the method gains nothing over the pass (KeptWhy::NoGain).
  bool no_gain = false;
  /// Times its blend was doubled.
  int doublings = 0;
};

/// The blend points of stretch `s` within `pass`, each with the input's weight (smoothstep).
template <class F>
void for_each_blend_point(const Stretch& s, const IndexRange& pass, F&& f) {
  for (std::size_t k = 1; k <= s.blend; ++k) {
    const double w = static_cast<double>(s.blend + 1 - k) / static_cast<double>(s.blend + 1);
    const double weight = w * w * (3.0 - 2.0 * w);
    if (s.begin >= pass.begin + k) f(s.begin - k, weight);
    if (s.end + k - 1 < pass.end) f(s.end + k - 1, weight);
  }
}

/// A join still too sharp after this many doublings of its blend widens its stretch instead.
constexpr int kMaxDoublings = 2;

/// One round's verdicts on a pass added to its stretches (see the file comment): a stretch
/// with a point judged worse within its reach doubles its blend once (rates) or widens to the
/// points that hit; runs of such points outside every reach start stretches of their own.
void mark(std::vector<Stretch>& stretches, const IndexRange& pass,
          const std::vector<PointVerdict>& verdict, std::size_t first_blend) {
  const std::size_t existing = stretches.size();
  std::vector<char> sharp(existing, 0);
  std::size_t run_begin = pass.end, run_end = pass.end;
  bool run_hit = false;
  const auto close_run = [&] {
    if (run_begin != pass.end) stretches.push_back({run_begin, run_end, first_blend, run_hit, 0});
    run_begin = run_end = pass.end;
    run_hit = false;
  };
  for (std::size_t i = pass.begin; i < pass.end; ++i) {
    if (verdict[i] == PointVerdict::Good) continue;
    const bool hit = verdict[i] == PointVerdict::Hits;
    bool reached = false;
    for (std::size_t k = 0; k < existing && !reached; ++k) {
      Stretch& s = stretches[k];
      const std::size_t lo = s.begin >= s.blend + 1 ? s.begin - s.blend - 1 : 0;
      if (i < lo || i > s.end + s.blend) continue;
      reached = true;
      if (hit || s.doublings >= kMaxDoublings) {
        s.hit = s.hit || hit;
        s.begin = std::min(s.begin, i);
        s.end = std::max(s.end, i + 1);
      } else {
        sharp[k] = 1;
      }
    }
    if (reached) continue;
    if (run_begin != pass.end && i > run_end) close_run();
    if (run_begin == pass.end) run_begin = i;
    run_end = i + 1;
    run_hit = run_hit || hit;
  }
  close_run();
  for (std::size_t k = 0; k < existing; ++k) {
    if (sharp[k]) {
      stretches[k].blend *= 2;
      ++stretches[k].doublings;
    }
  }
}

/// Stretches whose blend would leave the pass reach its end; stretches whose blends meet
/// merge. Returns whether one stretch covers the pass.
bool tidy(std::vector<Stretch>& stretches, const IndexRange& pass) {
  for (Stretch& s : stretches) {
    if (s.begin < pass.begin + s.blend) s.begin = pass.begin;
    if (s.end + s.blend > pass.end) s.end = pass.end;
  }
  std::sort(stretches.begin(), stretches.end(),
            [](const Stretch& a, const Stretch& b) { return a.begin < b.begin; });
  std::vector<Stretch> merged;
  for (const Stretch& s : stretches) {
    if (!merged.empty() && merged.back().end + merged.back().blend + s.blend >= s.begin) {
      Stretch& m = merged.back();
      m.end = std::max(m.end, s.end);
      m.blend = std::max(m.blend, s.blend);
      m.doublings = std::max(m.doublings, s.doublings);
      m.hit = m.hit || s.hit;
    } else {
      merged.push_back(s);
    }
  }
  stretches = merged;
  return stretches.size() == 1 && stretches[0].begin == pass.begin && stretches[0].end == pass.end;
}

/// One run of the guard over the passes: their states, stretches and the candidate axes.
class Guard {
 public:
  Guard(const std::vector<IndexRange>& passes, const std::vector<char>& guarded,
        const std::vector<Vec3d>& optimised, const std::vector<Vec3d>& input,
        const StretchGuardOptions& options)
      : passes_(passes),
        optimised_(optimised),
        input_(input),
        options_(options),
        state_(passes.size(), State::Settled),
        stretches_(passes.size()) {
    out_.axes = optimised;
    out_.why.assign(optimised.size(), KeptWhy::None);
    for (std::size_t q = 0; q < passes.size(); ++q) {
      if (q < guarded.size() && guarded[q] && passes[q].size() > 0) state_[q] = State::Open;
    }
  }

  StretchGuardResult run(const StretchEvaluation& evaluate) {
    for (std::size_t round = 0;; ++round) {
      std::vector<char> check;
      if (!open_points(check)) break;
      const StretchVerdicts verdicts = evaluate(out_.axes, out_.why, check);
      for (std::size_t q = 0; q < passes_.size(); ++q) {
        if (state_[q] == State::Open) judge(q, verdicts, round);
      }
    }
    totals();
    return std::move(out_);
  }

 private:
  /// The points of the open passes in `check`; false: none is open.
  bool open_points(std::vector<char>& check) const {
    check.assign(optimised_.size(), 0);
    bool any_open = false;
    for (std::size_t q = 0; q < passes_.size(); ++q) {
      if (state_[q] != State::Open) continue;
      any_open = true;
      std::fill(check.begin() + static_cast<long>(passes_[q].begin),
                check.begin() + static_cast<long>(passes_[q].end), 1);
    }
    return any_open;
  }

  /// Pass q after a round's verdicts: settled, its stretches grown, or kept whole.
  void judge(std::size_t q, const StretchVerdicts& verdicts, std::size_t round) {
    const std::vector<PointVerdict>& verdict = verdicts.points;
    const IndexRange& pass = passes_[q];
    bool worse = false, hit = false;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      worse = worse || verdict[i] != PointVerdict::Good;
      hit = hit || verdict[i] == PointVerdict::Hits;
    }
    const bool gains = q < verdicts.gains.size() && verdicts.gains[q];
    if (!worse && gains) {
      state_[q] = State::Settled;
      return;
    }
    if (!worse && stretches_[q].empty()) {
      // Nothing worse and nothing better: the axes would turn for nothing.
      stretches_[q] = {{pass.begin, pass.end, 0, false, true, 0}};
      state_[q] = State::Whole;
      apply(q);
      return;
    }
    bool whole = !worse || round + 1 >= options_.rounds;
    if (!whole) {
      mark(stretches_[q], pass, verdict, options_.first_blend);
      whole = tidy(stretches_[q], pass);
    }
    if (whole) {
      for (const Stretch& s : stretches_[q]) hit = hit || s.hit;
      stretches_[q] = {{pass.begin, pass.end, 0, hit, false, 0}};
      state_[q] = State::Whole;
    }
    apply(q);
  }

  /// The candidate of pass q from its stretches: the input's axes on them, blended at their
  /// ends, the optimised elsewhere.
  void apply(std::size_t q) {
    const IndexRange& pass = passes_[q];
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      out_.axes[i] = optimised_[i];
      out_.why[i] = KeptWhy::None;
    }
    for (const Stretch& s : stretches_[q]) {
      for (std::size_t i = s.begin; i < s.end; ++i) {
        out_.axes[i] = input_[i];
        out_.why[i] = s.no_gain ? KeptWhy::NoGain : s.hit ? KeptWhy::Collision : KeptWhy::PeakRate;
      }
      for_each_blend_point(s, pass, [&](std::size_t i, double weight) {
        if (angle_between(optimised_[i], input_[i]) > Constants<double>::pi() - 1e-6) {
          out_.axes[i] = input_[i];  // no unique arc between them: the input's
        } else {
          out_.axes[i] = slerp(optimised_[i], input_[i], weight).normalized();
        }
        out_.why[i] = KeptWhy::Join;
      });
    }
  }

  void totals() {
    for (std::size_t q = 0; q < passes_.size(); ++q) {
      if (state_[q] == State::Whole) ++out_.whole_passes;
      if (state_[q] == State::Settled) out_.stretches += stretches_[q].size();
    }
    for (const KeptWhy w : out_.why) {
      out_.points_hit += w == KeptWhy::Collision;
      out_.points_rate += w == KeptWhy::PeakRate;
      out_.points_blended += w == KeptWhy::Join;
      out_.points_no_gain += w == KeptWhy::NoGain;
    }
  }

  const std::vector<IndexRange>& passes_;
  const std::vector<Vec3d>& optimised_;
  const std::vector<Vec3d>& input_;
  const StretchGuardOptions& options_;
  std::vector<State> state_;
  std::vector<std::vector<Stretch>> stretches_;
  StretchGuardResult out_;
};

}  // namespace

StretchGuardResult guard_stretches(const std::vector<IndexRange>& passes,
                                   const std::vector<char>& guarded,
                                   const std::vector<Vec3d>& optimised,
                                   const std::vector<Vec3d>& input,
                                   const StretchEvaluation& evaluate,
                                   const StretchGuardOptions& options) {
  return Guard(passes, guarded, optimised, input, options).run(evaluate);
}

}  // namespace taxopt
