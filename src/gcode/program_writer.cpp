/// @file The program writer: the operations' points as blocks, each with its kind and origin
/// (GcodeProgram::blocks), in the machine's dialect (dialect.hpp).

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "gcode/dialect.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt {

Vec3d approach_tip_mm(const Vec3d& tip_mm, const Vec3d& axis, double clearance_z_mm,
                      double safe_distance_mm) {
  // Along the axis up to the clearance height where the axis rises steeply enough (within 60
  // deg of the vertical: at most twice the height to go), else the safe distance along it.
  const double rise_mm = clearance_z_mm - tip_mm.z();
  const double along_mm =
      axis.z() >= 0.5 && rise_mm > 0.0 ? rise_mm / axis.z() : std::max(0.0, safe_distance_mm);
  return tip_mm + along_mm * axis;
}

namespace {

using gcode::Dialect;
using gcode::fmt;
using gcode::round_to;

/// F with eight significant digits and at least `fd` decimals; where the controller takes
/// fewer than that (`max_fd`), rounded down: slower, never faster.
std::string precise_feed(double f, int fd, int max_fd) {
  const int digits =
      std::clamp(7 - static_cast<int>(std::floor(std::log10(std::max(f, 1e-300)))), fd, 15);
  if (digits <= max_fd) return fmt(f, digits);
  const double unit = std::pow(10.0, max_fd);
  return fmt(std::max(std::floor(f * unit), 1.0) / unit, max_fd);
}

/// Writes one program. The stages: the program's start, per operation its start (retract,
/// tool, spindle, coolant, table turn, length and TCP on), its points (events, arcs, index
/// moves, approaches, rapids, feed blocks) and its end, then the program's end. Every line is
/// recorded with its kind and origin (GcodeProgram::blocks).
class ProgramWriter {
 public:
  ProgramWriter(const std::vector<PostedOperation>& operations, const Machine& machine,
                LengthUnit units)
      : ops_(operations),
        machine_(machine),
        g_(machine.gcode),
        scale_(1.0 / mm_per_unit(units)),
        d_(g_.decimals),
        fd_(feed_decimals(g_)),
        max_fd_(max_feed_decimals(g_.dialect)),
        dialect_(g_, units),
        tcp_(g_.mode == GcodeMode::Tcp),
        // LinuxCNC plans a tcp rapid in the program's axes: where that would run a joint over
        // its velocity limit, the rapid is a feed block at a joint-safe feed
        // (joint_safe_rate_per_s).
        joint_safe_(tcp_ && g_.dialect == GcodeDialect::LinuxCNC),
        retracts_(g_.program.retract != SafeRetract::None),
        limits_(effective_limits(machine)),
        retract_z_(dialect_.number(g_.program.retract_z_mm * scale_, d_)),
        // The tilt axis's word: A or B (ac_machine.hpp).
        tilt_word_(std::string(" ") + machine.ac.tilt_letter()) {}

  GcodeProgram write(const std::vector<std::string>& comments) {
    program_start(comments);
    for (std::size_t k = 0; k < ops_.size(); ++k) operation(k);
    program_end();
    return std::move(prog_);
  }

 private:
  // --- emitting lines, each with its kind and origin -------------------------------------
  int raw(const std::string& s, BlockKind kind) {
    prog_.text += s;
    prog_.text += '\n';
    prog_.blocks.push_back({++line_no_, kind, op_index_, point_});
    return line_no_;
  }
  int line(const std::string& s, BlockKind kind) { return raw(dialect_.block(s), kind); }
  void lines(const std::vector<std::string>& v, BlockKind kind) {
    for (const auto& s : v) line(s, kind);
  }
  /// Blocks of the template, written as they are: the reader steps over them.
  void verbatim(const std::vector<std::string>& v, BlockKind kind) {
    for (const auto& s : v) prog_.verbatim_lines.push_back(line(s, kind));
  }
  /// A motion block; an operation's first carries Fanuc's length and TCP words.
  int motion(const std::string& s, BlockKind kind) {
    const int at = line(prefix_ + s, kind);
    prefix_.clear();
    return at;
  }

