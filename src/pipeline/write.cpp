// The write stage: the program written, read back as a controller reads it, and scheduled at
// the machine's limits (stages.hpp).
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "controller/feed_word.hpp"
#include "controller/linuxcnc_planner.hpp"
#include "dialects/dialect_rules.hpp"
#include "gcode/program_writer.hpp"
#include "pipeline/stages.hpp"
#include "taxopt/core/version.hpp"
#include "taxopt/kinematics/machine.hpp"
#include "util/parallel.hpp"
#include "util/progress.hpp"

namespace taxopt::pipeline {
namespace {

using controller::TcpBlock;

/// Reads `program` back and finds, per operation and point, the move that put the machine
/// there. A chord point inside a G2/G3 block gets the point of the arc read back at its angle
/// (with the block's words), so that every check sees the path the controller runs; the blocks
/// that split an arc at 180 deg belong to no point and are stepped over.
void read_back(const Machine& machine, const std::vector<PostedOperation>& posted,
               const GcodeProgram& program, Written& w, const StopSource* stop) {
  w.moves = gcode::read_moves(program.text, "written G-code", machine.gcode.dialect,
                              program.verbatim_lines, machine.rotary.tilt_letter(),
                              program.tool_calls, stop);
  w.on_arcs.clear();
  w.way_points.assign(posted.size(), {});
  w.point_moves.assign(posted.size(), {});
  const std::vector<GcodeMove>& moves = w.moves;
  std::size_t next = 0;
  const auto mismatch = [] {
    throw std::logic_error("run_job: G-code read back does not match what was written");
  };
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const GcodeMove* last = nullptr;
    w.way_points[k].resize(posted[k].points.size());
    for (std::size_t i = 0; i < posted[k].points.size(); ++i) {
      const int line = program.emitted[k][i];
      if (line != 0) {
        while (next < moves.size() && moves[next].line < std::abs(line)) {
          const GcodeMove& m = moves[next++];
          if (i > 0 && !m.arc && !m.positioning) {
            w.way_points[k][i].push_back({m.xyz_mm, m.tilt_deg, m.c_deg});
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
        w.on_arcs.push_back(at);
        last = &w.on_arcs.back();
      }
      if (!last) throw std::logic_error("run_job: first point of an operation not written");
      w.point_moves[k].push_back(last);
    }
  }
}

/// The linearisation blocks of every feed move read back (Linearised): the blocks between
/// two points' moves, their joints and their shares of the move's time as written.
std::vector<Linearised> linearised_blocks(const Machine& machine, const PostedOperation& po,
                                          const std::vector<const GcodeMove*>& at,
                                          const std::vector<GcodeMove>& moves, LengthUnit units,
                                          const StopSource* stop) {
  std::vector<Linearised> via(po.points.size());
  const auto index_of = [&](const GcodeMove* m) { return move_index(moves, m); };
  for (std::size_t i = 1; i < po.points.size(); ++i) {
    detail::look_at_stop(stop, i, detail::kPointStride);
    if (po.points[i].motion != Motion::Feed || at[i] == at[i - 1]) continue;
    const std::ptrdiff_t from = index_of(at[i - 1]), to = index_of(at[i]);
    if (from < 0 || to <= from + 1) continue;
    Linearised& l = via[i];
    double total = 0.0;
    for (std::ptrdiff_t j = from + 1; j <= to; ++j) {
      const GcodeMove& m = moves[static_cast<std::size_t>(j)];
      if (m.positioning || m.arc) return std::vector<Linearised>(po.points.size());
      if (j < to) l.joints.push_back(written_joints(machine, {&m}).front());
      l.share.push_back(block_time_s(moves[static_cast<std::size_t>(j - 1)], m, units));
      total += l.share.back();
    }
    if (!(total > 0.0)) {
      via[i] = Linearised{};
      continue;
    }
    for (double& s : l.share) s /= total;
  }
  return via;
}

/// FeedSummary::table_turn_s of every operation, before and after.
void count_table_turns(const Run& run, const std::vector<OperationContext>& ops,
                       const std::vector<PostedOperation>& posted, const JointLimits& limits,
                       Written& w) {
  const auto turn_s = [&](const Posed& from, const Posed& to) {
    JointPosition a{}, b{};
    a[static_cast<std::size_t>(Joint::Tilt)] = rad_to_deg(from.tilt_rad);
    a[static_cast<std::size_t>(Joint::C)] = rad_to_deg(from.c_rad);
    b[static_cast<std::size_t>(Joint::Tilt)] = rad_to_deg(to.tilt_rad);
    b[static_cast<std::size_t>(Joint::C)] = rad_to_deg(to.c_rad);
    return rapid_time_s(a, b, limits);
  };
  const bool home_at_end = run.machine.gcode.program.end_pose == EndPose::Home;
  for (int side = 0; side < 2; ++side) {
    Posed prev{0.0, 0.0};  // home
    for (std::size_t k = 0; k < posted.size(); ++k) {
      const std::vector<Posed>& poses =
          side == 1 && !ops[k].input_poses.empty() ? ops[k].input_poses : posted[k].poses;
      if (poses.empty()) continue;
      double t = turn_s(prev, poses.front());
      if (k + 1 == posted.size() && home_at_end) t += turn_s(poses.back(), Posed{0.0, 0.0});
      prev = poses.back();
      FeedSummary& s = (side == 0 ? w.schedule_after : w.schedule_before)[k].summary;
      s.table_turn_s = t;
    }
  }
}

/// GcodeProgram::time_s: the feed blocks at their scheduled times (the operations'
/// feed_time_s), every rapid block read back rest to rest (rapid_time_s) in the space the
/// controller plans it in. The machine's state is followed from the end of the first retract
/// as joints referred to the tip (kinematics/machine.hpp); the spindle's reference point is the
/// tool length above it.
class ProgramClock {
 public:
  ProgramClock(const Run& run, Written& w, const JointLimits& limits, LengthUnit units,
               const GcodeProgram& g, std::vector<TcpBlock>& tcp_blocks)
      : machine_(run.machine),
        t_(run.machine.gcode.program),
        w_(w),
        limits_(limits),
        units_(units),
        g_(g),
        tcp_blocks_(tcp_blocks),
        length_mm_(run.options.tool.gauge_length_mm.value_or(0.0)),
        placed_(run.machine.work_offset_mm && run.options.tool.gauge_length_mm),
        lcnc_(gcode::rules_of(run.machine.gcode.dialect).tcp_planned_in_program_axes()),
        stop_(run.options.stop) {
    tcp_blocks_.clear();
    if (lcnc_) tcp_blocks_.reserve(w_.moves.size());  // a block a move, not grown by doubling
    w_.spindle_mm.assign(w_.moves.size(), std::nullopt);
    w_.joints_after.assign(w_.moves.size(), std::nullopt);
    w_.tip_linear.assign(w_.moves.size(), 0);
    if (lcnc_) half_accel_ = controller::half_accel_rapids(w_.moves, g.text);
  }

  /// Walks every block read back; then the program's time into `g`.
  void run(GcodeProgram& g) {
    for (std::size_t index = 0; index < w_.moves.size(); ++index) {
      detail::look_at_stop(&stop_, index, detail::kPointStride);
      block(index);
    }
    flush_feed(true, nullptr);
    double feed_s = 0.0;
    for (const OperationSchedule& s : w_.schedule_after) feed_s += s.summary.feed_time_s;
    g.tcp_joint_peaks = controller::tcp_joint_peaks(machine_, tcp_blocks_, 1.0, &stop_);
    g.time_s = feed_s + rapid_s_;
    g.time_from_line = from_line_;
    g.time_tool_length_mm = length_mm_;
  }

 private:
  static constexpr std::size_t kA = static_cast<std::size_t>(Joint::Tilt);
  static constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
  using Gives = std::array<bool, 5>;

  void block(std::size_t index) {
    const GcodeMove& m = w_.moves[index];
    rapid_limits_ = limits_;
    if (index < half_accel_.size() && half_accel_[index]) {
      for (JointLimit& l : rapid_limits_) l.max_accel_per_s2 *= 0.5;
    }
    JointPosition to = q_;
    const Gives gives = {(m.given & 1u) != 0, (m.given & 2u) != 0, (m.given & 4u) != 0,
                         (m.given & 8u) != 0, (m.given & 16u) != 0};
    if (gives[3]) to[kA] = m.tilt_deg;
    if (gives[4]) to[kC] = m.c_deg;
    if (m.retract || !known_) flush_feed(true, nullptr);
    start_known_ = std::all_of(set_.begin(), set_.end(), [](bool b) { return b; });
    if (gives[3]) set_[kA] = true;
    if (gives[4]) set_[kC] = true;
    if (m.retract) {
      retract(m, gives, to);
    } else if (!known_ && !from_line_) {
      first(m, to);
    } else {
      // The reader takes LinuxCNC's kinematics as always on; a configuration that switches
      // them (tcp_on, M428) has them on where the writer put them: with the tool length offset.
      const bool switched = lcnc_ && !t_.tcp_on.empty();
      if (machine_.gcode.mode == GcodeMode::Tcp && m.tcp && (!switched || m.length_offset)) {
        tcp(m, gives, to, index);
      } else {
        joints(m, gives, to);
      }
    }
    q_ = to;
    if (known_) {
      w_.spindle_mm[index] = Vec3d(q_[0], q_[1], q_[2] + length_mm_);
      if (std::all_of(set_.begin(), set_.end(), [](bool b) { return b; })) {
        w_.joints_after[index] = q_;
      }
    }
  }

  /// Machine coordinates: the spindle's reference point to the retract height; X and Y (the
  /// end's park) where the block gives them; the joints, referred to the program's zero, less
  /// the work offset (Machine::work_offset_mm, else taken as zero).
  void retract(const GcodeMove& m, const Gives& gives, JointPosition& to) {
    const Vec3d offset = machine_.work_offset_mm.value_or(Vec3d::Zero());
    if (gives[2]) to[2] = t_.retract_z_mm - length_mm_ - offset.z();
    for (int k = 0; k < 2; ++k) {
      if (gives[k]) to[k] = m.machine_mm[k] - offset[k];
    }
    // In machine coordinates: where it leaves the tool relative to the part depends on the
    // work offset and the tool length, which the program does not hold; known where both are
    // given (the axes it names; those it does not name stay where they were).
    if (placed_) {
      for (std::size_t k = 0; k < 3; ++k) set_[k] = set_[k] || gives[k];
    } else {
      set_[0] = set_[1] = set_[2] = false;
    }
    tip_set_.fill(false);
    if (known_ && m.rapid) rapid_s_ += rapid_time_s(q_, to, rapid_limits_);
    if (!known_) from_line_ = m.line;
    known_ = true;
  }

  /// No retract before the first move: timed from its end.
  void first(const GcodeMove& m, JointPosition& to) {
    const Posed to_pose{deg_to_rad(to[kA]), deg_to_rad(to[kC])};
    const Vec3d xyz = joints_of_written_mm(machine_, m.xyz_mm, to_pose);
    to = {xyz.x(), xyz.y(), xyz.z(), to[kA], to[kC]};
    known_ = true;
    from_line_ = m.line;
    set_.fill(true);
  }

  /// A block in the program's axes: the tip where the joints stand, the words given replacing
  /// it; the tip on a straight line in the workpiece, the joints through the kinematics.
  void tcp(const GcodeMove& m, const Gives& gives, JointPosition& to, std::size_t index) {
    const Posed from_pose{deg_to_rad(q_[kA]), deg_to_rad(q_[kC])};
    const Posed to_pose{deg_to_rad(to[kA]), deg_to_rad(to[kC])};
    Vec3d tip = machine_.rotary.from_machine_mm(Vec3d(q_[0], q_[1], q_[2]), from_pose);
    const Vec3d written_tip = tip_of_written_mm(machine_, m.xyz_mm, to_pose);
    for (int k = 0; k < 3; ++k) {
      if (gives[k]) tip[k] = written_tip[k];
    }
    const Vec3d xyz = machine_.rotary.to_machine_mm(tip, to_pose);
    to[0] = xyz.x();
    to[1] = xyz.y();
    to[2] = xyz.z();
    w_.tip_linear[index] = 1;
    for (std::size_t k = 0; k < 3; ++k) tip_set_[k] = tip_set_[k] || gives[k];
    if (tip_set_[0] && tip_set_[1] && tip_set_[2]) set_[0] = set_[1] = set_[2] = true;
    const bool safe_rapid =
        std::binary_search(g_.joint_safe_rapids.begin(), g_.joint_safe_rapids.end(), m.line);
    const Vec3d was = machine_.rotary.from_machine_mm(Vec3d(q_[0], q_[1], q_[2]), from_pose);
    const JointPosition a{was.x(), was.y(), was.z(), q_[kA], q_[kC]};
    const JointPosition b{tip.x(), tip.y(), tip.z(), to[kA], to[kC]};
    // The written F as a rate of the block a second: the tip's distance (the rotary one when
    // only A and C turn) per minute, or under G93 the block's inverse time.
    const double tip_mm = (tip - was).norm();
    const double rot_deg = std::hypot(to[kA] - q_[kA], to[kC] - q_[kC]);
    const controller::FeedDistance d = controller::feed_distance(tip_mm, rot_deg);
    const double rate = !(m.feed > 0.0) || m.rapid ? 0.0
                        : m.inverse_time           ? m.feed / 60.0
                        : !d.rotary        ? m.feed * mm_per_unit(units_) / 60.0 / d.distance
                        : d.distance > 0.0 ? m.feed / 60.0 / d.distance
                                           : 0.0;
    if (m.rapid || safe_rapid) {
      JointLimits capped = safe_rapid ? limits_ : rapid_limits_;
      // A rapid written at a joint-safe feed: every axis at that rate along the move.
      for (std::size_t k = 0; k < kJointCount && safe_rapid && rate > 0.0; ++k) {
        const double v = rate * std::abs(b[k] - a[k]);
        if (v > 0.0 && (capped[k].max_velocity_per_s <= 0.0 || v < capped[k].max_velocity_per_s)) {
          capped[k].max_velocity_per_s = v;
        }
      }
      rapid_s_ += rapid_time_s(a, b, capped);
      flush_feed(true, nullptr);
      if (lcnc_) {
        tcp_blocks_.push_back(TcpBlock{a, b, capped, 0.0, true, true, m.line, 1.0, start_known_});
      }
    } else if (lcnc_) {
      // A feed block: from rest after a rapid (or as the program's first), to rest before one
      // (known at the next block).
      const TcpBlock feed_block{a, b, limits_, rate, !after_feed_, true, m.line, 1.0, start_known_};
      flush_feed(false, &feed_block);
      pending_ = feed_block;
    }
  }

  /// A block in the joints: the written X Y Z the controlled point, the tip with the tool
  /// length offset on, else the spindle's reference point.
  void joints(const GcodeMove& m, const Gives& gives, JointPosition& to) {
    flush_feed(true, nullptr);
    const double above = m.length_offset ? 0.0 : length_mm_;
    const Vec3d xyz = machine_.gcode.mode == GcodeMode::Machine
                          ? m.xyz_mm
                          : Vec3d(m.xyz_mm.x(), m.xyz_mm.y(), m.xyz_mm.z() - above);
    for (std::size_t k = 0; k < 3; ++k) {
      if (gives[k]) to[k] = xyz[static_cast<int>(k)];
      if (gives[k]) set_[k] = true;
    }
    tip_set_.fill(false);
    if (m.rapid) rapid_s_ += rapid_time_s(q_, to, rapid_limits_);
  }

  /// A block that turns A or C (LinuxCNC's tcRotaryMotionCheck).
  static bool turns(const TcpBlock& b) {
    return std::abs(b.to[kA] - b.from[kA]) > 1e-9 || std::abs(b.to[kC] - b.from[kC]) > 1e-9;
  }

  /// The pending feed block ends at rest, or goes on into `next`. LinuxCNC (tp.c) blends two
  /// feed blocks of which one turns A or C parabolically (no tangency or blend arc is tried
  /// where rotary axes move), and a block it blends parabolically with the next runs at half
  /// its acceleration (tcGetOverallMaxAccel): a chain's first block so blended starts from rest
  /// at half (measured: the peening file's line 33, joint Y 223.6 mm/s^2 and A 150 deg/s^2
  /// against 447.2 and 300 at the full acceleration). Its last block stops at the full one
  /// (measured: the demo's line 87, 327.53 as predicted at full).
  void flush_feed(bool ends_at_rest, const TcpBlock* next) {
    if (pending_) {
      pending_->end_rest = ends_at_rest;
      if (!ends_at_rest && pending_->start_rest && next && (turns(*pending_) || turns(*next))) {
        pending_->accel_share = 0.5;
      }
      tcp_blocks_.push_back(*pending_);
    }
    pending_.reset();
    after_feed_ = !ends_at_rest;
  }

  const Machine& machine_;
  const ProgramTemplate& t_;
  Written& w_;
  const JointLimits& limits_;
  LengthUnit units_;
  const GcodeProgram& g_;
  std::vector<TcpBlock>& tcp_blocks_;
  const double length_mm_;
  /// The work offset and the tool's gauge length are given: a retract's end is known.
  const bool placed_;
  const bool lcnc_;
  const StopSource& stop_;
  // LinuxCNC runs these rapids at half their acceleration (half_accel_rapids); the block's.
  std::vector<bool> half_accel_;
  JointLimits rapid_limits_{};
  // LinuxCNC with TCP on: a feed block waits for the next block to know whether it ends at
  // rest; after_feed_: the previous block was a tcp feed block (its chain goes on).
  std::optional<TcpBlock> pending_;
  bool after_feed_ = false;
  JointPosition q_{};
  bool known_ = false, start_known_ = false;
  int from_line_ = 0;
  double rapid_s_ = 0.0;
  // Which joints some block has set since the start (where the machine stands before is not
  // known): a block's end is known where all five are. With TCP on, which of the tip's X Y Z
  // some block has given since a block without it.
  std::array<bool, kJointCount> set_{};
  std::array<bool, 3> tip_set_{};
};

void program_time(const Run& run, Written& w, const JointLimits& limits, LengthUnit units,
                  GcodeProgram& g, std::vector<TcpBlock>& tcp_blocks) {
  ProgramClock(run, w, limits, units, g, tcp_blocks).run(g);
}

}  // namespace

std::vector<JointPosition> written_joints(const Machine& machine,
                                          const std::vector<const GcodeMove*>& at) {
  std::vector<JointPosition> q;
  for (const GcodeMove* m : at) {
    const Posed pose{deg_to_rad(m->tilt_deg), deg_to_rad(m->c_deg)};
    const Vec3d xyz = joints_of_written_mm(machine, m->xyz_mm, pose);
    q.push_back({xyz.x(), xyz.y(), xyz.z(), m->tilt_deg, m->c_deg});
  }
  return q;
}

std::vector<std::string> program_comments(const Run& run, const JobResult& res) {
  const Machine& machine = run.machine;
  std::vector<std::string> comments = {
      std::string("taxopt ") + kVersion + ", method " + to_string(run.options.method),
      "source " + run.tp.source,
      "machine " + machine.name + ", " +
          (machine.gcode.mode == GcodeMode::Tcp ? "tcp" : "machine") + " mode"};
  // What was not checked, in the program itself: the program travels without its report.
  for (const std::string& w : res.safety_warnings) comments.push_back("NOT CHECKED: " + w);
  return comments;
}

namespace {

/// The feed schedules of every operation at `limits` as written (the blocks read back):
/// Written::schedule_after, with the programmed times they start from.
void schedule_after(const Run& run, const std::vector<PostedOperation>& posted,
                    const JointLimits& limits, LengthUnit units, Written& w,
                    detail::StageProgress& writing) {
  const Machine& machine = run.machine;
  const StopSource& stop = run.options.stop;
  // Tcp mode: the joints follow the kinematics inside a block (schedule_operation).
  const bool tcp = machine.gcode.mode == GcodeMode::Tcp;
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const PostedOperation& po = posted[k];
    const std::vector<Linearised> via =
        linearised_blocks(machine, po, w.point_moves[k], w.moves, units, &stop);
    w.time_into_after.push_back(po.programmed_time_s.empty()
                                    ? programmed_block_times_s(po.points, po.poses)
                                    : po.programmed_time_s);
    w.schedule_after.push_back(schedule_operation(
        po.points, written_joints(machine, w.point_moves[k]), w.time_into_after.back(), limits,
        machine.rotary, &via, tcp ? &po.poses : nullptr, &stop));
    writing.advance(po.points.size());
  }
}

/// The feed schedules the input axes would run at `limits` (Written::schedule_before, with
/// the programmed times they start from), for the operations with input poses; those
/// without take the written path's (fill_schedule_before). They depend on the input alone:
/// made beside the program's writing.
void schedule_before(const Run& run, const std::vector<OperationContext>& ops,
                     const std::vector<PostedOperation>& posted, const JointLimits& limits,
                     Written& w, detail::StageProgress& writing) {
  const Machine& machine = run.machine;
  const bool tcp = machine.gcode.mode == GcodeMode::Tcp;
  w.time_into_before.resize(posted.size());
  w.schedule_before.resize(posted.size());
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const PostedOperation& po = posted[k];
    const Operationd& op = *ops[k].op;
    const std::vector<Posed>& input_poses = ops[k].input_poses;
    if (!input_poses.empty()) {
      std::vector<CLPointd> in_points = po.points;
      std::vector<Vec3d> in_tips;
      for (std::size_t i = 0; i < in_points.size(); ++i) {
        in_points[i].tip_mm = op.points[i].tip_mm;
        in_points[i].axis = op.points[i].axis;
        in_tips.push_back(in_points[i].tip_mm);
      }
      w.time_into_before[k] = programmed_block_times_s(in_points, input_poses);
      w.schedule_before[k] = schedule_operation(
          in_points, joints_of(machine.rotary, in_tips, input_poses), w.time_into_before[k], limits,
          machine.rotary, nullptr, tcp ? &input_poses : nullptr, &run.options.stop);
    }
    writing.advance(po.points.size());
  }
}

/// The operations without input poses run the written path before as after.
void fill_schedule_before(const std::vector<OperationContext>& ops, Written& w) {
  for (std::size_t k = 0; k < w.schedule_before.size(); ++k) {
    if (!ops[k].input_poses.empty()) continue;
    w.time_into_before[k] = w.time_into_after[k];
    w.schedule_before[k] = w.schedule_after[k];
  }
}

}  // namespace

