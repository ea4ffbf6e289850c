#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt {
namespace {

std::string fmt(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  // No "-0.0000": a negative zero after rounding is written as zero.
  bool all_zero = true;
  for (char c : s) {
    if (c != '-' && c != '0' && c != '.') all_zero = false;
  }
  if (all_zero && !s.empty() && s[0] == '-') s.erase(0, 1);
  return s;
}

/// The value a reader gets back from fmt(v, decimals).
double round_to(double v, int decimals) { return std::strtod(fmt(v, decimals).c_str(), nullptr); }

/// Comment text for a controller: no parentheses (they close a LinuxCNC or Fanuc comment),
/// no line breaks.
std::string comment_text(const std::string& text) {
  std::string s;
  for (char c : text) {
    if (c == '(') {
      s += '[';
    } else if (c == ')') {
      s += ']';
    } else if (c == '\n' || c == '\r') {
      s += ' ';
    } else {
      s += c;
    }
  }
  return s;
}

/// How one controller dialect writes a program (docs/gcode-dialects.md).
class Dialect {
 public:
  Dialect(const GcodeSettings& g, LengthUnit units)
      : d_(g.dialect), t_(g.program), inch_(units == LengthUnit::Inch) {}

  /// A block as written: Heidenhain ISO numbers blocks and ends them with " *".
  std::string block(const std::string& words) {
    if (d_ != GcodeDialect::Heidenhain) return words;
    block_no_ += 10;
    return "N" + std::to_string(block_no_) + " " + words + " *";
  }
  std::string comment(const std::string& text) {
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Fanuc:
      case GcodeDialect::Haas: return "(" + comment_text(text) + ")";
      case GcodeDialect::Siemens: return "; " + comment_text(text);
      case GcodeDialect::Heidenhain: return block("; " + comment_text(text));
    }
    return {};
  }
  std::string name() const { return t_.name.empty() ? "TAXOPT" : t_.name; }
  /// Lines before the comments: the program start.
  std::vector<std::string> start() const {
    switch (d_) {
      case GcodeDialect::Fanuc:
        return {"%", "O" + digits(t_.number, 4) + " (" + comment_text(name()) + ")"};
      case GcodeDialect::Haas:  // program numbers O00000 .. O99999
        return {"%", "O" + digits(t_.number, 5) + " (" + comment_text(name()) + ")"};
      case GcodeDialect::Heidenhain: return {"%" + name() + (inch_ ? " G70" : " G71") + " *"};
      default: return {};
    }
  }
  /// The modal set-up block (units, absolute, plane, feed mode).
  std::string setup(bool inverse_time) const {
    const std::string feed = inverse_time ? "G93" : "G94";
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Fanuc:
      case GcodeDialect::Haas:
        return std::string(inch_ ? "G20" : "G21") + " G90 G17 G40 G49 G80 " + feed;
      case GcodeDialect::Siemens:  // G700/G710: feeds in the program's units too
        return std::string(inch_ ? "G700" : "G710") + " G90 G17 G40 " + feed;
      case GcodeDialect::Heidenhain: return "G17 G90 G40";  // units in the first block
    }
    return {};
  }
  /// The work offset block: the template's, else G54 (none on a TNC: its active preset).
  std::string work_offset() const {
    if (t_.work_offset == "none") return {};
    if (!t_.work_offset.empty()) return t_.work_offset;
    return d_ == GcodeDialect::Heidenhain ? std::string() : "G54";
  }
  /// The retract to machine Z (SafeRetract::MachineZ), in the dialect's own way; the tool
  /// length offset is off after it (Sinumerik D0; the others cancel it before).
  std::vector<std::string> retract(const std::string& z) const {
    if (t_.retract == SafeRetract::None) return {};
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Haas: return {"G53 G0 Z" + z};
      case GcodeDialect::Fanuc: return {"G91 G28 Z0.", "G90"};
      case GcodeDialect::Siemens: return {"G0 SUPA Z" + z + " D0"};
      case GcodeDialect::Heidenhain: return {"G00 Z" + z + " M91"};
    }
    return {};
  }
  /// The end's park of X and Y in machine coordinates (ProgramTemplate::end_park_xy_mm), as the
  /// retract: G53 (LinuxCNC, Fanuc, Haas), SUPA (Sinumerik), M91 (TNC).
  std::vector<std::string> park(const std::string& x, const std::string& y) const {
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Fanuc:
      case GcodeDialect::Haas: return {"G53 G0 X" + x + " Y" + y};
      case GcodeDialect::Siemens: return {"G0 SUPA X" + x + " Y" + y};
      case GcodeDialect::Heidenhain: return {"G00 X" + x + " Y" + y + " M91"};
    }
    return {};
  }
  /// The tool change; true when the lines are the template's (written as they are).
  std::pair<std::vector<std::string>, bool> tool_change(int tool) const {
    const std::string n = std::to_string(tool);
    if (!t_.tool_change.empty()) {
      std::vector<std::string> out;
      for (std::string line : t_.tool_change) {
        for (std::size_t at = line.find("{tool}"); at != std::string::npos;
             at = line.find("{tool}", at + n.size())) {
          line.replace(at, 6, n);
        }
        out.push_back(line);
      }
      return {out, true};
    }
    switch (d_) {
      case GcodeDialect::Heidenhain: return {{"T" + n + " G17"}, false};
      default: return {{"T" + n + " M6"}, false};
    }
  }
  /// The tool length offset switched on for an operation, as its own block (LinuxCNC G43,
  /// Sinumerik D, Haas G43 in machine mode: its G234 carries the offset); Fanuc's is on the
  /// first move, a TNC's comes with the tool call.
  std::vector<std::string> length_on(bool tcp, int tool) const {
    const std::string h = std::to_string(std::max(tool, 1));
    switch (d_) {
      case GcodeDialect::LinuxCNC: return {"G43 H" + h};
      case GcodeDialect::Siemens: return {"D1"};
      case GcodeDialect::Haas:
        return tcp ? std::vector<std::string>{} : std::vector<std::string>{"G43 H" + h};
      default: return {};
    }
  }
  /// Tool centre point control on (tcp mode): blocks before an operation's first move.
  std::vector<std::string> tcp_on(bool tcp, int tool) const {
    if (!tcp) return {};
    switch (d_) {
      case GcodeDialect::Siemens: return {"TRAORI", "ORIAXES"};  // rotary axes linear
      case GcodeDialect::Heidenhain: return {"M128"};
      case GcodeDialect::Haas: return {"G234 H" + std::to_string(std::max(tool, 1))};
      default: return {};
    }
  }
  /// Fanuc starts tool centre point control (G43.4, or plain tool length compensation G43 in
  /// machine mode) on the operation's first motion block, with the tool's offset number.
  bool length_on_first_move() const { return d_ == GcodeDialect::Fanuc; }
  std::string first_move_prefix(bool tcp, int tool) const {
    if (d_ != GcodeDialect::Fanuc) return {};
    return std::string(tcp ? "G43.4" : "G43") + " H" + std::to_string(std::max(tool, 1)) + " ";
  }
  std::vector<std::string> tcp_off(bool tcp) const {
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Fanuc:
      case GcodeDialect::Haas: return {"G49"};  // Haas: G234 is in G49's group 08
      case GcodeDialect::Siemens:
        return tcp ? std::vector<std::string>{"TRAFOOF"} : std::vector<std::string>{};
      case GcodeDialect::Heidenhain:
        return tcp ? std::vector<std::string>{"M129"} : std::vector<std::string>{};
    }
    return {};
  }
  std::string coolant_on() const {
    switch (t_.coolant) {
      case Coolant::Flood: return "M8";
      case Coolant::Mist: return "M7";
      case Coolant::None: return {};
    }
    return {};
  }
  std::string rapid() const { return d_ == GcodeDialect::Heidenhain ? "G00" : "G0"; }
  std::string linear() const { return d_ == GcodeDialect::Heidenhain ? "G01" : "G1"; }
  std::string end() const { return d_ == GcodeDialect::LinuxCNC ? "M2" : "M30"; }
  std::vector<std::string> finish() const {
    switch (d_) {
      case GcodeDialect::Fanuc:
      case GcodeDialect::Haas: return {"%"};
      case GcodeDialect::Heidenhain:
        return {"N99999999 %" + name() + (inch_ ? " G70" : " G71") + " *"};
      default: return {};
    }
  }
  /// Fanuc reads a number without a decimal point in least input increments: "10" is
  /// 0.010 mm. Every coordinate gets its point (Haas too, as its posts write them).
  std::string number(double v, int decimals) const {
    std::string s = fmt(v, decimals);
    if ((d_ == GcodeDialect::Fanuc || d_ == GcodeDialect::Haas) &&
        s.find('.') == std::string::npos) {
      s += '.';
    }
    return s;
  }

 private:
  static std::string digits(int n, int width) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%0*d", width, n);
    return buf;
  }
  GcodeDialect d_;
  const ProgramTemplate& t_;
  bool inch_;
  int block_no_ = 0;
};

}  // namespace

