#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

#include "controller/feed_word.hpp"
#include "dialects/dialect_rules.hpp"
#include "gcode/program_writer.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"
#include "util/progress.hpp"

namespace taxopt {

namespace {

unsigned given_mask(const bool (&given)[5]) {
  unsigned mask = 0;
  for (int q = 0; q < 5; ++q) {
    if (given[q]) mask |= 1u << q;
  }
  return mask;
}

}  // namespace

namespace {

/// What one block says besides its axis words.
struct BlockWords {
  bool has_axis = false;
  bool given[5] = {false, false, false, false, false};
  bool reference_return = false, machine_coordinates = false;
  bool dwell = false, spindle_start = false, change_tool = false, blending = false;
  Vec3d offset = Vec3d::Zero();
  bool has_offset[3] = {false, false, false};
};

/// Reads a program block by block in the subset taxopt writes (read_gcode_moves), keeping the
/// modal state and the machine's (tool, spindle, coolant, length offset, TCP).
class GcodeReader {
 public:
  GcodeReader(const std::string& source, GcodeDialect dialect, char tilt_letter)
      : source_(source),
        dialect_(gcode::rules_of(dialect)),
        knows_(dialect_.read_words()),
        tilt_letter_(tilt_letter),
        length_offset_(knows_.length_from_start),
        tcp_(knows_.tcp_from_start) {}

  std::vector<GcodeMove> read(const std::string& text, const std::vector<int>& verbatim_lines,
                              const std::vector<std::pair<int, int>>& tool_calls,
                              const StopSource* stop) {
    std::size_t next_verbatim = 0;
    std::size_t pos = 0;
    // At most a move a line: reserved, not grown by doubling.
    moves_.reserve(static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1);
    while (pos <= text.size()) {
      detail::look_at_stop(stop, static_cast<std::size_t>(line_no_), detail::kPointStride);
      std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) end = text.size();
      std::string ln = text.substr(pos, end - pos);
      pos = end + 1;
      ++line_no_;
      while (next_verbatim < verbatim_lines.size() && verbatim_lines[next_verbatim] < line_no_) {
        ++next_verbatim;
      }
      if (next_verbatim < verbatim_lines.size() && verbatim_lines[next_verbatim] == line_no_) {
        for (const auto& [at, t] : tool_calls) {
          if (at == line_no_) tool_ = t;
        }
      } else {
        block(ln);
      }
      if (end == text.size()) break;
    }
    return std::move(moves_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(source_, line_no_, what);
  }

  void block(std::string ln) {
    BlockWords b;
    if (!dialect_words(ln, b)) return;
    const std::string code = code_of(ln);
    if (code.empty() || code == "%") return;
    const Vec3d start = xyz_;
    std::size_t i = 0;
    while (i < code.size()) {
      const char letter = code[i++];
      if (!std::isalpha(static_cast<unsigned char>(letter))) {
        fail(std::string("expected a word letter, got '") + letter + "'");
      }
      std::size_t j = i;
      while (j < code.size() && (std::isdigit(static_cast<unsigned char>(code[j])) ||
                                 code[j] == '.' || code[j] == '-' || code[j] == '+')) {
        ++j;
      }
      double v = 0.0;
      const char* first = code.data() + i + (i < code.size() && code[i] == '+' ? 1 : 0);
      auto [ptr, ec] = std::from_chars(first, code.data() + j, v);
      if (j == i || ec != std::errc() || ptr != code.data() + j || !std::isfinite(v)) {
        fail(std::string("bad number after '") + letter + "'");
      }
      i = j;
      word(letter, v, b);
    }
    if (b.spindle_start) spindle_on_ = spindle_rpm_ > 0.0;
    if (b.change_tool) tool_ = selected_;
    if (b.dwell && b.has_axis) fail("G4 with an axis word");
    if (b.has_axis && (b.machine_coordinates || incremental_)) {
      machine_move(b, start);
    } else if (b.has_axis) {
      workpiece_move(b, start);
    }
  }

