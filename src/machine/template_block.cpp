// The program template's blocks, checked by what they do (template_block.hpp).
#include "machine/template_block.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <set>
#include <utility>
#include <vector>

namespace taxopt {
namespace {

/// A block refused: why.
struct Refused {
  std::string why;
};
[[noreturn]] void refuse(const std::string& why) { throw Refused{why}; }

/// How a block is read: its dialect and the template key that holds it.
struct BlockRules {
  GcodeDialect dialect;
  bool siemens, heidenhain, parens, tool_change, work_offset, footer;
};

/// One word: a letter and its number ("G 64" too), or a Sinumerik identifier (FFWON).
struct Word {
  std::string letter, number;
};

bool g_is(const std::string& v, double want) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  return end && *end == '\0' && x == want;
}

bool has(const std::vector<Word>& words, const char* letter, double v) {
  for (const Word& w : words) {
    if (w.letter == letter && g_is(w.number, v)) return true;
  }
  return false;
}

/// The code outside comments, upper case; "{tool}" kept as one token.
std::string code_of(const std::string& block, const BlockRules& r) {
  std::string code;
  int depth = 0;
  for (std::size_t i = 0; i < block.size(); ++i) {
    const char ch = block[i];
    if (ch == '\n' || ch == '\r') refuse("holds a line break: one block per string");
    if (r.parens && ch == '(') {
      if (depth > 0) refuse("nests a comment");
      ++depth;
      continue;
    }
    if (r.parens && ch == ')') {
      if (depth == 0) refuse("closes a comment it did not open");
      --depth;
      continue;
    }
    if (depth > 0) continue;
    if (ch == ';') break;
    if (static_cast<unsigned char>(ch) < 0x20 || static_cast<unsigned char>(ch) > 0x7e) {
      refuse("holds a character outside printable ASCII");
    }
    code += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  }
  if (depth > 0) refuse("opens a comment it does not close");
  for (const char bad : std::string("%[]#=<>*/+^&!?$@\"'\\|")) {
    if (code.find(bad) != std::string::npos) {
      refuse(std::string("holds '") + bad +
             "': expressions, parameters, subroutine calls and program marks are not "
             "written as they are");
    }
  }
  return code;
}

/// CYCLE832's arguments after its name at `e`: numbers and names, nothing that nests; where
/// they end.
std::size_t cycle832_end(const std::string& code, std::size_t e) {
  std::size_t k = e;
  while (k < code.size() && std::isspace(static_cast<unsigned char>(code[k]))) ++k;
  if (k >= code.size() || code[k] != '(') return e;
  const std::size_t close = code.find(')', k);
  if (close == std::string::npos) refuse("opens CYCLE832( without closing it");
  for (std::size_t q = k + 1; q < close; ++q) {
    const char d = code[q];
    if (!(std::isalnum(static_cast<unsigned char>(d)) || d == '_' || d == '.' || d == ',' ||
          d == '-' || std::isspace(static_cast<unsigned char>(d)))) {
      refuse("holds '" + std::string(1, d) + "' in CYCLE832's arguments");
    }
  }
  return close + 1;
}

/// A Sinumerik identifier at `i` (FFWON, CYCLE832(...)) as one word, where it is one; the end.
std::size_t siemens_word(const std::string& code, std::size_t i, std::vector<Word>& words) {
  std::size_t e = i + 1;
  while (e < code.size() && (std::isalnum(static_cast<unsigned char>(code[e])) || code[e] == '_')) {
    ++e;
  }
  const std::string id = code.substr(i, e - i);
  const bool letter_number = id.size() >= 2 && std::all_of(id.begin() + 1, id.end(), [](char d) {
                               return std::isdigit(static_cast<unsigned char>(d)) != 0;
                             });
  if (letter_number || id.size() <= 1) return i;
  static const std::set<std::string> kSiemens = {"FFWON",   "FFWOF",    "SOFT",     "BRISK",
                                                 "COMPCAD", "COMPCURV", "COMPSURF", "COMPOF",
                                                 "UPATH",   "SPATH",    "CYCLE832"};
  if (!kSiemens.count(id)) {
    refuse("holds " + id +
           ", which is not on the list of Sinumerik words a template "
           "may hold (FFWON, FFWOF, SOFT, BRISK, COMPCAD, COMPCURV, "
           "COMPSURF, COMPOF, UPATH, SPATH, CYCLE832(...))");
  }
  if (id == "CYCLE832") e = cycle832_end(code, e);
  words.push_back({id, ""});
  return e;
}

/// The block's words: a letter and its number ("G 64" too); Sinumerik identifiers.
std::vector<Word> words_of(const std::string& code, const BlockRules& r) {
  std::vector<Word> words;
  for (std::size_t i = 0; i < code.size();) {
    const char c = code[i];
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
      continue;
    }
    if (!std::isalpha(static_cast<unsigned char>(c))) {
      refuse(std::string("holds '") + c + "' where a word letter belongs");
    }
    if (code.compare(i, 7, "T{TOOL}") == 0) {
      if (!r.tool_change) refuse("calls a tool: only the tool_change template does");
      words.push_back({"T", "{TOOL}"});
      i += 7;
      continue;
    }
    if (r.siemens) {
      if (const std::size_t e = siemens_word(code, i, words); e != i) {
        i = e;
        continue;
      }
    }
    std::size_t e = i + 1;
    while (e < code.size() && std::isspace(static_cast<unsigned char>(code[e]))) ++e;
    std::string v;
    while (e < code.size() && (std::isdigit(static_cast<unsigned char>(code[e])) ||
                               code[e] == '.' || code[e] == '-')) {
      v += code[e++];
    }
    if (v.empty() || v == "-" || v == ".") {
      refuse(std::string("holds the letter ") + c + " without a number");
    }
    words.push_back({std::string(1, c), v});
    i = e;
  }
  return words;
}

