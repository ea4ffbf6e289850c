/// @file The program writer: the program and its operations (start, tool, spindle, coolant,
/// events, length and TCP, end); the points' blocks are point_blocks.cpp.

#include "gcode/program_writer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "taxopt/core/error.hpp"
#include "util/progress.hpp"

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

namespace gcode {

int ProgramWriter::raw(const std::string& s, BlockKind kind) {
  prog_.text += s;
  prog_.text += '\n';
  prog_.blocks.push_back({++line_no_, kind, op_index_, point_, std::nullopt, std::nullopt});
  return line_no_;
}

void ProgramWriter::lines(const std::vector<std::string>& v, BlockKind kind) {
  for (const auto& s : v) line(s, kind);
}

void ProgramWriter::verbatim(const std::vector<std::string>& v, BlockKind kind) {
  for (const auto& s : v) prog_.verbatim_lines.push_back(line(s, kind));
}

PlannedMove ProgramWriter::move_to(PlannedMove::Type type, const Vec3d& xyz,
                                   const Posed& pose) const {
  PlannedMove m;
  m.type = type;
  m.given = 0x1F;
  m.xyz_mm = xyz;
  m.tilt_deg = rad_to_deg(pose.tilt_rad);
  m.c_deg = rad_to_deg(pose.c_rad);
  return m;
}

PlannedMove ProgramWriter::rapid_linear(unsigned given, const Vec3d& xyz) const {
  PlannedMove m;
  m.given = given;
  m.xyz_mm = xyz;
  return m;
}

PlannedMove ProgramWriter::rapid_rotary(double tilt_deg, double c_deg) const {
  PlannedMove m;
  m.given = 0x18;
  m.tilt_deg = tilt_deg;
  m.c_deg = c_deg;
  return m;
}

void ProgramWriter::set_feed(PlannedMove& m, const std::string& f) const {
  const std::size_t dot = f.find('.');
  m.feed_decimals = dot == std::string::npos ? 0 : static_cast<int>(f.size() - dot - 1);
  m.feed_per_min = std::strtod(f.c_str(), nullptr);
  m.inverse_time = g_.feed_mode == FeedMode::InverseTime;
  // The plan holds the F the feed planning decided, digits included: written again, it is
  // the same word (a scheduled F rounded down must not come back up).
  if (fmt(*m.feed_per_min, m.feed_decimals) != f) {
    throw std::logic_error("write_gcode: F" + f + " does not survive as a number");
  }
}

std::string ProgramWriter::motion_text(const PlannedMove& m) {
  std::string s;
  switch (m.type) {
    case PlannedMove::Type::Rapid: s = dialect_.rapid(); break;
    case PlannedMove::Type::Linear: s = dialect_.linear(); break;
    case PlannedMove::Type::ArcClockwise:
    case PlannedMove::Type::ArcCounterClockwise:
      s = std::string(m.arc_axis == 2   ? "G17"
                      : m.arc_axis == 1 ? "G18"
                                        : "G19") +
          (m.type == PlannedMove::Type::ArcCounterClockwise ? " G3" : " G2");
      break;
  }
  static const char* const kLinear[3] = {" X", " Y", " Z"};
  for (int q = 0; q < 3; ++q) {
    if (m.given & (1u << q)) s += kLinear[q] + dialect_.number(m.xyz_mm[q] * scale_, d_);
  }
  if (m.given & 0x8u) s += tilt_word_ + dialect_.number(m.tilt_deg, d_);
  if (m.given & 0x10u) s += " C" + dialect_.number(m.c_deg, d_);
  if (m.type == PlannedMove::Type::ArcClockwise ||
      m.type == PlannedMove::Type::ArcCounterClockwise) {
    for (int q = 0; q < 3; ++q) {
      if (q != m.arc_axis) {
        s += std::string(" ") + static_cast<char>('I' + q) +
             dialect_.number(m.centre_offset_mm[q] * scale_, d_);
      }
    }
  }
  if (m.feed_per_min) s += feed_word(fmt(*m.feed_per_min, m.feed_decimals));
  return s;
}

int ProgramWriter::motion(const PlannedMove& m, BlockKind kind, bool takes_prefix,
                          const std::string& modal) {
  const std::string text = motion_text(m);
  const int at = line((takes_prefix ? prefix_ : std::string()) + modal + text, kind);
  if (takes_prefix) prefix_.clear();
  ProgramBlock& b = prog_.blocks.back();
  b.move = m;
  for (int q = 0; q < 3; ++q) {
    if (m.given & (1u << q)) at_[q] = round_to(m.xyz_mm[q] * scale_, d_) / scale_;
  }
  if (m.given & 0x8u) at_[3] = round_to(m.tilt_deg, d_);
  if (m.given & 0x10u) at_[4] = round_to(m.c_deg, d_);
  if (std::all_of(at_.begin(), at_.end(), [](const auto& v) { return v.has_value(); })) {
    const Vec3d xyz = joints_of_written_mm(machine_, Vec3d(*at_[0], *at_[1], *at_[2]),
                                           Posed{deg_to_rad(*at_[3]), deg_to_rad(*at_[4])});
    b.joints = JointPosition{xyz.x(), xyz.y(), xyz.z(), *at_[3], *at_[4]};
    joints_ = b.joints;
  } else if (joints_ && !m.machine_frame) {
    joints_ = joints_after(*joints_, m);
  }
  return at;
}

std::optional<JointPosition> ProgramWriter::joints_after(const JointPosition& q,
                                                         const PlannedMove& m) const {
  const Posed from{deg_to_rad(q[3]), deg_to_rad(q[4])};
  JointPosition out = q;
  if (m.given & 0x8u) out[3] = round_to(m.tilt_deg, d_);
  if (m.given & 0x10u) out[4] = round_to(m.c_deg, d_);
  const Posed to{deg_to_rad(out[3]), deg_to_rad(out[4])};
  // TCP off: the linear joints stay where no word names them; the words' own frame is
  // another question (the tool length), left unknown.
  if (!tcp_in_force()) return (m.given & 0x7u) ? std::nullopt : std::optional(out);
  // TCP on: the tip stays put in the table's frame where no word names it.
  Vec3d tip = machine_.rotary.from_machine_mm(Vec3d(q[0], q[1], q[2]), from);
  const Vec3d written = tip_of_written_mm(machine_, rounded_mm(m.xyz_mm), to);
  for (int k = 0; k < 3; ++k) {
    if (m.given & (1u << k)) tip[k] = written[k];
  }
  const Vec3d xyz = machine_.rotary.to_machine_mm(tip, to);
  out[0] = xyz.x(), out[1] = xyz.y(), out[2] = xyz.z();
  return out;
}

void ProgramWriter::retract() {
  const std::vector<std::string> blocks = dialect_.retract(retract_z_);
  if (blocks.empty()) return;
  PlannedMove m = rapid_linear(0x4, Vec3d(0.0, 0.0, g_.program.retract_z_mm));
  // Fanuc's retract is a reference return (G91 G28 Z0.): to the machine's reference point.
  if (dialect_.rules().retract_to_reference()) m.xyz_mm.z() = 0.0;
  machine_frame_move(blocks, m, BlockKind::Retract);
}

void ProgramWriter::machine_frame_move(const std::vector<std::string>& blocks, PlannedMove m,
                                       BlockKind kind) {
  m.machine_frame = true;
  for (std::size_t j = 0; j < blocks.size(); ++j) {
    line(blocks[j], kind);
    if (j == 0) prog_.blocks.back().move = m;
  }
  // Where the tip stands in the program's frame is not known after a move in the machine's.
  at_[0] = at_[1] = at_[2] = std::nullopt;
  // The joints are, for a retract of Z alone to a height in machine coordinates.
  const bool z_only_retract =
      kind == BlockKind::Retract && m.given == 0x4u && !dialect_.rules().retract_to_reference();
  // Referred to the program's zero: less the work offset (taken as zero where not known).
  const Vec3d offset = machine_.work_offset_mm.value_or(Vec3d::Zero());
  if (joints_ && z_only_retract) {
    (*joints_)[2] = m.xyz_mm.z() - machine_.holder_gauge_length_mm.value_or(0.0) - offset.z();
  } else if (joints_ && m.given == 0x3u && kind == BlockKind::End) {
    (*joints_)[0] = m.xyz_mm.x() - offset.x();  // the end's park
    (*joints_)[1] = m.xyz_mm.y() - offset.y();
  } else {
    joints_.reset();
  }
}

bool ProgramWriter::tcp_in_force() const {
  // LinuxCNC without a kinematics switch: its TCP kinematics are always on. Else TCP is on
  // between the dialect's (or the switch's, M428) on and off; the turns between operations
  // and at the end come with it off: the joints are the axes.
  return tcp_ && (tcp_switched_on_ || (joint_safe_ && g_.program.tcp_on.empty()));
}

bool ProgramWriter::tcp_planned_now() const { return joint_safe_ && tcp_in_force(); }

std::optional<std::string> ProgramWriter::joint_safe_f(const PlannedMove& m) const {
  if (!tcp_planned_now()) return std::nullopt;
  if (!joints_) return joint_safe_f_any_direction(m);
  const JointPosition& q = *joints_;
  const std::optional<JointPosition> end = joints_after(q, m);
  if (!end) return std::nullopt;
  const JointPosition& e = *end;
  const Posed from{deg_to_rad(q[3]), deg_to_rad(q[4])}, to{deg_to_rad(e[3]), deg_to_rad(e[4])};
  const Vec3d from_tip = machine_.rotary.from_machine_mm(Vec3d(q[0], q[1], q[2]), from);
  const Vec3d to_tip = machine_.rotary.from_machine_mm(Vec3d(e[0], e[1], e[2]), to);
  const std::optional<double> rate =
      joint_safe_rate_per_s(machine_.rotary, limits_, from_tip, from, to_tip, to);
  if (!rate) return std::nullopt;
  const double rot_deg =
      std::hypot(rad_to_deg(to.tilt_rad - from.tilt_rad), rad_to_deg(to.c_rad - from.c_rad));
  return joint_safe_feed((to_tip - from_tip).norm(), rot_deg, *rate);
}

std::optional<std::string> ProgramWriter::joint_safe_f_any_direction(const PlannedMove& m) const {
  if ((m.given & 0x18u) != 0 || (m.given & 0x7u) == 0 || !at_[3] || !at_[4] ||
      g_.feed_mode == FeedMode::InverseTime) {
    return std::nullopt;
  }
  // With A and C held the joints are the tip turned with the table, J(tip) = M tip + o. The
  // rapid drives each named axis at up to its limit, so joint j at up to sum |M_ji| v_i; a
  // feed at the path speed f drives it at |M_j . dir| f <= |M_j| f whichever the direction.
  const Posed pose{deg_to_rad(*at_[3]), deg_to_rad(*at_[4])};
  const Vec3d o = machine_.rotary.to_machine_mm(Vec3d::Zero(), pose);
  Eigen::Matrix3d jac;
  for (int i = 0; i < 3; ++i) jac.col(i) = machine_.rotary.to_machine_mm(Vec3d::Unit(i), pose) - o;
  bool rapid_may_pass = false;
  double path_mm_s = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double v = limits_[static_cast<std::size_t>(i)].max_velocity_per_s;
    if ((m.given & (1u << i)) && v > 0.0) path_mm_s = std::min(path_mm_s, v);
  }
  for (int j = 0; j < 3; ++j) {
    const double limit = limits_[static_cast<std::size_t>(j)].max_velocity_per_s;
    if (!(limit > 0.0)) continue;
    double rapid = 0.0;
    for (int i = 0; i < 3; ++i) {
      if (!(m.given & (1u << i))) continue;
      const double v = limits_[static_cast<std::size_t>(i)].max_velocity_per_s;
      rapid += std::abs(jac(j, i)) * (v > 0.0 ? v : std::numeric_limits<double>::infinity());
    }
    rapid_may_pass = rapid_may_pass || rapid > limit * (1.0 + 1e-9);
    path_mm_s = std::min(path_mm_s, limit / std::max(jac.row(j).norm(), 1e-12));
  }
  if (!rapid_may_pass || !std::isfinite(path_mm_s)) return std::nullopt;
  return joint_safe_feed(1.0, 0.0, path_mm_s * (1.0 - 1e-3));  // 1 mm at path_mm_s
}

