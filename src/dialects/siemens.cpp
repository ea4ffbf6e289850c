// Siemens Sinumerik 840D: TRAORI with ORIAXES (the rotary axes interpolated linearly, as taxopt
// models them), TRAFOOF, SUPA (suppress all frames: machine coordinates) with D0, G700/G710
// (feeds in the program's units too), "; " comments.
#include <cctype>

#include "dialects/dialect_rules.hpp"

namespace taxopt::gcode {
namespace {

/// Removes the whole words `keywords` from a line, outside comments; returns which were there.
std::vector<std::string> take_keywords(std::string& line,
                                       const std::vector<std::string>& keywords) {
  std::vector<std::string> found;
  for (const std::string& key : keywords) {
    for (std::size_t at = line.find(key); at != std::string::npos; at = line.find(key, at)) {
      const bool starts = at == 0 || std::isspace(static_cast<unsigned char>(line[at - 1]));
      const std::size_t end = at + key.size();
      const bool ends = end == line.size() || std::isspace(static_cast<unsigned char>(line[end])) ||
                        line[end] == ';';
      if (starts && ends) {
        line.replace(at, key.size(), " ");
        found.push_back(key);
      } else {
        at = end;
      }
    }
  }
  return found;
}

class Siemens final : public DialectRules {
 public:
  GcodeDialect id() const override { return GcodeDialect::Siemens; }
  const char* name() const override { return "siemens"; }
  int max_decimals() const override { return 8; }

  std::string comment(const std::string& text, int&) const override {
    return "; " + comment_text(text);
  }
  bool names_program() const override { return true; }
  std::string setup(bool inch, bool inverse_time) const override {
    return std::string(inch ? "G700" : "G710") + " G90 G17 G40 " + (inverse_time ? "G93" : "G94");
  }
  /// The tool's length is off after it (D0): the spindle nose goes to the height.
  std::vector<std::string> retract(const std::string& z) const override {
    return {"G0 SUPA Z" + z + " D0"};
  }
  std::vector<std::string> park(const std::string& x, const std::string& y) const override {
    return {"G0 SUPA X" + x + " Y" + y};
  }
  std::vector<std::string> length_on(bool, int) const override { return {"D1"}; }
  std::vector<std::string> tcp_on(int) const override { return {"TRAORI", "ORIAXES"}; }
  std::vector<std::string> tcp_off(bool tcp) const override {
    if (!tcp) return {};
    return {"TRAFOOF"};
  }

  ReadWords read_words() const override {
    ReadWords r = ReadWords::without_iso_words();
    r.g700_g710_units = true;
    r.d_word = true;
    return r;
  }
  LineMarks own_words(std::string& line) const override {
    LineMarks marks;
    for (const auto& k : take_keywords(line, {"TRAORI", "ORIAXES", "TRAFOOF", "SUPA"})) {
      if (k == "TRAORI") marks.tcp = true;
      if (k == "TRAFOOF") marks.tcp = false;
      if (k == "SUPA") marks.machine_coordinates = true;
    }
    return marks;
  }

  /// G60 (exact stop), G641/G642 (continuous path with rounding) besides the common codes;
  /// the feed-forward, jerk, compressor and path-reference words and CYCLE832 (high-speed
  /// settings) of Sinumerik's posts; settable frames G505 ... G599.
  TemplateWords template_words() const override {
    return {false,
            {4, 40, 80, 61, 61.1, 64, 642, 641, 60},
            {65},
            {"FFWON", "FFWOF", "SOFT", "BRISK", "COMPCAD", "COMPCURV", "COMPSURF", "COMPOF",
             "UPATH", "SPATH", "CYCLE832"},
            true};
  }
};

}  // namespace

const DialectRules& siemens_rules() {
  static const Siemens kRules;
  return kRules;
}

}  // namespace taxopt::gcode
