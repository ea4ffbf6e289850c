// Fanuc 30i/31i-B5: tool centre point control G43.4 (FANUC Series 30i-MODEL A, Tool center
// point control for 5-axis machining, A-79348E), the reference-point return G91 G28 Z0 that
// Fanuc posts write before a tool change, numbers in least input increments without their
// decimal point (IS-B: "X10" is 0.010 mm).
#include <cmath>

#include "dialects/dialect_rules.hpp"

namespace taxopt::gcode {
namespace {

class Fanuc final : public DialectRules {
 public:
  GcodeDialect id() const override { return GcodeDialect::Fanuc; }
  const char* name() const override { return "fanuc"; }
  int max_decimals() const override { return 4; }  // IS-C, 0.0001 mm

  std::vector<std::string> start(const ProgramName& p) const override {
    return {"%", "O" + zero_padded(p.number, 4) + " (" + tape_comment_text(p.name) + ")"};
  }
  std::vector<std::string> retract(const std::string&) const override {
    return {"G91 G28 Z0.", "G90"};
  }
  bool retract_to_reference() const override { return true; }
  std::vector<std::string> park(const std::string& x, const std::string& y) const override {
    return {"G53 G0 X" + x + " Y" + y};
  }
  /// G43.4 (or plain G43 in machine mode) with the tool's offset number, on the operation's
  /// first motion block.
  bool length_on_first_move() const override { return true; }
  std::string first_move_prefix(bool tcp, int offset) const override {
    return std::string(tcp ? "G43.4" : "G43") + " H" + std::to_string(offset) + " ";
  }
  std::string dwell(double seconds) const override {
    return "G04 P" + std::to_string(std::lround(seconds * 1000.0));  // P in milliseconds
  }
  /// PS5421: G2/G3 after A or C has turned under G43.4 (A-79348E, pp. 22-24: circular
  /// interpolation is allowed where neither rotary axis moves after the G43.4 command).
  bool arc_after_tcp_turn() const override { return false; }
  std::vector<std::string> finish(const ProgramName&) const override { return {"%"}; }
  bool point_in_every_number() const override { return true; }

  ReadWords read_words() const override {
    ReadWords r;
    r.g4_dwell = true;
    r.g49_cancels_tcp = true;
    r.tcp_g_code = 43.4;
    r.g91_g28 = true;
    r.o_word = true;
    return r;
  }

  /// G5.1 (AI contour control) and G8 (look-ahead) besides the common codes.
  TemplateWords template_words() const override {
    return {true, {4, 40, 80, 61, 61.1, 64, 5.1, 8}, {65}, {}, false, true};
  }
};

}  // namespace

const DialectRules& fanuc_rules() {
  static const Fanuc kRules;
  return kRules;
}

}  // namespace taxopt::gcode