  // --- words -----------------------------------------------------------------------------
  Vec3d rounded(const Vec3d& v) const {
    return Vec3d(round_to(v.x(), d_), round_to(v.y(), d_), round_to(v.z(), d_));
  }
  Vec3d out_xyz(const Vec3d& tip, const Posed& pose) const {
    return written_xyz_mm(machine_, tip, pose);
  }
  std::string angle_words(const Posed& pose) const {
    return tilt_word_ + dialect_.number(rad_to_deg(pose.a_rad), d_) + " C" +
           dialect_.number(rad_to_deg(pose.c_rad), d_);
  }
  std::string xyz_words(const Vec3d& xyz) const {
    return "X" + dialect_.number(xyz.x() * scale_, d_) + " Y" +
           dialect_.number(xyz.y() * scale_, d_) + " Z" + dialect_.number(xyz.z() * scale_, d_);
  }
  static std::string spindle_words(double rpm, bool clockwise) {
    return "S" + fmt(rpm, 0) + (clockwise ? " M3" : " M4");
  }
  static std::string coolant_code(ClCoolant c) {
    return c == ClCoolant::Flood  ? std::string("M8")
           : c == ClCoolant::Mist ? std::string("M7")
                                  : std::string();
  }
  /// Coolant as the CL file asks (COOLNT), else as the machine file's default.
  std::string coolant_of(const PostedOperation& o) const {
    return o.coolant ? coolant_code(*o.coolant) : dialect_.coolant_on();
  }
  /// " F" and the feed where it changes (always under G93).
  std::string feed_word(const std::string& f) {
    const bool write = g_.feed_mode == FeedMode::InverseTime || f != last_feed_;
    last_feed_ = f;
    return write ? " F" + f : std::string();
  }

  // --- the program -----------------------------------------------------------------------
  void program_start(const std::vector<std::string>& comments) {
    for (const auto& s : dialect_.start()) raw(s, BlockKind::Start);
    if (g_.dialect == GcodeDialect::LinuxCNC || g_.dialect == GcodeDialect::Siemens) {
      raw(dialect_.comment("program " + dialect_.name()), BlockKind::Start);
    }
    for (const auto& c : comments) raw(dialect_.comment(c), BlockKind::Start);
    line(dialect_.setup(g_.feed_mode == FeedMode::InverseTime), BlockKind::Start);
    if (g_.dialect == GcodeDialect::LinuxCNC) {
      // The path's blending bound (ProgramTemplate::blend_tolerance_mm).
      const double blend = g_.program.blend_tolerance_mm;
      line(blend > 0.0 ? "G64 P" + fmt(blend * scale_, std::max(d_, 4)) + " Q0" : "G61",
           BlockKind::Start);
    }
    if (const std::string w = dialect_.work_offset(); !w.empty()) verbatim({w}, BlockKind::Start);
    verbatim(g_.program.header, BlockKind::Start);
  }

  void program_end() {
    op_index_ = -1;
    point_ = -1;
    lines(dialect_.retract(retract_z_), BlockKind::Retract);
    // The rotary axes home (a continuous C within one turn of it), with the tool up.
    if (g_.program.end_pose == EndPose::Home && retracts_ && !ops_.empty()) {
      line(dialect_.rapid() + tilt_word_ + dialect_.number(0.0, d_) + " C" +
               dialect_.number(0.0, d_),
           BlockKind::End);
    }
    if (g_.program.end_park_xy_mm && retracts_ && !ops_.empty()) {
      const auto& xy = *g_.program.end_park_xy_mm;
      lines(dialect_.park(dialect_.number(xy[0] * scale_, d_), dialect_.number(xy[1] * scale_, d_)),
            BlockKind::End);
    }
    verbatim(g_.program.footer, BlockKind::End);
    line(dialect_.end(), BlockKind::End);
    for (const auto& s : dialect_.finish()) raw(s, BlockKind::End);
  }

  // --- an operation ----------------------------------------------------------------------
  void operation(std::size_t k) {
    const PostedOperation& op = ops_[k];
    if (op.poses.size() != op.points.size()) {
      throw std::invalid_argument("write_gcode: operation '" + op.name + "' has no pose per point");
    }
    op_ = &op;
    op_index_ = static_cast<int>(k);
    point_ = -1;
    operation_start();
    emitted_.assign(op.points.size(), 0);
    own_times_ = programmed_block_times_s(op.points, op.poses);
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      point_ = static_cast<int>(i);
      events_before(i);
      if (arc_at(i)) {
        i = op.arcs[arc_cursor_].end;
        continue;
      }
      point(i);
    }
    point_ = -1;
    events_before(op.points.size());
    prog_.emitted.push_back(std::move(emitted_));
    operation_end(k + 1 < ops_.size() ? &ops_[k + 1] : nullptr);
  }

