#pragma once
/// @file The record words the CL reader knows: one entry per word, with its meaning, the CAM
/// systems that write it and where that meaning comes from (docs/cl-files.md shows this table;
/// a test keeps the two equal). A word that is not here stops the reader (exit 2) unless the
/// user skips it by name (ClReadOptions::skip_records).

#include <string>
#include <vector>

namespace taxopt {

/// What a record word does to the program taxopt writes.
enum class ClWordMeaning {
  Motion,       ///< moves the tool: becomes CL points
  State,        ///< sets what the following motion means (feed, axis, tool, units, spindle ...)
  Frame,        ///< names the frame the coordinates are in
  Program,      ///< reaches the program where it stands (stop, dwell)
  Structure,    ///< opens or closes operations or the file
  Information,  ///< bears no motion and changes nothing the program needs (kept for the CL file
                ///< written back, JobResult::out_cls)
  Refused,      ///< known, not interpreted: the reader stops naming it
};

/// One record word.
struct ClWord {
  const char* word;  ///< the major word, upper case, inner blanks folded ("TOOL PATH")
  ClWordMeaning meaning;
  const char* what;      ///< what taxopt does with it, in one line
  const char* writers;   ///< the CAM systems known to write it
  const char* evidence;  ///< where its meaning comes from
  /// A user may skip it (ClReadOptions::skip_records): true for information, program and refused
  /// words whose skipping leaves the motion as it is; never for motion, state or frame words.
  bool skippable;
};

/// Every word the reader knows, in the order docs/cl-files.md lists them.
const std::vector<ClWord>& cl_words();

/// The entry of `major` (upper case, blanks folded), or nullptr.
const ClWord* find_cl_word(const std::string& major);

const char* to_string(ClWordMeaning meaning);

/// The table as docs/cl-files.md shows it (Markdown, one row per word).
std::string cl_words_markdown();

}  // namespace taxopt