/// One work offset code: G54 ... G59, G59.1 ... G59.3 (LinuxCNC), G54.1 P1 ... P300 (Fanuc,
/// Haas), G505 ... G599 (Sinumerik's settable frames).
void check_work_offset(const std::vector<Word>& words, bool siemens) {
  bool ok = false;
  if (words.size() == 1 && words[0].letter == "G") {
    for (double g : {54.0, 55.0, 56.0, 57.0, 58.0, 59.0, 59.1, 59.2, 59.3}) {
      ok = ok || g_is(words[0].number, g);
    }
    const double x = std::strtod(words[0].number.c_str(), nullptr);
    ok = ok || (siemens && x >= 505.0 && x <= 599.0 && x == std::floor(x));
  } else if (words.size() == 2 && words[0].letter == "G" && g_is(words[0].number, 54.1) &&
             words[1].letter == "P") {
    const double p = std::strtod(words[1].number.c_str(), nullptr);
    ok = p >= 1.0 && p <= 300.0 && p == std::floor(p);
  }
  if (!ok) refuse("is no work offset code (G54 ... G59.3, G54.1 P1 ... P300, G505 ... G599)");
}

/// A footer's block that homes the rotaries (G28 with G91/G90 and rotary words of 0 only) or
/// restores G90 alone: true; G28 with anything more is refused.
bool footer_homes(const std::vector<Word>& words) {
  bool homes = false, only_homing = !words.empty(), only_g90 = !words.empty();
  for (const Word& w : words) {
    if (w.letter == "G" && g_is(w.number, 28.0)) homes = true;
    const bool g_ok =
        w.letter == "G" && (g_is(w.number, 28.0) || g_is(w.number, 91.0) || g_is(w.number, 90.0));
    const bool rotary_zero =
        (w.letter == "A" || w.letter == "B" || w.letter == "C") && g_is(w.number, 0.0);
    only_homing = only_homing && (g_ok || rotary_zero);
    only_g90 = only_g90 && w.letter == "G" && g_is(w.number, 90.0);
  }
  if ((homes && only_homing) || only_g90) return true;
  if (homes) {
    refuse(
        "holds G28 with more than rotary words of 0; a footer may home the rotary axes "
        "only (G91 G28 B0. C0.)");
  }
  return false;
}

/// An M code: no spindle, coolant, tool or program end (taxopt writes them); a subprogram call
/// in the tool change only; on LinuxCNC no restore of a modal state.
void check_m(const Word& w, bool tool_change, GcodeDialect dialect) {
  const std::string word = w.letter + w.number;
  const double x = std::strtod(w.number.c_str(), nullptr);
  if (!(x >= 0.0 && x <= 9999.0) || x != std::floor(x)) {
    refuse("holds " + word + ", no M code (a whole number up to 9999)");
  }
  const long m = static_cast<long>(x);
  const bool state = m == 2 || m == 3 || m == 4 || m == 5 || m == 7 || m == 8 || m == 9 ||
                     m == 30 || (m == 6 && !tool_change);
  if (state) {
    refuse("holds " + word +
           ": the spindle, coolant, tool and program end are written by taxopt (the CL "
           "file, the job's options, [defaults], gcode.coolant)");
  }
  // LinuxCNC's M70-M73 (docs: "Save Modal State" ... "Save Autorestore Modal State"): M72
  // restores what an M70 saved, and rs274 aborts there when none did (a footer's M72, in an
  // audit); M73 saves for a subroutine's return. Neither is known to a template's block.
  if (dialect == GcodeDialect::LinuxCNC && (m == 72 || m == 73)) {
    refuse("holds " + word +
           ": LinuxCNC restores with M72 only a modal state M70 saved (rs274 aborts where none "
           "was) and M73 belongs in a subroutine; the program sets every mode it needs");
  }
  if ((m == 97 || m == 98 || m == 99 || m == 198) && !tool_change) {
    refuse("holds " + word +
           ": a subprogram's blocks are not known to the check (put them in the template; "
           "the tool change alone may call the machine's own macro)");
  }
}

