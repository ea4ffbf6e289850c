#include "taxopt/job.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <sstream>

#include "taxopt/core/error.hpp"
#include "taxopt/core/version.hpp"
#include "taxopt/cspace/collision.hpp"
#include "taxopt/cspace/cspace.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"
#include "taxopt/plan/air_turn.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"
#include "taxopt/plan/pole_passage.hpp"
#include "taxopt/plan/stretch_guard.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"
#include "util/progress.hpp"

namespace taxopt {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double round_to(double v, int decimals) {
  const double s = std::pow(10.0, decimals);
  return std::round(v * s) / s;
}

/// Elements [begin, end) of `v`.
template <class T>
std::vector<T> slice(const std::vector<T>& v, std::size_t begin, std::size_t end) {
  return std::vector<T>(v.begin() + static_cast<long>(begin), v.begin() + static_cast<long>(end));
}

/// Ball radius of an operation's tool: the override, else the file's (0: not a ball-end mill).
double ball_radius_mm(const Operationd& op, const JobOptions& options) {
  return options.tool.ball_radius_mm.value_or(op.tool.ball_radius_mm());
}

/// Why an operation with no ball radius is left alone: no tool at all in the file, or another
/// kind of tool.
std::string not_a_ball(const Operationd& op) {
  if (!op.tool.from_file) {
    return "operation " + op.name +
           ": the CL file defines no tool (no TLDATA or CUTTER record); give the ball radius "
           "with --tool-radius";
  }
  return "operation " + op.name + ": not a ball-end mill";
}

/// The margins the collision checks judge the tool's bodies by (ToolMargins).
ToolMargins margins_of(const JobOptions& options) {
  ToolMargins m;
  m.shank_clearance_mm = options.shank_clearance_mm;
  m.holder_clearance_mm = options.holder_clearance_mm;
  if (options.part) {
    m.flute_tolerance_mm =
        options.part_tolerance_mm.value_or(contact_tolerance_mm(*options.part, options.contact));
  }
  return m;
}

/// The tool of an operation as the collision checks judge it.
ToolModel judged_tool(const Operationd& op, const JobOptions& options) {
  return ToolModel::ball_end(op.tool, options.tool).judged(margins_of(options));
}

/// Point whose path length the metrics measure: the ball centre for a ball-end mill (it does
/// not move when the axis turns, so before and after share one arc length), else the tip.
Vec3d reference_point(const CLPointd& p, double ball_radius_mm) {
  return p.tip_mm + ball_radius_mm * p.axis;
}

/// The tip that keeps the ball centre of `p` where it is with the tool along `axis`:
/// P' = C - R V' (the contact point does not move when the axis turns).
Vec3d tip_for_axis(const CLPointd& p, double ball_radius_mm, const Vec3d& axis) {
  return reference_point(p, ball_radius_mm) - ball_radius_mm * axis;
}

/// The feed of each point that the kinematic metrics use: --feed, else the file's, else
/// `fallback_mm_min`.
std::vector<double> metric_feeds_of(const Operationd& op, const JobOptions& options,
                                    double fallback_mm_min) {
  std::vector<double> feed;
  for (const CLPointd& p : op.points) {
    feed.push_back(options.feed_mm_per_min.value_or(p.feed_mm_per_min > 0.0 ? p.feed_mm_per_min
                                                                            : fallback_mm_min));
  }
  return feed;
}

/// The metric feeds of a pass's moves: the move from point i to i + 1 runs at point i + 1's.
std::vector<double> pass_feeds(const std::vector<double>& metric_feed, const IndexRange& pass) {
  return std::vector<double>(metric_feed.begin() + static_cast<long>(pass.begin) + 1,
                             metric_feed.begin() + static_cast<long>(pass.end));
}

/// The paper's L_i of a pass, from point i to i + 1: between contact points where both ends
/// touch the part, else between reference points. The metrics and the optimiser share them.
std::vector<double> segment_lengths_mm(const Operationd& op,
                                       const std::vector<ContactPoint>& contacts,
                                       double ball_radius_mm, const IndexRange& pass) {
  std::vector<double> len;
  for (std::size_t i = pass.begin; i + 1 < pass.end; ++i) {
    const bool cc = !contacts.empty() && contacts[i].state == ContactState::Touching &&
                    contacts[i + 1].state == ContactState::Touching;
    len.push_back(cc ? (contacts[i + 1].cc_mm - contacts[i].cc_mm).norm()
                     : (reference_point(op.points[i + 1], ball_radius_mm) -
                        reference_point(op.points[i], ball_radius_mm))
                           .norm());
  }
  return len;
}

/// Rotary kinematics of every pass of an operation; fills rows' omega/accel/arc when given.
/// Segment lengths are the paper's L_i between contact points where both ends touch the
/// part, else between reference points.
RotarySummary summarise(const Operationd& op, const std::vector<ContactPoint>& contacts,
                        double ball_radius_mm, const std::vector<double>& a_deg,
                        const std::vector<double>& c_deg, const std::vector<double>& metric_feed,
                        std::vector<PointRow>* rows, bool rows_before = false) {
  RotarySummary summary;
  double arc = 0.0;
  for (const IndexRange& pass : feed_passes(op)) {
    std::vector<double> a(a_deg.begin() + static_cast<long>(pass.begin),
                          a_deg.begin() + static_cast<long>(pass.end));
    std::vector<double> c(c_deg.begin() + static_cast<long>(pass.begin),
                          c_deg.begin() + static_cast<long>(pass.end));
    const std::vector<double> len = segment_lengths_mm(op, contacts, ball_radius_mm, pass);
    const RotaryKinematics k = rotary_kinematics(a, c, len, pass_feeds(metric_feed, pass));
    accumulate(summary, k, c);
    if (rows) {
      for (std::size_t j = 0; j < pass.size(); ++j) {
        PointRow& r = (*rows)[pass.begin + j];
        if (j > 0) arc += len[j - 1];
        r.arc_mm = arc;
        (rows_before ? r.omega_before_deg_s : r.omega_deg_s) = k.omega_deg_s[j];
        (rows_before ? r.accel_before_deg_s2 : r.accel_deg_s2) = k.accel_deg_s2[j];
      }
    }
  }
  return summary;
}

/// Joint positions (X Y Z mm, A C deg) of tips and poses: the machine-mode convention of
/// CLI.md, which is where the joints are whatever the G-code mode.
std::vector<JointPosition> joints_of(const ACMachined& ac, const std::vector<Vec3d>& tips_mm,
                                     const std::vector<Posed>& poses) {
  std::vector<JointPosition> q(tips_mm.size());
  for (std::size_t i = 0; i < q.size(); ++i) {
    const Vec3d m = ac.to_machine_mm(tips_mm[i], poses[i]);
    q[i] = {m.x(), m.y(), m.z(), rad_to_deg(poses[i].a_rad), rad_to_deg(poses[i].c_rad)};
  }
  return q;
}

/// The chains of feed moves of an operation: runs [begin, end) of points i >= 1 reached by a
/// feed move; a chain's joints are those of points begin - 1 .. end - 1.
std::vector<IndexRange> feed_chains(const std::vector<CLPointd>& points) {
  std::vector<IndexRange> chains;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].motion != Motion::Feed) continue;
    if (chains.empty() || chains.back().end != i) chains.push_back(IndexRange{i, i});
    chains.back().end = i + 1;
  }
  return chains;
}

/// An operation's feed schedule: per point the scheduled time of the move into it (0 for
/// rapids and the first point), the feed it reaches, and the summary.
struct OperationSchedule {
  std::vector<double> time_s;
  std::vector<std::optional<double>> feed_mm_min;
  FeedSummary summary;
};

OperationSchedule schedule_operation(const std::vector<CLPointd>& points,
                                     const std::vector<JointPosition>& joints,
                                     const std::vector<double>& programmed_s,
                                     const JointLimits& limits, const ACMachined& ac) {
  OperationSchedule out;
  const std::size_t n = points.size();
  out.time_s.assign(n, 0.0);
  out.feed_mm_min.assign(n, std::nullopt);
  std::vector<FeedBound> bound(n, FeedBound::Programmed);
  std::vector<Joint> bound_joint(n, Joint::X);
  for (const IndexRange& c : feed_chains(points)) {
    FeedChain chain;
    chain.joints = slice(joints, c.begin - 1, c.end);
    chain.min_time_s = slice(programmed_s, c.begin, c.end);
    const FeedSchedule s = schedule_feed(chain, limits);
    out.summary.sweeps = std::max(out.summary.sweeps, s.sweeps);
    for (std::size_t i = c.begin; i < c.end; ++i) {
      out.time_s[i] = s.time_s[i - c.begin];
      bound[i] = s.bound[i - c.begin];
      bound_joint[i] = s.bound_joint[i - c.begin];
    }
  }
  FeedSummary& sum = out.summary;
  double path_mm = 0.0, limited_mm = 0.0;
  std::array<double, kJointCount> by_velocity{}, by_accel{};
  bool any_feed = false;
  for (std::size_t i = 1; i < n; ++i) {
    if (points[i].motion == Motion::Rapid) {
      const double t = rapid_time_s(joints[i - 1], joints[i], limits);
      // The same move without the turn: the rotary joints held where the move starts, the
      // linear ones taking the tip to its point under that pose.
      constexpr std::size_t kA = static_cast<std::size_t>(Joint::A);
      constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
      const Posed start{deg_to_rad(joints[i - 1][kA]), deg_to_rad(joints[i - 1][kC])};
      const Vec3d xyz = ac.to_machine_mm(points[i].tip_mm, start);
      const JointPosition held = {xyz.x(), xyz.y(), xyz.z(), joints[i - 1][kA], joints[i - 1][kC]};
      sum.rapid_time_s += t;
      sum.transition_excess_s += std::max(0.0, t - rapid_time_s(joints[i - 1], held, limits));
      continue;
    }
    if (!(out.time_s[i] > 0.0)) continue;
    sum.feed_time_s += out.time_s[i];
    const double feed = points[i].feed_mm_per_min * programmed_s[i] / out.time_s[i];
    out.feed_mm_min[i] = feed;
    sum.min_feed_mm_min = any_feed ? std::min(sum.min_feed_mm_min, feed) : feed;
    any_feed = true;
    const double len = (points[i].tip_mm - points[i - 1].tip_mm).norm();
    path_mm += len;
    if (out.time_s[i] > programmed_s[i] * (1.0 + 1e-9)) {
      limited_mm += len;
      const std::size_t j = static_cast<std::size_t>(bound_joint[i]);
      (bound[i] == FeedBound::Velocity ? by_velocity : by_accel)[j] += len;
    }
  }
  sum.cycle_time_s = sum.feed_time_s + sum.rapid_time_s;
  sum.feed_limited_fraction = path_mm > 0.0 ? limited_mm / path_mm : 0.0;
  sum.feed_path_mm = path_mm;
  double most = 0.0;
  for (std::size_t j = 0; j < kJointCount; ++j) {
    for (const auto& [share, kind] : {std::pair<double, const char*>{by_velocity[j], "velocity"},
                                      {by_accel[j], "acceleration"}}) {
      if (share > most) {
        most = share;
        sum.limiting_axis = joint_name(static_cast<Joint>(j), ac.tilt_letter());
        sum.limiting_kind = kind;
      }
    }
  }
  return out;
}