  /// The dialect's own words and marks taken out of `ln` (DialectRules::own_words); false:
  /// nothing more to read in the line.
  bool dialect_words(std::string& ln, BlockWords& b) {
    const gcode::LineMarks marks = dialect_.own_words(ln);
    if (marks.mm_per_unit) scale_ = *marks.mm_per_unit;
    if (marks.tcp) tcp_ = *marks.tcp;
    if (marks.machine_coordinates) b.machine_coordinates = true;
    return !marks.nothing_more;
  }

  /// The line without comments and blanks, upper case.
  std::string code_of(const std::string& ln) const {
    std::string code;
    int depth = 0;
    for (char ch : ln) {
      if (ch == ';' && depth == 0) break;
      if (ch == '(') {
        ++depth;
      } else if (ch == ')') {
        if (depth == 0) fail("')' without '('");
        --depth;
      } else if (depth == 0 && !std::isspace(static_cast<unsigned char>(ch))) {
        code += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      }
    }
    if (depth != 0) fail("unclosed comment");
    return code;
  }

  void word(char letter, double v, BlockWords& b) {
    switch (letter) {
      case 'G': g_word(v, b); break;
      case 'X':
      case 'Y':
      case 'Z':
        xyz_[letter - 'X'] = v * scale_;
        b.has_axis = b.given[letter - 'X'] = true;
        break;
      case 'A':
      case 'B':
        if (letter != tilt_letter_) {
          fail(std::string("word '") + letter + "' is not an axis of this machine (" +
               tilt_letter_ + " and C turn its table)");
        }
        a_ = v;
        b.has_axis = b.given[3] = true;
        break;
      case 'C':
        c_ = v;
        b.has_axis = b.given[4] = true;
        break;
      case 'F': feed_ = v; break;
      case 'I':
      case 'J':
      case 'K':
        if (!knows_.g2_g3_arcs)
          fail(std::string("word '") + letter + "' is outside taxopt's subset");
        b.offset[letter - 'I'] = v * scale_;
        b.has_offset[letter - 'I'] = true;
        break;
      case 'M': m_word(v, b); break;
      default: other_word(letter, v, b);
    }
  }

  void g_word(double v, BlockWords& b) {
    const int gv = static_cast<int>(std::lround(v * 10));
    if (gv == 0) {
      motion_ = 0;
    } else if (gv == 10) {
      motion_ = 1;
    } else if ((gv == 20 || gv == 30) && knows_.g2_g3_arcs) {
      motion_ = gv / 10;
    } else if (gv == 170 || gv == 180 || gv == 190) {
      plane_ = gv == 170 ? 2 : gv == 180 ? 1 : 0;
    } else if (knows_.g20_g21_units && (gv == 200 || gv == 210)) {
      scale_ = gv == 200 ? kMmPerInch : 1.0;
    } else if (knows_.g700_g710_units && (gv == 7000 || gv == 7100)) {
      scale_ = gv == 7000 ? kMmPerInch : 1.0;
    } else if (gv == 930 || gv == 940) {
      inverse_time_ = gv == 930;
    } else if (gv == 900) {
      incremental_ = false;
    } else if (gv == 40 && knows_.g4_dwell) {
      b.dwell = true;  // the CL file's DELAY: P is its time
    } else if (gv == 400 || gv == 800 || gv == 540) {
    } else if (knows_.path_control && (gv == 640 || gv == 610)) {
      b.blending = true;  // path control: G64 P Q, G61
    } else if (!tool_length_word(gv, b)) {
      fail("G" + std::to_string(v) + " is outside taxopt's subset");
    }
  }

