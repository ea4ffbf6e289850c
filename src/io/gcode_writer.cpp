#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

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
  Dialect(GcodeDialect d, LengthUnit units) : d_(d), inch_(units == LengthUnit::Inch) {}

  /// A block as written: Heidenhain ISO numbers blocks and ends them with " *".
  std::string block(const std::string& words) {
    if (d_ != GcodeDialect::Heidenhain) return words;
    block_no_ += 10;
    return "N" + std::to_string(block_no_) + " " + words + " *";
  }
  std::string comment(const std::string& text) {
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Fanuc: return "(" + comment_text(text) + ")";
      case GcodeDialect::Siemens: return "; " + comment_text(text);
      case GcodeDialect::Heidenhain: return block("; " + comment_text(text));
    }
    return {};
  }
  /// Lines before the comments: the program start.
  std::vector<std::string> start() const {
    switch (d_) {
      case GcodeDialect::Fanuc: return {"%", "O1000 (TAXOPT)"};
      case GcodeDialect::Heidenhain:
        return {std::string("%TAXOPT ") + (inch_ ? "G70" : "G71") + " *"};
      default: return {};
    }
  }
  /// The modal set-up block (units, absolute, plane, feed mode).
  std::string setup(bool inverse_time) const {
    const std::string feed = inverse_time ? "G93" : "G94";
    switch (d_) {
      case GcodeDialect::LinuxCNC:
      case GcodeDialect::Fanuc:
        return std::string(inch_ ? "G20" : "G21") + " G90 G17 G40 G49 G80 " + feed;
      case GcodeDialect::Siemens:  // G700/G710: feeds in the program's units too
        return std::string(inch_ ? "G700" : "G710") + " G90 G17 G40 " + feed;
      case GcodeDialect::Heidenhain: return "G17 G90 G40";  // units in the first block
    }
    return {};
  }
  std::vector<std::string> tool_change(int tool) const {
    const std::string t = "T" + std::to_string(tool);
    switch (d_) {
      case GcodeDialect::Siemens: return {t + " D1 M6"};
      case GcodeDialect::Heidenhain: return {t + " G17"};
      default: return {t + " M6"};
    }
  }
  /// Tool centre point control on (tcp mode): blocks before an operation's first move.
  std::vector<std::string> tcp_on(bool tcp) const {
    if (!tcp) return {};
    switch (d_) {
      case GcodeDialect::Siemens: return {"TRAORI", "ORIAXES"};  // rotary axes linear
      case GcodeDialect::Heidenhain: return {"M128"};
      default: return {};
    }
  }
  /// Fanuc starts tool centre point control (G43.4, or plain tool length compensation G43 in
  /// machine mode) on the operation's first motion block, with the tool's offset number.
  std::string first_move_prefix(bool tcp, int tool) const {
    if (d_ != GcodeDialect::Fanuc) return {};
    return std::string(tcp ? "G43.4" : "G43") + " H" + std::to_string(std::max(tool, 1)) + " ";
  }
  std::vector<std::string> tcp_off(bool tcp) const {
    switch (d_) {
      case GcodeDialect::Fanuc: return {"G49"};
      case GcodeDialect::Siemens:
        return tcp ? std::vector<std::string>{"TRAFOOF"} : std::vector<std::string>{};
      case GcodeDialect::Heidenhain:
        return tcp ? std::vector<std::string>{"M129"} : std::vector<std::string>{};
      default: return {};
    }
  }
  std::string rapid() const { return d_ == GcodeDialect::Heidenhain ? "G00" : "G0"; }
  std::string linear() const { return d_ == GcodeDialect::Heidenhain ? "G01" : "G1"; }
  std::string end() const { return d_ == GcodeDialect::LinuxCNC ? "M2" : "M30"; }
  std::vector<std::string> finish() const {
    switch (d_) {
      case GcodeDialect::Fanuc: return {"%"};
      case GcodeDialect::Heidenhain:
        return {std::string("N99999999 %TAXOPT ") + (inch_ ? "G70" : "G71") + " *"};
      default: return {};
    }
  }
  /// Fanuc reads a number without a decimal point in least input increments: "10" is
  /// 0.010 mm. Every coordinate gets its point.
  std::string number(double v, int decimals) const {
    std::string s = fmt(v, decimals);
    if (d_ == GcodeDialect::Fanuc && s.find('.') == std::string::npos) s += '.';
    return s;
  }

 private:
  GcodeDialect d_;
  bool inch_;
  int block_no_ = 0;
};

}  // namespace

