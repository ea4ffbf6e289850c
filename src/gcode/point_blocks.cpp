/// @file The blocks that reach the CL points: arcs, index moves, approaches, rapids (joint-safe
/// on LinuxCNC), feed blocks and their F words, linearisation (program_writer.hpp).

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "controller/feed_word.hpp"
#include "gcode/program_writer.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt::gcode {
namespace {

/// F with eight significant digits and at least `fd` decimals; where the controller takes
/// fewer than that (`max_fd`), rounded down: slower, never faster.
std::string precise_feed(double f, int fd, int max_fd) {
  const int digits =
      std::clamp(7 - static_cast<int>(std::floor(std::log10(std::max(f, 1e-300)))), fd, 15);
  if (digits <= max_fd) return fmt(f, digits);
  const double unit = std::pow(10.0, max_fd);
  return fmt(std::max(std::floor(f * unit), 1.0) / unit, max_fd);
}

}  // namespace

bool ProgramWriter::arc_at(std::size_t i) {
  const PostedOperation& op = *op_;
  while (arc_cursor_ < op.arcs.size() && op.arcs[arc_cursor_].start + 1 < i) ++arc_cursor_;
  if (arc_cursor_ >= op.arcs.size() || op.arcs[arc_cursor_].start + 1 != i) return false;
  const ArcRun& run = op.arcs[arc_cursor_];
  bool event_inside = false;
  for (const ProgramEvent& e : op.events) {
    if (e.before_point > run.start + 1 && e.before_point <= run.end) event_inside = true;
  }
  if (!event_inside && write_arc(run)) {
    ++prog_.arcs_kept;
    last_feed_block_ = true;
    last_joint_safe_ = false;
    return true;
  }
  ++prog_.arcs_chorded;
  return false;
}

std::optional<std::pair<double, bool>> ProgramWriter::arc_programmed_s(
    const ArcRun& run, const std::string& pose_words) const {
  const PostedOperation& op = *op_;
  double programmed_s = 0.0;
  bool own = true;
  for (std::size_t j = run.start + 1; j <= run.end; ++j) {
    const CLPointd& q = op.points[j];
    if (q.motion != Motion::Feed || !(q.feed_mm_per_min > 0.0) ||
        angle_words(op.poses[j]) != pose_words ||
        (j < op.block_time_s.size() && op.block_time_s[j] > 0.0) ||
        q.feed_mm_per_min != op.points[run.end].feed_mm_per_min) {
      return std::nullopt;
    }
    const double given_s = j < op.programmed_time_s.size() ? op.programmed_time_s[j] : 0.0;
    own = own && (given_s <= 0.0 || std::abs(given_s - own_times_[j]) <= 1e-9 * own_times_[j]);
    programmed_s += given_s > 0.0 ? given_s : own_times_[j];
  }
  return std::make_pair(programmed_s, own);
}

std::optional<ProgramWriter::OutputArc> ProgramWriter::output_arc(const ArcRun& run) const {
  const PostedOperation& op = *op_;
  // The arc where the points are now (new axes move the tips by the same vector where the
  // axis is the same along the arc), in the output frame.
  const Posed& pose = op.poses[run.start];
  const Vec3d centre_tip = run.centre_mm + (op.points[run.start].tip_mm - run.start_tip_mm);
  OutputArc arc;
  arc.centre = out_xyz(centre_tip, pose);
  arc.normal = (out_xyz(centre_tip + run.normal, pose) - arc.centre).normalized();
  arc.axis = -1;
  for (int q = 0; q < 3; ++q) {
    if (std::abs(std::abs(arc.normal[q]) - 1.0) < 1e-9) arc.axis = q;
  }
  if (arc.axis < 0) return std::nullopt;
  const Vec3d s0 = out_xyz(op.points[run.start].tip_mm, pose) - arc.centre;
  const Vec3d u0 = s0 - s0.dot(arc.normal) * arc.normal;
  arc.radius = u0.norm();
  if (arc.radius < 1e-3) return std::nullopt;
  arc.towards_start = u0 / arc.radius;
  for (std::size_t j = run.start; j <= run.end; ++j) {
    const Vec3d dj = out_xyz(op.points[j].tip_mm, op.poses[j]) - arc.centre;
    if (std::abs((dj - dj.dot(arc.normal) * arc.normal).norm() - arc.radius) >
        1e-6 * std::max(1.0, arc.radius)) {
      return std::nullopt;
    }
  }
  arc.end = out_xyz(op.points[run.end].tip_mm, op.poses[run.end]);
  arc.start_height = s0.dot(arc.normal);
  arc.end_height = (arc.end - arc.centre).dot(arc.normal);
  return arc;
}