  /// The G codes of tool length, TCP, machine coordinates and reference return; false: none.
  bool tool_length_word(int gv, BlockWords& b) {
    if (gv == 490 && knows_.g49_cancels) {
      length_offset_ = false;
      if (knows_.g49_cancels_tcp) tcp_ = false;
    } else if (knows_.g43_length && gv == 430) {
      length_offset_ = true;
    } else if (knows_.tcp_g_code > 0.0 && gv == std::lround(knows_.tcp_g_code * 10)) {
      length_offset_ = tcp_ = true;
    } else if (knows_.g53_machine && gv == 530) {
      // G53: machine coordinates for this block (one-shot, group 00: Fanuc and the controls
      // that follow it, e.g. Mitsubishi M700V manual 14.4).
      b.machine_coordinates = true;
    } else if (knows_.g91_g28 && gv == 910) {
      incremental_ = true;
    } else if (knows_.g91_g28 && gv == 280) {
      b.reference_return = b.machine_coordinates = true;
    } else {
      return false;
    }
    return true;
  }

  void m_word(double v, BlockWords& b) {
    const long mv = std::lround(v);
    if (v != static_cast<double>(mv)) fail("M" + std::to_string(v) + " is not a whole M code");
    if (mv == 3 || mv == 4) b.spindle_start = true;  // with the block's S, wherever it stands
    if (mv == 5 || mv == 2 || mv == 30) spindle_on_ = false;
    if (mv == 7 || mv == 8) coolant_ = static_cast<int>(mv);
    if (mv == 9 || mv == 2 || mv == 30) coolant_ = 0;
    if (mv == 6) b.change_tool = true;
    if (knows_.m128_m91 && (mv == 128 || mv == 129)) tcp_ = mv == 128;
    if (knows_.m128_m91 && mv == 91) b.machine_coordinates = true;
  }

  void other_word(char letter, double v, BlockWords& b) {
    const std::string outside = std::string("word '") + letter + "' is outside taxopt's subset";
    switch (letter) {
      case 'T':
        if (!(v >= 0.0 && v <= 1e6) || v != std::floor(v)) fail("bad tool number after 'T'");
        selected_ = static_cast<int>(v);
        if (knows_.t_calls_tool) {
          length_offset_ = true;  // the tool call: tool and its length
          tool_ = selected_;
        }
        break;
      case 'S':
        if (!(v >= 0.0)) fail("negative spindle speed");
        spindle_rpm_ = v;
        if (v == 0.0) spindle_on_ = false;
        break;
      case 'N': break;
      case 'P':
      case 'Q':
        if (!(v >= 0.0) || !(b.blending || (b.dwell && letter == 'P'))) {
          fail(outside + " (G4 P, G64 P Q only)");
        }
        break;
      case 'H':
        if (!knows_.h_word) fail(outside);
        break;
      case 'O':
        if (!knows_.o_word) fail(outside);
        break;
      case 'D':
        if (!knows_.d_word) fail(outside);
        length_offset_ = v > 0.0;
        break;
      default: fail(outside);
    }
  }

  void stamp(GcodeMove& m, unsigned given) const {
    m.length_offset = length_offset_;
    m.tcp = tcp_;
    m.given = given;
    m.tool = tool_;
    m.spindle_on = spindle_on_;
    m.spindle_rpm = spindle_rpm_;
    m.coolant = coolant_;
  }

  /// The safe retract: in machine coordinates (or Fanuc's reference return); where the axes it
  /// moves are in the workpiece is not known until they are written again.
  void machine_move(const BlockWords& b, const Vec3d& xyz_before) {
    if (incremental_ && !b.reference_return) {
      fail("incremental moves (G91) are outside taxopt's subset");
    }
    if (b.given[3] || b.given[4] || (!b.reference_return && motion_ != 0)) {
      fail("a move in machine coordinates must be a rapid of X, Y or Z");
    }
    const Vec3d machine_xyz = xyz_;  // the words given, in machine coordinates
    xyz_ = xyz_before;
    for (int q = 0; q < 3; ++q) known_[q] = known_[q] && !b.given[q];
    // The way back in (a table turn, the positioning, a descent) is positioning until a block
    // gives X, Y, Z and both rotary axes together: the point the program comes down to.
    approaching_ = true;
    GcodeMove m{true, xyz_, a_, c_, feed_, inverse_time_, line_no_};
    m.positioning = true;
    m.retract = true;
    if (!b.reference_return) m.machine_mm = machine_xyz;
    stamp(m, given_mask(b.given));
    moves_.push_back(m);
  }