Written write_program(const Run& run, const std::vector<OperationContext>& ops,
                      std::vector<PostedOperation>& posted, JobResult& res) {
  const Machine& machine = run.machine;
  const std::vector<std::string> comments = program_comments(run, res);
  const auto t0 = Clock::now();
  Written w;
  if (run.options.feed_schedule) {
    // A scheduled block is written as a straight block (an arc's chords, not G2/G3: its F is
    // the scheduled time over the written distance), so the schedule is made on the program
    // as it will be written: the first program already writes every feed block that way, at
    // its programmed time. Scheduled on the arcs read back instead, the chords ran up to
    // 0.06 % over the velocity limit and 2.4 % over the acceleration limit (measured on
    // amorim-wall-holes at LinuxCNC's sample's rates).
    for (PostedOperation& po : posted) {
      po.block_time_s = po.programmed_time_s.empty() ? programmed_block_times_s(po.points, po.poses)
                                                     : po.programmed_time_s;
    }
  }
  const StopSource& stop = run.options.stop;
  // Per point: the program written and read back, the schedules after and before, (with a
  // feed schedule: the program written and read back again,) its time.
  std::size_t points = 0;
  for (const PostedOperation& po : posted) points += po.points.size();
  const std::size_t steps = run.options.feed_schedule ? 7 : 5;
  detail::StageProgress writing(run.options.progress, "writing", steps * points, stop);
  // Feed schedules at the machine's limits: the written path (from the words read back) and,
  // beside the writing (it depends on the input alone), the input axes; with --feed-schedule
  // the program is written again at the scheduled feeds.
  const JointLimits limits = effective_limits(machine);
  detail::parallel_invoke(
      [&] {
        res.gcode = gcode::write_program(posted, machine, res.gcode_units, comments, &stop);
        writing.advance(points);
        read_back(machine, posted, res.gcode, w, &stop);
        writing.advance(points);
        schedule_after(run, posted, limits, res.gcode_units, w, writing);
      },
      [&] { schedule_before(run, ops, posted, limits, w, writing); });
  fill_schedule_before(ops, w);
  if (run.options.feed_schedule) {
    for (std::size_t k = 0; k < posted.size(); ++k) {
      w.time_into_after[k] = w.schedule_after[k].time_s;
      w.time_into_before[k] = w.schedule_before[k].time_s;
    }
  }
  count_table_turns(run, ops, posted, limits, w);
  if (run.options.feed_schedule) {
    for (std::size_t k = 0; k < posted.size(); ++k) {
      posted[k].block_time_s = w.schedule_after[k].time_s;
      posted[k].linearised_time_s = w.schedule_after[k].block_time_s;
    }
    res.gcode = gcode::write_program(posted, machine, res.gcode_units, comments, &stop);
    writing.advance(points);
    read_back(machine, posted, res.gcode, w, &stop);
    writing.advance(points);
  }
  std::vector<TcpBlock> tcp_blocks;
  program_time(run, w, limits, res.gcode_units, res.gcode, tcp_blocks);
  writing.advance(points);
  tcp_joint_findings(machine, limits, run.options.feed_schedule, tcp_blocks, res, &stop);
  w.write_s = seconds_since(t0);
  return w;
}

void read_program_again(const Run& run, const std::vector<PostedOperation>& posted, Written& w,
                        JobResult& res) {
  read_back(run.machine, posted, res.gcode, w, &run.options.stop);
  std::vector<TcpBlock> tcp_blocks;
  program_time(run, w, effective_limits(run.machine), res.gcode_units, res.gcode, tcp_blocks);
}

}  // namespace taxopt::pipeline
