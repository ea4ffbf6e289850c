// Haas's Next Generation Control on a 5-axis mill (UMC series; the Haas mill operator's
// manual, G234 and G187): read and written as Fanuc's, with G234 tool centre point control
// (it carries the length offset: G43 in machine mode only), program numbers O00000 ... O99999
// and a retract in machine coordinates (G53) as Haas's posts write it.
#include "dialects/dialect_rules.hpp"

namespace taxopt::gcode {
namespace {

class Haas final : public DialectRules {
 public:
  GcodeDialect id() const override { return GcodeDialect::Haas; }
  const char* name() const override { return "haas"; }
  int max_decimals() const override { return 4; }

  /// O00001 to O99999 (issue 63.12: 10000 was refused citing Fanuc's O9999).
  int max_program_number() const override { return 99999; }
  std::vector<std::string> start(const ProgramName& p) const override {
    return {"%", "O" + zero_padded(p.number, 5) + " (" + tape_comment_text(p.name) + ")"};
  }
  std::vector<std::string> retract(const std::string& z) const override { return {"G53 G0 Z" + z}; }
  std::vector<std::string> park(const std::string& x, const std::string& y) const override {
    return {"G53 G0 X" + x + " Y" + y};
  }
  std::vector<std::string> length_on(bool tcp, int offset) const override {
    if (tcp) return {};  // G234 carries the offset
    return {"G43 H" + std::to_string(offset)};
  }
  std::vector<std::string> tcp_on(int offset) const override {
    return {"G234 H" + std::to_string(offset)};
  }
  // tcp_off: the default G49 ends G234 too (G234 is in G49's group 08).
  /// G234 is treated as Fanuc's G43.4 (its rule on arcs is not published here).
  bool arc_after_tcp_turn() const override { return false; }
  std::vector<std::string> finish(const ProgramName&) const override { return {"%"}; }
  bool point_in_every_number() const override { return true; }

  /// Read as Fanuc's, with G234 for G43.4 and no dwell written.
  ReadWords read_words() const override {
    ReadWords r = fanuc_rules().read_words();
    r.g4_dwell = false;
    r.tcp_g_code = 234;
    return r;
  }

  /// Fanuc's, and G187 (smoothness).
  TemplateWords template_words() const override {
    TemplateWords t = fanuc_rules().template_words();
    t.g_codes.push_back(187);
    return t;
  }
};

}  // namespace

const DialectRules& haas_rules() {
  static const Haas kRules;
  return kRules;
}

}  // namespace taxopt::gcode
