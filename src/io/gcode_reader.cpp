#include <cctype>
#include <charconv>
#include <cmath>
#include <initializer_list>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt {

namespace {

/// Removes the whole words `keywords` (Sinumerik's TRAORI ...) from a line, outside comments.
std::string without_keywords(const std::string& line, std::initializer_list<const char*> keywords) {
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
      } else {
        at = end;
      }
    }
  }
  return out;
}

}  // namespace

std::vector<GcodeMove> read_gcode_moves(const std::string& text, const std::string& source,
                                        GcodeDialect dialect) {
  std::vector<GcodeMove> moves;
  double scale = 1.0;
  bool inverse_time = false;
  int motion = -1;
  double feed = 0.0;
  Vec3d xyz = Vec3d::Zero();
  double a = 0.0, c = 0.0;
  int line_no = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string ln = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (dialect == GcodeDialect::Siemens) {
      ln = without_keywords(ln, {"TRAORI", "ORIAXES", "TRAFOOF"});
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
          const bool iso_units =
              dialect == GcodeDialect::LinuxCNC || dialect == GcodeDialect::Fanuc;
          if (gv == 0)
            motion = 0;
          else if (gv == 10)
            motion = 1;
          else if (iso_units && (gv == 200 || gv == 210))
            scale = gv == 200 ? kMmPerInch : 1.0;
          else if (dialect == GcodeDialect::Siemens && (gv == 7000 || gv == 7100))
            scale = gv == 7000 ? kMmPerInch : 1.0;
          else if (gv == 930)
            inverse_time = true;
          else if (gv == 940)
            inverse_time = false;
          else if (gv == 900 || gv == 170 || gv == 400 || gv == 490 || gv == 800) {
          } else if (dialect == GcodeDialect::Fanuc && (gv == 434 || gv == 430)) {
          } else {
            throw InputError(source, line_no,
                             "G" + std::to_string(v) + " is outside taxopt's subset");
          }
          break;
        }
        case 'X':
          xyz.x() = v * scale;
          has_axis = true;
          break;
        case 'Y':
          xyz.y() = v * scale;
          has_axis = true;
          break;
        case 'Z':
          xyz.z() = v * scale;
          has_axis = true;
          break;
        case 'A':
          a = v;
          has_axis = true;
          break;
        case 'C':
          c = v;
          has_axis = true;
          break;
        case 'F': feed = v; break;
        case 'M':
        case 'T':
        case 'S':
        case 'N': break;
        case 'H':
        case 'O':
          if (dialect != GcodeDialect::Fanuc) {
            throw InputError(source, line_no,
                             std::string("word '") + letter + "' is outside taxopt's subset");
          }
          break;
        case 'D':
          if (dialect != GcodeDialect::Siemens) {
            throw InputError(source, line_no, "word 'D' is outside taxopt's subset");
          }
          break;
        default:
          throw InputError(source, line_no,
                           std::string("word '") + letter + "' is outside taxopt's subset");
      }
    }
    if (has_axis) {
      if (motion < 0) throw InputError(source, line_no, "axis words without G0 or G1");
      moves.push_back(GcodeMove{motion == 0, xyz, a, c, feed, inverse_time, line_no});
    }
    if (end == text.size()) break;
  }
  return moves;
}

double block_time_s(const GcodeMove& from, const GcodeMove& to, LengthUnit units) {
  if (!(to.feed > 0.0)) return 0.0;
  if (to.inverse_time) return 60.0 / to.feed;
  const double xyz_mm = (to.xyz_mm - from.xyz_mm).norm();
  // A move whose XYZ words repeat has a rounded distance of exactly zero.
  if (xyz_mm > 0.0) return 60.0 * xyz_mm / (to.feed * mm_per_unit(units));
  return 60.0 * std::hypot(to.a_deg - from.a_deg, to.c_deg - from.c_deg) / to.feed;
}

}  // namespace taxopt
