// The CL records that stand between moves: stops, dwells, text, operations (reader.hpp).
#include <algorithm>
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

void Reader::insert(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // SOLIDWORKS CAM's INSERT/[HOLDER=C40-16ERP412] 16MM CRB 2FL 32 LOC: a bracketed note to
  // the operator, no block: dropped with a note. Any other text is what the post would write
  // into the program as it stands (INSERT/Stock Size X135. Y135. Z30. reads as a move):
  // refused, as unchecked text.
  const std::string text = trim(args_text);
  if (!text.empty() && (text.front() == '[' || text.front() == '(')) {
    tp_.warnings.push_back(format_location(
        source_, line, "INSERT/" + text.substr(0, 60) + ": an operator's note, not written"));
    skipped(major);
  } else {
    fail(line, "INSERT/" + args_text.substr(0, 60) +
                   ": text for the controller, which taxopt does not pass unchecked into a "
                   "program; --skip-record INSERT drops it");
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