std::optional<std::vector<ProgramWriter::ArcPiece>> ProgramWriter::arc_pieces(
    const ArcRun& run, const OutputArc& arc) const {
  const PostedOperation& op = *op_;
  const int pieces = std::max(1, static_cast<int>(std::ceil(run.sweep_rad / M_PI - 1e-9)));
  // Each piece as its words will read: start and end rounded, the centre offset rounded. A
  // controller refuses an arc whose radii to its rounded ends differ (our reader as LinuxCNC:
  // 0.002 mm + 0.1 %): a 0.05 in arc at 4 decimals in inches came out 1.2723 against 1.2677
  // mm and refused taxopt's own program. Such an arc is written as chords.
  std::vector<ArcPiece> planned(static_cast<std::size_t>(pieces));
  Vec3d from = rounded(out_xyz(op.points[run.start].tip_mm, op.poses[run.start]) * scale_) / scale_;
  const Vec3d& n = arc.normal;
  const Vec3d side = n.cross(arc.towards_start);
  for (int k = 1; k <= pieces; ++k) {
    const double frac = static_cast<double>(k) / pieces, th = run.sweep_rad * frac;
    ArcPiece& pc = planned[static_cast<std::size_t>(k - 1)];
    pc.to = k == pieces
                ? arc.end
                : arc.centre + (arc.start_height + (arc.end_height - arc.start_height) * frac) * n +
                      arc.radius * (std::cos(th) * arc.towards_start + std::sin(th) * side);
    pc.offset_mm = arc.centre - from;
    const Vec3d to_r = rounded(pc.to * scale_) / scale_;
    const Vec3d centre_r = from + rounded(pc.offset_mm * scale_) / scale_;
    const auto radius = [&](const Vec3d& p) {
      const Vec3d d = p - centre_r;
      return (d - d.dot(n) * n).norm();
    };
    const double r_from = radius(from), r_to = radius(to_r);
    if (std::abs(r_from - r_to) > 0.9 * (0.002 + 1e-3 * r_from)) return std::nullopt;
    from = to_r;
  }
  return planned;
}

