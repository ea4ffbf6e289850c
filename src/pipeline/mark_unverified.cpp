// A program the verification failed, marked as such in its first lines (stages.hpp,
// mark_unverified).
#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <string>
#include <vector>

#include "pipeline/stages.hpp"

namespace taxopt::pipeline {

namespace {

std::vector<std::string> unverified_comments(const Run& run, const JobResult& res) {
  std::vector<std::string> comments = program_comments(run, res);
  comments.push_back("NOT VERIFIED: the verification failed (" +
                     std::to_string(res.problems.size()) +
                     " problems); a program written anyway is not to be run as it is");
  for (std::size_t i = 0; i < res.problems.size() && i < 10; ++i) {
    comments.push_back("FAILED: " + res.problems[i].substr(0, 200));
  }
  return comments;
}

int line_count(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

/// "G-code line N" in a message, N moved by `shift`.
std::string shifted_gcode_lines(const std::string& message, int shift) {
  static const std::string kWords = "G-code line ";
  std::string out;
  std::size_t from = 0;
  for (std::size_t at = message.find(kWords); at != std::string::npos;
       at = message.find(kWords, from)) {
    std::size_t end = at + kWords.size();
    while (end < message.size() && std::isdigit(static_cast<unsigned char>(message[end]))) ++end;
    out += message.substr(from, at + kWords.size() - from);
    const std::string digits = message.substr(at + kWords.size(), end - at - kWords.size());
    out += digits.empty() ? digits : std::to_string(std::stoi(digits) + shift);
    from = end;
  }
  return out + message.substr(from);
}

}  // namespace

void mark_unverified(const Run& run, const std::vector<PostedOperation>& posted, JobResult& res) {
  if (res.problems.empty() || res.gcode.text.empty()) return;
  // The same program with the failed checks named in its first lines (comments only: every
  // block and its line's place after them is as verified, shifted). Every line the program's
  // record and the findings name moves down with it: the writer's own (blocks, points,
  // template lines, joint-safe rapids) are the marked program's; the G-code lines the
  // verification and the time model found are shifted, in the findings' messages too, before
  // those are written into the program. (Before, only the text and the blocks were replaced:
  // read back with its verbatim lines, the marked program's feed blocks were stepped over,
  // and a finding's G-code line named another block.)
  // Each comment is one line (comment_text folds line ends): the marks add one line per
  // comment beyond the program's own.
  const int shift =
      static_cast<int>(unverified_comments(run, res).size() - program_comments(run, res).size());
  for (Finding& f : res.findings) {
    if (f.gcode_line) *f.gcode_line += shift;
    f.message = shifted_gcode_lines(f.message, shift);
  }
  for (std::vector<std::string>* list : {&res.problems, &res.safety_warnings, &res.warnings}) {
    for (std::string& m : *list) m = shifted_gcode_lines(m, shift);
  }
  GcodeProgram marked =
      write_gcode(posted, run.machine, res.gcode_units, unverified_comments(run, res));
  if (line_count(marked.text) - line_count(res.gcode.text) != shift) {
    throw std::logic_error("mark_unverified: the marks are not one line each");
  }
  GcodeProgram& g = res.gcode;
  g.text = std::move(marked.text);
  g.blocks = std::move(marked.blocks);
  g.emitted = std::move(marked.emitted);
  g.joint_safe_rapids = std::move(marked.joint_safe_rapids);
  g.verbatim_lines = std::move(marked.verbatim_lines);
  g.tool_calls = std::move(marked.tool_calls);
  if (g.time_from_line > 0) g.time_from_line += shift;
  for (JointPeak& p : g.tcp_joint_peaks) {
    if (p.velocity_line > 0) p.velocity_line += shift;
    if (p.accel_line > 0) p.accel_line += shift;
  }
}

}  // namespace taxopt::pipeline
