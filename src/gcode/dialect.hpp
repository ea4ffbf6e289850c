#pragma once
/// @file How each controller dialect writes a program's words (docs/gcode-dialects.md): the
/// writer's formatting, internal to the library.

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "taxopt/core/toolpath.hpp"
#include "taxopt/kinematics/machine.hpp"

namespace taxopt::gcode {

inline std::string fmt(double v, int decimals) {
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
inline double round_to(double v, int decimals) {
  return std::strtod(fmt(v, decimals).c_str(), nullptr);
}

/// Comment text for a controller: no parentheses (they close a LinuxCNC or Fanuc comment),
/// no line breaks.
inline std::string comment_text(const std::string& text) {
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

}  // namespace taxopt::gcode
