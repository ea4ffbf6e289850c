// The CL records that stand between moves: stops, dwells, text, operations (reader.hpp).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "cl/reader.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt::cl {

void Reader::stop(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  ProgramEvent e;
  e.kind = major == "STOP" ? ProgramEvent::Kind::Stop : ProgramEvent::Kind::OptionalStop;
  add_event(e, line);
}

void Reader::delay(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  double sec = 0.0;
  if (args.size() != 1 || !parse_number(args[0], sec) || !(sec > 0.0 && sec <= 3600.0)) {
    fail(line,
         "DELAY expects a dwell in seconds within (0, 3600] (DELAY/REV,n is not "
         "interpreted)");
  }
  ProgramEvent e;
  e.kind = ProgramEvent::Kind::Dwell;
  e.dwell_s = sec;
  add_event(e, line);
}

namespace {

/// Whether every space-separated token of `text` is an NC address word (a letter and a number:
/// M00, G54, X135.): code the CAM meant the controller to run.
bool all_nc_words(const std::string& text) {
  std::istringstream in(text);
  std::string token;
  bool any = false;
  while (in >> token) {
    any = true;
    if (token.size() < 2 || !std::isalpha(static_cast<unsigned char>(token[0]))) return false;
    for (std::size_t k = 1; k < token.size(); ++k) {
      const char c = token[k];
      if (!std::isdigit(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '+') {
        return false;
      }
    }
  }
  return any;
}

/// An INSERT's text with its operator's notes, (...) and [...], taken out: `code` what stands
/// outside them, `notes` their contents joined by "; ". A bracket left open stays in `code`.
struct InsertParts {
  std::string code, notes;
};

InsertParts split_notes(const std::string& text) {
  InsertParts p;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    const char close = c == '(' ? ')' : c == '[' ? ']' : '\0';
    const std::size_t end = close ? text.find(close, k + 1) : std::string::npos;
    if (end == std::string::npos) {
      p.code += c;
      continue;
    }
    if (!p.notes.empty()) p.notes += "; ";
    p.notes += trim(text.substr(k + 1, end - k - 1));
    p.code += ' ';
    k = end;
  }
  p.code = trim(p.code);
  return p;
}

/// The first M word of `code` that stops or ends the program (M0, M1, M2, M30, M60, with any
/// leading zeros), "" when it holds none.
std::string stop_word_in(const std::string& code) {
  std::istringstream in(code);
  std::string token;
  while (in >> token) {
    if (token.size() < 2 || std::toupper(static_cast<unsigned char>(token[0])) != 'M') continue;
    if (!std::all_of(token.begin() + 1, token.end(),
                     [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
      continue;
    }
    const std::size_t digits = token.size() - 1;
    if (digits > 4) continue;
    const int value = std::stoi(token.substr(1));
    if (value == 0 || value == 1 || value == 2 || value == 30 || value == 60) return token;
  }
  return "";
}

}  // namespace

bool Reader::insert_stop(const std::string& text, const std::string& shown, int line) {
  const InsertParts parts = split_notes(text);
  const std::string word = stop_word_in(parts.code);
  if (word.empty()) return false;
  const int value = std::stoi(word.substr(1));
  if (upper(parts.code) != upper(word) || value > 1) {
    fail(line, shown + ": holds " + word +
                   ", a program stop or end, among other text; taxopt writes a stop as it "
                   "means only where it stands alone (INSERT/M00 (NOTE), or STOP / OPSTOP), "
                   "and does not drop it unasked (" +
                   options_.name_of("skip_records") + " INSERT drops every INSERT)");
  }
  if (!parts.notes.empty()) {
    ProgramEvent note;
    note.kind = ProgramEvent::Kind::Comment;
    note.text = parts.notes;
    add_event(note, line);
  }
  ProgramEvent e;
  e.kind = value == 0 ? ProgramEvent::Kind::Stop : ProgramEvent::Kind::OptionalStop;
  add_event(e, line);
  notice(line, shown + ": written as " + (value == 0 ? "M0" : "M1") +
                   (parts.notes.empty() ? "" : ", its note as a comment before it"));
  return true;
}

void Reader::insert(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // APT's INSERT passes its text to the controller as it stands (ISO 4343's post-processor
  // statements). What SOLIDWORKS CAM writes with it is text for the operator:
  // INSERT/[HOLDER=C40-16ERP412] 16MM CRB 2FL 32 LOC, a bracketed note, dropped with a note;
  // INSERT/Stock Size X135. Y135. Z30., prose no controller reads as a block (S, then 'tock'),
  // written as a comment where it stands. A program stop, M00 or M01, alone or beside an
  // operator's note (INSERT/M00 (REMOVE CLAMP), INSERT/[CHECK PART] M01), is written as STOP or
  // OPSTOP would be, the note as a comment before it; a stop or end among other text is
  // refused (a stop dropped or commented out runs the program on past the operator). Other
  // text made only of address words (INSERT/G54 G90) is code for the controller: taxopt does
  // not pass code it has not interpreted, so that is refused.
  const std::string text = trim(args_text);
  const std::string shown = "INSERT/" + text.substr(0, 60);
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
      fail(line, shown + ": holds a character outside printable ASCII");
    }
  }
  if (text.size() <= 200 && insert_stop(text, shown, line)) return;
  if (!text.empty() && (text.front() == '[' || text.front() == '(')) {
    tp_.warnings.push_back(
        format_location(source_, line, shown + ": an operator's note, not written"));
    skipped(major);
  } else if (text.empty() || all_nc_words(text)) {
    fail(line, shown +
                   ": code for the controller, which taxopt does not pass uninterpreted into "
                   "a program; " +
                   options_.name_of("skip_records") + " INSERT drops it");
  } else if (text.size() > 200) {
    fail(line, "INSERT text of " + std::to_string(text.size()) +
                   " characters: longer than the 200 a comment block is written with");
  } else {
    ProgramEvent e;
    e.kind = ProgramEvent::Kind::Comment;
    e.text = text;
    add_event(e, line);
    notice(line, shown + ": text for the operator, written as a comment where it stands");
  }
}

void Reader::fini(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  finished_line_ = line;
}

void Reader::tool_path(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  op_ = -1;
  in_block_ = true;
  pending_name_ = args.empty() ? std::string() : args[0];
  for (std::size_t k = 1; k + 1 < args.size(); ++k) {
    if (upper(args[k]) == "TOOL") tool_.name = args[k + 1];
  }
}

void Reader::end_of_path(const ClRecordArgs&) {
  op_ = -1;
  in_block_ = false;
}

}  // namespace taxopt::cl