/// Indices of the points of `op` whose tool collides, for axes `axes` (tips from the fixed
/// ball centres). In parallel; the result is sorted, whatever the thread count.
std::vector<std::size_t> colliding_points(const PartCheck& model, const ToolModel& tool,
                                          const Operationd& op, const std::vector<Vec3d>& axes,
                                          const std::vector<ContactPoint>& contacts,
                                          detail::StageProgress* progress = nullptr,
                                          const std::vector<char>* only = nullptr) {
  const double R = tool.ball_radius_mm;
  return detail::parallel_select(0, op.points.size(), [&](std::size_t i) {
    if (only && !(*only)[i]) return false;
    const Vec3d centre = op.points[i].tip_mm + R * op.points[i].axis;
    const bool in_air = contacts.empty() || contacts[i].state != ContactState::Touching;
    const bool hit = model.collides(tool, centre, axes[i], in_air);
    if (progress) progress->advance();
    return hit;
  });
}

/// A guaranteed lower bound of the least distance between the part and the tool's bodies that
/// do not cut (shank and holder, past the flutes; the flutes touch the part at a contact by
/// design) over the CL points with axes `axes`, and the point where it occurs; empty when the
/// tool has no such bodies. The bodies grown by d in radius and at both ends hold every point
/// within d of them, so where the grown bodies miss the part the clearance is at least d (and
/// at most d sqrt 2). d comes from bisecting FCL collision queries (exact distances cost 5 ms to
/// 0.3 s a query on flat parts): at 32 spread points first, then only at the points whose
/// bodies, grown by that bound, touch the part. Capped at 10 mm, 5 um steps; the same result
/// whatever the thread count.
std::optional<std::pair<double, std::size_t>> clearance_bound(const CollisionModel& model,
                                                              const ToolModel& tool,
                                                              const Operationd& op,
                                                              const std::vector<Vec3d>& axes,
                                                              detail::StageProgress* progress) {
  constexpr double kCapMm = 10.0, kStepMm = 0.005;
  const std::size_t n = op.points.size();
  ToolModel above = tool;
  if (!above.bodies.empty()) above.bodies.erase(above.bodies.begin());
  if (above.bodies.empty() || n == 0) {
    if (progress) progress->advance(n);
    return std::nullopt;
  }
  const auto free_at = [&](std::size_t i, double d_mm) {
    ToolModel grown = above;
    for (ToolBody& b : grown.bodies) {
      b.radius_mm += d_mm;
      b.start_mm -= d_mm;
      b.end_mm += d_mm;
    }
    return !model.collides(grown, reference_point(op.points[i], tool.ball_radius_mm), axes[i]);
  };
  // The largest d in [0, hi] (to kStepMm) with the grown bodies free at point i.
  const auto bisect = [&](std::size_t i, double hi) {
    if (!free_at(i, 0.0)) return 0.0;
    if (free_at(i, hi)) return hi;
    double lo = 0.0;
    while (hi - lo > kStepMm) {
      const double mid = 0.5 * (lo + hi);
      (free_at(i, mid) ? lo : hi) = mid;
    }
    return lo;
  };
  using Least = std::pair<double, std::size_t>;
  const auto least_over = [&](const std::vector<std::size_t>& at, double hi) {
    return detail::parallel_reduce(
        0, at.size(), Least{hi, n},
        [&](std::size_t lo, std::size_t end, Least acc) {
          for (std::size_t j = lo; j != end; ++j)
            acc = std::min(acc, Least{bisect(at[j], hi), at[j]});
          return acc;
        },
        [](const Least& a, const Least& b) { return std::min(a, b); });
  };
  std::vector<std::size_t> sample;
  for (std::size_t k = 0; k < 32; ++k) sample.push_back(k * (n - 1) / 31);
  sample.erase(std::unique(sample.begin(), sample.end()), sample.end());
  Least bound = least_over(sample, kCapMm);
  if (bound.second == n) bound.second = sample.front();  // every sample at the cap
  const std::vector<std::size_t> closer = detail::parallel_select(0, n, [&](std::size_t i) {
    const bool near = bound.first > 0.0 && !free_at(i, bound.first);
    if (progress) progress->advance();
    return near;
  });
  const Least found = least_over(closer, bound.first);
  return found.second == n ? bound : std::min(bound, found);
}

/// Index i of every move from point i-1 to point i during which the tool hits the part, with
/// the machine moving linearly in its joints between the values written (`xyz_w` as written,
/// `a_deg`/`c_deg`). Samples at most 0.5 deg and 0.1 mm apart. Between two contact points
/// only the bodies above the ball are checked (the ball's path between contacts is the CAM
/// system's chord tolerance); where either end is in the air, the ball too.
/// One written position on the way between two points (a linearisation block): X Y Z as
/// written (machine or tip by the mode), A and C in degrees.
struct WayPoint {
  Vec3d xyz = Vec3d::Zero();
  double a_deg = 0.0, c_deg = 0.0;
};

std::vector<std::size_t> colliding_moves(
    const PartCheck& model, const ToolModel& tool, const Machine& machine,
    const std::vector<Vec3d>& xyz_w, const std::vector<double>& a_deg,
    const std::vector<double>& c_deg, const std::vector<ContactPoint>& contacts,
    detail::StageProgress* progress = nullptr,
    const std::vector<std::vector<WayPoint>>* between = nullptr,
    const std::vector<char>* only = nullptr) {
  const double R = tool.ball_radius_mm;
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
    // The move as the machine runs it: joint-linear between the written blocks.
    std::vector<WayPoint> chain = {{xyz_w[i - 1], a_deg[i - 1], c_deg[i - 1]}};
    if (between && i < between->size()) {
      chain.insert(chain.end(), (*between)[i].begin(), (*between)[i].end());
    }
    chain.push_back({xyz_w[i], a_deg[i], c_deg[i]});
    for (std::size_t k = 1; k < chain.size(); ++k) {
      const WayPoint &p0 = chain[k - 1], &p1 = chain[k];
      const double da = p1.a_deg - p0.a_deg, dc = p1.c_deg - p0.c_deg;
      const double dx = (p1.xyz - p0.xyz).norm();
      const int steps = static_cast<int>(
          std::ceil(std::max({std::abs(da) / 0.5, std::abs(dc) / 0.5, dx / 0.1, 1.0})));
      for (int s = (k == 1 ? 1 : 0); s < steps; ++s) {
        const double t = static_cast<double>(s) / steps;
        const Posed pose{deg_to_rad(p0.a_deg + t * da), deg_to_rad(p0.c_deg + t * dc)};
        const Vec3d xyz = p0.xyz + t * (p1.xyz - p0.xyz);
        const Vec3d tip = tip_of_written_mm(machine, xyz, pose);
        const Vec3d axis = machine.ac.forward(pose);
        if (model.collides(tool, tip + R * axis, axis, in_air)) {
          return true;
        }
      }
    }
    return false;
  });
}

/// The axes of one operation after the paper's optimiser, and what it did.
struct OptimisedOperation {
  std::vector<Vec3d> axes;
  std::size_t intervals = 0, repairs = 0, smoothed_joints = 0, sharp_joints = 0;
  /// Stretches near the pole A = 0 whose C was re-planned (pole_passage.hpp).
  std::size_t pole_stretches = 0;
  /// Key points (ends of the optimiser's intervals), indices into the operation, ascending.
  std::vector<std::size_t> keys;
  /// What the guard after the paper's optimiser gave back their input axes.
  StretchGuardResult guard;
  /// Points with no acceptable axis within the cone (they keep their input axis).
  std::vector<std::size_t> no_free_axis;
  /// --method global: per point the pose it chose (branch, C on the pole), for plan_poses;
  /// empty otherwise. Passes refined by it, and given back the paper's axes by its guard.
  std::vector<std::optional<Posed>> preferred;
  std::size_t global_passes = 0;
  /// What the guard after --method global gave back the paper's axes.
  StretchGuardResult global_guard;
};

/// The cut of a pass: from its first to its last point where the ball touches the part (empty
/// when it never does); the whole pass without contacts (no part).
IndexRange contact_span(const std::vector<ContactPoint>& contacts, const IndexRange& pass) {
  if (contacts.empty()) return pass;
  IndexRange span{pass.end, pass.end};
  for (std::size_t i = pass.begin; i < pass.end; ++i) {
    if (contacts[i].state != ContactState::Touching) continue;
    if (span.begin == pass.end) span.begin = i;
    span.end = i + 1;
  }
  return span.begin == pass.end ? IndexRange{pass.begin, pass.begin} : span;
}

/// Whether an axis is acceptable at point i of an operation: the machine reaches it and, with
/// a part, the tool above the ball (and the ball, where it is in the air) misses the part.
struct Acceptance {
  const Operationd& op;
  const std::vector<ContactPoint>& contacts;
  double ball_radius_mm;
  const PartCheck* model;
  const ToolModel* tool;
  const ACMachined& machine;
  /// The deviation cone's half-angle, rad (--max-deviation).
  double max_deviation_rad;
  bool operator()(std::size_t i, const Vec3d& axis) const {
    if (!machine.reachable(axis)) return false;
    if (!model) return true;
    const bool in_air = contacts.empty() || contacts[i].state != ContactState::Touching;
    return !model->collides(*tool, reference_point(op.points[i], ball_radius_mm), axis, in_air);
  }
  /// Acceptable and within the cone around point i's input axis.
  bool in_cone(std::size_t i, const Vec3d& axis) const {
    return angle_between(axis, op.points[i].axis) <= max_deviation_rad + 1e-12 && (*this)(i, axis);
  }
};

/// Point `to` takes the axis (and the preferred pose, if any) of point `from`, where that axis
/// is within its cone and acceptable.
void carry_axis(OptimisedOperation& out, const Acceptance& acceptable, std::size_t to,
                std::size_t from) {
  if (!acceptable.in_cone(to, out.axes[from])) return;
  out.axes[to] = out.axes[from];
  if (!out.preferred.empty()) out.preferred[to] = out.preferred[from];
}

/// The points of `pass` in the air before its cut (an approach) and after it (a retract) take
/// the axis of the cut's first and last point (`carry(to, from)`, which checks): the tool comes
/// down and leaves along the orientation it cuts with, as CAM systems do, and does not turn on
/// the way (which the points alone would not check).
template <class Carry>
void carry_from_cut(const IndexRange& pass, const IndexRange& cut, Carry&& carry) {
  if (cut.size() == 0) return;
  for (std::size_t i = cut.begin; i-- > pass.begin;) carry(i, i + 1);
  for (std::size_t i = cut.end; i < pass.end; ++i) carry(i, i - 1);
}

/// Per point, whether the move into it is a rapid (the first point counts as one).
std::vector<bool> rapid_into_of(const Operationd& op) {
  std::vector<bool> rapid_into;
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    rapid_into.push_back(i == 0 || op.points[i].motion == Motion::Rapid);
  }
  return rapid_into;
}

/// The points outside every pass (retracts, rapids between passes) turn the tool from one
/// pass's last axis to the next one's first in a single move, the one of the run with the
/// longest tip travel (on a clearance plane the rotation then costs no time beside the
/// traverse): the points before that move keep the axis of the point before them, those from
/// it on take the axis of the point after them (`carry(to, from)`, which checks).
template <class Carry>
void carry_between_passes(const Operationd& op, const std::vector<IndexRange>& passes,
                          Carry&& carry) {
  std::vector<char> in_pass(op.points.size(), 0);
  for (const IndexRange& pass : passes) {
    std::fill(in_pass.begin() + static_cast<long>(pass.begin),
              in_pass.begin() + static_cast<long>(pass.end), 1);
  }
  const std::size_t n = op.points.size();
  for (std::size_t a = 0; a < n;) {
    if (in_pass[a]) {
      ++a;
      continue;
    }
    std::size_t b = a;  // the run is [a, b)
    while (b < n && !in_pass[b]) ++b;
    if (a == 0 && b == n) break;  // no pass at all
    // Moves into points a .. b (those that exist): the turn goes into the longest one.
    std::size_t turn = a == 0 ? 0 : b;
    if (a > 0 && b < n) {
      double longest = -1.0;
      for (std::size_t j = a; j <= b; ++j) {
        const double travel = (op.points[j].tip_mm - op.points[j - 1].tip_mm).norm();
        if (travel > longest) longest = travel, turn = j;
      }
    }
    for (std::size_t i = a; i < turn; ++i) carry(i, i - 1);
    for (std::size_t i = b; i-- > turn;) carry(i, i + 1);  // turn == b when b == n
    a = b;
  }
}