bool ProgramWriter::write_arc(const ArcRun& run) {
  const PostedOperation& op = *op_;
  if (g_.feed_mode != FeedMode::UnitsPerMinute || !dialect_.rules().writes_arcs() || !have_prev_ ||
      run.end >= op.points.size() || run.end <= run.start + 1) {
    return false;
  }
  const std::string pose_words = angle_words(op.poses[run.start]);
  // The rotary words where tool centre point control came on: a Fanuc 30i raises PS5421 for
  // G2/G3 after A or C has turned under G43.4 (DialectRules::arc_after_tcp_turn).
  if (tcp_ && !dialect_.rules().arc_after_tcp_turn() && pose_words != tcp_angles_) {
    return false;  // the table turned under TCP since it came on: chords
  }
  const auto timed = arc_programmed_s(run, pose_words);
  if (!timed) return false;
  if (xyz_words(out_xyz(op.points[run.start].tip_mm, op.poses[run.start])) + pose_words !=
      last_words_) {
    return false;
  }
  const std::optional<OutputArc> arc = output_arc(run);
  if (!arc) return false;
  const std::optional<std::vector<ArcPiece>> planned = arc_pieces(run, *arc);
  if (!planned) return false;
  const double length_mm =
      std::hypot(run.sweep_rad * arc->radius, arc->end_height - arc->start_height);
  const double feed =
      timed->second ? op.points[run.end].feed_mm_per_min : length_mm / (timed->first / 60.0);
  const std::string f = fmt(feed * scale_, fd_);
  std::vector<int> piece_line;
  point_ = run.end;
  for (const ArcPiece& pc : *planned) {
    PlannedMove block;
    block.type = arc->normal[arc->axis] > 0.0 ? PlannedMove::Type::ArcCounterClockwise
                                              : PlannedMove::Type::ArcClockwise;
    block.given = 0x7;
    block.xyz_mm = pc.to;
    block.arc_axis = arc->axis;
    block.centre_offset_mm = pc.offset_mm;
    set_feed(block, f);
    piece_line.push_back(motion(block, BlockKind::Arc, false));
    ++prog_.arc_blocks;
  }
  const std::size_t pieces = planned->size();
  for (std::size_t j = run.start + 1; j < run.end; ++j) {
    const double frac =
        static_cast<double>(j - run.start) / static_cast<double>(run.end - run.start);
    const auto piece = std::min<std::size_t>(
        static_cast<std::size_t>(frac * static_cast<double>(pieces)), pieces - 1);
    emitted_[j] = -piece_line[piece];
  }
  emitted_[run.end] = piece_line.back();
  last_words_ = xyz_words(arc->end) + pose_words;
  advance_to(arc->end, op.poses[run.end], op.points[run.end].tip_mm);
  return true;
}

void ProgramWriter::advance_to(const Vec3d& xyz, const Posed& pose, const Vec3d& tip) {
  prev_xyz_ = xyz;
  prev_pose_ = pose;
  prev_tip_ = tip;
}

void ProgramWriter::point(std::size_t i) {
  const CLPointd& p = op_->points[i];
  const Posed& pose = op_->poses[i];
  const Vec3d xyz = out_xyz(p.tip_mm, pose);
  const std::string words = xyz_words(xyz) + angle_words(pose);
  if (i < index_target_) {  // passed over by the index move to index_target_
    passed_over_.push_back(i);
    return;
  }
  if (words == last_words_) return;  // nothing would move
  if (p.motion == Motion::Rapid && have_prev_ && retracts_ && !op_->swept_moves_checked &&
      !approach_) {
    index_target_ = index_move_if_turning(i);
    if (index_target_ > i) {
      passed_over_.push_back(i);
      return;
    }
  }
  if (approach_) approach(p, pose, xyz);
  if (p.motion == Motion::Rapid) {
    if (rapid(i, xyz, words)) return;
  } else {
    feed(i, xyz, words);
  }
  have_prev_ = true;
}

std::size_t ProgramWriter::index_move_if_turning(std::size_t i) {
  const PostedOperation& op = *op_;
  const Posed& pose = op.poses[i];
  const double turn_deg = std::max(
      std::abs(round_to(rad_to_deg(pose.tilt_rad), d_) -
               round_to(rad_to_deg(prev_pose_.tilt_rad), d_)),
      std::abs(round_to(rad_to_deg(pose.c_rad), d_) - round_to(rad_to_deg(prev_pose_.c_rad), d_)));
  if (!(turn_deg > g_.program.index_threshold_deg)) return i;
  // Up at the retract, the rapids after this one up to the next feed (or an event, which
  // happens where the file puts it) lead nowhere the tool must pass: the cycle turns to the
  // last of them and comes down there.
  std::size_t last = i;
  const auto event_before = [&](std::size_t m) {
    return std::any_of(op.events.begin(), op.events.end(),
                       [&](const ProgramEvent& e) { return e.before_point == m; });
  };
  while (last + 1 < op.points.size() && op.points[last + 1].motion == Motion::Rapid &&
         !event_before(last + 1)) {
    ++last;
  }
  length_and_tcp_off();
  retract();
  turn_table(op.poses[last]);
  length_and_tcp_on();
  approach_ = true;
  ++prog_.index_moves;
  return last;
}

