// The list of dialects, and the words most of them share (dialect_rules.hpp).
#include <stdexcept>

#include "dialects/dialect_rules.hpp"

namespace taxopt::gcode {

std::string DialectRules::comment(const std::string& text, int& number) const {
  (void)number;
  // A tape dialect (Fanuc, Haas) reads its program from one % to the next: none in a comment.
  return "(" + (template_words().tape ? tape_comment_text(text) : comment_text(text)) + ")";
}

std::string DialectRules::setup(bool inch, bool inverse_time) const {
  return std::string(inch ? "G20" : "G21") + " G90 G17 G40 G49 G80 " +
         (inverse_time ? "G93" : "G94");
}

const std::vector<const DialectRules*>& all_dialects() {
  static const std::vector<const DialectRules*> kAll = {
      &linuxcnc_rules(), &fanuc_rules(), &siemens_rules(), &heidenhain_rules(), &haas_rules()};
  return kAll;
}

const DialectRules& rules_of(GcodeDialect dialect) {
  for (const DialectRules* r : all_dialects()) {
    if (r->id() == dialect) return *r;
  }
  throw std::invalid_argument("rules_of: a G-code dialect without its rules (" +
                              std::to_string(static_cast<int>(dialect)) + ")");
}

}  // namespace taxopt::gcode