  /// Safe start: up to the retract height, the tool, the spindle and the coolant, the table
  /// turned to the first pose with the tool up, then the tool length and TCP on.
  void operation_start() {
    const PostedOperation& op = *op_;
    raw(dialect_.comment("operation " + op.name), BlockKind::Start);
    // Every operation's first feed block carries its F (a reader of one operation, or a
    // restart at it, must not inherit the last operation's feed).
    last_feed_.clear();
    lines(dialect_.retract(retract_z_), BlockKind::Retract);
    tool_change(op.tool.number);
    if (op.spindle_rpm > 0.0 &&
        spindle_words(op.spindle_rpm, op.spindle_clockwise) != running_spindle_) {
      line(spindle_words(op.spindle_rpm, op.spindle_clockwise), BlockKind::Spindle);
    }
    coolant_ = coolant_of(op);
    if (!coolant_.empty() && coolant_ != running_coolant_) line(coolant_, BlockKind::Coolant);
    // The spindle's words in force (empty: stopped), as the coolant's.
    spindle_ =
        op.spindle_rpm > 0.0 ? spindle_words(op.spindle_rpm, op.spindle_clockwise) : std::string();
    next_event_ = 0;
    arc_cursor_ = 0;
    if (!op.points.empty()) point_ = 0;  // the first point's turn, length and TCP
    if (!op.points.empty()) turn_table(op.poses.front());
    // The tool length before the TCP switch: LinuxCNC's controller, switched to its TCP
    // kinematics (the sample's M428) with the table tilted and the length then turned on,
    // jumps its joints (Y by 17 mm at 7,227 mm/s, Z past its limit, measured on the real
    // motion controller: tests/controller); with G43 first the same programs run to the end.
    length_and_tcp_on();
    // From the retract height the tool goes XY first, then down (Haas's and Tormach's
    // pages: no diagonal rapid from the retract): set before the operation's first block and
    // after every index move.
    approach_ = retracts_;
    clearance_z_mm_ = clearance_z_mm(op);
    descend_ = tcp_ && !dialect_.length_on_first_move();
    last_words_.clear();
    prev_xyz_ = Vec3d::Zero();
    prev_pose_ = Posed();
    prev_tip_ = Vec3d::Zero();
    have_prev_ = false;
    last_feed_block_ = false;
    last_joint_safe_ = false;
    along_axis_leg_ = false;
  }

  void tool_change(int tool) {
    if (tool <= 0 || tool == current_tool_) return;
    const auto [change, custom] = dialect_.tool_change(tool);
    if (custom) {
      verbatim(change, BlockKind::ToolChange);
      prog_.tool_calls.emplace_back(prog_.verbatim_lines.back(), tool);
      // The machine's own tool-change macro may leave its modes behind: the set-up again.
      line(dialect_.setup(g_.feed_mode == FeedMode::InverseTime), BlockKind::ToolChange);
    } else {
      lines(change, BlockKind::ToolChange);
    }
    current_tool_ = tool;
  }

  /// Under tool centre point control the retract height can lie above the axes' range in the
  /// workpiece frame: LinuxCNC's sample (Z to 120, its limit) with the table tilted 19 deg
  /// refused the XY move there ("would exceed Z's positive limit", measured on its motion
  /// controller). So the tool first comes straight down to a clearance height, the operation's
  /// highest tip plus approach_clearance_mm, then XY, then down. Not on Fanuc, whose G43.4
  /// comes on with the block down: before it, Z would place the spindle nose. With a part
  /// model the clearance height stands above the part too (its highest point in the
  /// workpiece, PostedOperation::part_top_z_mm), not only above the operation's tips: an
  /// operation low on a tall part came down inside it (a Haas part's approach at Z1.5987 in,
  /// its top at Z3.0).
  double clearance_z_mm(const PostedOperation& op) const {
    double z = op.part_top_z_mm.value_or(-std::numeric_limits<double>::infinity());
    for (const CLPointd& q : op.points) z = std::max(z, q.tip_mm.z());
    return z + g_.program.approach_clearance_mm;
  }

  /// Left running into the next operation where it starts with the same tool, spindle and
  /// coolant (before its first point: its events may change them after that). The spindle and
  /// coolant words left running from the operation before (empty: stopped) spare a stop and a
  /// restart between operations (a machinist's read of a real NX program: 11 pointless M5 /
  /// S M3 pairs in 12 operations).
  void operation_end(const PostedOperation* next) {
    length_and_tcp_off();
    const bool same_tool = next && (next->tool.number <= 0 || next->tool.number == current_tool_);
    const bool keep_spindle = same_tool && !spindle_.empty() && next->spindle_rpm > 0.0 &&
                              spindle_words(next->spindle_rpm, next->spindle_clockwise) == spindle_;
    const bool keep_coolant = same_tool && !coolant_.empty() && coolant_of(*next) == coolant_;
    if (!coolant_.empty() && !keep_coolant) line("M9", BlockKind::Coolant);
    if (!spindle_.empty() && !keep_spindle) line("M5", BlockKind::Spindle);
    running_spindle_ = keep_spindle ? spindle_ : std::string();
    running_coolant_ = keep_coolant ? coolant_ : std::string();
    last_words_.clear();
  }

  /// The file's stops, dwells, spindle and coolant changes before point i.
  void events_before(std::size_t i) {
    const PostedOperation& op = *op_;
    for (; next_event_ < op.events.size() && op.events[next_event_].before_point <= i;
         ++next_event_) {
      event(op.events[next_event_]);
    }
  }