void ProgramWriter::approach(const CLPointd& p, const Posed& pose, const Vec3d& xyz) {
  const Vec3d above_tip =
      approach_tip_mm(p.tip_mm, p.axis, clearance_z_mm_, g_.program.approach_clearance_mm);
  const Vec3d above = descend_ ? out_xyz(above_tip, pose) : xyz;
  if (descend_) {
    // The first move after the retract and the turn is a complete positioning: X, Y and Z
    // at the clearance height over the way down, in one block (as a production post writes
    // its first block under TCPC), never a lone Z from wherever the turn left the tip.
    rapid_block(rapid_linear(0x7, Vec3d(above.x(), above.y(), clearance_z_mm_)),
                BlockKind::Approach);
  } else {
    // Fanuc: its length and TCP come on with the block below.
    rapid_block(rapid_linear(0x3, above), BlockKind::Approach, !dialect_.length_on_first_move());
  }
  if (descend_ && std::abs(above.z() - clearance_z_mm_) * scale_ > 0.5 * std::pow(10.0, -d_)) {
    // A tool within 30 deg of the horizontal: straight down to the safe distance on its
    // axis, then along it.
    rapid_block(rapid_linear(0x4, above), BlockKind::Approach, false);
  }
  approach_ = false;
  // The tool comes from the retract: no move to schedule or split; under TCP a rapid to
  // the point comes from `above` along the axis (at a joint-safe feed on LinuxCNC).
  have_prev_ = descend_ && p.motion == Motion::Rapid;
  if (have_prev_) advance_to(above, pose, above_tip);
}

std::vector<double> ProgramWriter::linearised(const Vec3d& tip, const Posed& pose) const {
  return linearise_fractions(machine_.rotary, prev_tip_, prev_pose_, tip, pose,
                             g_.program.linearise_tolerance_mm);
}

Posed ProgramWriter::pose_at(const Posed& pose, double t) const {
  return Posed{prev_pose_.tilt_rad + t * (pose.tilt_rad - prev_pose_.tilt_rad),
               prev_pose_.c_rad + t * (pose.c_rad - prev_pose_.c_rad)};
}

bool ProgramWriter::rapid(std::size_t i, const Vec3d& xyz, const std::string& words) {
  const CLPointd& p = op_->points[i];
  const Posed& pose = op_->poses[i];
  if (g_.mode == GcodeMode::Machine && have_prev_) {
    // Rapids too: a table that turns while the tool traverses above the part would swing
    // the tip through it (the controller must run G0 linearly in the joints, as LinuxCNC
    // does; Fanuc: non-linear positioning off).
    const std::vector<double> at = linearised(p.tip_mm, pose);
    for (std::size_t j = 1; j + 1 < at.size(); ++j) {
      const Posed mid = pose_at(pose, at[j]);
      const Vec3d mid_xyz = out_xyz(prev_tip_ + at[j] * (p.tip_mm - prev_tip_), mid);
      motion(move_to(PlannedMove::Type::Rapid, mid_xyz, mid), BlockKind::Linearised);
      ++prog_.linearised_blocks;
    }
  }
  if (joint_safe_ && have_prev_) {
    const std::optional<double> rate =
        joint_safe_rate_per_s(machine_.rotary, limits_, prev_tip_, prev_pose_, p.tip_mm, pose);
    if (rate) {
      joint_safe_rapid(i, xyz, words, *rate);
      return true;
    }
  }
  finish_point(i, xyz, words, move_to(PlannedMove::Type::Rapid, xyz, pose), false);
  return false;
}

std::string ProgramWriter::joint_safe_feed(double tip_mm, double rot_deg, double rate_per_s) const {
  const double per_min = 60.0 * rate_per_s;
  const controller::FeedDistance d = controller::feed_distance(tip_mm, rot_deg);
  const double feed =
      g_.feed_mode == FeedMode::InverseTime ? per_min : d.distance * d.scale(scale_) * per_min;
  const int digits = std::clamp(
      7 - static_cast<int>(std::floor(std::log10(std::max(feed, 1e-300)))), fd_, max_fd_);
  const double unit = std::pow(10.0, digits);
  return fmt(std::max(std::floor(feed * unit), 1.0) / unit, digits);
}