int ProgramWriter::rapid_block(PlannedMove m, BlockKind kind, bool takes_prefix) {
  const std::optional<std::string> f = joint_safe_f(m);
  if (!f) {
    last_joint_safe_ = false;
    return motion(m, kind, takes_prefix);
  }
  return joint_safe_block(m, *f, kind, takes_prefix);
}

void ProgramWriter::rotary_turn(const Posed& to, BlockKind kind) {
  rapid_block(rapid_rotary(rad_to_deg(to.tilt_rad), rad_to_deg(to.c_rad)), kind, false);
}

void ProgramWriter::park(const std::array<double, 2>& xy_mm) {
  const std::vector<std::string> blocks =
      dialect_.park(dialect_.number(xy_mm[0] * scale_, d_), dialect_.number(xy_mm[1] * scale_, d_));
  machine_frame_move(blocks, rapid_linear(0x3, Vec3d(xy_mm[0], xy_mm[1], 0.0)), BlockKind::End);
}

Vec3d ProgramWriter::rounded(const Vec3d& v) const {
  return Vec3d(round_to(v.x(), d_), round_to(v.y(), d_), round_to(v.z(), d_));
}

Vec3d ProgramWriter::rounded_mm(const Vec3d& v_mm) const {
  return Vec3d(round_to(v_mm.x() * scale_, d_) / scale_, round_to(v_mm.y() * scale_, d_) / scale_,
               round_to(v_mm.z() * scale_, d_) / scale_);
}

