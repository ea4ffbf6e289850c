// The sweep of every move against the part (colliding_moves, stages.hpp).
#include <algorithm>
#include <cmath>
#include <vector>

#include "pipeline/stages.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {
namespace {

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

/// Judges the samples of a move, clearing runs of them at once where it can: a body of radius r
/// from `start` to `end` along the axis, moved from one sample's pose to another's, has no point
/// that moved farther than |centre change| + |axis change| times sqrt(r^2 + max(start^2,
/// end^2)) (a rotation by angle phi about the ball centre moves a point at distance d by
/// 2 d sin(phi / 2) = d |axis change|; the ball turns into itself). So where each body, grown
/// by the most it moves over a run (radius and both ends: the grown cylinder holds every point
/// within that distance of it), misses the part at the run's middle sample, every sample of the
/// run misses it. A run the grown bodies hit is halved, down to a few samples, which `model`
/// judges one by one: the verdict is the samples' own, one query for most moves.
class MoveSweep {
 public:
  MoveSweep(const PartCheck& model, const CSpaceRasteriser* bounds, const ToolModel& tool,
            bool with_ball)
      : model_(model), bounds_(bounds), tool_(tool), with_ball_(with_ball) {
    for (const ToolBody& b : tool.bodies) {
      reach_.push_back(std::hypot(b.radius_mm, std::max(std::abs(b.start_mm), std::abs(b.end_mm))));
    }
  }

  /// Whether the tool hits the part at any of samples [lo, hi).
  bool hits(const std::vector<Sample>& samples, std::size_t lo, std::size_t hi) const {
    if (!bounds_ || hi - lo <= kFewSamples) {
      for (std::size_t s = lo; s < hi; ++s) {
        if (model_.collides(tool_, samples[s].centre, samples[s].axis, with_ball_)) return true;
      }
      return false;
    }
    const std::size_t mid = lo + (hi - lo) / 2;
    if (!grown_hits(samples, lo, hi, mid)) return false;
    return hits(samples, lo, mid) || hits(samples, mid, hi);
  }

 private:
  /// Runs this short are judged sample by sample.
  static constexpr std::size_t kFewSamples = 2;
  /// The bodies are grown this much more than the run needs (the models' own tolerances are
  /// far below it).
  static constexpr double kMarginMm = 1e-3;

  /// Whether the bodies at sample `at`, each grown by the most it moves from there over samples
  /// [lo, hi), meet the part.
  bool grown_hits(const std::vector<Sample>& samples, std::size_t lo, std::size_t hi,
                  std::size_t at) const {
    const Sample& a = samples[at];
    // One pass over the run: how far the centre moves, and each body (centre plus turn).
    double centre_moves = 0.0;
    std::vector<double> need(reach_.size(), 0.0);
    for (std::size_t t = lo; t < hi; ++t) {
      const double shift = (samples[t].centre - a.centre).norm();
      const double turn = (samples[t].axis - a.axis).norm();
      centre_moves = std::max(centre_moves, shift);
      for (std::size_t k = 0; k < need.size(); ++k) {
        need[k] = std::max(need[k], shift + turn * reach_[k]);
      }
    }
    ToolModel grown = tool_;
    for (std::size_t k = 0; k < grown.bodies.size(); ++k) {
      ToolBody& b = grown.bodies[k];
      b.radius_mm += need[k] + kMarginMm;
      b.start_mm -= need[k] + kMarginMm;
      b.end_mm += need[k] + kMarginMm;
    }
    grown.ball_radius_mm += centre_moves + kMarginMm;
    return bounds_->collides(grown, a.centre, a.axis, with_ball_);
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
    // The stop looked at before the move's check; counted on every return of it (a
    // destructor must not throw: the stop's Cancelled thrown there ended the process).
    if (progress) progress->check();
    struct Count {
      detail::StageProgress* p;
      ~Count() {
        if (p) p->count();
      }
    } count{progress};
    const bool in_air = contacts[i - 1].state != ContactState::Touching ||
                        contacts[i].state != ContactState::Touching;
    std::vector<WayPoint> chain = {{xyz_w[i - 1], tilt_deg[i - 1], c_deg[i - 1]}};
    if (between && i < between->size()) {
      chain.insert(chain.end(), (*between)[i].begin(), (*between)[i].end());
    }
    chain.push_back({xyz_w[i], tilt_deg[i], c_deg[i]});
    const std::vector<Sample> samples = samples_of(machine, chain, tool.ball_radius_mm);
    return MoveSweep(model, bounds, tool, in_air).hits(samples, 0, samples.size());
  });
}

}  // namespace taxopt::pipeline
