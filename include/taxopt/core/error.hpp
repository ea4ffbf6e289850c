#pragma once
/// @file The library's error type for bad input. Outcomes of the algorithms (no pose within
/// limits, verification failed) are returned as results with a status, not thrown.

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// Where in data a caller built in memory an error lies, for a program to read (a CL file's
/// errors carry its file and line as well): the operation (its index in
/// Toolpath::operations), the point (its index in that operation's points) and the field
/// ("Operation::tool.diameter_mm", "CLPoint::axis", "JobOptions::feed_mm_per_min"); each
/// empty where it does not apply.
struct ErrorPlace {
  std::optional<std::size_t> operation;
  std::optional<std::size_t> point;
  std::string field;
};

/// Bad input: a malformed file, an impossible option value. Carries the file and the
/// 1-based line (0 when no line applies) so that the CLI can print
/// `taxopt: error: FILE:LINE: what`, and where it applies the operation, point and field
/// (place()).
class TAXOPT_API InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, const std::string& what, ErrorPlace place = {});
  explicit InputError(const std::string& what, ErrorPlace place = {})
      : InputError("", 0, what, std::move(place)) {}

  const std::string& file() const noexcept { return file_; }
  int line() const noexcept { return line_; }
  /// The message without file and line.
  const std::string& message() const noexcept { return message_; }
  /// The operation, point and field the error is about, where it applies.
  const ErrorPlace& place() const noexcept { return place_; }

 private:
  std::string file_;
  int line_;
  std::string message_;
  ErrorPlace place_;
};

/// Formats `FILE:LINE: what` (parts left out when empty) for error lines.
TAXOPT_API std::string format_location(const std::string& file, int line, const std::string& what);

}  // namespace taxopt