Vec3d ProgramWriter::out_xyz(const Vec3d& tip, const Posed& pose) const {
  return written_xyz_mm(machine_, tip, pose);
}

std::string ProgramWriter::angle_words(const Posed& pose) const {
  return tilt_word_ + dialect_.number(rad_to_deg(pose.tilt_rad), d_) + " C" +
         dialect_.number(rad_to_deg(pose.c_rad), d_);
}

std::string ProgramWriter::xyz_words(const Vec3d& xyz) const {
  return "X" + dialect_.number(xyz.x() * scale_, d_) + " Y" +
         dialect_.number(xyz.y() * scale_, d_) + " Z" + dialect_.number(xyz.z() * scale_, d_);
}

std::string ProgramWriter::spindle_words(double rpm, bool clockwise) {
  return "S" + fmt(rpm, 0) + (clockwise ? " M3" : " M4");
}

std::string ProgramWriter::coolant_code(ClCoolant c) {
  return c == ClCoolant::Flood  ? std::string("M8")
         : c == ClCoolant::Mist ? std::string("M7")
                                : std::string();
}

std::string ProgramWriter::coolant_of(const PostedOperation& o) const {
  return o.coolant ? coolant_code(*o.coolant) : dialect_.coolant_on();
}

std::string ProgramWriter::feed_word(const std::string& f) {
  const bool write = g_.feed_mode == FeedMode::InverseTime || f != last_feed_;
  last_feed_ = f;
  return write ? " F" + f : std::string();
}