int ProgramWriter::joint_safe_block(PlannedMove m, const std::string& f, BlockKind kind,
                                    bool takes_prefix) {
  m.type = PlannedMove::Type::Linear;
  set_feed(m, f);
  // LinuxCNC blends two feed blocks, and the blend leaves the programmed A and C (0.12 deg
  // measured at the end of a pass), so a dwell G4 P0 (the controller runs its queue to a
  // stop) stands between such a rapid and a feed block.
  if (last_feed_block_) line("G4 P0", BlockKind::Dwell);
  // Said where it happens: a machinist's rapid override does not govern a G1 (a machinist's
  // review of a LinuxCNC program found the F1176.99 blocks unexplained).
  if (!last_joint_safe_) {
    raw(dialect_.comment("joint-safe rapid: a feed block at the joints' rate, which the rapid "
                         "override does not govern"),
        kind);
  }
  const int at = motion(m, kind, takes_prefix);
  last_feed_block_ = false;
  last_joint_safe_ = true;
  prog_.joint_safe_rapids.push_back(at);
  return at;
}

void ProgramWriter::joint_safe_rapid(std::size_t i, const Vec3d& xyz, const std::string& words,
                                     double rate_per_s) {
  const CLPointd& p = op_->points[i];
  const Posed& pose = op_->poses[i];
  const double tip_mm = (p.tip_mm - prev_tip_).norm();
  const double rot_deg = std::hypot(rad_to_deg(pose.tilt_rad - prev_pose_.tilt_rad),
                                    rad_to_deg(pose.c_rad - prev_pose_.c_rad));
  emitted_[i] = joint_safe_block(move_to(PlannedMove::Type::Linear, xyz, pose),
                                 joint_safe_feed(tip_mm, rot_deg, rate_per_s),
                                 BlockKind::JointSafeRapid, true);
  last_words_ = words;
  advance_to(xyz, pose, p.tip_mm);
}

void ProgramWriter::finish_point(std::size_t i, const Vec3d& xyz, const std::string& words,
                                 const PlannedMove& block, bool restore_inverse_time) {
  const CLPointd& p = op_->points[i];
  if (last_joint_safe_ && p.motion != Motion::Rapid) line("G4 P0", BlockKind::Dwell);
  emitted_[i] = motion(block, BlockKind::Point, true, restore_inverse_time ? "G94 " : "");
  if (restore_inverse_time) last_feed_.clear();
  last_feed_block_ = p.motion != Motion::Rapid;
  last_joint_safe_ = false;
  if (tcp_angles_.empty()) tcp_angles_ = angle_words(op_->poses[i]);
  if (restore_inverse_time) line("G93", BlockKind::Point);
  last_words_ = words;
  advance_to(xyz, op_->poses[i], p.tip_mm);
}