  void event(const ProgramEvent& e) {
    switch (e.kind) {
      case ProgramEvent::Kind::Stop: line("M0", BlockKind::Event); break;
      case ProgramEvent::Kind::OptionalStop: line("M1", BlockKind::Event); break;
      case ProgramEvent::Kind::Dwell:
        if (g_.dialect == GcodeDialect::LinuxCNC) {
          line("G4 P" + fmt(e.dwell_s, 3), BlockKind::Event);  // LinuxCNC: P in seconds
        } else if (g_.dialect == GcodeDialect::Fanuc) {
          line("G04 P" + std::to_string(std::lround(e.dwell_s * 1000.0)),
               BlockKind::Event);  // P in ms
        } else {
          throw InputError("CL line " + std::to_string(e.line) +
                           ": DELAY: taxopt writes a dwell for LinuxCNC (G4 P seconds) and "
                           "Fanuc (G04 P milliseconds) only, not for the " +
                           std::string(to_string(g_.dialect)) + " dialect");
        }
        break;
      case ProgramEvent::Kind::Spindle:
        if (e.spindle_rpm > 0.0) {
          spindle_ = spindle_words(e.spindle_rpm, e.spindle_clockwise);
          line(spindle_, BlockKind::Event);
        } else {
          spindle_.clear();
          line("M5", BlockKind::Event);
        }
        break;
      case ProgramEvent::Kind::Coolant: {
        const std::string c = coolant_code(e.coolant);
        line(c.empty() ? "M9" : c, BlockKind::Event);
        coolant_ = c;
        break;
      }
    }
  }

  /// The table turned with the tool up (after the retract), to `pose`.
  void turn_table(const Posed& pose) {
    if (!retracts_) return;
    line(dialect_.rapid() + tilt_word_ + dialect_.number(rad_to_deg(pose.a_rad), d_) + " C" +
             dialect_.number(rad_to_deg(pose.c_rad), d_),
         BlockKind::TableTurn);
  }

  void length_and_tcp_on() {
    tcp_angles_.clear();
    lines(dialect_.length_on(tcp_, current_tool_), BlockKind::LengthTcp);
    verbatim(tcp_ ? g_.program.tcp_on : std::vector<std::string>{}, BlockKind::LengthTcp);
    lines(dialect_.tcp_on(tcp_, current_tool_), BlockKind::LengthTcp);
    prefix_ = dialect_.first_move_prefix(tcp_, current_tool_);
  }
  void length_and_tcp_off() {
    lines(dialect_.tcp_off(tcp_), BlockKind::LengthTcp);
    verbatim(tcp_ ? g_.program.tcp_off : std::vector<std::string>{}, BlockKind::LengthTcp);
  }

