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

}  // namespace

void Reader::insert(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // APT's INSERT passes its text to the controller as it stands (ISO 4343's post-processor
  // statements). What SOLIDWORKS CAM writes with it is text for the operator:
  // INSERT/[HOLDER=C40-16ERP412] 16MM CRB 2FL 32 LOC, a bracketed note, dropped with a note;
  // INSERT/Stock Size X135. Y135. Z30., prose no controller reads as a block (S, then 'tock'),
  // written as a comment where it stands. Text made only of address words (INSERT/M00,
  // INSERT/G54 G90) is code for the controller: taxopt does not pass code it has not
  // interpreted, so that is refused.
  const std::string text = trim(args_text);
  const std::string shown = "INSERT/" + text.substr(0, 60);
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
      fail(line, shown + ": holds a character outside printable ASCII");
    }
  }
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
