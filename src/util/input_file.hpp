#pragma once
/// @file The whole of an input file that must be a regular file of a bounded size: the CL file,
/// the machine file, a LinuxCNC configuration (a FIFO would hang the reader, /dev/zero fill
/// memory: tests/test_bad_input.cpp).

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "taxopt/core/error.hpp"

namespace taxopt::detail {

/// The bytes of `path`. InputError naming the file where it is no regular file ("not a regular
/// file (`kind` is one)"), larger than `max_bytes` (`too_large`), or cannot be opened or read
/// ("cannot open `name`").
inline std::string read_input_file(const std::string& path, std::uintmax_t max_bytes,
                                   const std::string& kind, const std::string& name,
                                   const std::string& too_large) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, 0, "not a regular file (" + kind + " is one)");
  }
  if (std::filesystem::file_size(path, ec) > max_bytes) throw InputError(path, 0, too_large);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open " + name);
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "cannot read " + name);
  return ss.str();
}

}  // namespace taxopt::detail