void ProgramWriter::program_start(const std::vector<std::string>& comments) {
  for (const auto& s : dialect_.start()) raw(s, BlockKind::Start);
  if (dialect_.rules().names_program()) {
    raw(dialect_.comment("program " + dialect_.name()), BlockKind::Start);
  }
  for (const auto& c : comments) raw(dialect_.comment(c), BlockKind::Start);
  line(dialect_.setup(g_.feed_mode == FeedMode::InverseTime), BlockKind::Start);
  // The path's blending bound (ProgramTemplate::blend_tolerance_mm), where the dialect has one.
  const std::string path =
      dialect_.rules().path_control(g_.program.blend_tolerance_mm * scale_, d_);
  if (!path.empty()) line(path, BlockKind::Start);
  if (const std::string w = dialect_.work_offset(); !w.empty()) verbatim({w}, BlockKind::Start);
  verbatim(g_.program.header, BlockKind::Start);
  // A controller may start in its TCP kinematics (LinuxCNC's bridge-mill sample: M428's are
  // its start-up default), where the writer and the time model take the switch as off until
  // its tcp_on: the first table turn then swung the joints round the tip (X 221, Y 229 mm/s
  // against 200 on LinuxCNC's controller). The switch's off words say which holds.
  verbatim(g_.program.tcp_off, BlockKind::Start);
}

void ProgramWriter::program_end() {
  op_index_.reset();
  point_.reset();
  retract();
  // The rotary axes home, with the tool up; a continuous C to the turn of home nearest it (a
  // raster whose air turns wound C to -21,330 deg went back 59 turns to C0), a tie toward C0.
  if (g_.program.end_pose == EndPose::Home && retracts_ && !ops_.empty()) {
    Posed home{0.0, 0.0};
    if (machine_.rotary.c.continuous) {
      const double turns = prev_pose_.c_rad / Constants<double>::two_pi();
      double k = std::round(turns);
      if (std::abs(turns - k) > 0.5 - 1e-9) k = std::trunc(turns);
      home.c_rad = k * Constants<double>::two_pi();
    }
    rotary_turn(home, BlockKind::End);
  }
  if (g_.program.end_park_xy_mm && retracts_ && !ops_.empty()) park(*g_.program.end_park_xy_mm);
  verbatim(g_.program.footer, BlockKind::End);
  line(dialect_.end(), BlockKind::End);
  for (const auto& s : dialect_.finish()) raw(s, BlockKind::End);
}