  // --- the points ------------------------------------------------------------------------
  /// Point i starts the next CL arc: written as G2/G3 when it can be (true), else counted as
  /// left to its chords. An arc with an event inside it is left to its chords, so that the
  /// event stands where the file put it.
  bool arc_at(std::size_t i) {
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

  /// The programmed time of the arc's chords, s (each block's given time, else its own at the
  /// programmed feed), and whether every given time is the block's own; nullopt where the arc
  /// cannot be one block run (a rapid, a turn of A or C, a schedule, a change of feed).
  std::optional<std::pair<double, bool>> arc_programmed_s(const ArcRun& run,
                                                          const std::string& pose_words) const {
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

  /// Writes the arc `run` as G2/G3 blocks when it can be (PostedOperation::arcs); false: it
  /// is left to its chords.
  bool write_arc(const ArcRun& run) {
    const PostedOperation& op = *op_;
    if (g_.feed_mode != FeedMode::UnitsPerMinute || g_.dialect == GcodeDialect::Heidenhain ||
        !have_prev_ || run.end >= op.points.size() || run.end <= run.start + 1) {
      return false;
    }
    const std::string pose_words = angle_words(op.poses[run.start]);
    // The rotary words where tool centre point control came on: a Fanuc 30i raises PS5421 for
    // G2/G3 after A or C has turned under G43.4 (FANUC Series 30i-MODEL A, Tool center point
    // control for 5-axis machining, A-79348E, pp. 22-24: circular interpolation is allowed
    // where neither rotary axis moves after the G43.4 command). Haas's G234 is treated alike
    // (its rule is not published here).
    if (tcp_ && (g_.dialect == GcodeDialect::Fanuc || g_.dialect == GcodeDialect::Haas) &&
        pose_words != tcp_angles_) {
      return false;  // the table turned under TCP since it came on: chords
    }
    const auto timed = arc_programmed_s(run, pose_words);
    if (!timed) return false;
    if (xyz_words(out_xyz(op.points[run.start].tip_mm, op.poses[run.start])) + pose_words !=
        last_words_) {
      return false;
    }
    // The arc where the points are now (new axes move the tips by the same vector where the
    // axis is the same along the arc), in the output frame.
    const Posed& pose = op.poses[run.start];
    const Vec3d centre_tip = run.centre_mm + (op.points[run.start].tip_mm - run.start_tip_mm);
    const Vec3d c = out_xyz(centre_tip, pose);
    const Vec3d n = (out_xyz(centre_tip + run.normal, pose) - c).normalized();
    int axis = -1;
    for (int q = 0; q < 3; ++q) {
      if (std::abs(std::abs(n[q]) - 1.0) < 1e-9) axis = q;
    }
    if (axis < 0) return false;
    const Vec3d s0 = out_xyz(op.points[run.start].tip_mm, pose) - c;
    const Vec3d u0 = s0 - s0.dot(n) * n;
    const double r0 = u0.norm();
    if (r0 < 1e-3) return false;
    for (std::size_t j = run.start; j <= run.end; ++j) {
      const Vec3d dj = out_xyz(op.points[j].tip_mm, op.poses[j]) - c;
      if (std::abs((dj - dj.dot(n) * n).norm() - r0) > 1e-6 * std::max(1.0, r0)) return false;
    }
    const Vec3d e_out = out_xyz(op.points[run.end].tip_mm, op.poses[run.end]);
    const double hs = s0.dot(n), he = (e_out - c).dot(n);
    const double length_mm = std::hypot(run.sweep_rad * r0, he - hs);
    const double feed =
        timed->second ? op.points[run.end].feed_mm_per_min : length_mm / (timed->first / 60.0);
    const std::string f = fmt(feed * scale_, fd_);
    const int pieces = std::max(1, static_cast<int>(std::ceil(run.sweep_rad / M_PI - 1e-9)));
    const char* plane = axis == 2 ? "G17" : axis == 1 ? "G18" : "G19";
    const char* sense = n[axis] > 0.0 ? "G3" : "G2";
    std::vector<int> piece_line(static_cast<std::size_t>(pieces));
    Vec3d from = rounded(out_xyz(op.points[run.start].tip_mm, pose) * scale_) / scale_;
    const Vec3d dir = u0 / r0, side = n.cross(dir);
    point_ = static_cast<int>(run.end);
    for (int k = 1; k <= pieces; ++k) {
      const double frac = static_cast<double>(k) / pieces, th = run.sweep_rad * frac;
      const Vec3d to = k == pieces ? e_out
                                   : c + (hs + (he - hs) * frac) * n +
                                         r0 * (std::cos(th) * dir + std::sin(th) * side);
      const Vec3d offset = (c - from) * scale_;
      std::string block = std::string(plane) + " " + sense + " " + xyz_words(to);
      for (int q = 0; q < 3; ++q) {
        if (q != axis)
          block += std::string(" ") + static_cast<char>('I' + q) + dialect_.number(offset[q], d_);
      }
      piece_line[static_cast<std::size_t>(k - 1)] = line(block + feed_word(f), BlockKind::Arc);
      ++prog_.arc_blocks;
      from = rounded(to * scale_) / scale_;
    }
    for (std::size_t j = run.start + 1; j < run.end; ++j) {
      const double frac =
          static_cast<double>(j - run.start) / static_cast<double>(run.end - run.start);
      const auto piece = std::min<std::size_t>(static_cast<std::size_t>(frac * pieces),
                                               static_cast<std::size_t>(pieces - 1));
      emitted_[j] = -piece_line[piece];
    }
    emitted_[run.end] = piece_line.back();
    last_words_ = xyz_words(e_out) + pose_words;
    advance_to(e_out, op.poses[run.end], op.points[run.end].tip_mm);
    return true;
  }

  void advance_to(const Vec3d& xyz, const Posed& pose, const Vec3d& tip) {
    prev_xyz_ = xyz;
    prev_pose_ = pose;
    prev_tip_ = tip;
  }

  /// The block (or blocks) that reach point i.
  void point(std::size_t i) {
    const CLPointd& p = op_->points[i];
    const Posed& pose = op_->poses[i];
    const Vec3d xyz = out_xyz(p.tip_mm, pose);
    const std::string words = xyz_words(xyz) + angle_words(pose);
    if (words == last_words_) return;  // nothing would move
    along_axis_leg_ = false;
    if (p.motion == Motion::Rapid && have_prev_ && retracts_ && !op_->swept_moves_checked) {
      index_move_if_turning(pose);
    }
    if (approach_) approach(p, pose, xyz);
    if (p.motion == Motion::Rapid) {
      if (rapid(i, xyz, words)) return;
    } else {
      feed(i, xyz, words);
    }
    have_prev_ = true;
  }

  /// An index move: a rapid that turns the table by more than the threshold goes up to the
  /// retract, turns there and comes down XY first (docs/gcode-dialects.md "Index moves").
  /// With a part model the turns stay in the air: the check verifies their swept moves.
  void index_move_if_turning(const Posed& pose) {
    const double turn_deg = std::max(
        std::abs(round_to(rad_to_deg(pose.a_rad), d_) - round_to(rad_to_deg(prev_pose_.a_rad), d_)),
        std::abs(round_to(rad_to_deg(pose.c_rad), d_) -
                 round_to(rad_to_deg(prev_pose_.c_rad), d_)));
    if (!(turn_deg > g_.program.index_threshold_deg)) return;
    length_and_tcp_off();
    lines(dialect_.retract(retract_z_), BlockKind::Retract);
    turn_table(pose);
    length_and_tcp_on();
    approach_ = true;
    ++prog_.index_moves;
  }

  /// The way down from the retract height to point `p`: under TCP straight down to the
  /// clearance height, XY to above the point on its axis, then along the axis (as CAM links an
  /// approach: a tool tilted 90 deg that came straight down in the workpiece's Z swept through
  /// a wall); in machine mode the machine's Z is the tool axis already. Not on Fanuc, whose TCP
  /// comes on with the block down from the retract height (straight down to the point).
  void approach(const CLPointd& p, const Posed& pose, const Vec3d& xyz) {
    if (descend_) {
      motion(dialect_.rapid() + " Z" + dialect_.number(clearance_z_mm_ * scale_, d_),
             BlockKind::Approach);
    }
    const Vec3d above_tip =
        approach_tip_mm(p.tip_mm, p.axis, clearance_z_mm_, g_.program.approach_clearance_mm);
    const Vec3d above = descend_ ? out_xyz(above_tip, pose) : xyz;
    const std::string xy = dialect_.rapid() + " X" + dialect_.number(above.x() * scale_, d_) +
                           " Y" + dialect_.number(above.y() * scale_, d_);
    if (dialect_.length_on_first_move()) {
      line(xy, BlockKind::Approach);  // Fanuc: its length and TCP come on with the Z block below
    } else {
      motion(xy, BlockKind::Approach);
    }
    if (descend_ && std::abs(above.z() - clearance_z_mm_) * scale_ > 0.5 * std::pow(10.0, -d_)) {
      // A tool within 30 deg of the horizontal: straight down to the safe distance on its
      // axis, then along it.
      line(dialect_.rapid() + " Z" + dialect_.number(above.z() * scale_, d_), BlockKind::Approach);
    }
    approach_ = false;
    // The tool comes from the retract: no move to schedule or split; under TCP a rapid to
    // the point comes from `above` along the axis (at a joint-safe feed on LinuxCNC).
    have_prev_ = descend_ && p.motion == Motion::Rapid;
    along_axis_leg_ = have_prev_;
    if (have_prev_) advance_to(above, pose, above_tip);
  }

  /// The blocks of a machine-mode move from the last point to (tip, pose) between its ends
  /// (linearise_fractions): the fractions at which they stand.
  std::vector<double> linearised(const Vec3d& tip, const Posed& pose) const {
    return linearise_fractions(machine_.ac, prev_tip_, prev_pose_, tip, pose,
                               g_.program.linearise_tolerance_mm);
  }
  Posed pose_at(const Posed& pose, double t) const {
    return Posed{prev_pose_.a_rad + t * (pose.a_rad - prev_pose_.a_rad),
                 prev_pose_.c_rad + t * (pose.c_rad - prev_pose_.c_rad)};
  }

  /// A rapid to point i; true when it was written as a joint-safe feed block (the point is
  /// done), false when the rapid block is written and the point's bookkeeping follows.
  bool rapid(std::size_t i, const Vec3d& xyz, const std::string& words) {
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
        motion(dialect_.rapid() + " " + xyz_words(mid_xyz) + angle_words(mid),
               BlockKind::Linearised);
        ++prog_.linearised_blocks;
      }
    }
    if (joint_safe_ && have_prev_) {
      const std::optional<double> rate = joint_safe_rate_per_s(
          machine_.ac, limits_, prev_tip_, prev_pose_, p.tip_mm, pose, along_axis_leg_);
      if (rate) {
        joint_safe_rapid(i, xyz, words, *rate);
        return true;
      }
    }
    finish_point(i, xyz, words, dialect_.rapid() + " " + words, false);
    return false;
  }

