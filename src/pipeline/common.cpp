// Helpers shared by the stages of a run (stages.hpp).
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "pipeline/stages.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"
#include "util/parallel_select.hpp"
#include "util/progress.hpp"

namespace taxopt::pipeline {
namespace {

/// The severity of a kind of finding (job.hpp groups them).
Severity severity_of(FindingCode code) {
  switch (code) {
    case FindingCode::NoPart:
    case FindingCode::NoHolderModel:
    case FindingCode::NoSafeRetract:
    case FindingCode::NoLinearisation:
    case FindingCode::NoToolModel:
    case FindingCode::NoCoolant:
    case FindingCode::NoWorkOffset: return Severity::Safety;
    case FindingCode::NotABallMill:
    case FindingCode::LocalGouge:
    case FindingCode::InputAxesKept:
    case FindingCode::MissingFeed:
    case FindingCode::JerkLimitExceeded:
    case FindingCode::LongerCycle:
    case FindingCode::ClFileNote:
    case FindingCode::TcpJointLimit:
    case FindingCode::FeedInAir:
    case FindingCode::MeshSlivers:
    case FindingCode::PartTolerance:
    case FindingCode::AxisRateRose:
    case FindingCode::LeastTiltNotKept: return Severity::Warning;
    default: return Severity::Problem;
  }
}

}  // namespace

/// Records a finding, and its message by severity (JobResult's display lists).
void add_finding(JobResult& res, FindingCode code, std::optional<std::size_t> operation, int line,
                 const std::string& message, std::optional<int> gcode_line) {
  const Severity severity = severity_of(code);
  res.findings.push_back(Finding{code, severity, operation, line, message, gcode_line});
  (severity == Severity::Problem  ? res.problems
   : severity == Severity::Safety ? res.safety_warnings
                                  : res.warnings)
      .push_back(message);
}

/// Ball radius of an operation's tool: the override, else the file's (0: not a ball-end mill).
double ball_radius_mm(const Operationd& op, const JobOptions& options) {
  return options.tool.ball_radius_mm.value_or(op.tool.ball_radius_mm());
}

/// Why an operation with no ball radius is left alone: no tool at all in the file, or another
/// kind of tool.
std::string not_a_ball(const Operationd& op, const JobOptions& options) {
  if (!op.tool.from_file) {
    return "operation " + op.name +
           ": the CL file defines no tool (no TLDATA or CUTTER record); give the ball radius "
           "with " +
           options.name_of("tool.ball_radius_mm");
  }
  return "operation " + op.name + ": not a ball-end mill";
}

std::string shown(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

/// The margins the collision checks judge the tool's bodies by (ToolMargins).
ToolMargins margins_of(const JobOptions& options, const Operationd& op) {
  ToolMargins m;
  m.shank_clearance_mm = options.shank_clearance_mm.value_or(kDefaultShankClearanceMm);
  m.holder_clearance_mm = options.holder_clearance_mm.value_or(kDefaultHolderClearanceMm);
  if (options.part) m.flute_tolerance_mm = part_tolerance_mm(options, op);
  return m;
}

namespace {

/// The contact options with the tolerance left to its default (derived from the mesh and the
/// CL file): what the part tolerance follows.
ContactOptions derived_contact(const JobOptions& options) {
  ContactOptions derived = options.contact;
  derived.tolerance_mm = 0.0;
  return derived;
}

}  // namespace

/// The part tolerance: how deep the flutes may reach into the mesh (--part-tolerance), else
/// what the contact tolerance is derived from (the mesh's chordal error and the CL file's
/// tolerance) -- never the contact tolerance as given: a tolerance that lets a ball sit on a
/// coarse mesh is no budget for the tool's side to gouge the part.
double part_tolerance_mm(const JobOptions& options, const Operationd& op) {
  if (options.part_tolerance_mm) return *options.part_tolerance_mm;
  return contact_tolerance_mm(*options.part, derived_contact(options), op.cam_tolerance_mm);
}

/// Where part_tolerance_mm comes from, in words.
std::string part_tolerance_source(const JobOptions& options, const Operationd& op) {
  if (options.part_tolerance_mm) return "as given";
  return contact_tolerance_source(*options.part, derived_contact(options), op.cam_tolerance_mm);
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

std::vector<double> segment_lengths_mm(const Operationd& op, double ball_radius_mm,
                                       const IndexRange& pass) {
  std::vector<double> len;
  for (std::size_t i = pass.begin; i + 1 < pass.end; ++i) {
    len.push_back((reference_point(op.points[i + 1], ball_radius_mm) -
                   reference_point(op.points[i], ball_radius_mm))
                      .norm());
  }
  return len;
}

std::vector<double> contact_lengths_mm(const Operationd& op,
                                       const std::vector<ContactPoint>& contacts,
                                       double ball_radius_mm, const IndexRange& pass, bool facets) {
  std::vector<double> len = segment_lengths_mm(op, ball_radius_mm, pass);
  const auto at = [&](std::size_t i) -> const Vec3d& {
    return facets ? contacts[i].cc_mm : contacts[i].surface_cc_mm;
  };
  for (std::size_t i = pass.begin; i + 1 < pass.end; ++i) {
    if (!contacts.empty() && contacts[i].state == ContactState::Touching &&
        contacts[i + 1].state == ContactState::Touching) {
      len[i - pass.begin] = (at(i + 1) - at(i)).norm();
    }
  }
  return len;
}

BlockTiming block_timing(const Operationd& op, const Machine& machine,
                         const PosePlanOptions& pose_options,
                         const std::vector<double>& metric_feed) {
  BlockTiming timing;
  timing.feed_mm_per_min = metric_feed;
  timing.max_feed_ratio = machine.gcode.max_feed_ratio;
  if (machine.gcode.feed_reference != FeedReference::CutterPath) return timing;
  std::vector<Vec3d> axes;
  for (const CLPointd& p : op.points) axes.push_back(p.axis);
  const PosePlan input = plan_poses(machine.rotary, axes, rapid_into_of(op), {}, pose_options);
  if (!input.ok()) return timing;
  timing.kept_s.assign(op.points.size(), 0.0);
  for (std::size_t i = 1; i < op.points.size(); ++i) {
    if (op.points[i].motion != Motion::Feed || !(metric_feed[i] > 0.0)) continue;
    timing.kept_s[i] = programmed_move_time_s(op.points[i - 1].tip_mm, input.poses[i - 1],
                                              op.points[i].tip_mm, input.poses[i], metric_feed[i]);
  }
  return timing;
}

std::vector<double> move_times_s(const Operationd& op, double ball_radius_mm,
                                 const MachineKinematicsd& ac, const std::vector<Posed>& poses,
                                 const BlockTiming& timing, const IndexRange& range) {
  std::vector<double> t;
  Vec3d from = Vec3d::Zero();
  for (std::size_t i = range.begin; i < range.end; ++i) {
    const Vec3d tip = tip_for_axis(op.points[i], ball_radius_mm, ac.forward(poses[i]));
    if (i > range.begin) t.push_back(timing.move_time_s(i, from, poses[i - 1], tip, poses[i]));
    from = tip;
  }
  return t;
}

namespace {

/// Adds the passes of `op` to a summary with each move's time from `time_of(pass)`; fills the
/// rows' omega and accel (before or after) and, with `arc_mm`, their arc length.
template <class TimeOf>
RotarySummary summarise_passes(const Operationd& op, const std::vector<double>& tilt_deg,
                               const std::vector<double>& c_deg, const TimeOf& time_of,
                               std::vector<PointRow>* rows, bool rows_before) {
  RotarySummary summary;
  for (const IndexRange& pass : feed_passes(op)) {
    const std::vector<double> a = slice(tilt_deg, pass.begin, pass.end);
    const std::vector<double> c = slice(c_deg, pass.begin, pass.end);
    const RotaryKinematics k = rotary_kinematics_from_times(a, c, time_of(pass));
    accumulate(summary, k, c);
    if (rows) {
      for (std::size_t j = 0; j < pass.size(); ++j) {
        PointRow& r = (*rows)[pass.begin + j];
        (rows_before ? r.omega_before_deg_s : r.omega_deg_s) = k.omega_deg_s[j];
        (rows_before ? r.accel_before_deg_s2 : r.accel_deg_s2) = k.accel_deg_s2[j];
        if (!rows_before) {
          r.omega_tilt_deg_s = k.omega_tilt_deg_s[j];
          r.omega_c_deg_s = k.omega_c_deg_s[j];
          r.accel_tilt_deg_s2 = k.accel_tilt_deg_s2[j];
          r.accel_c_deg_s2 = k.accel_c_deg_s2[j];
        }
        // A flip as RotarySummary::c_jumps counts it (metrics.cpp).
        if (j > 0 && std::abs(c[j] - c[j - 1]) > 90.0) {
          r.mark(rows_before ? PointMark::CFlipBefore : PointMark::CFlip);
        }
      }
    }
  }
  return summary;
}

}  // namespace

RotarySummary summarise_timed(const Operationd& op, const std::vector<double>& tilt_deg,
                              const std::vector<double>& c_deg,
                              const std::vector<double>& time_into_s, std::vector<PointRow>* rows,
                              bool rows_before) {
  return summarise_passes(
      op, tilt_deg, c_deg,
      [&](const IndexRange& pass) { return slice(time_into_s, pass.begin + 1, pass.end); }, rows,
      rows_before);
}

RotarySummary summarise_paper(const Operationd& op, const std::vector<ContactPoint>& contacts,
                              double ball_radius_mm, const std::vector<double>& tilt_deg,
                              const std::vector<double>& c_deg,
                              const std::vector<double>& metric_feed, std::vector<PointRow>* rows,
                              bool facets) {
  double arc = 0.0;
  return summarise_passes(
      op, tilt_deg, c_deg,
      [&](const IndexRange& pass) {
        const std::vector<double> len =
            contact_lengths_mm(op, contacts, ball_radius_mm, pass, facets);
        if (rows) {
          for (std::size_t j = 0; j < pass.size(); ++j) {
            if (j > 0) arc += len[j - 1];
            (*rows)[pass.begin + j].arc_mm = arc;
          }
        }
        const std::vector<double> a = slice(tilt_deg, pass.begin, pass.end);
        const std::vector<double> c = slice(c_deg, pass.begin, pass.end);
        return segment_times_s(len, pass_feeds(metric_feed, pass), a, c);
      },
      nullptr, false);
}

/// Joint positions (X Y Z mm, A C deg) of tips and poses: the machine-mode convention of
/// CLI.md, which is where the joints are whatever the G-code mode.
std::vector<JointPosition> joints_of(const MachineKinematicsd& ac,
                                     const std::vector<Vec3d>& tips_mm,
                                     const std::vector<Posed>& poses) {
  std::vector<JointPosition> q(tips_mm.size());
  for (std::size_t i = 0; i < q.size(); ++i) {
    const Vec3d m = ac.to_machine_mm(tips_mm[i], poses[i]);
    q[i] = {m.x(), m.y(), m.z(), rad_to_deg(poses[i].tilt_rad), rad_to_deg(poses[i].c_rad)};
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

namespace {

/// One operation's schedule: its feed chains each scheduled on the joints (FeedScheduler),
/// a point's time the sum of its blocks', then the operation's summary (feed and rapid times,
/// the path the limits slow and the axis that slows most of it).
class OperationScheduler {
 public:
  OperationScheduler(const std::vector<CLPointd>& points, const std::vector<JointPosition>& joints,
                     const std::vector<double>& programmed_s, const JointLimits& limits,
                     const MachineKinematicsd& ac, const std::vector<Linearised>* via,
                     const std::vector<Posed>* tcp_poses, const StopSource* stop)
      : points_(points),
        joints_(joints),
        programmed_s_(programmed_s),
        limits_(limits),
        ac_(ac),
        via_(via),
        tcp_poses_(tcp_poses),
        stop_(stop),
        n_(points.size()),
        bound_(n_, FeedBound::Programmed),
        bound_joint_(n_, Joint::X),
        joint_bound_(n_) {
    out_.time_s.assign(n_, 0.0);
    out_.feed_mm_min.assign(n_, std::nullopt);
    out_.block_time_s.assign(n_, {});
  }

  OperationSchedule run() {
    for (const IndexRange& c : feed_chains(points_)) {
      if (stop_) stop_->throw_if_stop_requested();
      schedule_chain(c);
    }
    summarise();
    return std::move(out_);
  }

 private:
  const Linearised* blocks_of(std::size_t i) const {
    return via_ && i < via_->size() && !(*via_)[i].share.empty() ? &(*via_)[i] : nullptr;
  }

  /// The chain's blocks: one a point, or a linearised move's blocks, each with its share of
  /// the programmed time; `owner` maps a block to its point.
  FeedChain chain_of(const IndexRange& c, std::vector<std::size_t>& owner) {
    FeedChain chain;
    chain.joints = {joints_[c.begin - 1]};
    for (std::size_t i = c.begin; i < c.end; ++i) {
      detail::look_at_stop(stop_, i, detail::kPointStride);
      if (const Linearised* l = blocks_of(i)) {
        for (std::size_t j = 0; j < l->share.size(); ++j) {
          chain.joints.push_back(j < l->joints.size() ? l->joints[j] : joints_[i]);
          chain.min_time_s.push_back(programmed_s_[i] * l->share[j]);
          owner.push_back(i);
        }
        continue;
      }
      chain.joints.push_back(joints_[i]);
      double least_s = programmed_s_[i];
      if (tcp_poses_ && i < tcp_poses_->size()) {
        const auto [rate, joint] =
            joint_velocity_rate_per_s(ac_, limits_, points_[i - 1].tip_mm, (*tcp_poses_)[i - 1],
                                      points_[i].tip_mm, (*tcp_poses_)[i]);
        if (1.0 / rate > least_s) {
          least_s = 1.0 / rate;
          joint_bound_[i] = joint;
        }
      }
      chain.min_time_s.push_back(least_s);
      owner.push_back(i);
    }
    return chain;
  }

  void schedule_chain(const IndexRange& c) {
    std::vector<std::size_t> owner;
    const FeedChain chain = chain_of(c, owner);
    const FeedSchedule s = schedule_feed(chain, limits_);
    out_.summary.sweeps = std::max(out_.summary.sweeps, s.sweeps);
    // A point's time adds up its blocks'; its bound is that of its most slowed block.
    std::vector<double> slowed(n_, 0.0);
    for (std::size_t b = 0; b < owner.size(); ++b) {
      const std::size_t i = owner[b];
      out_.time_s[i] += s.time_s[b];
      if (blocks_of(i)) out_.block_time_s[i].push_back(s.time_s[b]);
      const double ratio = chain.min_time_s[b] > 0.0 ? s.time_s[b] / chain.min_time_s[b] : 1.0;
      if (ratio > slowed[i]) {
        slowed[i] = ratio;
        bound_[i] = s.bound[b];
        bound_joint_[i] = s.bound_joint[b];
        if (s.bound[b] == FeedBound::Programmed && joint_bound_[i]) {
          // At its joints' velocity limit inside the block (tcp_poses).
          bound_[i] = FeedBound::Velocity;
          bound_joint_[i] = *joint_bound_[i];
        }
      }
    }
  }

  /// A rapid's time, and what its turn adds: the same move without the turn holds the rotary
  /// joints where the move starts, the linear ones taking the tip to its point under that pose.
  void rapid(std::size_t i) {
    FeedSummary& sum = out_.summary;
    const double t = rapid_time_s(joints_[i - 1], joints_[i], limits_);
    constexpr std::size_t kA = static_cast<std::size_t>(Joint::Tilt);
    constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
    const Posed start{deg_to_rad(joints_[i - 1][kA]), deg_to_rad(joints_[i - 1][kC])};
    const Vec3d xyz = ac_.to_machine_mm(points_[i].tip_mm, start);
    const JointPosition held = {xyz.x(), xyz.y(), xyz.z(), joints_[i - 1][kA], joints_[i - 1][kC]};
    sum.rapid_time_s += t;
    sum.transition_excess_s += std::max(0.0, t - rapid_time_s(joints_[i - 1], held, limits_));
  }

  void summarise() {
    FeedSummary& sum = out_.summary;
    double path_mm = 0.0, limited_mm = 0.0;
    std::array<double, kJointCount> by_velocity{}, by_accel{};
    bool any_feed = false;
    for (std::size_t i = 1; i < n_; ++i) {
      detail::look_at_stop(stop_, i, detail::kPointStride);
      if (points_[i].motion == Motion::Rapid) {
        rapid(i);
        continue;
      }
      if (!(out_.time_s[i] > 0.0)) continue;
      sum.feed_time_s += out_.time_s[i];
      const double feed = points_[i].feed_mm_per_min * programmed_s_[i] / out_.time_s[i];
      out_.feed_mm_min[i] = feed;
      sum.min_feed_mm_min = any_feed ? std::min(sum.min_feed_mm_min, feed) : feed;
      any_feed = true;
      const double len = (points_[i].tip_mm - points_[i - 1].tip_mm).norm();
      path_mm += len;
      if (out_.time_s[i] > programmed_s_[i] * (1.0 + 1e-9)) {
        limited_mm += len;
        const std::size_t j = static_cast<std::size_t>(bound_joint_[i]);
        (bound_[i] == FeedBound::Velocity ? by_velocity : by_accel)[j] += len;
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
          sum.limiting_axis = joint_name(static_cast<Joint>(j), ac_.tilt_letter());
          sum.limiting_kind = kind;
        }
      }
    }
  }

  const std::vector<CLPointd>& points_;
  const std::vector<JointPosition>& joints_;
  const std::vector<double>& programmed_s_;
  const JointLimits& limits_;
  const MachineKinematicsd& ac_;
  const std::vector<Linearised>* via_;
  const std::vector<Posed>* tcp_poses_;
  const StopSource* stop_;
  const std::size_t n_;
  OperationSchedule out_;
  std::vector<FeedBound> bound_;
  std::vector<Joint> bound_joint_;
  std::vector<std::optional<Joint>> joint_bound_;
};

}  // namespace

OperationSchedule schedule_operation(const std::vector<CLPointd>& points,
                                     const std::vector<JointPosition>& joints,
                                     const std::vector<double>& programmed_s,
                                     const JointLimits& limits, const MachineKinematicsd& ac,
                                     const std::vector<Linearised>* via,
                                     const std::vector<Posed>* tcp_poses, const StopSource* stop) {
  return OperationScheduler(points, joints, programmed_s, limits, ac, via, tcp_poses, stop).run();
}

/// Indices of the points of `op` whose tool collides, for axes `axes` (tips from the fixed
/// ball centres). In parallel; the result is sorted, whatever the thread count.
std::vector<std::size_t> colliding_points(const PartCheck& model, const ToolModel& tool,
                                          const Operationd& op, const std::vector<Vec3d>& axes,
                                          const std::vector<ContactPoint>& contacts,
                                          detail::StageProgress* progress,
                                          const std::vector<char>* only) {
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

std::optional<std::string> outside_travel(const Machine& machine, int q, double v_mm) {
  const auto& range = machine.linear_range[static_cast<std::size_t>(q)];
  if (range.contains(v_mm) ||
      std::abs(v_mm - std::clamp(v_mm, range.min_mm, range.max_mm)) < 1e-6) {
    return std::nullopt;
  }
  std::ostringstream os;
  os << ", outside the machine's travel [" << range.min_mm << ", " << range.max_mm << "] mm";
  return os.str();
}

std::ptrdiff_t move_index(const std::vector<GcodeMove>& moves, const GcodeMove* m) {
  // std::less: a pointer into another container compares without unspecified behaviour.
  const std::less<const GcodeMove*> before;
  if (moves.empty() || before(m, moves.data()) || !before(m, moves.data() + moves.size())) {
    return -1;
  }
  return m - moves.data();
}

/// Per point, whether the move into it is a rapid (the first point counts as one).
std::vector<bool> rapid_into_of(const Operationd& op) {
  std::vector<bool> rapid_into;
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    rapid_into.push_back(i == 0 || op.points[i].motion == Motion::Rapid);
  }
  return rapid_into;
}

/// The feed points of `op` as posted: feed moves without a feed get `fallback_feed`.
std::vector<CLPointd> posted_feeds(const Operationd& op, double fallback_feed) {
  std::vector<CLPointd> points = op.points;
  for (CLPointd& p : points) {
    if (!(p.feed_mm_per_min > 0.0)) p.feed_mm_per_min = fallback_feed;
  }
  return points;
}

std::string msys_remedy(const Run& run, const CLPointd& p) {
  const ClFrame* frame = nullptr;
  for (const ClFrame& f : run.tp.declared_frames) {
    if (f.line <= p.line) frame = &f;
  }
  if (!frame || !run.machine.rotary.reachable(Vec3d(frame->rotation.transpose() * p.axis)))
    return "";
  return "; the file's MSYS (line " + std::to_string(frame->line) +
         ") turns its axes: its coordinates taken into that frame (" +
         option_name(run.options.option_names, "ClReadOptions::apply_msys") +
         ") give an axis the machine reaches";
}

}  // namespace taxopt::pipeline
