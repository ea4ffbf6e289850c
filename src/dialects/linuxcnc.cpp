// LinuxCNC (rs274ngc, its G-code reference: linuxcnc.org/docs/html/gcode/g-code.html, and the
// M-code page for M70-M73). Every program taxopt writes for it is read by its own interpreter
// in the tests (tests/test_rs274.cpp).
#include <algorithm>

#include "dialects/dialect_rules.hpp"

namespace taxopt::gcode {
namespace {

class LinuxCnc final : public DialectRules {
 public:
  GcodeDialect id() const override { return GcodeDialect::LinuxCNC; }
  const char* name() const override { return "linuxcnc"; }
  int max_decimals() const override { return 8; }

  bool names_program() const override { return true; }
  /// The path's blending bound (ProgramTemplate::blend_tolerance_mm): G64 P Q0, G61 at 0.
  std::string path_control(double blend_tolerance, int decimals) const override {
    return blend_tolerance > 0.0 ? "G64 P" + fmt(blend_tolerance, std::max(decimals, 4)) + " Q0"
                                 : "G61";
  }
  std::vector<std::string> retract(const std::string& z) const override { return {"G53 G0 Z" + z}; }
  std::vector<std::string> park(const std::string& x, const std::string& y) const override {
    return {"G53 G0 X" + x + " Y" + y};
  }
  std::vector<std::string> length_on(bool, int offset) const override {
    return {"G43 H" + std::to_string(offset)};
  }
  std::string dwell(double seconds) const override { return "G4 P" + fmt(seconds, 3); }
  bool tcp_planned_in_program_axes() const override { return true; }
  std::string end() const override { return "M2"; }

  ReadWords read_words() const override {
    ReadWords r;
    r.g4_dwell = true;
    r.path_control = true;
    r.tcp_from_start = true;  // TCP is the machine's kinematics (xyzac-trt-kins ...)
    return r;
  }

  TemplateWords template_words() const override { return {true, {4, 40, 80}, {65}, {}, false}; }
  std::string template_refusal(char letter, double number) const override {
    // M70-M73 ("Save Modal State" ... "Save Autorestore Modal State"): M72 restores what an
    // M70 saved, and rs274 aborts there when none did (a footer's M72, in an audit); M73
    // saves for a subroutine's return. Neither is known to a template's block.
    if (letter == 'M' && (number == 72 || number == 73)) {
      return "LinuxCNC restores with M72 only a modal state M70 saved (rs274 aborts where none "
             "was) and M73 belongs in a subroutine; the program sets every mode it needs";
    }
    // The path blending is the machine file's: taxopt writes G64 P<blend_tolerance_mm> Q0 (G61
    // at 0) after the set-up and the report states it; a template's G64 P50 (or a bare G64,
    // no bound at all) would override it unseen.
    if (letter == 'G' && (number == 64 || number == 61 || number == 61.1)) {
      return "on LinuxCNC the path blending is gcode.blend_tolerance_mm's (taxopt writes G64 "
             "P<it> Q0, or G61 at 0, and the report states it); set that key instead";
    }
    return {};
  }
};

}  // namespace

const DialectRules& linuxcnc_rules() {
  static const LinuxCnc kRules;
  return kRules;
}

}  // namespace taxopt::gcode