  void workpiece_move(const BlockWords& b, const Vec3d& start) {
    if (motion_ < 0) fail("axis words without G0 or G1");
    for (int q = 0; q < 5; ++q) known_[q] = known_[q] || b.given[q];
    // The way back in ends at the block that names the whole pose: the point's (the
    // positioning before it names X, Y and Z at the clearance height, not the angles).
    if (b.given[0] && b.given[1] && b.given[2] && b.given[3] && b.given[4]) approaching_ = false;
    GcodeMove m{motion_ == 0, xyz_, a_, c_, feed_, inverse_time_, line_no_};
    m.positioning =
        approaching_ || !(known_[0] && known_[1] && known_[2] && known_[3] && known_[4]);
    stamp(m, given_mask(b.given));
    if (motion_ == 2 || motion_ == 3) {
      arc(b, start, m);
    } else if (b.has_offset[0] || b.has_offset[1] || b.has_offset[2]) {
      fail("I J K without G2 or G3");
    }
    moves_.push_back(m);
  }

  /// A G2/G3 block: the centre is the start plus I J K in the plane (incremental, as taxopt
  /// writes), at the same distance from both ends.
  void arc(const BlockWords& b, const Vec3d& start, GcodeMove& m) const {
    for (int q = 0; q < 3; ++q) {
      if (q != plane_ && !b.has_offset[q]) {
        fail(std::string("G2/G3 needs its centre word '") + static_cast<char>('I' + q) +
             "' in this plane");
      }
    }
    m.arc = true;
    m.arc_centre_mm = start + b.offset;
    m.arc_centre_mm[plane_] = start[plane_];
    m.arc_normal = Vec3d::Unit(plane_) * (motion_ == 3 ? 1.0 : -1.0);
    const Vec3d rs = start - m.arc_centre_mm, re = xyz_ - m.arc_centre_mm;
    const double r_start = std::hypot(rs[(plane_ + 1) % 3], rs[(plane_ + 2) % 3]);
    const double r_end = std::hypot(re[(plane_ + 1) % 3], re[(plane_ + 2) % 3]);
    if (!(r_start > 0.0) || std::abs(r_start - r_end) > 0.002 + 1e-3 * r_start) {
      fail("G2/G3: the radius to the end (" + std::to_string(r_end) +
           " mm) differs from the radius to the start (" + std::to_string(r_start) + " mm)");
    }
  }