  /// A rapid as a feed block at the rate that keeps the joints within their limits: F is the
  /// tip's distance (the rotary one when only A and C turn) per minute, or under G93 the
  /// block's inverse time; eight significant digits, rounded down: slower, never faster.
  void joint_safe_rapid(std::size_t i, const Vec3d& xyz, const std::string& words,
                        double rate_per_s) {
    const CLPointd& p = op_->points[i];
    const Posed& pose = op_->poses[i];
    const double tip_mm = (p.tip_mm - prev_tip_).norm();
    const double rot_deg = std::hypot(rad_to_deg(pose.a_rad - prev_pose_.a_rad),
                                      rad_to_deg(pose.c_rad - prev_pose_.c_rad));
    const double per_min = 60.0 * rate_per_s;
    const double feed = g_.feed_mode == FeedMode::InverseTime
                            ? per_min
                            : (tip_mm > 1e-9 ? tip_mm * scale_ : rot_deg) * per_min;
    const int digits = std::clamp(
        7 - static_cast<int>(std::floor(std::log10(std::max(feed, 1e-300)))), fd_, max_fd_);
    const double unit = std::pow(10.0, digits);
    const std::string f = fmt(std::max(std::floor(feed * unit), 1.0) / unit, digits);
    const std::string block = dialect_.linear() + " " + words + feed_word(f);
    // LinuxCNC blends two feed blocks, and the blend leaves the programmed A and C (0.12 deg
    // measured at the end of a pass), so a dwell G4 P0 (the controller runs its queue to a
    // stop) stands between such a rapid and a feed block.
    if (last_feed_block_) line("G4 P0", BlockKind::Dwell);
    emitted_[i] = motion(block, BlockKind::JointSafeRapid);
    last_feed_block_ = false;
    last_joint_safe_ = true;
    prog_.joint_safe_rapids.push_back(emitted_[i]);
    last_words_ = words;
    advance_to(xyz, pose, p.tip_mm);
  }

