#pragma once
/// @file The CL file's lines as the reader sees them: logical lines over `$` continuations,
/// NX's listing lines, record words and their fields, APT numbers, the CAM system's dialect.

#include <string>
#include <utility>
#include <vector>

#include "taxopt/io/cl_file.hpp"
#include "util/text.hpp"

namespace taxopt::cl {

using detail::trim;

/// The text in upper case (ASCII).
std::string upper(std::string s);
/// A number as APT writes it (sign, digits, point, exponent), whole token; false otherwise.
bool parse_number(const std::string& token, double& out);
bool is_number_like(const std::string& token);
/// The fields of a record after its slash, split at commas, trimmed.
std::vector<std::string> split_args(const std::string& args);
/// A line of 3 or 6 numbers and nothing else ("7.4675, 5.8717, 1.8000").
bool is_point_line(const std::string& code);

/// A logical line: physical lines joined over `$` continuations.
struct LogicalLine {
  std::string raw;   // physical lines joined by '\n'
  std::string code;  // the record text with continuations joined and `$$` comments removed
  int line = 0;
  RecordKind kind = RecordKind::Record;
};

/// Major word of a record line, or "" when the line is no record.
std::string major_word(const std::string& code, std::string& args);
/// The file's logical lines; `line_end` and `final_line_end` say how its lines end.
std::vector<LogicalLine> split_logical(const std::string& text, const std::string& source,
                                       std::string& line_end, bool& final_line_end);
/// The lines NX's listing window puts around a CLSF.
bool is_listing_line(const std::string& code);
/// The CAM system a file's own structure names, and where: its first such record, and every
/// system's (a file that shows two is told apart where it matters: their CIRCLE senses).
struct DialectEvidence {
  ClDialect dialect = ClDialect::Generic;
  std::string evidence;  ///< "line 1: NX CLSF's TOOL PATH record"; empty for Generic
  struct Seen {
    ClDialect dialect;
    int line;
    std::string what;
  };
  std::vector<Seen> seen;
};
/// The first record that makes the file a turning file (MACHIN/...,TURN or LATHE, CATIA's
/// TOOLNO/n,TURN, a TURRET, MODE/TURN): its line and text; line 0 where there is none.
std::pair<int, std::string> turning_record(const std::vector<LogicalLine>& lines);
/// Recognises the CAM system from the records and header comments it writes in its own
/// structure, never from free text (docs/cl-files.md).
DialectEvidence detect_dialect(const std::vector<LogicalLine>& lines);
/// The sense in which a dialect's CIRCLE records run (docs/cl-files.md); Auto where nothing is
/// documented or measured.
ArcDirection documented_arc_direction(ClDialect dialect);

}  // namespace taxopt::cl
