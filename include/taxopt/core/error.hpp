#pragma once
/// @file The library's error type for bad input. Outcomes of the algorithms (no pose within
/// limits, verification failed) are returned as results with a status, not thrown.

#include <stdexcept>
#include <string>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// Bad input: a malformed file, an impossible option value. Carries the file and the
/// 1-based line (0 when no line applies) so that the CLI can print
/// `taxopt: error: FILE:LINE: what`.
class TAXOPT_API InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, const std::string& what);
  explicit InputError(const std::string& what) : InputError("", 0, what) {}

  const std::string& file() const noexcept { return file_; }
  int line() const noexcept { return line_; }
  /// The message without file and line.
  const std::string& message() const noexcept { return message_; }

 private:
  std::string file_;
  int line_;
  std::string message_;
};

/// Formats `FILE:LINE: what` (parts left out when empty) for error lines.
TAXOPT_API std::string format_location(const std::string& file, int line, const std::string& what);

}  // namespace taxopt