std::vector<double> programmed_block_times_s(const std::vector<CLPointd>& points,
                                             const std::vector<Posed>& poses) {
  if (poses.size() != points.size()) {
    throw std::invalid_argument("programmed_block_times_s: one pose per point is needed");
  }
  std::vector<double> t(points.size(), 0.0);
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].motion != Motion::Feed || !(points[i].feed_mm_per_min > 0.0)) continue;
    const double tip_mm = (points[i].tip_mm - points[i - 1].tip_mm).norm();
    const double rot_deg = std::hypot(rad_to_deg(poses[i].a_rad - poses[i - 1].a_rad),
                                      rad_to_deg(poses[i].c_rad - poses[i - 1].c_rad));
    // A move too small to time still gets a positive time: its words may differ after
    // rounding, and a feed schedule needs a bound for every move.
    t[i] = 60.0 * (tip_mm > 1e-9 ? tip_mm : std::max(rot_deg, 1e-9)) / points[i].feed_mm_per_min;
  }
  return t;
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
  Dialect dialect(g.dialect, units);
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
  const bool tcp = g.mode == GcodeMode::Tcp;
  for (const auto& s : dialect.start()) raw(s);
  for (const auto& c : comments) raw(dialect.comment(c));
  line(dialect.setup(g.feed_mode == FeedMode::InverseTime));
  int current_tool = -1;
  std::string last_words;
  std::string last_feed;
  for (const auto& op : operations) {
    if (op.poses.size() != op.points.size()) {
      throw std::invalid_argument("write_gcode: operation '" + op.name + "' has no pose per point");
    }
    raw(dialect.comment("operation " + op.name));
    if (op.tool.number > 0 && op.tool.number != current_tool) {
      lines(dialect.tool_change(op.tool.number));
      current_tool = op.tool.number;
    }
    if (op.spindle_rpm > 0.0) {
      line("S" + fmt(op.spindle_rpm, 0) + (op.spindle_clockwise ? " M3" : " M4"));
    }
    lines(dialect.tcp_on(tcp));
    std::string prefix = dialect.first_move_prefix(tcp, current_tool);
    std::vector<int> emitted(op.points.size(), 0);
    const std::vector<double> own_times = programmed_block_times_s(op.points, op.poses);
    last_words.clear();
    Vec3d prev_xyz = Vec3d::Zero();
    Posed prev_pose;
    Vec3d prev_tip = Vec3d::Zero();
    bool have_prev = false;
    const auto out_xyz = [&](const Vec3d& tip, const Posed& pose) {
      return g.mode == GcodeMode::Machine ? machine.ac.to_machine_mm(tip, pose) : tip;
    };
    const auto angle_words = [&](const Posed& pose) {
      return " A" + dialect.number(rad_to_deg(pose.a_rad), d) + " C" +
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
      const std::string f = fmt(feed * scale, std::max(d, 3));
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
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      while (arc_cursor < op.arcs.size() && op.arcs[arc_cursor].start + 1 < i) ++arc_cursor;
      if (arc_cursor < op.arcs.size() && op.arcs[arc_cursor].start + 1 == i) {
        if (write_arc(op.arcs[arc_cursor])) {
          ++prog.arcs_kept;
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
      std::string block;
      bool restore_inverse_time = false;
      if (p.motion == Motion::Rapid) {
        block = dialect.rapid() + " " + words;
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
        // digits, so that rounding cannot carry it over the limits it was scheduled for.
        const bool scheduled = i < op.block_time_s.size() && op.block_time_s[i] > 0.0 && have_prev;
        const double time_min =
            scheduled ? std::max(programmed_min, op.block_time_s[i] / 60.0) : programmed_min;
        const auto fmt_feed = [&](double f) {
          if (!scheduled) return fmt(f, std::max(d, 3));
          const int digits = 7 - static_cast<int>(std::floor(std::log10(std::max(f, 1e-300))));
          return fmt(f, std::clamp(digits, std::max(d, 3), 15));
        };
        std::string f;
        if (!have_prev) {
          // First block of an operation at feed: where the tool comes from is unknown, so
          // the move is written at the programmed feed in G94 (G93 needs a block time).
          f = fmt(p.feed_mm_per_min * scale, std::max(d, 3));
          restore_inverse_time = g.feed_mode == FeedMode::InverseTime;
        } else if (g.feed_mode == FeedMode::InverseTime) {
          f = fmt_feed(1.0 / time_min);
        } else if (scheduled) {
          // The controller times the block from the written (rounded) words: so does F.
          const Vec3d written = rounded(xyz * scale), before = rounded(prev_xyz * scale);
          const double len = (written - before).norm();
          const double rot = std::hypot(
              round_to(rad_to_deg(pose.a_rad), d) - round_to(rad_to_deg(prev_pose.a_rad), d),
              round_to(rad_to_deg(pose.c_rad), d) - round_to(rad_to_deg(prev_pose.c_rad), d));
          f = fmt_feed((len > 0.0 ? len : rot) / time_min);
        } else if (g.mode == GcodeMode::Machine) {
          // Joint-space XYZ moves differ from the tip's: scale F so the block takes the
          // same time as the tip at the programmed feed.
          const double joint = (xyz - prev_xyz).norm();
          f = fmt(joint > 1e-9 ? joint * scale / time_min : rot_deg / time_min, std::max(d, 3));
        } else {
          // TCP: the tip moves at F. Its distance over the block time is the programmed feed
          // unless the programmed time is another path's (FeedReference::CutterPath).
          const double tip_feed =
              tip_mm > 1e-9 ? tip_mm / programmed_min : rot_deg / programmed_min;
          const bool own = std::abs(tip_feed - p.feed_mm_per_min) <= 1e-9 * p.feed_mm_per_min;
          f = fmt((own ? p.feed_mm_per_min : tip_feed) * scale, std::max(d, 3));
        }
        block = std::string(restore_inverse_time ? "G94 " : "") + dialect.linear() + " " + words;
        if (g.feed_mode == FeedMode::InverseTime || f != last_feed) block += " F" + f;
        last_feed = restore_inverse_time ? std::string() : f;
      }
      emitted[i] = line(prefix + block);
      prefix.clear();
      if (restore_inverse_time) line("G93");
      last_words = words;
      prev_xyz = xyz;
      prev_pose = pose;
      prev_tip = p.tip_mm;
      have_prev = true;
    }
    prog.emitted.push_back(std::move(emitted));
    lines(dialect.tcp_off(tcp));
    if (op.spindle_rpm > 0.0) line("M5");
  }
  line(dialect.end());
  for (const auto& s : dialect.finish()) raw(s);
  return prog;
}

}  // namespace taxopt
