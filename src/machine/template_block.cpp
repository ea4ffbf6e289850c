// The program template's blocks, checked by what they do (template_block.hpp).
#include "machine/template_block.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "dialects/dialect_rules.hpp"

namespace taxopt {
namespace {

/// A block refused: why.
struct Refused {
  std::string why;
};
[[noreturn]] void refuse(const std::string& why) { throw Refused{why}; }

/// How a block is read: its dialect's words and the template key that holds it.
struct BlockRules {
  const gcode::DialectRules* dialect;
  gcode::TemplateWords words;
  bool tool_change, work_offset, footer;
};

/// One word: a letter and its number ("G 64" too), or a Sinumerik identifier (FFWON).
struct Word {
  std::string letter, number;
};

/// The number `v` is, where all of it is one.
std::optional<double> number_of(const std::string& v) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (!end || *end != '\0') return std::nullopt;
  return x;
}

bool g_is(const std::string& v, double want) {
  const std::optional<double> x = number_of(v);
  return x && *x == want;
}

bool has(const std::vector<Word>& words, const char* letter, double v) {
  for (const Word& w : words) {
    if (w.letter == letter && g_is(w.number, v)) return true;
  }
  return false;
}

/// LinuxCNC's active comments that act (issue 63.12: a header's "(ABORT, x)" stopped rs274
/// there): ABORT ends the program, PROBEOPEN / LOGOPEN / LOGAPPEND open files on the machine.
void check_active_comment(const std::string& comment, const BlockRules& r) {
  if (r.dialect->id() != GcodeDialect::LinuxCNC) return;
  std::string head;
  for (char ch : comment) {
    if (ch == ',') break;
    if (!std::isspace(static_cast<unsigned char>(ch))) {
      head += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    }
  }
  for (const char* word : {"ABORT", "PROBEOPEN", "LOGOPEN", "LOGAPPEND"}) {
    if (head == word && comment.find(',') != std::string::npos) {
      refuse(std::string("holds the comment (") + word +
             ", ...), which LinuxCNC acts on (ABORT ends the program there; the others open "
             "files on the machine)");
    }
  }
}

/// The code outside comments, upper case; "{tool}" kept as one token.
std::string code_of(const std::string& block, const BlockRules& r) {
  std::string code, comment;
  int depth = 0;
  for (std::size_t i = 0; i < block.size(); ++i) {
    const char ch = block[i];
    if (ch == '\n' || ch == '\r') refuse("holds a line break: one block per string");
    if (r.words.paren_comments && ch == '(') {
      if (depth > 0) refuse("nests a comment");
      ++depth;
      continue;
    }
    if (r.words.paren_comments && ch == ')') {
      if (depth == 0) refuse("closes a comment it did not open");
      --depth;
      check_active_comment(comment, r);
      comment.clear();
      continue;
    }
    if (depth > 0) {
      comment += ch;
      if (ch == '%' && r.words.tape) {
        refuse("holds '%' in a comment: the controller reads its program from one % to the next");
      }
      continue;
    }
    if (ch == ';') {
      if (r.words.tape) refuse("holds ';': no comment on this controller (use parentheses)");
      break;
    }
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

/// A word of several letters at `i` (Sinumerik's FFWON, CYCLE832(...)) as one word, where it
/// is one; the end.
std::size_t long_word(const std::string& code, std::size_t i, const BlockRules& r,
                      std::vector<Word>& words) {
  std::size_t e = i + 1;
  while (e < code.size() && (std::isalnum(static_cast<unsigned char>(code[e])) || code[e] == '_')) {
    ++e;
  }
  const std::string id = code.substr(i, e - i);
  const bool letter_number = id.size() >= 2 && std::all_of(id.begin() + 1, id.end(), [](char d) {
                               return std::isdigit(static_cast<unsigned char>(d)) != 0;
                             });
  if (letter_number || id.size() <= 1) return i;
  const std::vector<std::string>& known = r.words.long_words;
  if (std::find(known.begin(), known.end(), id) == known.end()) {
    std::string list;
    for (const std::string& k : known) {
      list += (list.empty() ? "" : ", ") + k + (k == "CYCLE832" ? "(...)" : "");
    }
    refuse("holds " + id + ", which is not on the list of " + r.dialect->name() +
           " words a template may hold (" + list + ")");
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
    if (!r.words.long_words.empty()) {
      if (const std::size_t e = long_word(code, i, r, words); e != i) {
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

/// One work offset code of the dialect: G54 ... G59, G59.1 ... G59.3 (LinuxCNC), G54.1 P1 ...
/// P300 (Fanuc, Haas), G505 ... G599 (Sinumerik's settable frames). LinuxCNC has no G54.1 P
/// (rs274: an unknown G code, issue 63.12), Fanuc and Haas no G59.1.
void check_work_offset(const std::vector<Word>& words, const BlockRules& r) {
  const bool lcnc = r.dialect->id() == GcodeDialect::LinuxCNC;
  bool ok = false;
  if (words.size() == 1 && words[0].letter == "G") {
    for (double g : {54.0, 55.0, 56.0, 57.0, 58.0, 59.0}) ok = ok || g_is(words[0].number, g);
    for (double g : {59.1, 59.2, 59.3}) ok = ok || (lcnc && g_is(words[0].number, g));
    const double x = std::strtod(words[0].number.c_str(), nullptr);
    ok = ok || (r.words.settable_frames && x >= 505.0 && x <= 599.0 && x == std::floor(x));
  } else if (!lcnc && !r.words.settable_frames && words.size() == 2 && words[0].letter == "G" &&
             g_is(words[0].number, 54.1) && words[1].letter == "P") {
    const double p = std::strtod(words[1].number.c_str(), nullptr);
    ok = p >= 1.0 && p <= 300.0 && p == std::floor(p);
  }
  if (!ok) {
    refuse(std::string("is no work offset code of ") + r.dialect->name() +
           (lcnc                      ? " (G54 ... G59, G59.1 ... G59.3)"
            : r.words.settable_frames ? " (G54 ... G59, G505 ... G599)"
                                      : " (G54 ... G59, G54.1 P1 ... P300)"));
  }
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
void check_m(const Word& w, bool tool_change, const gcode::DialectRules& dialect) {
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
           ": the spindle, coolant, tool and program end are written by taxopt (from the CL "
           "file, the job's options and the machine's defaults and coolant: "
           "Machine::default_tool_number, default_spindle_rpm, gcode.program.coolant)");
  }
  if (const std::string why = dialect.template_refusal('M', x); !why.empty()) {
    refuse("holds " + word + ": " + why);
  }
  if ((m == 97 || m == 98 || m == 99 || m == 198) && !tool_change) {
    refuse("holds " + word +
           ": a subprogram's blocks are not known to the check (put them in the template; "
           "the tool change alone may call the machine's own macro)");
  }
}

/// A G code of the dialect's list (DialectRules::template_words).
void check_g(const Word& w, const BlockRules& r) {
  if (const std::optional<double> x = number_of(w.number)) {
    if (const std::string why = r.dialect->template_refusal('G', *x); !why.empty()) {
      refuse("holds " + w.letter + w.number + ": " + why);
    }
  }
  bool ok = false;
  for (double g : r.words.g_codes) ok = ok || g_is(w.number, g);
  for (double g : r.words.tool_change_g_codes) ok = ok || (r.tool_change && g_is(w.number, g));
  if (!ok) {
    refuse("holds " + w.letter + w.number +
           ", a motion, mode or frame code taxopt writes itself or does not know "
           "(a template may hold G4 P, G40, G61, G61.1, G64, G80; Fanuc/Haas G5.1, G8; "
           "Haas G187; Sinumerik G60, G641, G642; the others are the machine's G-code settings, "
           "Machine::gcode, a machine file's [gcode])");
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
      check_m(w, r.tool_change, *r.dialect);
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
  r.dialect = &gcode::rules_of(dialect);
  r.words = r.dialect->template_words();
  r.tool_change = what == "gcode.tool_change";
  r.work_offset = what == "gcode.work_offset";
  r.footer = footer;
  try {
    const std::vector<Word> words = words_of(code_of(block, r), r);
    if (r.work_offset) {
      check_work_offset(words, r);
      return {};
    }
    if (r.footer && footer_homes(words)) return {};
    check_words(words, r);
  } catch (const Refused& e) {
    return e.why;
  }
  return {};
}

bool program_name_characters_ok(const std::string& name) {
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-';
  });
}

}  // namespace taxopt