void ProgramWriter::feed(std::size_t i, const Vec3d& xyz, const std::string& words) {
  const PostedOperation& op = *op_;
  const CLPointd& p = op.points[i];
  if (!(p.feed_mm_per_min > 0.0)) {
    throw std::invalid_argument("write_gcode: feed move without a feed");
  }
  const double programmed_min = programmed_minutes(i);
  // A scheduled block (never faster than programmed) writes its F with 8 significant
  // digits, so that rounding cannot carry it over the limits it was scheduled for; where
  // the controller takes fewer decimals, F is rounded down (slower, never faster).
  const bool scheduled = i < op.block_time_s.size() && op.block_time_s[i] > 0.0 && have_prev_;
  const double time_min =
      scheduled ? std::max(programmed_min, op.block_time_s[i] / 60.0) : programmed_min;
  const FeedBlock fb{programmed_min, time_min, scheduled};
  bool restore_inverse_time = false;
  std::string f;
  if (!have_prev_) {
    // First block of an operation at feed: where the tool comes from is unknown, so the
    // move is written at the programmed feed in G94 (G93 needs a block time).
    f = fmt(p.feed_mm_per_min * scale_, fd_);
    restore_inverse_time = g_.feed_mode == FeedMode::InverseTime;
  } else if (g_.mode == GcodeMode::Machine) {
    f = linearised_feed(i, xyz, fb);
  } else if (g_.feed_mode == FeedMode::InverseTime || scheduled) {
    // Hold F only where no limit slowed the block (the schedule keeps its programmed time)
    // and the next block does not speed up: a held F is slower than asked, so the step up to
    // a faster next block grows past what the schedule allowed (X at 100.116 of its
    // 100 mm/s^2 on LinuxCNC's max5, SOLIDWORKS CAM's glue file, where a new FEDRAT ramps up).
    f = joint_feed(prev_xyz_, prev_pose_, xyz, op.poses[i], time_min, scheduled,
                   keeps_programmed_time(i) && next_not_faster(i));
  } else {
    f = tcp_feed(i, programmed_min);
  }
  PlannedMove block = move_to(PlannedMove::Type::Linear, xyz, op.poses[i]);
  set_feed(block, f);
  finish_point(i, xyz, words, block, restore_inverse_time);
}

double ProgramWriter::programmed_minutes(std::size_t i) const {
  const PostedOperation& op = *op_;
  const double given_s = i < op.programmed_time_s.size() ? op.programmed_time_s[i] : 0.0;
  return (given_s > 0.0 ? given_s : own_times_[i]) / 60.0;
}

bool ProgramWriter::keeps_programmed_time(std::size_t i) const {
  const PostedOperation& op = *op_;
  return !(i < op.block_time_s.size() &&
           op.block_time_s[i] / 60.0 > programmed_minutes(i) * (1.0 + 1e-12));
}

bool ProgramWriter::next_not_faster(std::size_t i) const {
  const PostedOperation& op = *op_;
  const std::size_t n = i + 1;
  if (n >= op.points.size() || op.points[n].motion == Motion::Rapid) return true;
  return op.points[n].feed_mm_per_min == op.points[i].feed_mm_per_min && keeps_programmed_time(n);
}

std::string ProgramWriter::tcp_feed(std::size_t i, double programmed_min) const {
  const CLPointd& p = op_->points[i];
  const Posed& pose = op_->poses[i];
  const double tip_mm = (p.tip_mm - prev_tip_).norm();
  const double rot_deg = std::hypot(rad_to_deg(pose.tilt_rad - prev_pose_.tilt_rad),
                                    rad_to_deg(pose.c_rad - prev_pose_.c_rad));
  const controller::FeedDistance d = controller::feed_distance(tip_mm, rot_deg);
  const double feed = d.distance / programmed_min;  // mm/min, or deg/min where only A C turn
  const bool own = std::abs(feed - p.feed_mm_per_min) <= 1e-9 * p.feed_mm_per_min;
  // A turn of A and C alone is read in deg/min whatever the length unit (G20 too): F is not
  // scaled to inches there (it was, and such a block ran 25.4 times slower than planned).
  return fmt((own ? p.feed_mm_per_min : feed) * d.scale(scale_), fd_);
}

