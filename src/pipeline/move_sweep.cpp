// The sweep of every move against the part (colliding_moves, stages.hpp).
#include <algorithm>
#include <cmath>
#include <vector>

#include "pipeline/stages.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {
namespace {

/// A body's clearance bound counts only this much beyond what the move needs of it (the
/// FCL model's own tolerance is far below it).
constexpr double kClearMarginMm = 1e-3;
/// The largest clearance a bound looks for: the walk of the part grows with it, and a move
/// that needs more is bounded again further on.
constexpr double kMaxReachMm = 2.0;

/// One sample of a move: the ball centre and the tool axis.
struct Sample {
  Vec3d centre = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
};

/// The samples of one move as the machine runs it: joint-linear between the written blocks,
/// at most 0.5 deg and 0.1 mm apart, the move's start left out.
std::vector<Sample> samples_of(const Machine& machine, const std::vector<WayPoint>& chain,
                               double ball_radius_mm) {
  std::vector<Sample> out;
  for (std::size_t k = 1; k < chain.size(); ++k) {
    const WayPoint &p0 = chain[k - 1], &p1 = chain[k];
    const double da = p1.tilt_deg - p0.tilt_deg, dc = p1.c_deg - p0.c_deg;
    const double dx = (p1.xyz - p0.xyz).norm();
    const int steps = static_cast<int>(
        std::ceil(std::max({std::abs(da) / 0.5, std::abs(dc) / 0.5, dx / 0.1, 1.0})));
    for (int s = (k == 1 ? 1 : 0); s < steps; ++s) {
      const double t = static_cast<double>(s) / steps;
      const Posed pose{deg_to_rad(p0.tilt_deg + t * da), deg_to_rad(p0.c_deg + t * dc)};
      const Vec3d xyz = p0.xyz + t * (p1.xyz - p0.xyz);
      const Vec3d axis = machine.rotary.forward(pose);
      out.push_back({tip_of_written_mm(machine, xyz, pose) + ball_radius_mm * axis, axis});
    }
  }
  return out;
}

/// Judges the samples of a move in order, skipping those that a clearance bound clears: a
/// body of radius r from `start` to `end` along the axis, moved from one sample's pose to
/// another's, has no point that moved farther than |centre change| + |axis change| times
/// sqrt(r^2 + max(start^2, end^2)) (a rotation by angle phi about the ball centre moves a
/// point at distance d by 2 d sin(phi / 2) = d |axis change|; the ball turns into itself).
/// Where every body stays within its bound from the last sample that was bounded, the sample
/// is as clear as that one was.
class MoveSweep {
 public:
  MoveSweep(const PartCheck& model, const CSpaceRasteriser* bounds, const ToolModel& tool,
            bool with_ball)
      : model_(model), bounds_(bounds), tool_(tool), with_ball_(with_ball) {
    for (const ToolBody& b : tool.bodies) {
      reach_.push_back(std::hypot(b.radius_mm, std::max(std::abs(b.start_mm), std::abs(b.end_mm))));
    }
    reach_.push_back(0.0);  // the ball
  }

  bool hits(const std::vector<Sample>& samples) {
    std::size_t wait = 0, backoff = 1;
    for (std::size_t s = 0; s < samples.size();) {
      if (!bounds_ || wait > 0) {
        if (wait > 0) --wait;
        if (collides(samples[s])) return true;
        ++s;
        continue;
      }
      const std::size_t next = bounded(samples, s);
      if (next == s) {  // no clearance to speak of: query this sample and a few more plainly
        if (collides(samples[s])) return true;
        ++s;
        wait = backoff;
        backoff = std::min<std::size_t>(2 * backoff, 16);
        continue;
      }
      backoff = 1;
      s = next;
    }
    return false;
  }

 private:
  bool collides(const Sample& p) const {
    return model_.collides(tool_, p.centre, p.axis, with_ball_);
  }

  /// How far body k (the ball after the bodies) of sample t lies from where it was at sample a.
  double moved(const Sample& a, const Sample& t, std::size_t k) const {
    return (t.centre - a.centre).norm() + (t.axis - a.axis).norm() * reach_[k];
  }

  /// The first sample after `a` that sample a's clearances do not clear, or `a` itself when
  /// they do not clear sample a.
  std::size_t bounded(const std::vector<Sample>& samples, std::size_t a) const {
    double need = 0.0;
    for (std::size_t t = a + 1; t < samples.size() && need < kMaxReachMm; ++t) {
      for (std::size_t k = 0; k < reach_.size(); ++k) {
        need = std::max(need, moved(samples[a], samples[t], k));
      }
    }
    need = std::min(need, kMaxReachMm);
    const std::vector<double> clear =
        bounds_->clearances_mm(tool_, samples[a].centre, samples[a].axis, with_ball_,
                               need + 2.0 * kClearMarginMm, kClearMarginMm);
    if (std::any_of(clear.begin(), clear.end(), [](double c) { return !(c > kClearMarginMm); })) {
      return a;
    }
    std::size_t t = a + 1;
    for (; t < samples.size(); ++t) {
      bool inside = true;
      for (std::size_t k = 0; k < reach_.size() && inside; ++k) {
        inside = moved(samples[a], samples[t], k) + kClearMarginMm < clear[k];
      }
      if (!inside) break;
    }
    return t;
  }

  const PartCheck& model_;
  const CSpaceRasteriser* bounds_;
  const ToolModel& tool_;
  bool with_ball_;
  std::vector<double> reach_;
};

}  // namespace

std::vector<std::size_t> colliding_moves(
    const PartCheck& model, const ToolModel& tool, const Machine& machine,
    const std::vector<Vec3d>& xyz_w, const std::vector<double>& tilt_deg,
    const std::vector<double>& c_deg, const std::vector<ContactPoint>& contacts,
    detail::StageProgress* progress, const std::vector<std::vector<WayPoint>>* between,
    const std::vector<char>* only, const CSpaceRasteriser* bounds) {
  return detail::parallel_select(1, xyz_w.size(), [&](std::size_t i) {
    if (only && !(*only)[i]) return false;
    struct Advance {  // on every return of this move's check
      detail::StageProgress* p;
      ~Advance() {
        if (p) p->advance();
      }
    } advance{progress};
    const bool in_air = contacts[i - 1].state != ContactState::Touching ||
                        contacts[i].state != ContactState::Touching;
    std::vector<WayPoint> chain = {{xyz_w[i - 1], tilt_deg[i - 1], c_deg[i - 1]}};
    if (between && i < between->size()) {
      chain.insert(chain.end(), (*between)[i].begin(), (*between)[i].end());
    }
    chain.push_back({xyz_w[i], tilt_deg[i], c_deg[i]});
    return MoveSweep(model, bounds, tool, in_air)
        .hits(samples_of(machine, chain, tool.ball_radius_mm));
  });
}

}  // namespace taxopt::pipeline
