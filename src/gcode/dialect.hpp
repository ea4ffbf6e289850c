#pragma once
/// @file The writer's words for one program: a dialect's rules (src/dialects/) with the
/// machine file's program template (its name, work offset, tool change, coolant) and the
/// program's block numbers. Internal to the library.

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "dialects/dialect_rules.hpp"
#include "taxopt/core/toolpath.hpp"
#include "taxopt/kinematics/machine.hpp"

namespace taxopt::gcode {

/// How one program is written in its controller's dialect (docs/gcode-dialects.md).
class Dialect {
 public:
  Dialect(const GcodeSettings& g, LengthUnit units)
      : r_(rules_of(g.dialect)),
        t_(g.program),
        program_{t_.name.empty() ? "TAXOPT" : t_.name, t_.number, units == LengthUnit::Inch} {}

  const DialectRules& rules() const { return r_; }
  /// A block as written (a TNC numbers its blocks).
  std::string block(const std::string& words) { return r_.block(words, block_no_); }
  std::string comment(const std::string& text) { return r_.comment(text, block_no_); }
  const std::string& name() const { return program_.name; }
  /// Lines before the comments: the program start.
  std::vector<std::string> start() const { return r_.start(program_); }
  /// The modal set-up block (units, absolute, plane, feed mode).
  std::string setup(bool inverse_time) const { return r_.setup(program_.inch, inverse_time); }
  /// The work offset block: the template's, else the dialect's (G54; none on a TNC).
  std::string work_offset() const {
    if (t_.work_offset == "none") return {};
    if (!t_.work_offset.empty()) return t_.work_offset;
    return r_.default_work_offset();
  }
  /// The retract to machine Z (SafeRetract::MachineZ), in the dialect's own way.
  std::vector<std::string> retract(const std::string& z) const {
    if (t_.retract == SafeRetract::None) return {};
    return r_.retract(z);
  }
  std::vector<std::string> park(const std::string& x, const std::string& y) const {
    return r_.park(x, y);
  }
  /// The tool change; true when the lines are the template's (written as they are).
  std::pair<std::vector<std::string>, bool> tool_change(int tool) const {
    if (t_.tool_change.empty()) return {r_.tool_change(tool), false};
    const std::string n = std::to_string(tool);
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
  /// The tool length offset on for an operation, as blocks of their own.
  std::vector<std::string> length_on(bool tcp, int tool) const {
    return r_.length_on(tcp, offset(tool));
  }
  /// Tool centre point control on (tcp mode): blocks before an operation's first move.
  std::vector<std::string> tcp_on(bool tcp, int tool) const {
    if (!tcp) return {};
    return r_.tcp_on(offset(tool));
  }
  bool length_on_first_move() const { return r_.length_on_first_move(); }
  std::string first_move_prefix(bool tcp, int tool) const {
    return r_.first_move_prefix(tcp, offset(tool));
  }
  std::vector<std::string> tcp_off(bool tcp) const { return r_.tcp_off(tcp); }
  std::string coolant_on() const {
    switch (t_.coolant) {
      case Coolant::Flood: return "M8";
      case Coolant::Mist: return "M7";
      case Coolant::None: return {};
    }
    return {};
  }
  std::string rapid() const { return r_.rapid(); }
  std::string linear() const { return r_.linear(); }
  std::string end() const { return r_.end(); }
  std::vector<std::string> finish() const { return r_.finish(program_); }
  /// A coordinate as written (DialectRules::number).
  std::string number(double v, int decimals) const { return r_.number(v, decimals); }

 private:
  /// The tool's length offset number: the tool's, at least 1.
  static int offset(int tool) { return std::max(tool, 1); }
  const DialectRules& r_;
  const ProgramTemplate& t_;
  ProgramName program_;
  int block_no_ = 0;
};

}  // namespace taxopt::gcode