/// Runs plan_pass_paper on every feed pass of `op` (in parallel over passes; each pass is
/// planned alone, so the result does not depend on the thread count). An axis is acceptable
/// when the machine reaches it and, with a part, the tool above the ball (and the ball, where
/// it is in the air) misses the part. Points outside the feed passes keep their axes. Then
/// each pass's stretches near the pole get C re-planned in machine space (pole_passage.hpp).
OptimisedOperation optimise_paper(const Operationd& op, const std::vector<ContactPoint>& contacts,
                                  double ball_radius_mm, const PartCheck* model,
                                  const ToolModel* tool, const Machine& machine,
                                  const std::vector<double>& metric_feed,
                                  const PosePlanOptions& pose_options, const PaperOptions& options,
                                  detail::StageProgress& progress) {
  OptimisedOperation out;
  for (const CLPointd& p : op.points) out.axes.push_back(p.axis);
  const std::vector<IndexRange> passes = feed_passes(op);
  std::vector<PassPlan> plans(passes.size());
  std::vector<std::size_t> pole_stretches(passes.size(), 0);
  const double R = ball_radius_mm;
  const double max_dev_rad = deg_to_rad(options.max_deviation_deg);
  const auto touching = [&](std::size_t i) {
    return !contacts.empty() && contacts[i].state == ContactState::Touching;
  };
  const Acceptance acceptable_at{op, contacts, R, model, tool, machine.ac, max_dev_rad};
  detail::parallel_for(std::size_t(0), passes.size(), [&](std::size_t q) {
    const detail::StageProgress::Step step(progress);
    const IndexRange pass = passes[q];
    PassProblem problem;
    problem.segment_mm = segment_lengths_mm(op, contacts, R, pass);
    Vec3d mean = Vec3d::Zero();
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      problem.input_axes.push_back(op.points[i].axis);
      mean += op.points[i].axis;
    }
    problem.up = mean.norm() > 1e-9 ? Vec3d(mean.normalized()) : Vec3d::UnitZ();
    // The curve of the segmenter: the contact points; where the ball is in the air, the ball
    // centre offset by the normal of the nearest contact point (no jump of R at an approach);
    // without any contact, the ball centres (an offset of the contact curve).
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      const Vec3d centre = reference_point(op.points[i], R);
      if (touching(i)) {
        problem.curve_mm.push_back(contacts[i].cc_mm);
        continue;
      }
      std::optional<Vec3d> normal;
      for (std::size_t d = 1; !normal && d < pass.size(); ++d) {
        if (i >= pass.begin + d && touching(i - d)) normal = contacts[i - d].normal;
        if (i + d < pass.end && touching(i + d)) normal = contacts[i + d].normal;
      }
      problem.curve_mm.push_back(normal ? Vec3d(centre - R * *normal) : centre);
    }
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at(pass.begin + j, axis);
    };
    PassPlan plan = plan_pass_paper(problem, acceptable, options);
    std::vector<bool> rapid_into(pass.size(), false);
    rapid_into[0] = true;
    const PosePlan poses = plan_poses(machine.ac, plan.axes, rapid_into, {}, pose_options);
    if (poses.ok()) {
      const AxisTest in_cone = [&](std::size_t j, const Vec3d& axis) {
        return acceptable_at.in_cone(pass.begin + j, axis);
      };
      PolePassage pole =
          smooth_pole_passages(machine.ac, plan.axes, poses.poses, problem.segment_mm,
                               pass_feeds(metric_feed, pass), in_cone);
      plan.axes = std::move(pole.axes);
      pole_stretches[q] = pole.stretches;
    }
    plans[q] = std::move(plan);
  });
  for (std::size_t q = 0; q < passes.size(); ++q) {
    const PassPlan& plan = plans[q];
    std::copy(plan.axes.begin(), plan.axes.end(),
              out.axes.begin() + static_cast<long>(passes[q].begin));
    out.intervals += plan.intervals();
    out.repairs += plan.repairs;
    out.smoothed_joints += plan.smoothed_joints;
    out.sharp_joints += plan.sharp_joints;
    out.pole_stretches += pole_stretches[q];
    for (std::size_t j : plan.keys) out.keys.push_back(passes[q].begin + j);
    for (std::size_t j : plan.no_free_axis) out.no_free_axis.push_back(passes[q].begin + j);
  }
  const auto carry = [&](std::size_t to, std::size_t from) {
    carry_axis(out, acceptable_at, to, from);
  };
  for (const IndexRange& pass : passes) carry_from_cut(pass, contact_span(contacts, pass), carry);
  carry_between_passes(op, passes, carry);
  return out;
}

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
    a.push_back(rad_to_deg(poses[i].a_rad));
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

/// The guard after the optimiser (plan/stretch_guard.hpp): where the optimised axes would
/// raise a pass's peak omega or a, or sweep the tool through the part between two CL points as
/// the machine moves it, the pass keeps its input axes over those stretches, provided the
/// input pass is itself safe; whole when a few rounds of joins do not make it good.
/// With `reference` given (--method global against the paper's axes, with its preferred poses)
/// the stretches keep those instead, when the peak a rises or the moves hit.
/// With `rates` false (--objective time, whose objective is the schedule, not the peaks) only
/// the moves that hit give stretches back.
struct GuardReference {
  std::vector<Vec3d> axes;
  std::vector<std::optional<Posed>> preferred;
  bool rates = true;
};

StretchGuardResult guard_passes(const Operationd& op, const std::vector<ContactPoint>& contacts,
                                double ball_radius_mm, const PartCheck* model,
                                const ToolModel* tool, const Machine& machine,
                                const std::vector<double>& metric_feed,
                                const PosePlanOptions& pose_options, OptimisedOperation& out,
                                const GuardReference* reference = nullptr) {
  const std::size_t n = op.points.size();
  const std::vector<bool> rapid_into = rapid_into_of(op);
  std::vector<Vec3d> in_axes;
  for (const CLPointd& p : op.points) in_axes.push_back(p.axis);
  if (reference) in_axes = reference->axes;
  const std::vector<std::optional<Posed>> in_preferred =
      reference ? reference->preferred : std::vector<std::optional<Posed>>{};
  const PosePlan in_plan =
      plan_poses(machine.ac, in_axes, rapid_into, {}, pose_options, in_preferred);
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
      a.push_back(rad_to_deg(poses[i].a_rad));
      c.push_back(rad_to_deg(poses[i].c_rad));
    }
    PassRates r{rotary_kinematics(a, c, segment_lengths_mm(op, contacts, ball_radius_mm, pass),
                                  pass_feeds(metric_feed, pass)),
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
        plan_poses(machine.ac, axes, rapid_into, {}, pose_options, preferred_of(why));
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

/// What --objective time adds to an operation's passes: the least time of the move into every
/// point (its programmed feed), the machine's limits, and whole-operation pose sequences each
/// pass weighs beside the paper's (the sum-squares plan, the input's).
struct TimeContext {
  std::vector<double> programmed_s;
  JointLimits limits{};
  std::vector<std::vector<Posed>> alternatives;
};

/// --method global (global_optimiser.hpp) on every feed pass of `op`, from the paper's axes in
/// `out` (the warm start), in parallel over passes. The points between passes then follow the
/// new pass ends; a guard gives a pass back the paper's axes (or `reference`'s) where its peak
/// a would rise or its moves would hit the part. With `time` (--objective time) the passes get
/// their joints, programmed times and alternatives from it.
void refine_global(const Operationd& op, const std::vector<ContactPoint>& contacts,
                   double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                   const Machine& machine, const std::vector<double>& metric_feed,
                   const PosePlanOptions& pose_options, const GlobalOptions& options,
                   OptimisedOperation& out, detail::StageProgress& progress,
                   const TimeContext* time = nullptr, const GuardReference* reference = nullptr) {
  const std::size_t n = op.points.size();
  const std::vector<IndexRange> passes = feed_passes(op);
  const PosePlan warm = plan_poses(machine.ac, out.axes, rapid_into_of(op), {}, pose_options);
  if (!warm.ok()) {
    for (std::size_t q = 0; q < passes.size(); ++q) progress.advance();
    return;
  }
  const GuardReference paper{out.axes, {}};
  const Acceptance acceptable_at{
      op, contacts, ball_radius_mm, model, tool, machine.ac, deg_to_rad(options.max_deviation_deg)};
  std::vector<std::optional<GlobalPassPlan>> plans(passes.size());
  std::vector<IndexRange> cut(passes.size());
  detail::parallel_for(std::size_t(0), passes.size(), [&](std::size_t q) {
    // The cut: from the first to the last contact of the pass (all of it without a part). The
    // points in the air before and after keep the axis of the nearest contact, as with the
    // paper method: the tool comes down and leaves along the axis it cuts with.
    const detail::StageProgress::Step step(progress);
    const IndexRange pass = contact_span(contacts, passes[q]);
    if (pass.size() < 3) return;
    cut[q] = pass;
    GlobalPassProblem problem;
    std::vector<double> a_deg, c_deg;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      problem.input_axes.push_back(op.points[i].axis);
      problem.warm_start.push_back(warm.poses[i]);
      a_deg.push_back(rad_to_deg(warm.poses[i].a_rad));
      c_deg.push_back(rad_to_deg(warm.poses[i].c_rad));
    }
    // The metrics' segment times; a move too short to time gets a floor (it would divide).
    problem.segment_time_s = segment_times_s(segment_lengths_mm(op, contacts, ball_radius_mm, pass),
                                             pass_feeds(metric_feed, pass), a_deg, c_deg);
    for (double& t : problem.segment_time_s) t = std::max(t, 1e-6);
    const AxisTest acceptable = [&](std::size_t j, const Vec3d& axis) {
      return acceptable_at.in_cone(pass.begin + j, axis);
    };
    if (time) {
      // The machine's joints of a pose (the schedule's, whatever the G-code mode): the tip
      // under the fixed ball centre, carried by the table.
      problem.joints_at = [&op, &machine, ball_radius_mm, b = pass.begin](std::size_t j,
                                                                          const Posed& pose) {
        const Vec3d tip = tip_for_axis(op.points[b + j], ball_radius_mm, machine.ac.forward(pose));
        const Vec3d xyz = machine.ac.to_machine_mm(tip, pose);
        return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.a_rad),
                             rad_to_deg(pose.c_rad)};
      };
      problem.programmed_time_s = slice(time->programmed_s, pass.begin + 1, pass.end);
      problem.limits = time->limits;
      for (const std::vector<Posed>& alt : time->alternatives) {
        std::vector<Posed> poses = slice(alt, pass.begin, pass.end);
        bool ok = true;
        for (std::size_t j = 0; ok && j < poses.size(); ++j) {
          ok = machine.ac.a.contains(poses[j].a_rad) && acceptable(j, machine.ac.forward(poses[j]));
        }
        if (ok) problem.alternatives.push_back(std::move(poses));
      }
    }
    plans[q] = plan_pass_global(machine.ac, problem, acceptable, options);
  });
  out.preferred.assign(n, std::nullopt);
  const auto carry = [&](std::size_t to, std::size_t from) {
    carry_axis(out, acceptable_at, to, from);
  };
  for (std::size_t q = 0; q < passes.size(); ++q) {
    if (!plans[q]) continue;
    ++out.global_passes;
    for (std::size_t j = 0; j < cut[q].size(); ++j) {
      out.axes[cut[q].begin + j] = plans[q]->axes[j];
      out.preferred[cut[q].begin + j] = plans[q]->poses[j];
    }
    carry_from_cut(passes[q], cut[q], carry);
  }
  carry_between_passes(op, passes, carry);
  out.global_guard = guard_passes(op, contacts, ball_radius_mm, model, tool, machine, metric_feed,
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
    return tip_for_axis(op.points[i], ball_radius_mm, machine.ac.forward(pose));
  };
  const auto joints_at = [&](std::size_t i, const Posed& pose) {
    const Vec3d xyz = machine.ac.to_machine_mm(tip_at(i, pose), pose);
    return JointPosition{xyz.x(), xyz.y(), xyz.z(), rad_to_deg(pose.a_rad), rad_to_deg(pose.c_rad)};
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
    const double turn_rad = std::abs(to.a_rad - from.a_rad) + std::abs(to.c_rad - from.c_rad);
    for (std::size_t j = first; j <= b; ++j) {
      const double turned = std::abs(po.poses[j].a_rad - po.poses[j - 1].a_rad) +
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
        cand[j - first + 1] = Posed{from.a_rad + f * (to.a_rad - from.a_rad),
                                    from.c_rad + f * (to.c_rad - from.c_rad)};
      }
      return cand;
    };
    std::vector<std::vector<double>> starts = {now};
    const std::vector<double> by_capacity =
        spread_turn(linear_s, rapid, rad_to_deg(to.a_rad - from.a_rad),
                    rad_to_deg(to.c_rad - from.c_rad), limits);
    if (!by_capacity.empty()) starts.push_back(by_capacity);
    const std::vector<double> share = best_turn_shares(
        starts, rapid,
        [&](const std::vector<double>& sh) { return chain_time(first, b, poses_for(sh)); });
    const std::vector<Posed> cand = poses_for(share);
    bool ok = true;
    for (std::size_t j = first; j < b && ok; ++j) {
      const Posed& pose = cand[j - first + 1];
      ok =
          angle_between(machine.ac.forward(pose), op.points[j].axis) <= max_deviation_rad + 1e-12 &&
          machine.ac.a.contains(pose.a_rad) &&
          (machine.ac.c.continuous || machine.ac.c.contains(pose.c_rad));
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
    std::vector<double> a_deg, c_deg;
    for (std::size_t i = 0; i < n; ++i) {
      axes.push_back(machine.ac.forward(trial[i]));
      const Vec3d tip = tip_at(i, trial[i]);
      xyz.push_back(written_xyz_mm(machine, tip, trial[i]));
      a_deg.push_back(rad_to_deg(trial[i].a_rad));
      c_deg.push_back(rad_to_deg(trial[i].c_rad));
    }
    std::vector<ContactPoint> air(n);  // no contacts known: every point in the air
    const std::vector<ContactPoint>& state = contacts.empty() ? air : contacts;
    std::vector<char> hit(n, 0);
    for (std::size_t i : colliding_points(*model, tool, op, axes, state, nullptr, &check_point)) {
      hit[i] = 1;
    }
    for (std::size_t i : colliding_moves(*model, tool, machine, xyz, a_deg, c_deg, state, nullptr,
                                         nullptr, &check_move)) {
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
    if (trial[i].a_rad == po.poses[i].a_rad && trial[i].c_rad == po.poses[i].c_rad) continue;
    po.points[i].axis = machine.ac.forward(trial[i]);
    po.points[i].tip_mm = tip_for_axis(op.points[i], ball_radius_mm, po.points[i].axis);
  }
  po.poses = std::move(trial);
}