/// A G code of the list, each in the dialects that know it.
void check_g(const Word& w, const BlockRules& r) {
  static const double kAllowed[] = {4, 40, 80, 61, 61.1, 64, 5.1, 8, 187, 642, 641, 60};
  bool ok = false;
  for (double g : kAllowed) ok = ok || g_is(w.number, g);
  if (g_is(w.number, 65) && r.tool_change) ok = true;
  if (g_is(w.number, 17) && r.tool_change && r.heidenhain) ok = true;  // TNC: T n G17
  if ((g_is(w.number, 5.1) || g_is(w.number, 8)) && r.dialect != GcodeDialect::Fanuc &&
      r.dialect != GcodeDialect::Haas) {
    ok = false;
  }
  if (g_is(w.number, 187) && r.dialect != GcodeDialect::Haas) ok = false;
  if (r.heidenhain && !(g_is(w.number, 4) || g_is(w.number, 40) || g_is(w.number, 17))) {
    ok = false;  // a TNC in ISO: dwell and radius compensation off only
  }
  if ((g_is(w.number, 642) || g_is(w.number, 641) || g_is(w.number, 60)) && !r.siemens) {
    ok = false;
  }
  // LinuxCNC's path blending is the machine file's: taxopt writes G64 P<blend_tolerance_mm>
  // Q0 (G61 at 0) after the set-up and the report states it; a template's G64 P50 (or a bare
  // G64, no bound at all) would override it unseen.
  if (r.dialect == GcodeDialect::LinuxCNC &&
      (g_is(w.number, 64) || g_is(w.number, 61) || g_is(w.number, 61.1))) {
    refuse("holds " + w.letter + w.number +
           ": on LinuxCNC the path blending is gcode.blend_tolerance_mm's (taxopt writes G64 "
           "P<it> Q0, or G61 at 0, and the report states it); set that key instead");
  }
  if (!ok) {
    refuse("holds " + w.letter + w.number +
           ", a motion, mode or frame code taxopt writes itself or does not know "
           "(a template may hold G4 P, G40, G61, G61.1, G64, G80; Fanuc/Haas G5.1, G8; "
           "Haas G187; Sinumerik G60, G641, G642; use the [gcode] keys)");
  }
}

/// Every word of a block that is no work offset and no footer's homing.
void check_words(const std::vector<Word>& words, const BlockRules& r) {
  // Codes that take P Q E L parameters.
  bool takes_parameters = false;
  for (const auto& [letter, v] : std::vector<std::pair<const char*, double>>{{"G", 4},
                                                                             {"G", 64},
                                                                             {"G", 5.1},
                                                                             {"G", 8},
                                                                             {"G", 187},
                                                                             {"G", 65},
                                                                             {"M", 98},
                                                                             {"M", 66},
                                                                             {"M", 62},
                                                                             {"M", 63},
                                                                             {"M", 64},
                                                                             {"M", 65}}) {
    takes_parameters = takes_parameters || has(words, letter, v);
  }
  for (const Word& w : words) {
    if (w.letter.size() > 1) continue;  // a Sinumerik word of the list
    const char c = w.letter[0];
    const std::string word = w.letter + w.number;
    if (std::string("XYZABCUVWIJKR").find(c) != std::string::npos) {
      refuse("moves an axis (" + std::string(1, c) + "); taxopt writes every move itself");
    }
    if (c == 'T') {
      if (!r.tool_change) refuse("holds " + word + ": only the tool_change template calls a tool");
      if (w.number != "{TOOL}") refuse("calls tool " + word + ": the template calls T{tool}");
      continue;
    }
    if (c == 'M') {
      check_m(w, r.tool_change, r.dialect);
      continue;
    }
    if (c == 'G') {
      check_g(w, r);
      continue;
    }
    if ((c == 'P' || c == 'Q' || c == 'E' || c == 'L') && takes_parameters) continue;
    refuse("holds " + word + ", a word a template may not hold (" + std::string(1, c) + ": " +
           (c == 'H' || c == 'D'   ? "a tool offset, written by taxopt"
            : c == 'F' || c == 'S' ? "feed and spindle speed are taxopt's"
            : c == 'N' || c == 'O' ? "block and program numbers are taxopt's"
                                   : "not on the list") +
           ")");
  }
}

}  // namespace

std::string template_block_problem(const std::string& block, const std::string& what,
                                   GcodeDialect dialect, bool footer) {
  BlockRules r{};
  r.dialect = dialect;
  r.siemens = dialect == GcodeDialect::Siemens;
  r.heidenhain = dialect == GcodeDialect::Heidenhain;
  r.parens = !r.siemens && !r.heidenhain;  // ( ) comments
  r.tool_change = what == "gcode.tool_change";
  r.work_offset = what == "gcode.work_offset";
  r.footer = footer;
  try {
    const std::vector<Word> words = words_of(code_of(block, r), r);
    if (r.work_offset) {
      check_work_offset(words, r.siemens);
      return {};
    }
    if (r.footer && footer_homes(words)) return {};
    check_words(words, r);
  } catch (const Refused& e) {
    return e.why;
  }
  return {};
}

}  // namespace taxopt