Vec3d approach_tip_mm(const Vec3d& tip_mm, const Vec3d& axis, double clearance_z_mm,
                      double safe_distance_mm) {
  // Along the axis up to the clearance height where the axis rises steeply enough (within 60
  // deg of the vertical: at most twice the height to go), else the safe distance along it.
  const double rise_mm = clearance_z_mm - tip_mm.z();
  const double along_mm =
      axis.z() >= 0.5 && rise_mm > 0.0 ? rise_mm / axis.z() : std::max(0.0, safe_distance_mm);
  return tip_mm + along_mm * axis;
}

std::vector<double> programmed_block_times_s(const std::vector<CLPointd>& points,
                                             const std::vector<Posed>& poses) {
  if (poses.size() != points.size()) {
    throw std::invalid_argument("programmed_block_times_s: one pose per point is needed");
  }
  std::vector<double> t(points.size(), 0.0);
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].motion != Motion::Feed || !(points[i].feed_mm_per_min > 0.0)) continue;
    t[i] = programmed_move_time_s(points[i - 1].tip_mm, poses[i - 1], points[i].tip_mm, poses[i],
                                  points[i].feed_mm_per_min);
  }
  return t;
}

double programmed_move_time_s(const Vec3d& from_tip_mm, const Posed& from, const Vec3d& to_tip_mm,
                              const Posed& to, double feed_mm_per_min) {
  const double tip_mm = (to_tip_mm - from_tip_mm).norm();
  const double rot_deg =
      std::hypot(rad_to_deg(to.a_rad - from.a_rad), rad_to_deg(to.c_rad - from.c_rad));
  // A move too small to time still gets a positive time: its words may differ after
  // rounding, and a feed schedule needs a bound for every move.
  return 60.0 * (tip_mm > 1e-9 ? tip_mm : std::max(rot_deg, 1e-9)) / feed_mm_per_min;
}