  const std::string& source_;
  const gcode::DialectRules& dialect_;
  const gcode::ReadWords knows_;
  const char tilt_letter_;
  std::vector<GcodeMove> moves_;
  /// Workpiece positions known of X Y Z A C: none before the first full move, nor of an axis
  /// moved in machine coordinates since.
  bool known_[5] = {false, false, false, false, false};
  bool approaching_ = false;
  bool length_offset_, tcp_;
  bool incremental_ = false;
  double scale_ = 1.0;
  bool inverse_time_ = false;
  int motion_ = -1;
  int plane_ = 2;  // the axis normal to the plane: 0 (G19, YZ), 1 (G18, XZ), 2 (G17, XY)
  double feed_ = 0.0;
  Vec3d xyz_ = Vec3d::Zero();
  double a_ = 0.0, c_ = 0.0;
  int line_no_ = 0;
  /// The machine's state (GcodeMove::tool ...): T selects, M6 changes.
  int tool_ = 0, selected_ = 0, coolant_ = 0;
  bool spindle_on_ = false;
  double spindle_rpm_ = 0.0;
};

}  // namespace

std::vector<GcodeMove> read_gcode_moves(const std::string& text, const std::string& source,
                                        GcodeDialect dialect,
                                        const std::vector<int>& verbatim_lines, char tilt_letter,
                                        const std::vector<std::pair<int, int>>& tool_calls) {
  return gcode::read_moves(text, source, dialect, verbatim_lines, tilt_letter, tool_calls, nullptr);
}

std::vector<GcodeMove> gcode::read_moves(const std::string& text, const std::string& source,
                                         GcodeDialect dialect,
                                         const std::vector<int>& verbatim_lines, char tilt_letter,
                                         const std::vector<std::pair<int, int>>& tool_calls,
                                         const StopSource* stop) {
  return GcodeReader(source, dialect, tilt_letter).read(text, verbatim_lines, tool_calls, stop);
}

namespace {

/// Angle of an arc from its start to `p`, counter-clockwise about its normal, in [0, 2 pi);
/// and the in-plane parts.
double arc_angle(const Vec3d& start_rel, const Vec3d& p_rel, const Vec3d& n) {
  const Vec3d a = start_rel - start_rel.dot(n) * n, b = p_rel - p_rel.dot(n) * n;
  double t = std::atan2(a.cross(b).dot(n), a.dot(b));
  if (t < 0.0) t += 2.0 * M_PI;
  return t;
}

/// The arc's sweep: the end's angle, a full turn when it ends where it starts.
double arc_sweep(const Vec3d& from_mm, const GcodeMove& to) {
  const Vec3d s = from_mm - to.arc_centre_mm, e = to.xyz_mm - to.arc_centre_mm;
  const double t = arc_angle(s, e, to.arc_normal);
  return t < 1e-12 ? 2.0 * M_PI : t;
}

}  // namespace

Vec3d point_on_arc(const Vec3d& from_mm, const GcodeMove& to, const Vec3d& near_mm) {
  const Vec3d& n = to.arc_normal;
  const Vec3d s = from_mm - to.arc_centre_mm, e = to.xyz_mm - to.arc_centre_mm;
  const double sweep = arc_sweep(from_mm, to);
  double t = arc_angle(s, near_mm - to.arc_centre_mm, n);
  if (t > sweep) t = (t - sweep < 2.0 * M_PI - t) ? sweep : 0.0;  // past the end: nearer end
  const double f = sweep > 0.0 ? t / sweep : 0.0;
  const Vec3d u = s - s.dot(n) * n, ue = e - e.dot(n) * n;
  const double r = u.norm() + (ue.norm() - u.norm()) * f;
  const Vec3d dir = (u.norm() > 0.0 ? u / u.norm() : u);
  const Vec3d rotated = std::cos(t) * dir + std::sin(t) * n.cross(dir);
  return to.arc_centre_mm + (s.dot(n) + (e.dot(n) - s.dot(n)) * f) * n + r * rotated;
}

double arc_length_mm(const Vec3d& from_mm, const GcodeMove& to) {
  const Vec3d& n = to.arc_normal;
  const Vec3d s = from_mm - to.arc_centre_mm, e = to.xyz_mm - to.arc_centre_mm;
  const double r = 0.5 * ((s - s.dot(n) * n).norm() + (e - e.dot(n) * n).norm());
  return std::hypot(arc_sweep(from_mm, to) * r, (e - s).dot(n));
}

double block_time_s(const GcodeMove& from, const GcodeMove& to, LengthUnit units) {
  if (!(to.feed > 0.0)) return 0.0;
  if (to.inverse_time) return 60.0 / to.feed;
  const double xyz_mm = to.arc ? arc_length_mm(from.xyz_mm, to) : (to.xyz_mm - from.xyz_mm).norm();
  const controller::FeedDistance d = controller::feed_distance(
      xyz_mm, std::hypot(to.tilt_deg - from.tilt_deg, to.c_deg - from.c_deg));
  return 60.0 * d.distance / (to.feed * d.scale(mm_per_unit(units)));
}

}  // namespace taxopt
