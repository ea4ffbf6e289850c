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

}  // namespace

StretchGuardResult guard_stretches(const std::vector<IndexRange>& passes,
                                   const std::vector<char>& guarded,
                                   const std::vector<Vec3d>& optimised,
                                   const std::vector<Vec3d>& input,
                                   const StretchEvaluation& evaluate,
                                   const StretchGuardOptions& options) {
  const std::size_t n = optimised.size();
  StretchGuardResult out;
  out.axes = optimised;
  out.why.assign(n, KeptWhy::None);
  std::vector<State> state(passes.size(), State::Settled);
  for (std::size_t q = 0; q < passes.size(); ++q) {
    if (q < guarded.size() && guarded[q] && passes[q].size() > 0) state[q] = State::Open;
  }
  std::vector<std::vector<Stretch>> stretches(passes.size());
  // The candidate of pass q from its state and stretches.
  const auto apply = [&](std::size_t q) {
    const IndexRange& pass = passes[q];
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      out.axes[i] = optimised[i];
      out.why[i] = KeptWhy::None;
    }
    for (const Stretch& s : stretches[q]) {
      for (std::size_t i = s.begin; i < s.end; ++i) {
        out.axes[i] = input[i];
        out.why[i] = s.hit ? KeptWhy::Collision : KeptWhy::PeakRate;
      }
      for_each_blend_point(s, pass, [&](std::size_t i, double weight) {
        if (angle_between(optimised[i], input[i]) > Constants<double>::pi() - 1e-6) {
          out.axes[i] = input[i];  // no unique arc between them: the input's
        } else {
          out.axes[i] = slerp(optimised[i], input[i], weight).normalized();
        }
        out.why[i] = KeptWhy::Join;
      });
    }
  };
  for (std::size_t round = 0;; ++round) {
    std::vector<char> check(n, 0);
    bool any_open = false;
    for (std::size_t q = 0; q < passes.size(); ++q) {
      if (state[q] != State::Open) continue;
      any_open = true;
      std::fill(check.begin() + static_cast<long>(passes[q].begin),
                check.begin() + static_cast<long>(passes[q].end), 1);
    }
    if (!any_open) break;
    const StretchVerdicts verdicts = evaluate(out.axes, out.why, check);
    const std::vector<PointVerdict>& verdict = verdicts.points;
    for (std::size_t q = 0; q < passes.size(); ++q) {
      if (state[q] != State::Open) continue;
      const IndexRange& pass = passes[q];
      bool worse = false, hit = false;
      for (std::size_t i = pass.begin; i < pass.end; ++i) {
        worse = worse || verdict[i] != PointVerdict::Good;
        hit = hit || verdict[i] == PointVerdict::Hits;
      }
      const bool gains = q < verdicts.gains.size() && verdicts.gains[q];
      if (!worse && (stretches[q].empty() || gains)) {
        state[q] = State::Settled;
        continue;
      }
      bool whole = !worse || round + 1 >= options.rounds;
      if (!whole) {
        mark(stretches[q], pass, verdict, options.first_blend);
        whole = tidy(stretches[q], pass);
      }
      if (whole) {
        for (const Stretch& s : stretches[q]) hit = hit || s.hit;
        stretches[q] = {{pass.begin, pass.end, 0, hit, 0}};
        state[q] = State::Whole;
      }
      apply(q);
    }
  }
  for (std::size_t q = 0; q < passes.size(); ++q) {
    if (state[q] == State::Whole) ++out.whole_passes;
    if (state[q] == State::Settled) out.stretches += stretches[q].size();
  }
  for (const KeptWhy w : out.why) {
    out.points_hit += w == KeptWhy::Collision;
    out.points_rate += w == KeptWhy::PeakRate;
    out.points_blended += w == KeptWhy::Join;
  }
  return out;
}

}  // namespace taxopt