/// The feed points of `op` as posted: feed moves without a feed get `fallback_feed`.
std::vector<CLPointd> posted_feeds(const Operationd& op, double fallback_feed) {
  std::vector<CLPointd> points = op.points;
  for (CLPointd& p : points) {
    if (!(p.feed_mm_per_min > 0.0)) p.feed_mm_per_min = fallback_feed;
  }
  return points;
}

/// An operation's scheduled cycle (feed moves and rapids at the machine's effective limits)
/// with tool axes `axes` about the fixed ball centres, posed as run_job poses them (the turns
/// between passes in one move); `programmed_s` the least time of every move. Infinite when the
/// axes cannot be posed.
double operation_cycle_s(const Operationd& op, const std::vector<ContactPoint>& contacts,
                         double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                         const Machine& machine, double max_deviation_rad,
                         const std::vector<Vec3d>& axes,
                         const std::vector<std::optional<Posed>>& preferred,
                         const PosePlanOptions& pose_options, double fallback_feed,
                         const std::vector<double>& programmed_s) {
  const PosePlan plan =
      plan_poses(machine.ac, axes, rapid_into_of(op), {}, pose_options, preferred);
  if (!plan.ok()) return std::numeric_limits<double>::infinity();
  PostedOperation po;
  po.points = posted_feeds(op, fallback_feed);
  po.poses = plan.poses;
  for (std::size_t i = 0; i < po.points.size(); ++i) {
    po.points[i].axis = axes[i];
    po.points[i].tip_mm = tip_for_axis(op.points[i], ball_radius_mm, axes[i]);
  }
  spread_turns_in_air(op, contacts, ball_radius_mm, model, tool ? *tool : ToolModel{}, machine,
                      max_deviation_rad, po);
  std::vector<Vec3d> tips;
  for (const CLPointd& p : po.points) tips.push_back(p.tip_mm);
  const std::vector<double> programmed = machine.gcode.feed_reference == FeedReference::CutterPath
                                             ? programmed_s
                                             : programmed_block_times_s(po.points, po.poses);
  return schedule_operation(po.points, joints_of(machine.ac, tips, po.poses), programmed,
                            effective_limits(machine), machine.ac)
      .summary.cycle_time_s;
}

/// --method global --objective time (docs/global-method.md): the sum-squares plan first (a
/// start and an alternative every pass weighs, and the reference of the guard, which gives it
/// back over stretches whose moves hit), then every pass planned for its scheduled time; of
/// the paper's, the sum-squares and the time plan the operation keeps the one with the
/// shortest scheduled cycle (ties to the sum-squares plan, then the paper's). `out` holds the
/// paper's plan on entry. The input's axes are kept instead where their cycle is shorter still
/// and none of their points or moves hits the part. Returns a line for the log.
std::string refine_time(const Operationd& op, const std::vector<ContactPoint>& contacts,
                        double ball_radius_mm, const PartCheck* model, const ToolModel* tool,
                        const Machine& machine, const std::vector<double>& metric_feed,
                        const PosePlanOptions& pose_options, const GlobalOptions& options,
                        double fallback_feed, OptimisedOperation& out,
                        detail::StageProgress& progress) {
  const OptimisedOperation paper = out;
  OptimisedOperation smooth = out;
  GlobalOptions sum_squares = options;
  sum_squares.objective = GlobalObjective::SumSquares;
  refine_global(op, contacts, ball_radius_mm, model, tool, machine, metric_feed, pose_options,
                sum_squares, smooth, progress);
  const std::vector<bool> rapid_into = rapid_into_of(op);
  std::vector<Vec3d> in_axes;
  for (const CLPointd& p : op.points) in_axes.push_back(p.axis);
  const PosePlan in_plan = plan_poses(machine.ac, in_axes, rapid_into, {}, pose_options);
  const PosePlan smooth_plan =
      plan_poses(machine.ac, smooth.axes, rapid_into, {}, pose_options, smooth.preferred);
  TimeContext time;
  time.limits = effective_limits(machine);
  // Every feed block keeps the time the input block takes at its feed (cutter-path), as
  // posted; with the tip-path reference that time moves with the tip (the input's here).
  time.programmed_s = programmed_block_times_s(posted_feeds(op, fallback_feed),
                                               in_plan.ok() ? in_plan.poses : smooth_plan.poses);
  if (smooth_plan.ok()) time.alternatives.push_back(smooth_plan.poses);
  if (in_plan.ok()) time.alternatives.push_back(in_plan.poses);
  OptimisedOperation fast = out;
  const GuardReference reference{smooth.axes, smooth.preferred, false};
  refine_global(op, contacts, ball_radius_mm, model, tool, machine, metric_feed, pose_options,
                options, fast, progress, &time, &reference);
  const auto cycle = [&](const OptimisedOperation& o) {
    return operation_cycle_s(op, contacts, ball_radius_mm, model, tool, machine,
                             deg_to_rad(options.max_deviation_deg), o.axes, o.preferred,
                             pose_options, fallback_feed, time.programmed_s);
  };
  const double paper_s = cycle(paper), smooth_s = cycle(smooth), fast_s = cycle(fast);
  const char* chosen = "sum-squares";
  double best_s = smooth_s;
  out = smooth;
  if (paper_s < best_s * (1.0 - 1e-9)) out = paper, best_s = paper_s, chosen = "paper";
  if (fast_s < best_s * (1.0 - 1e-9)) out = std::move(fast), best_s = fast_s, chosen = "time";
  // The input's axes, where they are faster still and every point and move of theirs is free.
  const double input_s = in_plan.ok()
                             ? operation_cycle_s(op, contacts, ball_radius_mm, model, tool, machine,
                                                 deg_to_rad(options.max_deviation_deg), in_axes, {},
                                                 pose_options, fallback_feed, time.programmed_s)
                             : std::numeric_limits<double>::infinity();
  if (input_s < best_s * (1.0 - 1e-9)) {
    Machine path_machine = machine;
    if (machine.gcode.program.linearise_tolerance_mm > 0.0) {
      path_machine.gcode.mode = GcodeMode::Tcp;
    }
    const std::vector<char> hit =
        points_and_moves_hit(op, contacts, ball_radius_mm, model, tool, path_machine, in_axes,
                             in_plan.poses, std::vector<char>(op.points.size(), 1));
    if (std::find(hit.begin(), hit.end(), 1) == hit.end()) {
      out = paper;
      out.axes = in_axes;
      out.preferred.clear();
      best_s = input_s;
      chosen = "input";
    }
  }
  char line[240];
  std::snprintf(line, sizeof line,
                "scheduled cycle %.3f s (paper), %.3f s (sum-squares), %.3f s (time plan), "
                "%.3f s (input): %s axes kept",
                paper_s, smooth_s, fast_s, input_s, chosen);
  return line;
}

}  // namespace