  /// The block reaching point i, and the state after it.
  void finish_point(std::size_t i, const Vec3d& xyz, const std::string& words,
                    const std::string& block, bool restore_inverse_time) {
    const CLPointd& p = op_->points[i];
    if (last_joint_safe_ && p.motion != Motion::Rapid) line("G4 P0", BlockKind::Dwell);
    emitted_[i] = motion(block, BlockKind::Point);
    last_feed_block_ = p.motion != Motion::Rapid;
    last_joint_safe_ = false;
    if (tcp_angles_.empty()) tcp_angles_ = angle_words(op_->poses[i]);
    if (restore_inverse_time) line("G93", BlockKind::Point);
    last_words_ = words;
    advance_to(xyz, op_->poses[i], p.tip_mm);
  }

  /// The feed block (machine mode: blocks) reaching point i.
  void feed(std::size_t i, const Vec3d& xyz, const std::string& words) {
    const PostedOperation& op = *op_;
    const CLPointd& p = op.points[i];
    if (!(p.feed_mm_per_min > 0.0)) {
      throw std::invalid_argument("write_gcode: feed move without a feed");
    }
    const double given_s = i < op.programmed_time_s.size() ? op.programmed_time_s[i] : 0.0;
    const double programmed_min = (given_s > 0.0 ? given_s : own_times_[i]) / 60.0;
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
      f = joint_feed(prev_xyz_, prev_pose_, xyz, op.poses[i], time_min, scheduled);
    } else {
      f = tcp_feed(i, programmed_min);
    }
    std::string block =
        std::string(restore_inverse_time ? "G94 " : "") + dialect_.linear() + " " + words;
    block += feed_word(f);
    if (restore_inverse_time) last_feed_.clear();
    finish_point(i, xyz, words, block, restore_inverse_time);
  }

  struct FeedBlock {
    double programmed_min, time_min;
    bool scheduled;
  };

  /// TCP: the tip moves at F. Its distance over the block time is the programmed feed unless
  /// the programmed time is another path's (FeedReference::CutterPath).
  std::string tcp_feed(std::size_t i, double programmed_min) const {
    const CLPointd& p = op_->points[i];
    const Posed& pose = op_->poses[i];
    const double tip_mm = (p.tip_mm - prev_tip_).norm();
    const double rot_deg = std::hypot(rad_to_deg(pose.a_rad - prev_pose_.a_rad),
                                      rad_to_deg(pose.c_rad - prev_pose_.c_rad));
    const double tip_feed = tip_mm > 1e-9 ? tip_mm / programmed_min : rot_deg / programmed_min;
    const bool own = std::abs(tip_feed - p.feed_mm_per_min) <= 1e-9 * p.feed_mm_per_min;
    return fmt((own ? p.feed_mm_per_min : tip_feed) * scale_, fd_);
  }

  /// F of a joint-space block (machine mode, inverse time, a schedule) from `from` to `to`
  /// that takes `minutes`.
  std::string joint_feed(const Vec3d& from, const Posed& from_pose, const Vec3d& to,
                         const Posed& to_pose, double minutes, bool scheduled) const {
    const auto fmt_feed = [&](double f) {
      return scheduled ? precise_feed(f, fd_, max_fd_) : fmt(f, fd_);
    };
    if (g_.feed_mode == FeedMode::InverseTime) return fmt_feed(1.0 / minutes);
    if (scheduled) {
      // The controller times the block from the written (rounded) words: so does F.
      const double len = (rounded(to * scale_) - rounded(from * scale_)).norm();
      const double rot = std::hypot(
          round_to(rad_to_deg(to_pose.a_rad), d_) - round_to(rad_to_deg(from_pose.a_rad), d_),
          round_to(rad_to_deg(to_pose.c_rad), d_) - round_to(rad_to_deg(from_pose.c_rad), d_));
      return fmt_feed((len > 0.0 ? len : rot) / minutes);
    }
    // Joint-space XYZ moves differ from the tip's: F makes the block take the time of the
    // tip at the programmed feed.
    const double joint = (to - from).norm();
    const double rot = std::hypot(rad_to_deg(to_pose.a_rad - from_pose.a_rad),
                                  rad_to_deg(to_pose.c_rad - from_pose.c_rad));
    return fmt(joint > 1e-9 ? joint * scale_ / minutes : rot / minutes, fd_);
  }

  /// Machine mode: where the joints moving linearly would take the tip off the straight line
  /// by more than the tolerance, blocks in between keep it on. Writes them and returns the F
  /// of the last (the point's own block).
  std::string linearised_feed(std::size_t i, const Vec3d& xyz, const FeedBlock& fb) {
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
        minutes = std::max(fb.programmed_min * (at[j] - at[j - 1]),
                           op.linearised_time_s[i][j - 1] / 60.0);
      }
      if (j + 1 == at.size()) return joint_feed(from, from_pose, xyz, pose, minutes, fb.scheduled);
      const std::string piece = joint_feed(from, from_pose, mid_xyz, mid, minutes, fb.scheduled);
      motion(dialect_.linear() + " " + xyz_words(mid_xyz) + angle_words(mid) + feed_word(piece),
             BlockKind::Linearised);
      ++prog_.linearised_blocks;
      from = mid_xyz;
      from_pose = mid;
    }
    return {};
  }

  // --- the program's settings --------------------------------------------------------------
  const std::vector<PostedOperation>& ops_;
  const Machine& machine_;
  const GcodeSettings& g_;
  const double scale_;
  const int d_, fd_, max_fd_;
  Dialect dialect_;
  const bool tcp_, joint_safe_, retracts_;
  const JointLimits limits_;
  const std::string retract_z_, tilt_word_;

  // --- the program so far ------------------------------------------------------------------
  GcodeProgram prog_;
  int line_no_ = 0;
  int current_tool_ = -1;
  std::string last_feed_;
  std::string running_spindle_, running_coolant_;

  // --- the operation being written ---------------------------------------------------------
  const PostedOperation* op_ = nullptr;
  int op_index_ = -1, point_ = -1;
  std::string spindle_, coolant_;  ///< the words in force (empty: stopped, off)
  std::size_t next_event_ = 0, arc_cursor_ = 0;
  /// Fanuc's length and TCP words for the operation's (or index move's) first motion block.
  std::string prefix_;
  /// The rotary words of the first block after TCP came on (write_arc).
  std::string tcp_angles_;
  bool approach_ = false, descend_ = false;
  double clearance_z_mm_ = 0.0;
  std::vector<int> emitted_;
  std::vector<double> own_times_;
  std::string last_words_;
  Vec3d prev_xyz_ = Vec3d::Zero(), prev_tip_ = Vec3d::Zero();
  Posed prev_pose_;
  bool have_prev_ = false;
  /// The last block written is a feed block (not a joint-safe rapid), or a joint-safe rapid.
  bool last_feed_block_ = false, last_joint_safe_ = false;
  /// The block written next is an approach's last leg, along the tool axis.
  bool along_axis_leg_ = false;
};

}  // namespace

GcodeProgram write_gcode(const std::vector<PostedOperation>& operations, const Machine& machine,
                         LengthUnit units, const std::vector<std::string>& comments) {
  const GcodeSettings& g = machine.gcode;
  if (g.dialect == GcodeDialect::Heidenhain && g.feed_mode == FeedMode::InverseTime) {
    throw std::invalid_argument("write_gcode: the heidenhain dialect has no inverse time (G93)");
  }
  if (g.decimals < 0 || g.decimals > max_decimals(g.dialect)) {
    throw std::invalid_argument("write_gcode: " + std::to_string(g.decimals) +
                                " decimals are more than " + to_string(g.dialect) + " takes (" +
                                std::to_string(max_decimals(g.dialect)) + ")");
  }
  return ProgramWriter(operations, machine, units).write(comments);
}

}  // namespace taxopt