std::string ProgramWriter::joint_feed(const Vec3d& from, const Posed& from_pose, const Vec3d& to,
                                      const Posed& to_pose, double minutes, bool scheduled,
                                      bool may_hold) {
  const auto fmt_feed = [&](double f) {
    return scheduled ? precise_feed(f, fd_, max_fd_) : fmt(f, fd_);
  };
  // The feed of the unrounded move: its joint-space XYZ length (or, where X Y Z stand still,
  // its turn in deg) over the block's time, in the program's units.
  const double joint = (to - from).norm();
  const double rot = std::hypot(rad_to_deg(to_pose.tilt_rad - from_pose.tilt_rad),
                                rad_to_deg(to_pose.c_rad - from_pose.c_rad));
  const controller::FeedDistance d = controller::feed_distance(joint, rot);
  const double unrounded = d.distance * d.scale(scale_) / minutes;
  if (g_.feed_mode == FeedMode::InverseTime) return fmt_feed(1.0 / minutes);
  if (scheduled) {
    // The controller times the block from the written (rounded) words: so does F.
    const double len = (rounded(to * scale_) - rounded(from * scale_)).norm();
    const double rounded_rot = std::hypot(
        round_to(rad_to_deg(to_pose.tilt_rad), d_) - round_to(rad_to_deg(from_pose.tilt_rad), d_),
        round_to(rad_to_deg(to_pose.c_rad), d_) - round_to(rad_to_deg(from_pose.c_rad), d_));
    const double exact = (len > 0.0 ? len : rounded_rot) / minutes;
    // The feed the schedule asks for, before rounding: on blocks a few rounding steps long
    // the rounded length swings `exact` from block to block at one scheduled feed (a Fusion
    // inch file: F2.7528 ... F2.8724, +4.2 %, on blocks under 0.001 in). Where the block runs
    // at its programmed feed (no limit slowed it) and the scheduled feed is the previous
    // block's, the F in force is held if it is not faster than this block's `exact` and slower
    // by no more than the block's rounding uncertainty (both ends' words, sqrt(3) 10^-d, of its
    // length; at most 5 %): never faster than scheduled, and the controller keeps one feed.
    // Where the schedule ramps or a limit holds the feed down, F follows it block by block:
    // held over a ramp, the jump after it broke a B axis's acceleration (2027 deg/s^2), and on
    // arcs at an acceleration limit a held block put X at 300.03 of its 300 mm/s^2.
    const bool steady = std::abs(unrounded - last_asked_) <= 1e-9 * unrounded;
    last_asked_ = unrounded;
    if (may_hold && steady && !last_feed_.empty() && exact > 0.0) {
      const double held = std::strtod(last_feed_.c_str(), nullptr);
      const double slack = std::min(0.05, std::sqrt(3.0) * std::pow(10.0, -d_) /
                                              std::max(len > 0.0 ? len : rounded_rot, 1e-300));
      if (held <= exact && held >= exact * (1.0 - slack)) return last_feed_;
    }
    return fmt_feed(exact);
  }
  // Joint-space XYZ moves differ from the tip's: F makes the block take the time of the
  // tip at the programmed feed.
  return fmt(unrounded, fd_);
}

std::string ProgramWriter::linearised_feed(std::size_t i, const Vec3d& xyz, const FeedBlock& fb) {
  const PostedOperation& op = *op_;
  const CLPointd& p = op.points[i];
  const Posed& pose = op.poses[i];
  const std::vector<double> at = linearised(p.tip_mm, pose);
  Vec3d from = prev_xyz_;
  Posed from_pose = prev_pose_;
  for (std::size_t j = 1; j < at.size(); ++j) {
    const Posed mid = pose_at(pose, at[j]);
    const Vec3d mid_xyz = out_xyz(prev_tip_ + at[j] * (p.tip_mm - prev_tip_), mid);
    double minutes = fb.time_min * (at[j] - at[j - 1]);
    if (fb.scheduled && i < op.linearised_time_s.size() &&
        op.linearised_time_s[i].size() + 1 == at.size()) {
      // Block by block as scheduled, never faster than programmed.
      minutes =
          std::max(fb.programmed_min * (at[j] - at[j - 1]), op.linearised_time_s[i][j - 1] / 60.0);
    }
    if (j + 1 == at.size()) return joint_feed(from, from_pose, xyz, pose, minutes, fb.scheduled);
    const std::string piece = joint_feed(from, from_pose, mid_xyz, mid, minutes, fb.scheduled);
    PlannedMove block = move_to(PlannedMove::Type::Linear, mid_xyz, mid);
    set_feed(block, piece);
    motion(block, BlockKind::Linearised);
    ++prog_.linearised_blocks;
    from = mid_xyz;
    from_pose = mid;
  }
  return {};
}

}  // namespace taxopt::gcode