namespace {

/// Checks the joints' velocity, acceleration and jerk at the written feeds against `check`
/// The severity of a kind of finding (job.hpp groups them).
Severity severity_of(FindingCode code) {
  switch (code) {
    case FindingCode::NoPart:
    case FindingCode::NoHolderModel:
    case FindingCode::NoSafeRetract:
    case FindingCode::NoLinearisation: return Severity::Safety;
    case FindingCode::NotABallMill:
    case FindingCode::LocalGouge:
    case FindingCode::InputAxesKept:
    case FindingCode::MissingFeed:
    case FindingCode::JerkLimitExceeded:
    case FindingCode::LongerCycle:
    case FindingCode::ClFileNote: return Severity::Warning;
    default: return Severity::Problem;
  }
}

/// Records a finding, and its message by severity (JobResult's display lists).
void add_finding(JobResult& res, FindingCode code, std::optional<std::size_t> operation, int line,
                 const std::string& message) {
  const Severity severity = severity_of(code);
  res.findings.push_back(Finding{code, severity, operation, line, message});
  (severity == Severity::Problem  ? res.problems
   : severity == Severity::Safety ? res.safety_warnings
                                  : res.warnings)
      .push_back(message);
}

/// (0: no limit), as the controller moves: block times from the F words read back, each
/// chain of feed moves from rest to rest. Velocity and acceleration beyond a limit are
/// problems, jerk a warning (the schedule does not bound it).
void check_dynamic_limits(OperationResult& r, const PostedOperation& po,
                          const std::vector<JointPosition>& joints,
                          const std::vector<const GcodeMove*>& at,
                          const std::vector<GcodeMove>& moves, JobResult& res,
                          const std::string& source, const JointLimits& check, bool scheduled,
                          char tilt_letter, std::size_t op_index) {
  const std::size_t n = po.points.size();
  std::vector<double> written_s(n, 0.0);
  const auto index_of = [&](const GcodeMove* m) -> std::ptrdiff_t {
    if (moves.empty() || m < moves.data() || m >= moves.data() + moves.size()) return -1;
    return m - moves.data();
  };
  for (std::size_t i = 1; i < n; ++i) {
    if (po.points[i].motion != Motion::Feed || at[i] == at[i - 1]) continue;
    // A linearised move: the blocks between the points, each at its own F.
    const std::ptrdiff_t from = index_of(at[i - 1]), to = index_of(at[i]);
    if (from >= 0 && to > from + 1) {
      for (std::ptrdiff_t j = from + 1; j <= to; ++j) {
        written_s[i] += block_time_s(moves[static_cast<std::size_t>(j - 1)],
                                     moves[static_cast<std::size_t>(j)], res.gcode_units);
      }
    } else {
      written_s[i] = block_time_s(*at[i - 1], *at[i], res.gcode_units);
    }
  }
  struct Worst {
    double value = 0.0;
    std::size_t point = 0;
  };
  std::array<Worst, kJointCount> velocity{}, accel{}, jerk{};
  for (const IndexRange& c : feed_chains(po.points)) {
    const JointRates jr =
        joint_rates(slice(joints, c.begin - 1, c.end), slice(written_s, c.begin, c.end));
    for (std::size_t j = 0; j < kJointCount; ++j) {
      const auto keep = [](Worst& w, double v, std::size_t point) {
        if (v > w.value) w = Worst{v, point};
      };
      keep(velocity[j], jr.max_velocity_per_s[j], c.begin + jr.velocity_at[j]);
      keep(accel[j], jr.max_accel_per_s2[j], std::min(n - 1, c.begin - 1 + jr.accel_at[j]));
      keep(jerk[j], jr.max_jerk_per_s3[j], std::min(n - 1, c.begin - 1 + jr.jerk_at[j]));
    }
  }
  const char* at_feed = scheduled ? " at the scheduled feed" : " at the programmed feed";
  for (std::size_t j = 0; j < kJointCount; ++j) {
    const std::string unit = j < 3 ? "mm" : "deg";
    const std::string axis = "axis " + joint_name(static_cast<Joint>(j), tilt_letter);
    const auto describe = [&](const Worst& w, double limit, const char* what,
                              const std::string& per) {
      return format_location(source, po.points[w.point].line,
                             "operation " + po.name + ": " + axis + " " + what + " " +
                                 std::to_string(w.value) + " " + unit + per + at_feed +
                                 ", the machine allows " + std::to_string(limit));
    };
    if (check[j].max_velocity_per_s > 0.0 &&
        velocity[j].value > check[j].max_velocity_per_s * (1.0 + 1e-9)) {
      r.verification.within_dynamic_limits = false;
      add_finding(res, FindingCode::DynamicLimitExceeded, op_index,
                  po.points[velocity[j].point].line,
                  describe(velocity[j], check[j].max_velocity_per_s, "velocity", "/s"));
    }
    if (check[j].max_accel_per_s2 > 0.0 &&
        accel[j].value > check[j].max_accel_per_s2 * (1.0 + 1e-9)) {
      r.verification.within_dynamic_limits = false;
      add_finding(res, FindingCode::DynamicLimitExceeded, op_index, po.points[accel[j].point].line,
                  describe(accel[j], check[j].max_accel_per_s2, "acceleration", "/s^2"));
    }
    if (check[j].max_jerk_per_s3 > 0.0 && jerk[j].value > check[j].max_jerk_per_s3 * (1.0 + 1e-9)) {
      add_finding(res, FindingCode::JerkLimitExceeded, op_index, po.points[jerk[j].point].line,
                  describe(jerk[j], check[j].max_jerk_per_s3, "jerk", "/s^3") +
                      " (feed schedules bound velocity and acceleration, not jerk)");
    }
  }
  if (!r.verification.within_dynamic_limits && !scheduled) {
    add_finding(
        res, FindingCode::DynamicLimitExceeded, op_index, 0,
        "operation " + po.name + ": --feed-schedule writes feeds within the machine's limits");
  }
}

}  // namespace

TriangleMesh part_mesh_for(const Toolpath& toolpath, TriangleMesh mesh, LengthUnit mesh_units) {
  const double scale = mm_per_unit(mesh_units);
  for (Vec3d& v : mesh.vertices) {
    if (!v.allFinite()) throw InputError("the part mesh has a vertex that is not a number");
    v *= scale;
  }
  if (toolpath.frames.empty()) return mesh;
  const ClFrame& f = toolpath.frames.front();
  for (const ClFrame& g : toolpath.frames) {
    if ((g.rotation - f.rotation).cwiseAbs().maxCoeff() > 1e-9 ||
        (g.origin_mm - f.origin_mm).norm() > 1e-9) {
      throw InputError(toolpath.source + ": its MSYS records name different frames (lines " +
                       std::to_string(f.line) + " and " + std::to_string(g.line) +
                       "): one part cannot be in all of them; use --msys ignore or split the "
                       "file");
    }
  }
  for (Vec3d& v : mesh.vertices) v = f.rotation.transpose() * (v - f.origin_mm);
  return mesh;
}

ToolOverrides tool_overrides(const ToolDimensions& given) {
  const double u = mm_per_unit(given.units);
  const auto mm = [u](const std::optional<double>& v) -> std::optional<double> {
    if (v && !(*v > 0.0 && std::isfinite(*v))) {
      throw InputError("tool dimensions must be positive");
    }
    return v ? std::optional<double>(*v * u) : std::nullopt;
  };
  ToolOverrides o;
  o.ball_radius_mm = mm(given.ball_radius);
  o.shank_radius_mm = mm(given.shank_radius);
  o.flute_length_mm = mm(given.flute_length);
  o.holder_radius_mm = mm(given.holder_radius);
  o.holder_length_mm = mm(given.holder_length);
  o.gauge_length_mm = mm(given.gauge_length);
  return o;
}

const char* to_string(FindingCode code) {
  switch (code) {
    case FindingCode::NoPart: return "no_part";
    case FindingCode::NoHolderModel: return "no_holder_model";
    case FindingCode::NoSafeRetract: return "no_safe_retract";
    case FindingCode::NoLinearisation: return "no_linearisation";
    case FindingCode::NotABallMill: return "not_a_ball_mill";
    case FindingCode::LocalGouge: return "local_gouge";
    case FindingCode::InputAxesKept: return "input_axes_kept";
    case FindingCode::MissingFeed: return "missing_feed";
    case FindingCode::JerkLimitExceeded: return "jerk_limit_exceeded";
    case FindingCode::LongerCycle: return "longer_cycle";
    case FindingCode::ClFileNote: return "cl_file_note";
    case FindingCode::NoFreeAxis: return "no_free_axis";
    case FindingCode::UnreachablePose: return "unreachable_pose";
    case FindingCode::AxisRangeExceeded: return "axis_range_exceeded";
    case FindingCode::TravelExceeded: return "travel_exceeded";
    case FindingCode::DynamicLimitExceeded: return "dynamic_limit_exceeded";
    case FindingCode::ToolLengthOffsetOff: return "tool_length_offset_off";
    case FindingCode::ReadBackMismatch: return "read_back_mismatch";
    case FindingCode::DeviationExceeded: return "deviation_exceeded";
    case FindingCode::PointCollision: return "point_collision";
    case FindingCode::MoveCollision: return "move_collision";
  }
  return "?";
}

const char* to_string(Severity severity) {
  switch (severity) {
    case Severity::Safety: return "safety";
    case Severity::Warning: return "warning";
    case Severity::Problem: return "problem";
  }
  return "?";
}

bool JobResult::has(FindingCode code) const {
  return std::any_of(findings.begin(), findings.end(),
                     [code](const Finding& f) { return f.code == code; });
}

const char* to_string(Method method) {
  switch (method) {
    case Method::None: return "none";
    case Method::Paper: return "paper";
    case Method::Global: return "global";
  }
  return "none";
}