std::vector<double> linearise_fractions(const ACMachined& machine, const Vec3d& from_tip_mm,
                                        const Posed& from, const Vec3d& to_tip_mm, const Posed& to,
                                        double tolerance_mm) {
  std::vector<double> at = {0.0, 1.0};
  if (!(tolerance_mm > 0.0)) return at;
  const Vec3d from_joint = machine.to_machine_mm(from_tip_mm, from);
  const Vec3d to_joint = machine.to_machine_mm(to_tip_mm, to);
  // Largest distance of the tip from the straight line between t0 and t1 while the joints
  // run linearly from their values at t0 to those at t1 (sampled; the deviation is smooth).
  const auto joints_at = [&](double t) {
    const Posed pose{from.a_rad + t * (to.a_rad - from.a_rad),
                     from.c_rad + t * (to.c_rad - from.c_rad)};
    const Vec3d xyz =
        (t == 0.0 || t == 1.0)
            ? (t == 0.0 ? from_joint : to_joint)
            : machine.to_machine_mm(from_tip_mm + t * (to_tip_mm - from_tip_mm), pose);
    return std::make_pair(xyz, pose);
  };
  const auto deviation = [&](double t0, double t1) {
    const auto [x0, p0] = joints_at(t0);
    const auto [x1, p1] = joints_at(t1);
    const Vec3d a = from_tip_mm + t0 * (to_tip_mm - from_tip_mm);
    const Vec3d b = from_tip_mm + t1 * (to_tip_mm - from_tip_mm);
    double worst = 0.0;
    constexpr int kSamples = 16;
    for (int s = 1; s < kSamples; ++s) {
      const double u = static_cast<double>(s) / kSamples;
      const Posed pose{p0.a_rad + u * (p1.a_rad - p0.a_rad), p0.c_rad + u * (p1.c_rad - p0.c_rad)};
      const Vec3d tip = machine.from_machine_mm(x0 + u * (x1 - x0), pose);
      const Vec3d ab = b - a;
      const double len2 = ab.squaredNorm();
      const double w = len2 > 0.0 ? std::clamp((tip - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      worst = std::max(worst, (tip - (a + w * ab)).norm());
    }
    return worst;
  };
  // Halve every piece that deviates more than the tolerance, at most 2^12 pieces a move.
  for (int depth = 0; depth < 12; ++depth) {
    std::vector<double> next = {0.0};
    bool split = false;
    for (std::size_t j = 1; j < at.size(); ++j) {
      if (deviation(at[j - 1], at[j]) > tolerance_mm) {
        next.push_back(0.5 * (at[j - 1] + at[j]));
        split = true;
      }
      next.push_back(at[j]);
    }
    at.swap(next);
    if (!split) break;
  }
  return at;
}

std::pair<double, Joint> joint_velocity_rate_per_s(const ACMachined& ac, const JointLimits& limits,
                                                   const Vec3d& from_tip_mm, const Posed& from,
                                                   const Vec3d& to_tip_mm, const Posed& to) {
  // With A and C held the joints are an affine map of the tip: they move linearly, and the
  // chord (the schedule's own model) is exact.
  const double turn_rad = std::hypot(to.a_rad - from.a_rad, to.c_rad - from.c_rad);
  if (turn_rad == 0.0) return {std::numeric_limits<double>::infinity(), Joint::X};
  // Steps of at most 0.25 deg of turn (at most 64): the joints' rate of change varies by less
  // than the step's turn (in rad) relative within a step, which the margin below covers.
  const int steps = std::clamp(static_cast<int>(std::ceil(rad_to_deg(turn_rad) / 0.25)), 1, 64);
  double rate = std::numeric_limits<double>::infinity();
  Joint by = Joint::X;
  const Vec3d d = to_tip_mm - from_tip_mm;
  Vec3d prev = ac.to_machine_mm(from_tip_mm, from);
  for (int s = 1; s <= steps; ++s) {
    const double u = static_cast<double>(s) / steps;
    const Posed pose{from.a_rad + u * (to.a_rad - from.a_rad),
                     from.c_rad + u * (to.c_rad - from.c_rad)};
    const Vec3d q = ac.to_machine_mm(from_tip_mm + u * d, pose);
    for (std::size_t j = 0; j < 3; ++j) {
      const double v = limits[j].max_velocity_per_s;
      const auto e = static_cast<Eigen::Index>(j);
      const double dq = std::abs(q[e] - prev[e]) * steps;
      if (v > 0.0 && dq > 0.0 && v / dq < rate) {
        rate = v / dq;
        by = static_cast<Joint>(j);
      }
    }
    prev = q;
  }
  return {rate * (1.0 - 1e-3 - turn_rad / steps), by};
}

std::optional<double> joint_safe_rate_per_s(const ACMachined& ac, const JointLimits& limits,
                                            const Vec3d& from_tip_mm, const Posed& from,
                                            const Vec3d& to_tip_mm, const Posed& to,
                                            bool held_pose) {
  const double da_deg = rad_to_deg(to.a_rad - from.a_rad);
  const double dc_deg = rad_to_deg(to.c_rad - from.c_rad);
  const Vec3d d = to_tip_mm - from_tip_mm;
  const double axis_delta[kJointCount] = {d.x(), d.y(), d.z(), da_deg, dc_deg};
  // The rapid's own rate: every axis within its velocity limit.
  double axis_rate = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < kJointCount; ++k) {
    const double v = limits[k].max_velocity_per_s;
    if (v > 0.0 && axis_delta[k] != 0.0)
      axis_rate = std::min(axis_rate, v / std::abs(axis_delta[k]));
  }
  if (!std::isfinite(axis_rate)) return std::nullopt;
  double joint_rate = joint_velocity_rate_per_s(ac, limits, from_tip_mm, from, to_tip_mm, to).first;
  if (da_deg == 0.0 && dc_deg == 0.0) {
    if (!held_pose) return std::nullopt;  // the joints move as the axes (tcp_joint_peaks warns)
    // A and C held: the joints are the tip turned with the table, each a straight line, which
    // the axes' limits do not bound where the table is tilted (a rapid along a tilted tool axis
    // is the spindle's Z alone, up to 1/cos A faster than the program's Z).
    const Vec3d dq = ac.to_machine_mm(to_tip_mm, to) - ac.to_machine_mm(from_tip_mm, from);
    for (std::size_t j = 0; j < 3; ++j) {
      const double v = limits[j].max_velocity_per_s;
      const double q = std::abs(dq[static_cast<Eigen::Index>(j)]);
      if (v > 0.0 && q > 0.0) joint_rate = std::min(joint_rate, v / q);
    }
    // Within the axes' own rate (a table not tilted: the joints are the axes): a rapid.
    if (!(joint_rate < axis_rate * (1.0 - 1e-6))) return std::nullopt;
    joint_rate *= 1.0 - 1e-3;
  }
  if (!(joint_rate < axis_rate)) return std::nullopt;
  return joint_rate;
}

GcodeProgram write_gcode(const std::vector<PostedOperation>& operations, const Machine& machine,
                         LengthUnit units, const std::vector<std::string>& comments) {
  const GcodeSettings& g = machine.gcode;
  const double scale = 1.0 / mm_per_unit(units);
  const int d = g.decimals;
  const auto rounded = [d](const Vec3d& v) {
    return Vec3d(round_to(v.x(), d), round_to(v.y(), d), round_to(v.z(), d));
  };
  if (g.dialect == GcodeDialect::Heidenhain && g.feed_mode == FeedMode::InverseTime) {
    throw std::invalid_argument("write_gcode: the heidenhain dialect has no inverse time (G93)");
  }
  if (d < 0 || d > max_decimals(g.dialect)) {
    throw std::invalid_argument("write_gcode: " + std::to_string(d) + " decimals are more than " +
                                to_string(g.dialect) + " takes (" +
                                std::to_string(max_decimals(g.dialect)) + ")");
  }
  const int fd = feed_decimals(g);
  const int max_fd = max_feed_decimals(g.dialect);
  Dialect dialect(g, units);
  GcodeProgram prog;
  int line_no = 0;
  const auto raw = [&](const std::string& s) {
    prog.text += s;
    prog.text += '\n';
    return ++line_no;
  };
  const auto line = [&](const std::string& s) { return raw(dialect.block(s)); };
  const auto lines = [&](const std::vector<std::string>& v) {
    for (const auto& s : v) line(s);
  };
  // Blocks of the template, written as they are: the reader steps over them.
  const auto verbatim = [&](const std::vector<std::string>& v) {
    for (const auto& s : v) prog.verbatim_lines.push_back(line(s));
  };
  const bool tcp = g.mode == GcodeMode::Tcp;
  // LinuxCNC plans a tcp rapid in the program's axes: where that would run a joint over its
  // velocity limit, the rapid is a feed block at a joint-safe feed (joint_safe_rate_per_s).
  const bool joint_safe = tcp && g.dialect == GcodeDialect::LinuxCNC;
  const JointLimits limits = effective_limits(machine);
  const std::string retract_z = dialect.number(g.program.retract_z_mm * scale, d);
  // The tilt axis's word: A or B (ac_machine.hpp).
  const std::string tilt_word = std::string(" ") + machine.ac.tilt_letter();
  for (const auto& s : dialect.start()) raw(s);
  if (g.dialect == GcodeDialect::LinuxCNC || g.dialect == GcodeDialect::Siemens) {
    raw(dialect.comment("program " + dialect.name()));
  }
  for (const auto& c : comments) raw(dialect.comment(c));
  line(dialect.setup(g.feed_mode == FeedMode::InverseTime));
  if (g.dialect == GcodeDialect::LinuxCNC) {
    // The path's blending bound (ProgramTemplate::blend_tolerance_mm).
    const double blend = g.program.blend_tolerance_mm;
    line(blend > 0.0 ? "G64 P" + fmt(blend * scale, std::max(d, 4)) + " Q0" : "G61");
  }
  if (const std::string w = dialect.work_offset(); !w.empty()) verbatim({w});
  verbatim(g.program.header);
  int current_tool = -1;
  std::string last_words;
  std::string last_feed;
  // The spindle's and the coolant's words left running from the operation before (empty:
  // stopped): an operation that keeps the same tool, speed and coolant goes on without a stop
  // and a restart between them (a machinist's read of a real NX program: 11 pointless M5 / S M3
  // pairs in 12 operations).
  std::string running_spindle, running_coolant;
  for (std::size_t op_index = 0; op_index < operations.size(); ++op_index) {
    const PostedOperation& op = operations[op_index];
    if (op.poses.size() != op.points.size()) {
      throw std::invalid_argument("write_gcode: operation '" + op.name + "' has no pose per point");
    }
    raw(dialect.comment("operation " + op.name));
    // Every operation's first feed block carries its F (a reader of one operation, or a
    // restart at it, must not inherit the last operation's feed).
    last_feed.clear();
    // Safe start: up to the retract height, the tool, the spindle and the coolant, the table
    // turned to the first pose with the tool up, then the tool length and TCP on.
    lines(dialect.retract(retract_z));
    if (op.tool.number > 0 && op.tool.number != current_tool) {
      const auto [change, custom] = dialect.tool_change(op.tool.number);
      if (custom) {
        verbatim(change);
        prog.tool_calls.emplace_back(prog.verbatim_lines.back(), op.tool.number);
        // The machine's own tool-change macro may leave its modes behind: the set-up again.
        line(dialect.setup(g.feed_mode == FeedMode::InverseTime));
      } else {
        lines(change);
      }
      current_tool = op.tool.number;
    }
    const auto spindle_words = [](double rpm, bool clockwise) {
      return "S" + fmt(rpm, 0) + (clockwise ? " M3" : " M4");
    };
    if (op.spindle_rpm > 0.0 &&
        spindle_words(op.spindle_rpm, op.spindle_clockwise) != running_spindle) {
      line(spindle_words(op.spindle_rpm, op.spindle_clockwise));
    }
    // Coolant as the CL file asks (COOLNT), else as the machine file's default.
    const auto coolant_code = [](ClCoolant c) {
      return c == ClCoolant::Flood  ? std::string("M8")
             : c == ClCoolant::Mist ? std::string("M7")
                                    : std::string();
    };
    const auto coolant_of = [&](const PostedOperation& o) {
      return o.coolant ? coolant_code(*o.coolant) : dialect.coolant_on();
    };
    std::string coolant = coolant_of(op);
    if (!coolant.empty() && coolant != running_coolant) line(coolant);
    // The spindle's words in force (empty: stopped), as the coolant's.
    std::string spindle =
        op.spindle_rpm > 0.0 ? spindle_words(op.spindle_rpm, op.spindle_clockwise) : std::string();
    // The file's stops, dwells, spindle and coolant changes before point i.
    std::size_t next_event = 0;
    const auto events_before = [&](std::size_t i) {
      for (; next_event < op.events.size() && op.events[next_event].before_point <= i;
           ++next_event) {
        const ProgramEvent& e = op.events[next_event];
        switch (e.kind) {
          case ProgramEvent::Kind::Stop: line("M0"); break;
          case ProgramEvent::Kind::OptionalStop: line("M1"); break;
          case ProgramEvent::Kind::Dwell:
            if (g.dialect == GcodeDialect::LinuxCNC) {
              line("G4 P" + fmt(e.dwell_s, 3));  // LinuxCNC: P in seconds
            } else if (g.dialect == GcodeDialect::Fanuc) {
              line("G04 P" + std::to_string(std::lround(e.dwell_s * 1000.0)));  // P in ms
            } else {
              throw InputError("CL line " + std::to_string(e.line) +
                               ": DELAY: taxopt writes a dwell for LinuxCNC (G4 P seconds) and "
                               "Fanuc (G04 P milliseconds) only, not for the " +
                               std::string(to_string(g.dialect)) + " dialect");
            }
            break;
          case ProgramEvent::Kind::Spindle:
            if (e.spindle_rpm > 0.0) {
              spindle = spindle_words(e.spindle_rpm, e.spindle_clockwise);
              line(spindle);
            } else {
              spindle.clear();
              line("M5");
            }
            break;
          case ProgramEvent::Kind::Coolant: {
            const std::string c = coolant_code(e.coolant);
            line(c.empty() ? "M9" : c);
            coolant = c;
            break;
          }
        }
      }
    };
    const bool retracts = g.program.retract != SafeRetract::None;
    // The table turned with the tool up (after the retract), to `pose`.
    const auto turn_table = [&](const Posed& pose) {
      if (!retracts) return;
      line(dialect.rapid() + tilt_word + dialect.number(rad_to_deg(pose.a_rad), d) + " C" +
           dialect.number(rad_to_deg(pose.c_rad), d));
    };
    if (!op.points.empty()) turn_table(op.poses.front());
    std::string prefix;
    // The tool length before the TCP switch: LinuxCNC's controller, switched to its TCP
    // kinematics (the sample's M428) with the table tilted and the length then turned on,
    // jumps its joints (Y by 17 mm at 7,227 mm/s, Z past its limit: issue 36, measured on the
    // real motion controller); with G43 first the same programs run to the end.
    // The rotary words where tool centre point control came on (set by the first block after
    // it): a Fanuc 30i raises PS5421 for G2/G3 after A or C has turned under G43.4 (FANUC
    // Series 30i-MODEL A, Tool center point control for 5-axis machining, A-79348E, pp. 22-24:
    // circular interpolation is allowed where neither rotary axis moves after the G43.4
    // command). Haas's G234 is treated alike (its rule is not published here).
    std::string tcp_angles;
    const auto length_and_tcp_on = [&] {
      tcp_angles.clear();
      lines(dialect.length_on(tcp, current_tool));
      verbatim(tcp ? g.program.tcp_on : std::vector<std::string>{});
      lines(dialect.tcp_on(tcp, current_tool));
      prefix = dialect.first_move_prefix(tcp, current_tool);
    };
    const auto length_and_tcp_off = [&] {
      lines(dialect.tcp_off(tcp));
      verbatim(tcp ? g.program.tcp_off : std::vector<std::string>{});
    };
    length_and_tcp_on();
    // From the retract height the tool goes XY first, then down (Haas's and Tormach's
    // pages: no diagonal rapid from the retract): set before the operation's first block and
    // after every index move.
    bool approach = retracts;
    // Under tool centre point control the retract height can lie above the axes' range in the
    // workpiece frame: LinuxCNC's sample (Z to 120, its limit) with the table tilted 19 deg
    // refused the XY move there ("would exceed Z's positive limit", measured on its motion
    // controller, issue 36). So the tool first comes straight down to a clearance height, the
    // operation's highest tip plus approach_clearance_mm, then XY, then down. Not on Fanuc,
    // whose G43.4 comes on with the block down: before it, Z would place the spindle nose.
    // With a part model the clearance height stands above the part too (its highest point in
    // the workpiece, PostedOperation::part_top_z_mm), not only above the operation's tips: an
    // operation low on a tall part came down inside it (a Haas part's approach at Z1.5987 in,
    // its top at Z3.0).
    double clearance_z_mm = op.part_top_z_mm.value_or(-std::numeric_limits<double>::infinity());
    for (const CLPointd& q : op.points) clearance_z_mm = std::max(clearance_z_mm, q.tip_mm.z());
    clearance_z_mm += g.program.approach_clearance_mm;
    const bool descend = tcp && !dialect.length_on_first_move();
    std::vector<int> emitted(op.points.size(), 0);
    const std::vector<double> own_times = programmed_block_times_s(op.points, op.poses);
    last_words.clear();
    Vec3d prev_xyz = Vec3d::Zero();
    Posed prev_pose;
    Vec3d prev_tip = Vec3d::Zero();
    bool have_prev = false;
    // The last block written is a feed block (G1 of a feed move, not a joint-safe rapid), and
    // a joint-safe rapid: LinuxCNC blends two feed blocks, and the blend leaves the programmed
    // A and C (0.12 deg measured at the end of a pass), so a dwell G4 P0 (the controller runs
    // its queue to a stop) stands between such a rapid and a feed block.
    bool last_feed_block = false, last_joint_safe = false;
    // The block written next is an approach's last leg, along the tool axis.
    bool along_axis_leg = false;
    const auto out_xyz = [&](const Vec3d& tip, const Posed& pose) {
      return written_xyz_mm(machine, tip, pose);
    };
    const auto angle_words = [&](const Posed& pose) {
      return tilt_word + dialect.number(rad_to_deg(pose.a_rad), d) + " C" +
             dialect.number(rad_to_deg(pose.c_rad), d);
    };
    const auto xyz_words = [&](const Vec3d& xyz) {
      return "X" + dialect.number(xyz.x() * scale, d) + " Y" + dialect.number(xyz.y() * scale, d) +
             " Z" + dialect.number(xyz.z() * scale, d);
    };
    // Writes the arc `run` as G2/G3 blocks when it can be (PostedOperation::arcs); false: it
    // is left to its chords.
    const auto write_arc = [&](const ArcRun& run) {
      if (g.feed_mode != FeedMode::UnitsPerMinute || g.dialect == GcodeDialect::Heidenhain ||
          !have_prev || run.end >= op.points.size() || run.end <= run.start + 1) {
        return false;
      }
      const std::string pose_words = angle_words(op.poses[run.start]);
      if (tcp && (g.dialect == GcodeDialect::Fanuc || g.dialect == GcodeDialect::Haas) &&
          pose_words != tcp_angles) {
        return false;  // the table turned under TCP since it came on: chords
      }
      double programmed_s = 0.0;
      bool own = true;
      for (std::size_t j = run.start + 1; j <= run.end; ++j) {
        const CLPointd& q = op.points[j];
        if (q.motion != Motion::Feed || !(q.feed_mm_per_min > 0.0) ||
            angle_words(op.poses[j]) != pose_words ||
            (j < op.block_time_s.size() && op.block_time_s[j] > 0.0) ||
            q.feed_mm_per_min != op.points[run.end].feed_mm_per_min) {
          return false;
        }
        const double given_s = j < op.programmed_time_s.size() ? op.programmed_time_s[j] : 0.0;
        own = own && (given_s <= 0.0 || std::abs(given_s - own_times[j]) <= 1e-9 * own_times[j]);
        programmed_s += given_s > 0.0 ? given_s : own_times[j];
      }
      if (xyz_words(out_xyz(op.points[run.start].tip_mm, op.poses[run.start])) + pose_words !=
          last_words) {
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
          own ? op.points[run.end].feed_mm_per_min : length_mm / (programmed_s / 60.0);
      const std::string f = fmt(feed * scale, fd);
      const int pieces = std::max(1, static_cast<int>(std::ceil(run.sweep_rad / M_PI - 1e-9)));
      const char* plane = axis == 2 ? "G17" : axis == 1 ? "G18" : "G19";
      const char* sense = n[axis] > 0.0 ? "G3" : "G2";
      std::vector<int> piece_line(static_cast<std::size_t>(pieces));
      Vec3d from = rounded(out_xyz(op.points[run.start].tip_mm, pose) * scale) / scale;
      const Vec3d dir = u0 / r0, side = n.cross(dir);
      for (int k = 1; k <= pieces; ++k) {
        const double frac = static_cast<double>(k) / pieces, th = run.sweep_rad * frac;
        const Vec3d to = k == pieces ? e_out
                                     : c + (hs + (he - hs) * frac) * n +
                                           r0 * (std::cos(th) * dir + std::sin(th) * side);
        const Vec3d offset = (c - from) * scale;
        std::string block = std::string(plane) + " " + sense + " " + xyz_words(to);
        for (int q = 0; q < 3; ++q) {
          if (q != axis)
            block += std::string(" ") + static_cast<char>('I' + q) + dialect.number(offset[q], d);
        }
        if (f != last_feed) block += " F" + f;
        last_feed = f;
        piece_line[static_cast<std::size_t>(k - 1)] = line(block);
        ++prog.arc_blocks;
        from = rounded(to * scale) / scale;
      }
      for (std::size_t j = run.start + 1; j < run.end; ++j) {
        const double frac =
            static_cast<double>(j - run.start) / static_cast<double>(run.end - run.start);
        const auto piece = std::min<std::size_t>(static_cast<std::size_t>(frac * pieces),
                                                 static_cast<std::size_t>(pieces - 1));
        emitted[j] = -piece_line[piece];
      }
      emitted[run.end] = piece_line.back();
      last_words = xyz_words(e_out) + pose_words;
      prev_xyz = e_out;
      prev_pose = op.poses[run.end];
      prev_tip = op.points[run.end].tip_mm;
      return true;
    };
    std::size_t arc_cursor = 0;
    // An arc with an event inside it is left to its chords, so that the event stands where
    // the file put it.
    const auto event_inside = [&](const ArcRun& run) {
      for (const ProgramEvent& e : op.events) {
        if (e.before_point > run.start + 1 && e.before_point <= run.end) return true;
      }
      return false;
    };
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      events_before(i);
      while (arc_cursor < op.arcs.size() && op.arcs[arc_cursor].start + 1 < i) ++arc_cursor;
      if (arc_cursor < op.arcs.size() && op.arcs[arc_cursor].start + 1 == i) {
        if (!event_inside(op.arcs[arc_cursor]) && write_arc(op.arcs[arc_cursor])) {
          ++prog.arcs_kept;
          last_feed_block = true;
          last_joint_safe = false;
          i = op.arcs[arc_cursor].end;
          continue;
        }
        ++prog.arcs_chorded;
      }
      const CLPointd& p = op.points[i];
      const Posed& pose = op.poses[i];
      const Vec3d xyz = out_xyz(p.tip_mm, pose);
      const std::string words = xyz_words(xyz) + angle_words(pose);
      if (words == last_words) continue;  // nothing would move
      along_axis_leg = false;
      // An index move: a rapid that turns the table by more than the threshold goes up to the
      // retract, turns there and comes down XY first (docs/gcode-dialects.md "Index moves").
      // With a part model the turns stay in the air: the check verifies their swept moves.
      if (p.motion == Motion::Rapid && have_prev && retracts && !op.swept_moves_checked) {
        const double turn_deg = std::max(std::abs(round_to(rad_to_deg(pose.a_rad), d) -
                                                  round_to(rad_to_deg(prev_pose.a_rad), d)),
                                         std::abs(round_to(rad_to_deg(pose.c_rad), d) -
                                                  round_to(rad_to_deg(prev_pose.c_rad), d)));
        if (turn_deg > g.program.index_threshold_deg) {
          length_and_tcp_off();
          lines(dialect.retract(retract_z));
          turn_table(pose);
          length_and_tcp_on();
          approach = true;
          ++prog.index_moves;
        }
      }
      if (approach) {
        if (descend) {
          line(prefix + dialect.rapid() + " Z" + dialect.number(clearance_z_mm * scale, d));
          prefix.clear();
        }
        // Under TCP the last leg comes down along the tool axis, as CAM links an approach:
        // XY to above the point on its axis, then along it (a tool tilted 90 deg that came
        // straight down in the workpiece's Z swept through a wall, issue 45). In machine mode
        // the machine's Z is the tool axis already.
        // Not on Fanuc, whose TCP comes on with the block down from the retract height (left as
        // it was: straight down to the point).
        const Vec3d above_tip =
            approach_tip_mm(p.tip_mm, p.axis, clearance_z_mm, g.program.approach_clearance_mm);
        const Vec3d above = descend ? out_xyz(above_tip, pose) : xyz;
        std::string xy = dialect.rapid() + " X" + dialect.number(above.x() * scale, d) + " Y" +
                         dialect.number(above.y() * scale, d);
        if (dialect.length_on_first_move()) {
          line(xy);  // Fanuc: its length and TCP come on with the Z block below
        } else {
          line(prefix + xy);
          prefix.clear();
        }
        if (descend && std::abs(above.z() - clearance_z_mm) * scale > 0.5 * std::pow(10.0, -d)) {
          // A tool within 30 deg of the horizontal: straight down to the safe distance on its
          // axis, then along it.
          line(dialect.rapid() + " Z" + dialect.number(above.z() * scale, d));
        }
        approach = false;
        // The tool comes from the retract: no move to schedule or split; under TCP a rapid to
        // the point comes from `above` along the axis (at a joint-safe feed on LinuxCNC).
        have_prev = descend && p.motion == Motion::Rapid;
        along_axis_leg = have_prev;
        if (have_prev) {
          prev_tip = above_tip;
          prev_pose = pose;
          prev_xyz = above;
        }
      }
      std::string block;
      bool restore_inverse_time = false;
      if (p.motion == Motion::Rapid) {
        if (g.mode == GcodeMode::Machine && have_prev) {
          // Rapids too: a table that turns while the tool traverses above the part would
          // swing the tip through it (the controller must run G0 linearly in the joints, as
          // LinuxCNC does; Fanuc: non-linear positioning off).
          const std::vector<double> at = linearise_fractions(
              machine.ac, prev_tip, prev_pose, p.tip_mm, pose, g.program.linearise_tolerance_mm);
          for (std::size_t j = 1; j + 1 < at.size(); ++j) {
            const Posed mid{prev_pose.a_rad + at[j] * (pose.a_rad - prev_pose.a_rad),
                            prev_pose.c_rad + at[j] * (pose.c_rad - prev_pose.c_rad)};
            const Vec3d mid_xyz = out_xyz(prev_tip + at[j] * (p.tip_mm - prev_tip), mid);
            line(prefix + dialect.rapid() + " " + xyz_words(mid_xyz) + angle_words(mid));
            prefix.clear();
            ++prog.linearised_blocks;
          }
        }
        block = dialect.rapid() + " " + words;
        if (joint_safe && have_prev) {
          const std::optional<double> rate = joint_safe_rate_per_s(
              machine.ac, limits, prev_tip, prev_pose, p.tip_mm, pose, along_axis_leg);
          if (rate) {
            // A feed block at the rate that keeps the joints within their limits: F is the
            // tip's distance (the rotary one when only A and C turn) per minute, or under G93
            // the block's inverse time.
            const double tip_mm = (p.tip_mm - prev_tip).norm();
            const double rot_deg = std::hypot(rad_to_deg(pose.a_rad - prev_pose.a_rad),
                                              rad_to_deg(pose.c_rad - prev_pose.c_rad));
            const double per_min = 60.0 * *rate;
            const double feed = g.feed_mode == FeedMode::InverseTime
                                    ? per_min
                                    : (tip_mm > 1e-9 ? tip_mm * scale : rot_deg) * per_min;
            // Eight significant digits, rounded down: slower, never faster.
            const int digits = std::clamp(
                7 - static_cast<int>(std::floor(std::log10(std::max(feed, 1e-300)))), fd, max_fd);
            const double unit = std::pow(10.0, digits);
            const std::string f = fmt(std::max(std::floor(feed * unit), 1.0) / unit, digits);
            block = dialect.linear() + " " + words;
            if (g.feed_mode == FeedMode::InverseTime || f != last_feed) block += " F" + f;
            last_feed = f;
            if (last_feed_block) line("G4 P0");
            emitted[i] = line(prefix + block);
            last_feed_block = false;
            last_joint_safe = true;
            prog.joint_safe_rapids.push_back(emitted[i]);
            prefix.clear();
            last_words = words;
            prev_xyz = xyz;
            prev_pose = pose;
            prev_tip = p.tip_mm;
            continue;
          }
        }
      } else {
        if (!(p.feed_mm_per_min > 0.0)) {
          throw std::invalid_argument("write_gcode: feed move without a feed");
        }
        const double tip_mm = have_prev ? (p.tip_mm - prev_tip).norm() : 0.0;
        const double rot_deg = have_prev ? std::hypot(rad_to_deg(pose.a_rad - prev_pose.a_rad),
                                                      rad_to_deg(pose.c_rad - prev_pose.c_rad))
                                         : 0.0;
        const double given_s = i < op.programmed_time_s.size() ? op.programmed_time_s[i] : 0.0;
        const double programmed_min = (given_s > 0.0 ? given_s : own_times[i]) / 60.0;
        // A scheduled block (never faster than programmed) writes its F with 8 significant
        // digits, so that rounding cannot carry it over the limits it was scheduled for; where
        // the controller takes fewer decimals, F is rounded down (slower, never faster).
        const bool scheduled = i < op.block_time_s.size() && op.block_time_s[i] > 0.0 && have_prev;
        const double time_min =
            scheduled ? std::max(programmed_min, op.block_time_s[i] / 60.0) : programmed_min;
        const auto fmt_feed = [&](double f) {
          if (!scheduled) return fmt(f, fd);
          const int digits =
              std::clamp(7 - static_cast<int>(std::floor(std::log10(std::max(f, 1e-300)))), fd, 15);
          if (digits <= max_fd) return fmt(f, digits);
          const double unit = std::pow(10.0, max_fd);
          return fmt(std::max(std::floor(f * unit), 1.0) / unit, max_fd);
        };
        // F of a joint-space block (machine mode, inverse time, a schedule) from `from` to
        // `to` that takes `minutes`.
        const auto joint_feed = [&](const Vec3d& from, const Posed& from_pose, const Vec3d& to,
                                    const Posed& to_pose, double minutes) {
          if (g.feed_mode == FeedMode::InverseTime) return fmt_feed(1.0 / minutes);
          if (scheduled) {
            // The controller times the block from the written (rounded) words: so does F.
            const double len = (rounded(to * scale) - rounded(from * scale)).norm();
            const double rot = std::hypot(
                round_to(rad_to_deg(to_pose.a_rad), d) - round_to(rad_to_deg(from_pose.a_rad), d),
                round_to(rad_to_deg(to_pose.c_rad), d) - round_to(rad_to_deg(from_pose.c_rad), d));
            return fmt_feed((len > 0.0 ? len : rot) / minutes);
          }
          // Joint-space XYZ moves differ from the tip's: F makes the block take the time
          // of the tip at the programmed feed.
          const double joint = (to - from).norm();
          const double rot = std::hypot(rad_to_deg(to_pose.a_rad - from_pose.a_rad),
                                        rad_to_deg(to_pose.c_rad - from_pose.c_rad));
          return fmt(joint > 1e-9 ? joint * scale / minutes : rot / minutes, fd);
        };
        std::string f;
        if (!have_prev) {
          // First block of an operation at feed: where the tool comes from is unknown, so
          // the move is written at the programmed feed in G94 (G93 needs a block time).
          f = fmt(p.feed_mm_per_min * scale, fd);
          restore_inverse_time = g.feed_mode == FeedMode::InverseTime;
        } else if (g.mode == GcodeMode::Machine) {
          // Linearisation: where the joints moving linearly would take the tip off the
          // straight line by more than the tolerance, blocks in between keep it on.
          const std::vector<double> at = linearise_fractions(
              machine.ac, prev_tip, prev_pose, p.tip_mm, pose, g.program.linearise_tolerance_mm);
          Vec3d from = prev_xyz;
          Posed from_pose = prev_pose;
          for (std::size_t j = 1; j < at.size(); ++j) {
            const Posed mid{prev_pose.a_rad + at[j] * (pose.a_rad - prev_pose.a_rad),
                            prev_pose.c_rad + at[j] * (pose.c_rad - prev_pose.c_rad)};
            const Vec3d mid_xyz = out_xyz(prev_tip + at[j] * (p.tip_mm - prev_tip), mid);
            double minutes = time_min * (at[j] - at[j - 1]);
            if (scheduled && i < op.linearised_time_s.size() &&
                op.linearised_time_s[i].size() + 1 == at.size()) {
              // Block by block as scheduled, never faster than programmed.
              minutes = std::max(programmed_min * (at[j] - at[j - 1]),
                                 op.linearised_time_s[i][j - 1] / 60.0);
            }
            if (j + 1 == at.size()) {
              f = joint_feed(from, from_pose, xyz, pose, minutes);
              break;
            }
            const std::string piece = joint_feed(from, from_pose, mid_xyz, mid, minutes);
            std::string mid_block = dialect.linear() + " " + xyz_words(mid_xyz) + angle_words(mid);
            if (g.feed_mode == FeedMode::InverseTime || piece != last_feed) {
              mid_block += " F" + piece;
            }
            last_feed = piece;
            line(prefix + mid_block);
            prefix.clear();
            ++prog.linearised_blocks;
            from = mid_xyz;
            from_pose = mid;
          }
        } else if (g.feed_mode == FeedMode::InverseTime || scheduled) {
          f = joint_feed(prev_xyz, prev_pose, xyz, pose, time_min);
        } else {
          // TCP: the tip moves at F. Its distance over the block time is the programmed feed
          // unless the programmed time is another path's (FeedReference::CutterPath).
          const double tip_feed =
              tip_mm > 1e-9 ? tip_mm / programmed_min : rot_deg / programmed_min;
          const bool own = std::abs(tip_feed - p.feed_mm_per_min) <= 1e-9 * p.feed_mm_per_min;
          f = fmt((own ? p.feed_mm_per_min : tip_feed) * scale, fd);
        }
        block = std::string(restore_inverse_time ? "G94 " : "") + dialect.linear() + " " + words;
        if (g.feed_mode == FeedMode::InverseTime || f != last_feed) block += " F" + f;
        last_feed = restore_inverse_time ? std::string() : f;
      }
      if (last_joint_safe && p.motion != Motion::Rapid) line("G4 P0");
      emitted[i] = line(prefix + block);
      last_feed_block = p.motion != Motion::Rapid;
      last_joint_safe = false;
      prefix.clear();
      if (tcp_angles.empty()) tcp_angles = angle_words(pose);
      if (restore_inverse_time) line("G93");
      last_words = words;
      prev_xyz = xyz;
      prev_pose = pose;
      prev_tip = p.tip_mm;
      have_prev = true;
    }
    events_before(op.points.size());
    prog.emitted.push_back(std::move(emitted));
    length_and_tcp_off();
    // Left running into the next operation where it starts with the same tool, spindle and
    // coolant (before its first point: its events may change them after that).
    const PostedOperation* next =
        op_index + 1 < operations.size() ? &operations[op_index + 1] : nullptr;
    const bool same_tool = next && (next->tool.number <= 0 || next->tool.number == current_tool);
    const bool keep_spindle = same_tool && !spindle.empty() && next->spindle_rpm > 0.0 &&
                              spindle_words(next->spindle_rpm, next->spindle_clockwise) == spindle;
    const bool keep_coolant = same_tool && !coolant.empty() && coolant_of(*next) == coolant;
    if (!coolant.empty() && !keep_coolant) line("M9");
    if (!spindle.empty() && !keep_spindle) line("M5");
    running_spindle = keep_spindle ? spindle : std::string();
    running_coolant = keep_coolant ? coolant : std::string();
    last_words.clear();
  }
  lines(dialect.retract(retract_z));
  // The rotary axes home (a continuous C within one turn of it), with the tool up.
  if (g.program.end_pose == EndPose::Home && g.program.retract != SafeRetract::None &&
      !operations.empty()) {
    line(dialect.rapid() + tilt_word + dialect.number(0.0, d) + " C" + dialect.number(0.0, d));
  }
  if (g.program.end_park_xy_mm && g.program.retract != SafeRetract::None && !operations.empty()) {
    const auto& xy = *g.program.end_park_xy_mm;
    lines(dialect.park(dialect.number(xy[0] * scale, d), dialect.number(xy[1] * scale, d)));
  }
  verbatim(g.program.footer);
  line(dialect.end());
  for (const auto& s : dialect.finish()) raw(s);
  return prog;
}

}  // namespace taxopt