void ProgramWriter::operation(std::size_t k) {
  const PostedOperation& op = ops_[k];
  if (op.poses.size() != op.points.size()) {
    throw std::invalid_argument("write_gcode: operation '" + op.name + "' has no pose per point");
  }
  op_ = &op;
  op_index_ = k;
  point_.reset();
  operation_start();
  emitted_.assign(op.points.size(), 0);
  passed_over_.clear();
  index_target_ = 0;
  own_times_ = programmed_block_times_s(op.points, op.poses);
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    detail::look_at_stop(stop_, i, detail::kPointStride);
    point_ = i;
    events_before(i);
    if (arc_at(i)) {
      i = op.arcs[arc_cursor_].end;
      continue;
    }
    point(i);
  }
  point_.reset();
  events_before(op.points.size());
  prog_.emitted.push_back(std::move(emitted_));
  prog_.passed_over.push_back(std::move(passed_over_));
  operation_end(k + 1 < ops_.size() ? &ops_[k + 1] : nullptr);
}

void ProgramWriter::operation_start() {
  const PostedOperation& op = *op_;
  raw(dialect_.comment("operation " + op.name), BlockKind::Start);
  // Every operation's first feed block carries its F (a reader of one operation, or a
  // restart at it, must not inherit the last operation's feed).
  last_feed_.clear();
  retract();
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
}

void ProgramWriter::tool_change(int tool) {
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

double ProgramWriter::clearance_z_mm(const PostedOperation& op) const {
  double z = op.part_top_z_mm.value_or(-std::numeric_limits<double>::infinity());
  for (const CLPointd& q : op.points) z = std::max(z, q.tip_mm.z());
  return z + g_.program.approach_clearance_mm;
}

void ProgramWriter::operation_end(const PostedOperation* next) {
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

void ProgramWriter::events_before(std::size_t i) {
  const PostedOperation& op = *op_;
  for (; next_event_ < op.events.size() && op.events[next_event_].before_point <= i;
       ++next_event_) {
    event(op.events[next_event_]);
  }
}

void ProgramWriter::event(const ProgramEvent& e) {
  switch (e.kind) {
    case ProgramEvent::Kind::Stop: line("M0", BlockKind::Event); break;
    case ProgramEvent::Kind::OptionalStop: line("M1", BlockKind::Event); break;
    case ProgramEvent::Kind::Comment: raw(dialect_.comment(e.text), BlockKind::Event); break;
    case ProgramEvent::Kind::Dwell: {
      const std::string dwell = dialect_.rules().dwell(e.dwell_s);
      if (dwell.empty()) {
        throw InputError("CL line " + std::to_string(e.line) +
                         ": DELAY: taxopt writes a dwell for LinuxCNC (G4 P seconds) and "
                         "Fanuc (G04 P milliseconds) only, not for the " +
                         std::string(to_string(g_.dialect)) + " dialect");
      }
      line(dwell, BlockKind::Event);
      break;
    }
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

void ProgramWriter::turn_table(const Posed& pose) {
  if (!retracts_) return;
  rotary_turn(pose, BlockKind::TableTurn);
}

void ProgramWriter::length_and_tcp_on() {
  tcp_angles_.clear();
  tcp_switched_on_ = tcp_;
  lines(dialect_.length_on(tcp_, current_tool_), BlockKind::LengthTcp);
  verbatim(tcp_ ? g_.program.tcp_on : std::vector<std::string>{}, BlockKind::LengthTcp);
  lines(dialect_.tcp_on(tcp_, current_tool_), BlockKind::LengthTcp);
  prefix_ = dialect_.first_move_prefix(tcp_, current_tool_);
}

void ProgramWriter::length_and_tcp_off() {
  tcp_switched_on_ = false;
  lines(dialect_.tcp_off(tcp_), BlockKind::LengthTcp);
  verbatim(tcp_ ? g_.program.tcp_off : std::vector<std::string>{}, BlockKind::LengthTcp);
}

GcodeProgram write_program(const std::vector<PostedOperation>& operations, const Machine& machine,
                           LengthUnit units, const std::vector<std::string>& comments,
                           const StopSource* stop) {
  const GcodeSettings& g = machine.gcode;
  if (!has_inverse_time(g.dialect) && g.feed_mode == FeedMode::InverseTime) {
    throw std::invalid_argument("write_gcode: the heidenhain dialect has no inverse time (G93)");
  }
  if (g.decimals < 0 || g.decimals > max_decimals(g.dialect)) {
    throw std::invalid_argument("write_gcode: " + std::to_string(g.decimals) +
                                " decimals are more than " + to_string(g.dialect) + " takes (" +
                                std::to_string(max_decimals(g.dialect)) + ")");
  }
  return ProgramWriter(operations, machine, units).write(comments, stop);
}

}  // namespace gcode

GcodeProgram write_gcode(const std::vector<PostedOperation>& operations, const Machine& machine,
                         LengthUnit units, const std::vector<std::string>& comments) {
  return gcode::write_program(operations, machine, units, comments, nullptr);
}

}  // namespace taxopt
