#include <cctype>
#include <charconv>
#include <cmath>
#include <initializer_list>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt {

namespace {

/// Removes the whole words `keywords` (Sinumerik's TRAORI ...) from a line, outside comments;
/// `found` receives which were there.
std::string without_keywords(const std::string& line, std::initializer_list<const char*> keywords,
                             std::vector<std::string>* found = nullptr) {
  std::string out = line;
  for (const char* k : keywords) {
    const std::string key = k;
    for (std::size_t at = out.find(key); at != std::string::npos; at = out.find(key, at)) {
      const bool starts = at == 0 || std::isspace(static_cast<unsigned char>(out[at - 1]));
      const std::size_t end = at + key.size();
      const bool ends = end == out.size() || std::isspace(static_cast<unsigned char>(out[end])) ||
                        out[end] == ';';
      if (starts && ends) {
        out.replace(at, key.size(), " ");
        if (found) found->push_back(key);
      } else {
        at = end;
      }
    }
  }
  return out;
}

unsigned given_mask(const bool (&given)[5]) {
  unsigned mask = 0;
  for (int q = 0; q < 5; ++q) {
    if (given[q]) mask |= 1u << q;
  }
  return mask;
}

}  // namespace

std::vector<GcodeMove> read_gcode_moves(const std::string& text, const std::string& source,
                                        GcodeDialect dialect,
                                        const std::vector<int>& verbatim_lines, char tilt_letter,
                                        const std::vector<std::pair<int, int>>& tool_calls) {
  // Haas is read as Fanuc is, with G234 (tool centre point control) beside.
  const bool haas = dialect == GcodeDialect::Haas;
  const bool fanuc_like = dialect == GcodeDialect::Fanuc || haas;
  std::vector<GcodeMove> moves;
  // Workpiece positions known of X Y Z A C: none before the first full move, nor of an axis
  // moved in machine coordinates since.
  bool known[5] = {false, false, false, false, false};
  bool approaching = false;
  // A TNC applies the length of the tool in the spindle always (its TOOL CALL may come
  // before the program); LinuxCNC's TCP is its kinematics.
  bool length_offset = dialect == GcodeDialect::Heidenhain;
  bool tcp = dialect == GcodeDialect::LinuxCNC;
  bool incremental = false;
  std::size_t next_verbatim = 0;
  double scale = 1.0;
  bool inverse_time = false;
  int motion = -1;
  int plane = 2;  // the axis normal to the plane: 0 (G19, YZ), 1 (G18, XZ), 2 (G17, XY)
  double feed = 0.0;
  Vec3d xyz = Vec3d::Zero();
  double a = 0.0, c = 0.0;
  int line_no = 0;
  // The machine's state (GcodeMove::tool ...): T selects, M6 changes.
  int tool = 0, selected = 0, coolant = 0;
  bool spindle_on = false;
  double spindle_rpm = 0.0;
  const auto stamp = [&](GcodeMove& m, unsigned given) {
    m.length_offset = length_offset;
    m.tcp = tcp;
    m.given = given;
    m.tool = tool;
    m.spindle_on = spindle_on;
    m.spindle_rpm = spindle_rpm;
    m.coolant = coolant;
  };
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string ln = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    while (next_verbatim < verbatim_lines.size() && verbatim_lines[next_verbatim] < line_no) {
      ++next_verbatim;
    }
    if (next_verbatim < verbatim_lines.size() && verbatim_lines[next_verbatim] == line_no) {
      for (const auto& [at, t] : tool_calls) {
        if (at == line_no) tool = t;
      }
      if (end == text.size()) break;
      continue;
    }
    bool machine_coordinates = false;
    if (dialect == GcodeDialect::Siemens) {
      std::vector<std::string> found;
      ln = without_keywords(ln, {"TRAORI", "ORIAXES", "TRAFOOF", "SUPA"}, &found);
      for (const auto& k : found) {
        if (k == "TRAORI") tcp = true;
        if (k == "TRAFOOF") tcp = false;
        if (k == "SUPA") machine_coordinates = true;
      }
    } else if (dialect == GcodeDialect::Heidenhain) {
      // Program begin and end blocks (%NAME G71 *), and the block end "*".
      if (ln.find('%') != std::string::npos) {
        const std::size_t unit = ln.find("G7");
        if (unit != std::string::npos && unit + 2 < ln.size()) {
          scale = ln[unit + 2] == '0' ? kMmPerInch : 1.0;
        }
        if (end == text.size()) break;
        continue;
      }
      const std::size_t star = ln.rfind('*');
      const std::size_t semi = ln.find(';');
      if (star != std::string::npos && (semi == std::string::npos || star < semi)) {
        ln.erase(star, 1);
      }
    }
    // Remove comments.
    std::string code;
    int depth = 0;
    for (char ch : ln) {
      if (ch == ';' && depth == 0) break;
      if (ch == '(') {
        ++depth;
      } else if (ch == ')') {
        if (depth == 0) throw InputError(source, line_no, "')' without '('");
        --depth;
      } else if (depth == 0 && !std::isspace(static_cast<unsigned char>(ch))) {
        code += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      }
    }
    if (depth != 0) throw InputError(source, line_no, "unclosed comment");
    if (code.empty() || code == "%") continue;
    bool has_axis = false;
    bool given[5] = {false, false, false, false, false};
    bool reference_return = false;
    bool dwell = false;
    bool spindle_start = false, change_tool = false, blending = false;
    const Vec3d start = xyz;
    const Vec3d xyz_before = xyz;
    Vec3d offset = Vec3d::Zero();
    bool has_offset[3] = {false, false, false};
    std::size_t i = 0;
    while (i < code.size()) {
      const char letter = code[i++];
      if (!std::isalpha(static_cast<unsigned char>(letter))) {
        throw InputError(source, line_no,
                         std::string("expected a word letter, got '") + letter + "'");
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
        throw InputError(source, line_no, std::string("bad number after '") + letter + "'");
      }
      i = j;
      switch (letter) {
        case 'G': {
          const int gv = static_cast<int>(std::lround(v * 10));
          const bool iso_units = dialect == GcodeDialect::LinuxCNC || fanuc_like;
          if (gv == 0)
            motion = 0;
          else if (gv == 10)
            motion = 1;
          else if ((gv == 20 || gv == 30) && dialect != GcodeDialect::Heidenhain)
            motion = gv / 10;
          else if (gv == 170 || gv == 180 || gv == 190)
            plane = gv == 170 ? 2 : gv == 180 ? 1 : 0;
          else if (iso_units && (gv == 200 || gv == 210))
            scale = gv == 200 ? kMmPerInch : 1.0;
          else if (dialect == GcodeDialect::Siemens && (gv == 7000 || gv == 7100))
            scale = gv == 7000 ? kMmPerInch : 1.0;
          else if (gv == 930)
            inverse_time = true;
          else if (gv == 940)
            inverse_time = false;
          else if (gv == 900)
            incremental = false;
          else if (gv == 40 &&
                   (dialect == GcodeDialect::LinuxCNC || dialect == GcodeDialect::Fanuc)) {
            dwell = true;  // the CL file's DELAY: P is its time
          } else if (gv == 400 || gv == 800 || gv == 540) {
          } else if (dialect == GcodeDialect::LinuxCNC && (gv == 640 || gv == 610)) {
            blending = true;  // path control: G64 P Q, G61
          } else if (gv == 490 && dialect != GcodeDialect::Heidenhain &&
                     dialect != GcodeDialect::Siemens) {
            length_offset = false;
            if (fanuc_like) tcp = false;
          } else if ((fanuc_like || dialect == GcodeDialect::LinuxCNC) && gv == 430) {
            length_offset = true;
          } else if (dialect == GcodeDialect::Fanuc && gv == 434) {
            length_offset = tcp = true;
          } else if (haas && gv == 2340) {
            length_offset = tcp = true;
          } else if ((dialect == GcodeDialect::LinuxCNC || fanuc_like) && gv == 530) {
            // G53: machine coordinates for this block (one-shot, group 00: Fanuc and the
            // controls that follow it, e.g. Mitsubishi M700V manual 14.4).
            machine_coordinates = true;
          } else if (fanuc_like && gv == 910) {
            incremental = true;
          } else if (fanuc_like && gv == 280) {
            reference_return = machine_coordinates = true;
          } else {
            throw InputError(source, line_no,
                             "G" + std::to_string(v) + " is outside taxopt's subset");
          }
          break;
        }
        case 'X':
          xyz.x() = v * scale;
          has_axis = given[0] = true;
          break;
        case 'Y':
          xyz.y() = v * scale;
          has_axis = given[1] = true;
          break;
        case 'Z':
          xyz.z() = v * scale;
          has_axis = given[2] = true;
          break;
        case 'A':
        case 'B':
          if (letter != tilt_letter) {
            throw InputError(source, line_no,
                             std::string("word '") + letter + "' is not an axis of this machine (" +
                                 tilt_letter + " and C turn its table)");
          }
          a = v;
          has_axis = given[3] = true;
          break;
        case 'C':
          c = v;
          has_axis = given[4] = true;
          break;
        case 'F': feed = v; break;
        case 'I':
        case 'J':
        case 'K':
          if (dialect == GcodeDialect::Heidenhain) {
            throw InputError(source, line_no,
                             std::string("word '") + letter + "' is outside taxopt's subset");
          }
          offset[letter - 'I'] = v * scale;
          has_offset[letter - 'I'] = true;
          break;
        case 'M': {
          const long mv = std::lround(v);
          if (v != static_cast<double>(mv)) {
            throw InputError(source, line_no, "M" + std::to_string(v) + " is not a whole M code");
          }
          if (mv == 3 || mv == 4) spindle_start = true;  // with the block's S, wherever it stands
          if (mv == 5 || mv == 2 || mv == 30) spindle_on = false;
          if (mv == 7 || mv == 8) coolant = static_cast<int>(mv);
          if (mv == 9 || mv == 2 || mv == 30) coolant = 0;
          if (mv == 6) change_tool = true;
          if (dialect == GcodeDialect::Heidenhain && (mv == 128 || mv == 129)) tcp = mv == 128;
          if (dialect == GcodeDialect::Heidenhain && mv == 91) machine_coordinates = true;
          break;
        }
        case 'T':
          if (!(v >= 0.0 && v <= 1e6) || v != std::floor(v)) {
            throw InputError(source, line_no, "bad tool number after 'T'");
          }
          selected = static_cast<int>(v);
          if (dialect == GcodeDialect::Heidenhain) {
            length_offset = true;  // the tool call: tool and its length
            tool = selected;
          }
          break;
        case 'S':
          if (!(v >= 0.0)) throw InputError(source, line_no, "negative spindle speed");
          spindle_rpm = v;
          if (v == 0.0) spindle_on = false;
          break;
        case 'N': break;
        case 'P':
        case 'Q':
          if (!(v >= 0.0) || !(blending || (dwell && letter == 'P'))) {
            throw InputError(source, line_no,
                             std::string("word '") + letter +
                                 "' is outside taxopt's subset (G4 P, G64 P Q only)");
          }
          break;
        case 'H':
          if (!fanuc_like && dialect != GcodeDialect::LinuxCNC) {
            throw InputError(source, line_no, "word 'H' is outside taxopt's subset");
          }
          break;
        case 'O':
          if (!fanuc_like) {
            throw InputError(source, line_no,
                             std::string("word '") + letter + "' is outside taxopt's subset");
          }
          break;
        case 'D':
          if (dialect != GcodeDialect::Siemens) {
            throw InputError(source, line_no, "word 'D' is outside taxopt's subset");
          }
          length_offset = v > 0.0;
          break;
        default:
          throw InputError(source, line_no,
                           std::string("word '") + letter + "' is outside taxopt's subset");
      }
    }
    if (spindle_start) spindle_on = spindle_rpm > 0.0;
    if (change_tool) tool = selected;
    if (dwell && has_axis) throw InputError(source, line_no, "G4 with an axis word");
    if (has_axis && (machine_coordinates || incremental)) {
      // The safe retract: in machine coordinates (or Fanuc's reference return); where the
      // axes it moves are in the workpiece is not known until they are written again.
      if (incremental && !reference_return) {
        throw InputError(source, line_no, "incremental moves (G91) are outside taxopt's subset");
      }
      if (given[3] || given[4] || (!reference_return && motion != 0)) {
        throw InputError(source, line_no,
                         "a move in machine coordinates must be a rapid of X, Y or Z");
      }
      const Vec3d machine_xyz = xyz;  // the words given, in machine coordinates
      xyz = xyz_before;
      for (int q = 0; q < 3; ++q) known[q] = known[q] && !given[q];
      // The way back in (a table turn, a descent, an XY move) is positioning until a block
      // gives X, Y and Z together: the point the program comes down to.
      approaching = true;
      GcodeMove m{true, xyz, a, c, feed, inverse_time, line_no};
      m.positioning = true;
      m.retract = true;
      if (!reference_return) m.machine_mm = machine_xyz;
      stamp(m, given_mask(given));
      moves.push_back(m);
      if (end == text.size()) break;
      continue;
    }
    if (has_axis) {
      if (motion < 0) throw InputError(source, line_no, "axis words without G0 or G1");
      for (int q = 0; q < 5; ++q) known[q] = known[q] || given[q];
      if (given[0] && given[1] && given[2]) approaching = false;
      GcodeMove m{motion == 0, xyz, a, c, feed, inverse_time, line_no};
      m.positioning = approaching || !(known[0] && known[1] && known[2] && known[3] && known[4]);
      stamp(m, given_mask(given));
      if (motion == 2 || motion == 3) {
        // The centre is the start plus I J K in the plane (incremental, as taxopt writes).
        for (int q = 0; q < 3; ++q) {
          if (q != plane && !has_offset[q]) {
            throw InputError(source, line_no,
                             std::string("G2/G3 needs its centre word '") +
                                 static_cast<char>('I' + q) + "' in this plane");
          }
        }
        m.arc = true;
        m.arc_centre_mm = start + offset;
        m.arc_centre_mm[plane] = start[plane];
        m.arc_normal = Vec3d::Unit(plane) * (motion == 3 ? 1.0 : -1.0);
        const Vec3d rs = start - m.arc_centre_mm, re = xyz - m.arc_centre_mm;
        const double r_start = std::hypot(rs[(plane + 1) % 3], rs[(plane + 2) % 3]);
        const double r_end = std::hypot(re[(plane + 1) % 3], re[(plane + 2) % 3]);
        if (!(r_start > 0.0) || std::abs(r_start - r_end) > 0.002 + 1e-3 * r_start) {
          throw InputError(source, line_no,
                           "G2/G3: the radius to the end (" + std::to_string(r_end) +
                               " mm) differs from the radius to the start (" +
                               std::to_string(r_start) + " mm)");
        }
      } else if (has_offset[0] || has_offset[1] || has_offset[2]) {
        throw InputError(source, line_no, "I J K without G2 or G3");
      }
      moves.push_back(m);
    }
    if (end == text.size()) break;
  }
  return moves;
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
  // A move whose XYZ words repeat has a rounded distance of exactly zero.
  if (xyz_mm > 0.0) return 60.0 * xyz_mm / (to.feed * mm_per_unit(units));
  return 60.0 * std::hypot(to.a_deg - from.a_deg, to.c_deg - from.c_deg) / to.feed;
}

}  // namespace taxopt
