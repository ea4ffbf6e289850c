// Heidenhain TNC in ISO mode (TNC ISO programming manual): blocks numbered N10 ... and ended
// with " *", the program's begin and end blocks (%NAME G71 *), M128/M129 for tool centre point
// control, M91 (positions referenced to the machine datum), the tool call T n G17 that applies
// the tool's length; 4 decimals of positions, 3 of F; no G93 and no G2/G3 written.
#include "dialects/dialect_rules.hpp"

namespace taxopt::gcode {
namespace {

class Heidenhain final : public DialectRules {
 public:
  GcodeDialect id() const override { return GcodeDialect::Heidenhain; }
  const char* name() const override { return "heidenhain"; }
  int max_decimals() const override { return 4; }
  int max_feed_decimals() const override { return 3; }
  bool inverse_time() const override { return false; }

  std::string block(const std::string& words, int& number) const override {
    number += 10;
    return "N" + std::to_string(number) + " " + words + " *";
  }
  std::string comment(const std::string& text, int& number) const override {
    return block("; " + comment_text(text), number);
  }
  std::vector<std::string> start(const ProgramName& p) const override {
    return {"%" + p.name + (p.inch ? " G70" : " G71") + " *"};
  }
  std::string setup(bool, bool) const override { return "G17 G90 G40"; }  // units: the start
  std::string default_work_offset() const override { return {}; }         // the active preset
  std::vector<std::string> retract(const std::string& z) const override {
    return {"G00 Z" + z + " M91"};
  }
  std::vector<std::string> park(const std::string& x, const std::string& y) const override {
    return {"G00 X" + x + " Y" + y + " M91"};
  }
  std::vector<std::string> tool_change(int tool) const override {
    return {"T" + std::to_string(tool) + " G17"};
  }
  std::vector<std::string> tcp_on(int) const override { return {"M128"}; }
  std::vector<std::string> tcp_off(bool tcp) const override {
    if (!tcp) return {};
    return {"M129"};
  }
  std::string rapid() const override { return "G00"; }
  std::string linear() const override { return "G01"; }
  bool writes_arcs() const override { return false; }
  std::vector<std::string> finish(const ProgramName& p) const override {
    return {"N99999999 %" + p.name + (p.inch ? " G70" : " G71") + " *"};
  }

  ReadWords read_words() const override {
    ReadWords r = ReadWords::without_iso_words();
    r.g2_g3_arcs = false;
    r.m128_m91 = true;
    r.t_calls_tool = true;
    r.length_from_start = true;  // the TOOL CALL may come before the program
    return r;
  }
  /// The program's begin and end blocks (%NAME G71 *: a '%' before any comment) set the units
  /// by their last G70/G71 (a name may hold "G70" too); the block end "*" goes. A '%' in a
  /// comment ("; 50% stepover *") is the comment's.
  LineMarks own_words(std::string& line) const override {
    LineMarks marks;
    const std::size_t semi = line.find(';');
    const auto before_comment = [&](std::size_t at) {
      return at != std::string::npos && (semi == std::string::npos || at < semi);
    };
    if (before_comment(line.find('%'))) {
      const std::size_t unit = line.rfind("G7", semi);
      if (before_comment(unit) && unit + 2 < line.size()) {
        marks.mm_per_unit = line[unit + 2] == '0' ? kMmPerInch : 1.0;
      }
      marks.nothing_more = true;
      return marks;
    }
    const std::size_t star = line.rfind('*');
    if (before_comment(star)) line.erase(star, 1);
    return marks;
  }

  /// Dwell and radius compensation off only; G17 in the tool call.
  TemplateWords template_words() const override { return {false, {4, 40}, {17}, {}, false}; }
  /// M128 / M129: tool centre point control is taxopt's, on per operation after the table turn
  /// and the tool call (a header's M128 turned it on before both).
  std::string template_refusal(char letter, double number) const override {
    if (letter == 'M' && (number == 128 || number == 129)) {
      return "tool centre point control (M128, M129) is switched by taxopt per operation, "
             "after the table turn and the tool call";
    }
    return {};
  }
};

}  // namespace

const DialectRules& heidenhain_rules() {
  static const Heidenhain kRules;
  return kRules;
}

}  // namespace taxopt::gcode