JobResult run_job(const Toolpath& tp, const Machine& machine, const JobOptions& given) {
  JobResult res;
  // The deviation cone: as given; without a part to check the axes against, no wider than a
  // controller's own orientation tolerance unless asked for.
  JobOptions options = given;
  if (given.max_deviation_deg) {
    options.paper.max_deviation_deg = *given.max_deviation_deg;
  } else if (!given.part) {
    options.paper.max_deviation_deg =
        std::min(options.paper.max_deviation_deg, kNoPartMaxDeviationDeg);
  }
  res.collision_checked = given.part != nullptr;
  if (!given.part) {
    std::ostringstream os;
    os << "no part (--part): the tool and holder are not checked against the part";
    if (given.method != Method::None) {
      os << "; each tool axis stays within " << options.paper.max_deviation_deg
         << " deg of its input";
      if (given.max_deviation_deg && *given.max_deviation_deg > kNoPartMaxDeviationDeg) {
        os << " as --max-deviation asks, unchecked: give --part to check it";
      } else {
        os << " (--max-deviation widens it, unchecked)";
      }
    }
    add_finding(res, FindingCode::NoPart, std::nullopt, 0, os.str());
  } else if (!given.tool.holder_radius_mm) {
    add_finding(
        res, FindingCode::NoHolderModel, std::nullopt, 0,
        "no holder model (--holder-radius, --holder-length): the holder is not checked against "
        "the part, only the tool");
  }
  if (machine.gcode.program.retract == SafeRetract::None) {
    add_finding(
        res, FindingCode::NoSafeRetract, std::nullopt, 0,
        "the machine file's gcode.safe_retract is \"none\": no retract before an operation's "
        "first move nor after the last, and the table turns where the tool stands");
  }
  if (machine.gcode.mode == GcodeMode::Machine &&
      !(machine.gcode.program.linearise_tolerance_mm > 0.0)) {
    add_finding(
        res, FindingCode::NoLinearisation, std::nullopt, 0,
        "the machine file's gcode.linearise_tolerance_mm is 0: the tip leaves the straight line "
        "between points where the table turns (the moves are checked as the joints run)");
  }
  if (!(options.global.jerk_weight_s2 >= 0.0) || !std::isfinite(options.global.jerk_weight_s2)) {
    throw InputError("--jerk-weight must be a number >= 0 (s^2)");
  }
  if (!(options.paper.max_deviation_deg >= 0.0 && options.paper.max_deviation_deg <= 90.0)) {
    throw InputError("--max-deviation must be within [0, 90] deg");
  }
  if (!(options.paper.grid_deg > 0.0 && options.paper.grid_deg <= 10.0)) {
    throw InputError("--grid must be within (0, 10] deg");
  }
  if (options.feed_mm_per_min && !(*options.feed_mm_per_min > 0.0)) {
    throw InputError("--feed must be positive");
  }
  for (const std::string& w : tp.warnings) {
    add_finding(res, FindingCode::ClFileNote, std::nullopt, 0, w);
  }
  res.gcode_units = options.units_out.value_or(tp.units);
  const int decimals = machine.gcode.decimals;
  const double fallback_feed = options.feed_mm_per_min.value_or(options.default_feed_mm_per_min);

  // Contact recovery for the ball-end operations when the part is known.
  std::vector<std::vector<ContactPoint>> contacts(tp.operations.size());
  std::vector<ContactSummary> contact_summaries(tp.operations.size());
  std::vector<double> contacts_time(tp.operations.size(), 0.0);
  // Two collision models of the part, built beside contact recovery: the occlusion map's tree
  // (cspace.hpp), which the optimisers and the guard ask, and FCL's (one thread: ~2 s at
  // 800k triangles), the independent reference every output is verified with.
  std::optional<CollisionModel> collision;
  std::optional<CSpaceRasteriser> checker;
  const auto recover_all = [&] {
    if (!options.part) return;
    detail::StageProgress progress(options.progress, "contact recovery", tp.operations.size());
    for (std::size_t k = 0; k < tp.operations.size(); ++k) {
      const Operationd& op = tp.operations[k];
      const auto t0 = Clock::now();
      struct Advance {  // on every way out of this operation
        detail::StageProgress& p;
        ~Advance() { p.advance(); }
      } advance{progress};
      const double ball_r = options.tool.ball_radius_mm.value_or(op.tool.ball_radius_mm());
      if (!(ball_r > 0.0)) {
        add_finding(res, FindingCode::NotABallMill, k,
                    op.points.empty() ? 0 : op.points.front().line,
                    not_a_ball(op) + ", no contact recovery and no collision check");
        continue;
      }
      contacts[k] = recover_contacts(*options.part, op, ball_r, options.contact);
      ContactSummary& cs = contact_summaries[k];
      cs.recovered = true;
      cs.tolerance_mm = contact_tolerance_mm(*options.part, options.contact);
      bool any_feed = false;
      for (std::size_t i = 0; i < op.points.size(); ++i) {
        const ContactPoint& c = contacts[k][i];
        any_feed = any_feed || op.points[i].motion == Motion::Feed;
        if (c.state == ContactState::Gouging) {
          throw InputError(tp.source, op.points[i].line,
                           "operation " + op.name + ": the ball cuts " + std::to_string(-c.gap_mm) +
                               " mm into the part here (wrong part, wrong tool or wrong units?)");
        }
        if (c.state == ContactState::Touching) {
          ++cs.touching;
          cs.max_abs_gap_mm = std::max(cs.max_abs_gap_mm, std::abs(c.gap_mm));
          if (c.local_gouge) ++cs.local_gouges;
        } else {
          ++cs.in_air;
        }
      }
      if (any_feed && cs.touching == 0) {
        throw InputError(
            tp.source, op.points.front().line,
            "operation " + op.name + ": no CL point touches the part (wrong part or wrong units?)");
      }
      if (cs.local_gouges) {
        add_finding(res, FindingCode::LocalGouge, k, 0,
                    "operation " + op.name + ": " + std::to_string(cs.local_gouges) +
                        " contact points where a concave radius is below the ball radius "
                        "(local gouge, eq. 19)");
      }
      contacts_time[k] = seconds_since(t0);
    }
  };
  detail::parallel_invoke(recover_all, [&] {
    if (!options.part) return;
    detail::parallel_invoke([&] { collision.emplace(options.part->mesh()); },
                            [&] { checker.emplace(options.part->mesh()); });
  });
  const PartCheck* planner_check = checker ? &*checker : nullptr;

  // The paper's optimiser: new axes about the fixed ball centres.
  std::vector<std::optional<OptimisedOperation>> optimised(tp.operations.size());
  std::vector<double> optimise_time(tp.operations.size(), 0.0);
  if (options.method != Method::None) {
    std::size_t all_passes = 0;
    for (const Operationd& op : tp.operations) all_passes += feed_passes(op).size();
    detail::StageProgress progress(
        options.progress, "optimisation",
        all_passes * (options.method != Method::Global                    ? 1
                      : options.global.objective == GlobalObjective::Time ? 3
                                                                          : 2));
    for (std::size_t k = 0; k < tp.operations.size(); ++k) {
      const Operationd& op = tp.operations[k];
      const double R = ball_radius_mm(op, options);
      if (!(R > 0.0)) {
        add_finding(res, FindingCode::NotABallMill, k,
                    op.points.empty() ? 0 : op.points.front().line,
                    not_a_ball(op) + ", the input tool axes are kept");
        continue;
      }
      if (options.part && !contact_summaries[k].recovered) continue;
      const auto t0 = Clock::now();
      std::optional<ToolModel> tool;
      if (collision) tool = judged_tool(op, options);
      const std::vector<double> metric_feed = metric_feeds_of(op, options, fallback_feed);
      optimised[k] =
          optimise_paper(op, contacts[k], R, planner_check, tool ? &*tool : nullptr, machine,
                         metric_feed, options.pose_options, options.paper, progress);
      optimised[k]->guard = guard_passes(op, contacts[k], R, planner_check, tool ? &*tool : nullptr,
                                         machine, metric_feed, options.pose_options, *optimised[k]);
      std::string time_line;
      if (options.method == Method::Global) {
        GlobalOptions global = options.global;
        global.max_deviation_deg = options.paper.max_deviation_deg;
        global.candidate_step_deg =
            std::max(global.candidate_step_deg, options.paper.max_deviation_deg / 2.0);
        if (global.objective == GlobalObjective::Time) {
          time_line = refine_time(op, contacts[k], R, planner_check, tool ? &*tool : nullptr,
                                  machine, metric_feed, options.pose_options, global, fallback_feed,
                                  *optimised[k], progress);
        } else {
          refine_global(op, contacts[k], R, planner_check, tool ? &*tool : nullptr, machine,
                        metric_feed, options.pose_options, global, *optimised[k], progress);
        }
      }
      if (const StretchGuardResult& g = optimised[k]->guard; g.whole_passes + g.stretches > 0) {
        add_finding(res, FindingCode::InputAxesKept, k, 0,
                    "operation " + op.name + ": " + std::to_string(g.points_hit + g.points_rate) +
                        " points keep their input axes (" + std::to_string(g.whole_passes) +
                        " whole passes, " + std::to_string(g.stretches) +
                        " stretches within passes, joined over " +
                        std::to_string(g.points_blended) + " points): there the optimised axes " +
                        (g.points_hit ? "swept the tool through the part between points" : "") +
                        (g.points_hit && g.points_rate ? " or " : "") +
                        (g.points_rate ? "raised the pass's peak omega or a" : ""));
      }
      for (std::size_t i : optimised[k]->no_free_axis) {
        add_finding(
            res, FindingCode::NoFreeAxis, k, op.points[i].line,
            format_location(tp.source, op.points[i].line,
                            "operation " + op.name + ": no tool axis within " +
                                std::to_string(options.paper.max_deviation_deg) +
                                " deg of the input axis is reachable and collision-free here"));
      }
      optimise_time[k] = seconds_since(t0);
      if (options.log) {
        const OptimisedOperation& o = *optimised[k];
        options.log(
            "operation " + op.name + ": " + std::to_string(o.intervals) + " intervals, " +
            std::to_string(o.repairs) + " repair keys, " + std::to_string(o.smoothed_joints) +
            " joints smoothed, " + std::to_string(o.sharp_joints) + " left sharp, " +
            std::to_string(o.pole_stretches) + " pole passages re-planned" +
            (options.method == Method::Global
                 ? "; global: " + std::to_string(o.global_passes) + " passes refined, " +
                       std::to_string(o.global_guard.whole_passes) + " kept the paper's axes, " +
                       std::to_string(o.global_guard.stretches) + " stretches kept them"
                 : std::string()) +
            (time_line.empty() ? std::string() : "; time: " + time_line));
      }
    }
  }

  std::vector<PostedOperation> posted;
  std::vector<std::vector<double>> metric_feeds;
  std::vector<std::vector<Posed>> input_poses;
  std::vector<double> post_time;
  std::optional<Posed> start, input_start;
  bool posting_failed = false;
  for (std::size_t k = 0; k < tp.operations.size(); ++k) {
    const Operationd& op = tp.operations[k];
    const auto t0 = Clock::now();
    PostedOperation po{op.name, op.tool, op.spindle_rpm, op.spindle_clockwise, op.points, {},
                       {},      {},      op.arcs};
    if (optimised[k]) {
      const double R = ball_radius_mm(op, options);
      for (std::size_t i = 0; i < po.points.size(); ++i) {
        po.points[i].axis = optimised[k]->axes[i];
        po.points[i].tip_mm = tip_for_axis(op.points[i], R, po.points[i].axis);
      }
    }
    std::vector<double> mf = metric_feeds_of(op, options, fallback_feed);
    bool missing_feed = false;
    for (CLPointd& p : po.points) {
      if (!(p.feed_mm_per_min > 0.0)) {
        if (p.motion == Motion::Feed) missing_feed = true;
        p.feed_mm_per_min = fallback_feed;
      }
    }
    if (missing_feed) {
      add_finding(res, FindingCode::MissingFeed, k, 0,
                  "operation " + op.name + ": feed moves without FEDRAT use " +
                      std::to_string(fallback_feed) + " mm/min");
    }
    std::vector<Vec3d> axes, in_axes;
    const std::vector<bool> rapid_into = rapid_into_of(op);
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      axes.push_back(po.points[i].axis);
      in_axes.push_back(op.points[i].axis);
    }
    const PosePlan plan =
        plan_poses(machine.ac, axes, rapid_into, start, options.pose_options,
                   optimised[k] ? optimised[k]->preferred : std::vector<std::optional<Posed>>{});
    // The input axes as the machine would have run them, for the "before" metrics.
    if (optimised[k]) {
      const PosePlan before =
          plan_poses(machine.ac, in_axes, rapid_into, input_start, options.pose_options);
      if (before.ok()) input_start = before.poses.back();
      input_poses.push_back(before.ok() ? before.poses : std::vector<Posed>{});
    } else {
      input_poses.push_back(plan.ok() ? plan.poses : std::vector<Posed>{});
      if (plan.ok()) input_start = plan.poses.back();
    }
    if (!plan.ok()) {
      posting_failed = true;
      add_finding(res, FindingCode::UnreachablePose, k, op.points[plan.failed_index].line,
                  format_location(tp.source, op.points[plan.failed_index].line,
                                  "operation " + op.name + ": " + plan.message));
      continue;
    }
    po.poses = plan.poses;
    if (optimised[k]) {
      spread_turns_in_air(op, contacts[k], ball_radius_mm(op, options), planner_check,
                          planner_check ? judged_tool(op, options) : ToolModel{}, machine,
                          deg_to_rad(options.paper.max_deviation_deg), po);
    }
    if (optimised[k] && machine.gcode.feed_reference == FeedReference::CutterPath) {
      // Every feed block keeps the time of the input block at its feed: the ball centre and
      // the contact point run as the CAM system programmed them, whatever the tip does.
      std::vector<CLPointd> in_points = po.points;
      for (std::size_t i = 0; i < in_points.size(); ++i) in_points[i].tip_mm = op.points[i].tip_mm;
      po.programmed_time_s = programmed_block_times_s(
          in_points, input_poses.back().empty() ? po.poses : input_poses.back());
    }
    start = po.poses.back();
    posted.push_back(std::move(po));
    metric_feeds.push_back(std::move(mf));
    post_time.push_back(seconds_since(t0));
  }
  if (posting_failed) return res;

  std::vector<std::string> comments = {
      std::string("taxopt ") + kVersion + ", method " + to_string(options.method),
      "source " + tp.source,
      "machine " + machine.name + ", " +
          (machine.gcode.mode == GcodeMode::Tcp ? "tcp" : "machine") + " mode"};
  auto t_write = Clock::now();
  res.gcode = write_gcode(posted, machine, res.gcode_units, comments);
  std::vector<GcodeMove> moves =
      read_gcode_moves(res.gcode.text, "written G-code", machine.gcode.dialect,
                       res.gcode.verbatim_lines, machine.ac.tilt_letter());
  // Per operation and point, the move read back that put the machine there. A chord point
  // inside a G2/G3 block gets the point of the arc read back at its angle (with the block's
  // words), so that every check sees the path the controller runs; the blocks that split an
  // arc at 180 deg belong to no point and are stepped over.
  std::deque<GcodeMove> on_arcs;
  // Per operation and point, the linearisation blocks on the way into it.
  std::vector<std::vector<std::vector<WayPoint>>> way_points;
  const auto moves_of_points = [&] {
    on_arcs.clear();
    way_points.assign(posted.size(), {});
    std::vector<std::vector<const GcodeMove*>> out(posted.size());
    std::size_t next = 0;
    const auto mismatch = [] {
      throw std::logic_error("run_job: G-code read back does not match what was written");
    };
    for (std::size_t k = 0; k < posted.size(); ++k) {
      const GcodeMove* last = nullptr;
      way_points[k].resize(posted[k].points.size());
      for (std::size_t i = 0; i < posted[k].points.size(); ++i) {
        const int line = res.gcode.emitted[k][i];
        if (line != 0) {
          while (next < moves.size() && moves[next].line < std::abs(line)) {
            const GcodeMove& m = moves[next++];
            if (i > 0 && !m.arc && !m.positioning) {
              way_points[k][i].push_back({m.xyz_mm, m.a_deg, m.c_deg});
            }
            last = &m;
          }
          if (next >= moves.size() || moves[next].line != std::abs(line)) mismatch();
        }
        if (line > 0) {
          if (moves[next].positioning) mismatch();
          last = &moves[next++];
        } else if (line < 0) {
          const GcodeMove& arc = moves[next];
          if (!arc.arc || !last) mismatch();
          const PostedOperation& po = posted[k];
          const Vec3d want = written_xyz_mm(machine, po.points[i].tip_mm, po.poses[i]);
          GcodeMove at = arc;
          at.xyz_mm = point_on_arc(last->xyz_mm, arc, want);
          on_arcs.push_back(at);
          last = &on_arcs.back();
        }
        if (!last) throw std::logic_error("run_job: first point of an operation not written");
        out[k].push_back(last);
      }
    }
    return out;
  };
  // Joint positions as written: the words read back (in tcp mode mapped to the joints).
  const auto written_joints = [&](const std::vector<const GcodeMove*>& at) {
    std::vector<JointPosition> q;
    for (const GcodeMove* m : at) {
      const Posed pose{deg_to_rad(m->a_deg), deg_to_rad(m->c_deg)};
      const Vec3d xyz = joints_of_written_mm(machine, m->xyz_mm, pose);
      q.push_back({xyz.x(), xyz.y(), xyz.z(), m->a_deg, m->c_deg});
    }
    return q;
  };
  std::vector<std::vector<const GcodeMove*>> point_moves = moves_of_points();

  // Feed schedules at the machine's limits: the written path (from the words read back) and
  // the input axes; with --feed-schedule the program is written again at the scheduled feeds.
  const JointLimits limits = effective_limits(machine);
  std::vector<OperationSchedule> schedule_after, schedule_before;
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const PostedOperation& po = posted[k];
    schedule_after.push_back(schedule_operation(po.points, written_joints(point_moves[k]),
                                                po.programmed_time_s.empty()
                                                    ? programmed_block_times_s(po.points, po.poses)
                                                    : po.programmed_time_s,
                                                limits, machine.ac));
    std::vector<CLPointd> in_points = po.points;
    std::vector<Vec3d> in_tips;
    for (std::size_t i = 0; i < in_points.size(); ++i) {
      in_points[i].tip_mm = tp.operations[k].points[i].tip_mm;
      in_points[i].axis = tp.operations[k].points[i].axis;
      in_tips.push_back(in_points[i].tip_mm);
    }
    schedule_before.push_back(
        input_poses[k].empty()
            ? schedule_after.back()
            : schedule_operation(in_points, joints_of(machine.ac, in_tips, input_poses[k]),
                                 programmed_block_times_s(in_points, input_poses[k]), limits,
                                 machine.ac));
  }
  if (options.feed_schedule) {
    for (std::size_t k = 0; k < posted.size(); ++k)
      posted[k].block_time_s = schedule_after[k].time_s;
    res.gcode = write_gcode(posted, machine, res.gcode_units, comments);
    moves = read_gcode_moves(res.gcode.text, "written G-code", machine.gcode.dialect,
                             res.gcode.verbatim_lines, machine.ac.tilt_letter());
    point_moves = moves_of_points();
  }
  const double write_time = seconds_since(t_write);

  std::vector<Operationd> out_ops = tp.operations;
  const CSpaceRasteriser* rasteriser =
      (options.count_free_cells || options.cspace_maps) && checker ? &*checker : nullptr;
  // Progress of the checks: per point, its pose before and after and the move into it, and
  // its C-space cells.
  std::size_t check_items = 0;
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const std::size_t n = tp.operations[k].points.size();
    if (collision && contact_summaries[k].recovered) check_items += 4 * n;
    if (rasteriser && !contacts[k].empty()) check_items += n;
  }
  detail::StageProgress checking(options.progress, "verification", check_items);
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const PostedOperation& po = posted[k];
    const Operationd& op = tp.operations[k];
    const auto t_verify = Clock::now();
    OperationResult r;
    r.name = op.name;
    r.points = op.points.size();
    r.time_post_s = post_time[k] + write_time / static_cast<double>(posted.size());
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      if (op.points[i].motion == Motion::Feed) {
        r.feed_mm_min = metric_feeds[k][i];
        break;
      }
    }
    // Read back: the A/C values actually written, and what they mean in the workpiece.
    std::vector<double> a_w(op.points.size()), c_w(op.points.size());
    std::vector<Vec3d> xyz_w(op.points.size());
    std::vector<double> a_in(op.points.size()), c_in(op.points.size());
    r.rows.resize(op.points.size());
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      const GcodeMove* last = point_moves[k][i];
      // Where TCP is asked for, the controller's must be on, with the tool length offset
      // (LinuxCNC's kinematics steer the spindle nose without it); in machine mode the offset.
      const bool tcp_mode = machine.gcode.mode == GcodeMode::Tcp;
      if (!last->length_offset || (tcp_mode && !last->tcp)) {
        if (r.verification.tool_length_active) {
          add_finding(
              res, FindingCode::ToolLengthOffsetOff, k, op.points[i].line,
              "operation " + op.name + ": G-code line " + std::to_string(last->line) +
                  " moves with " +
                  (!last->length_offset ? std::string("the tool length offset off")
                                        : std::string("tool centre point control off")) +
                  " (the written program must switch it on before the operation's first move)");
        }
        r.verification.tool_length_active = false;
      }
      a_w[i] = last->a_deg;
      xyz_w[i] = last->xyz_mm;
      c_w[i] = last->c_deg;
      if (!input_poses[k].empty()) {
        a_in[i] = round_to(rad_to_deg(input_poses[k][i].a_rad), decimals);
        c_in[i] = round_to(rad_to_deg(input_poses[k][i].c_rad), decimals);
      }
      const Posed written{deg_to_rad(last->a_deg), deg_to_rad(last->c_deg)};
      const Vec3d axis = machine.ac.forward(written);
      const Vec3d tip = tip_of_written_mm(machine, last->xyz_mm, written);
      const CLPointd& want = po.points[i];
      r.verification.roundtrip_max_mm =
          std::max(r.verification.roundtrip_max_mm, (tip - want.tip_mm).norm());
      r.verification.roundtrip_max_deg =
          std::max(r.verification.roundtrip_max_deg, rad_to_deg(angle_between(axis, want.axis)));
      if (!machine.ac.a.contains(written.a_rad) || !machine.ac.c.contains(written.c_rad)) {
        if (r.verification.within_axis_limits) {
          add_finding(res, FindingCode::AxisRangeExceeded, k, want.line,
                      format_location(
                          tp.source, want.line,
                          "operation " + op.name + ": written " + machine.ac.tilt_letter() + " " +
                              std::to_string(last->a_deg) + " / C " + std::to_string(last->c_deg) +
                              " deg is outside the machine's axis ranges"));
        }
        r.verification.within_axis_limits = false;
      }
      // The linear travel, in machine coordinates, where the machine file gives it.
      const Vec3d joints_mm = joints_of_written_mm(machine, last->xyz_mm, written);
      for (int q = 0; q < 3; ++q) {
        const auto& range = machine.linear_range[static_cast<std::size_t>(q)];
        if (range.contains(joints_mm[q])) continue;
        if (r.verification.within_axis_limits) {
          std::ostringstream os;
          os << "operation " << op.name << ": "
             << "XYZ"[q] << " would be " << joints_mm[q]
             << " mm in machine coordinates, outside the machine's travel [" << range.min_mm << ", "
             << range.max_mm << "] mm";
          add_finding(res, FindingCode::TravelExceeded, k, want.line,
                      format_location(tp.source, want.line, os.str()));
        }
        r.verification.within_axis_limits = false;
      }
      r.max_axis_change_deg =
          std::max(r.max_axis_change_deg, rad_to_deg(angle_between(op.points[i].axis, want.axis)));
      PointRow& row = r.rows[i];
      row.index = i;
      row.tip_mm = want.tip_mm;
      row.axis = want.axis;
      row.a_deg = a_w[i];
      row.c_deg = c_w[i];
      out_ops[k].points[i].axis = want.axis;
      out_ops[k].points[i].tip_mm = want.tip_mm;
    }
    // The round trip may differ from the intent only by the rounding of the written
    // decimals: half a unit of the last decimal per word, mapped to mm and to the axis angle;
    // in machine mode the angle rounding also moves the mapped point by its lever arm.
    const double half_unit = 0.5 * std::pow(10.0, -decimals);
    const double ang_tol = std::sqrt(2.0) * half_unit + 1e-9;
    double lever_mm = 0.0;
    if (machine.gcode.mode == GcodeMode::Machine) {
      for (const auto& p : po.points) {
        lever_mm = std::max(lever_mm,
                            (p.tip_mm - machine.ac.c_axis_point_mm).norm() +
                                (machine.ac.c_axis_point_mm - machine.ac.a_axis_point_mm).norm());
      }
    }
    const double pos_tol = std::sqrt(3.0) * half_unit * mm_per_unit(res.gcode_units) +
                           2.0 * lever_mm * deg_to_rad(ang_tol) + 1e-9;
    if (r.verification.roundtrip_max_mm > pos_tol) {
      add_finding(res, FindingCode::ReadBackMismatch, k, 0,
                  "operation " + op.name + ": G-code read back is " +
                      std::to_string(r.verification.roundtrip_max_mm) +
                      " mm from the intended tips (rounding allows " + std::to_string(pos_tol) +
                      ")");
    }
    if (r.verification.roundtrip_max_deg > ang_tol) {
      add_finding(res, FindingCode::ReadBackMismatch, k, 0,
                  "operation " + op.name + ": G-code read back is " +
                      std::to_string(r.verification.roundtrip_max_deg) +
                      " deg from the intended axes (rounding allows " + std::to_string(ang_tol) +
                      ")");
    }
    r.contact = contact_summaries[k];
    r.time_contacts_s = contacts_time[k];
    r.time_optimise_s = optimise_time[k];
    if (optimised[k]) {
      r.segments = static_cast<int>(optimised[k]->intervals);
      // Why points kept their input axes: the paper's guard, else no free axis in the cone.
      const OptimisedOperation& o = *optimised[k];
      OperationResult::KeptInputPoints kept;
      kept.passes = o.guard.whole_passes;
      kept.stretches = o.guard.stretches;
      std::vector<KeptWhy> why = o.guard.why;
      why.resize(op.points.size(), KeptWhy::None);
      for (std::size_t i : o.no_free_axis) {
        if (why[i] == KeptWhy::None) ++kept.no_free_axis;
      }
      for (const KeptWhy w : why) {
        kept.collision += w == KeptWhy::Collision;
        kept.peak_rate += w == KeptWhy::PeakRate;
        kept.join_points += w == KeptWhy::Join;
      }
      r.kept_input_points = kept;
      // The optimiser keeps every axis within the cone; this proves it on what is written.
      const double allowed = options.paper.max_deviation_deg + 1e-6;
      if (r.max_axis_change_deg > allowed) {
        add_finding(res, FindingCode::DeviationExceeded, k, 0,
                    "operation " + op.name + ": an output axis is " +
                        std::to_string(r.max_axis_change_deg) +
                        " deg from its input axis, more than --max-deviation");
      }
    }
    if (collision && r.contact.recovered) {
      // Judged with the margins; the clearance is measured from the real bodies.
      const ToolModel real_tool = ToolModel::ball_end(op.tool, options.tool);
      const ToolModel tool = real_tool.judged(margins_of(options));
      std::vector<Vec3d> in_axes, out_axes;
      for (std::size_t i = 0; i < op.points.size(); ++i) {
        in_axes.push_back(op.points[i].axis);
        out_axes.push_back(po.points[i].axis);
      }
      // The input's count is information, not a check of the output: where the axes changed,
      // the planner's check (which agrees with FCL) counts it; what is written is checked with
      // FCL (where they did not change, the one count is that check).
      const bool same_axes = in_axes == out_axes;
      const PartCheck& counter =
          checker && !same_axes ? static_cast<const PartCheck&>(*checker) : *collision;
      const auto before = colliding_points(counter, tool, op, in_axes, contacts[k], &checking);
      if (same_axes) checking.advance(op.points.size());
      const auto after =
          same_axes ? before
                    : colliding_points(*collision, tool, op, out_axes, contacts[k], &checking);
      r.colliding_before = static_cast<long>(before.size());
      r.colliding_after = static_cast<long>(after.size());
      r.verification.collision_free = after.empty();
      if (!after.empty()) {
        // Told apart: the flutes reaching deeper than the part tolerance (a gouge of the cutter)
        // and the bodies that never cut (shank, holder, a ball in the air) within their margins.
        ToolModel flutes = tool, rest = tool;
        flutes.bodies.resize(static_cast<std::size_t>(tool.flute_bodies));
        rest.bodies.erase(rest.bodies.begin(), rest.bodies.begin() + tool.flute_bodies);
        std::vector<std::size_t> gouges, hits;
        for (std::size_t i : after) {
          const Vec3d centre = op.points[i].tip_mm + tool.ball_radius_mm * out_axes[i];
          const bool in_air = contacts[k].empty() || contacts[k][i].state != ContactState::Touching;
          if (!flutes.bodies.empty() && collision->collides(flutes, centre, out_axes[i], false)) {
            gouges.push_back(i);
          }
          if (collision->collides(rest, centre, out_axes[i], in_air)) hits.push_back(i);
        }
        r.verification.flute_gouge_points = static_cast<long>(gouges.size());
        const auto report = [&](const std::vector<std::size_t>& at, const std::string& what) {
          if (at.empty()) return;
          std::string lines;
          for (std::size_t j = 0; j < at.size() && j < 10; ++j) {
            lines += (j ? ", " : "") + std::to_string(op.points[at[j]].line);
          }
          if (at.size() > 10) lines += ", ...";
          add_finding(res, FindingCode::PointCollision, k, op.points[at.front()].line,
                      format_location(tp.source, op.points[at.front()].line,
                                      "operation " + op.name + ": " + std::to_string(at.size()) +
                                          " CL points " + what + ", at lines " + lines));
        };
        report(hits,
               "where the tool hits the part (the shank or holder within its clearance, or a "
               "ball in the air)");
        report(gouges,
               "where the flutes reach into the part deeper than the part tolerance "
               "(a gouge; --part-tolerance)");
        if (hits.empty() && gouges.empty()) {
          report(after, "where the tool hits the part");  // never: the bodies are the same
        }
      } else {
        r.verification.flute_gouge_points = 0;
      }
      const auto moves_hit = colliding_moves(*collision, tool, machine, xyz_w, a_w, c_w,
                                             contacts[k], &checking, &way_points[k]);
      r.verification.colliding_moves = static_cast<long>(moves_hit.size());
      if (const auto least = clearance_bound(*collision, real_tool, op, out_axes, &checking)) {
        r.verification.min_clearance_mm = least->first;
        r.verification.min_clearance_index = least->second;
      }
      if (!moves_hit.empty()) {
        r.verification.collision_free = false;
        const std::size_t i = moves_hit.front();
        add_finding(
            res, FindingCode::MoveCollision, k, op.points[i].line,
            format_location(tp.source, op.points[i].line,
                            "operation " + op.name + ": " + std::to_string(moves_hit.size()) +
                                " moves where the tool hits the part between CL points as the "
                                "machine moves it, "
                                "first from line " +
                                std::to_string(op.points[i - 1].line) + " to line " +
                                std::to_string(op.points[i].line)));
      }
    }
    if (!contacts[k].empty()) {
      for (std::size_t i = 0; i < op.points.size(); ++i) {
        const ContactPoint& c = contacts[k][i];
        if (c.state != ContactState::Touching) continue;
        PointRow& row = r.rows[i];
        row.has_contact = true;
        row.cc_mm = c.cc_mm;
        row.normal = c.normal;
        row.tilt_deg = rad_to_deg(c.tilt_rad);
        row.yaw_deg = rad_to_deg(c.yaw_rad);
      }
      if (rasteriser && ball_radius_mm(op, options) > 0.0) {
        const auto t0 = Clock::now();
        const double R = ball_radius_mm(op, options);
        const ToolModel tool = judged_tool(op, options);
        CSpaceOptions cs;
        // The grid's cell must divide 180 deg: the nearest such to --grid.
        cs.cell_deg = 180.0 / std::max(1.0, std::round(180.0 / options.paper.grid_deg));
        cs.max_deviation_deg = options.paper.max_deviation_deg;
        detail::parallel_for(std::size_t(0), op.points.size(), [&](std::size_t i) {
          const ContactPoint& c = contacts[k][i];
          checking.advance();
          if (c.state != ContactState::Touching) return;
          const CSpaceGrid g = rasteriser->free_axes(tool, c, reference_point(op.points[i], R),
                                                     op.points[i].axis, cs);
          r.rows[i].free_cells = g.free_count() / 2;  // the grid holds every axis twice
        });
        if (options.cspace_maps) {
          // The most constrained contact, and the one whose axis the optimiser turned most.
          std::optional<std::size_t> fewest, turned;
          double most_deg = -1.0;
          for (std::size_t i = 0; i < op.points.size(); ++i) {
            if (!r.rows[i].free_cells) continue;
            if (!fewest || *r.rows[i].free_cells < *r.rows[*fewest].free_cells) fewest = i;
            const double dev = rad_to_deg(angle_between(op.points[i].axis, r.rows[i].axis));
            if (dev > most_deg) most_deg = dev, turned = i;
          }
          const auto tilt_yaw = [](const ContactPoint& c, const Vec3d& v) {
            return std::pair<double, double>(
                rad_to_deg(angle_between(c.normal, v)),
                rad_to_deg(std::atan2(v.dot(c.side), v.dot(c.feed_dir))));
          };
          for (const auto& [at, why] :
               {std::pair<std::optional<std::size_t>, const char*>{fewest, "fewest free cells"},
                {turned, "largest axis change"}}) {
            if (!at) continue;
            if (!r.cspace_maps.empty() && r.cspace_maps.back().index == *at) continue;
            const ContactPoint& c = contacts[k][*at];
            CSpaceMap map;
            map.index = *at;
            map.why = why;
            map.max_deviation_deg = cs.max_deviation_deg;
            map.grid = rasteriser->free_axes(tool, c, reference_point(op.points[*at], R),
                                             op.points[*at].axis, cs);
            std::tie(map.input_tilt_deg, map.input_yaw_deg) = tilt_yaw(c, op.points[*at].axis);
            std::tie(map.output_tilt_deg, map.output_yaw_deg) = tilt_yaw(c, r.rows[*at].axis);
            r.cspace_maps.push_back(std::move(map));
          }
        }
        r.time_cspace_s += seconds_since(t0);
      }
    }
    r.before = summarise(op, contacts[k], ball_radius_mm(op, options), a_in, c_in, metric_feeds[k],
                         &r.rows, true);
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      r.rows[i].a_before_deg = a_in[i];
      r.rows[i].c_before_deg = c_in[i];
    }
    if (optimised[k]) {
      for (std::size_t i : optimised[k]->keys) r.rows[i].key = true;
    }
    r.after =
        summarise(op, contacts[k], ball_radius_mm(op, options), a_w, c_w, metric_feeds[k], &r.rows);
    r.feed_after = schedule_after[k].summary;
    r.feed_before = schedule_before[k].summary;
    if (optimised[k] && r.feed_after.cycle_time_s > r.feed_before.cycle_time_s * (1.0 + 1e-9)) {
      add_finding(
          res, FindingCode::LongerCycle, k, 0,
          "operation " + op.name + ": at the machine's limits the new axes take " +
              std::to_string(r.feed_after.cycle_time_s) + " s, the input's " +
              std::to_string(r.feed_before.cycle_time_s) + " s (" +
              (machine.gcode.feed_reference == FeedReference::Tip
                   ? "tip path of the feed moves " + std::to_string(r.feed_after.feed_path_mm) +
                         " mm against " + std::to_string(r.feed_before.feed_path_mm) +
                         " mm: with feed_reference \"tip\" the programmed feed applies to it)"
                   : std::string(
                         "the machine's limits hold the new axes back more; limiting axis ") +
                         (r.feed_after.limiting_axis.empty() ? "none"
                                                             : r.feed_after.limiting_axis) +
                         ")"));
    }
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      r.rows[i].feed_mm_min = schedule_after[k].feed_mm_min[i];
      r.rows[i].feed_before_mm_min = schedule_before[k].feed_mm_min[i];
    }
    check_dynamic_limits(r, po, written_joints(point_moves[k]), point_moves[k], moves, res,
                         tp.source, options.feed_schedule ? limits : machine.limits,
                         options.feed_schedule, machine.ac.tilt_letter(), k);
    // The checks' own time: this operation's verification without its C-space raster.
    r.time_verify_s = std::max(0.0, seconds_since(t_verify) - r.time_cspace_s);
    res.operations.push_back(std::move(r));
  }
  res.out_cls = format_cl(tp, out_ops);
  return res;
}

}  // namespace taxopt
