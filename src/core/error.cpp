#include "taxopt/core/error.hpp"

#include "taxopt/core/option_names.hpp"

namespace taxopt {

std::string format_location(const std::string& file, int line, const std::string& what) {
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) out += ":" + std::to_string(line);
    out += ": ";
  }
  return out + what;
}

InputError::InputError(std::string file, int line, const std::string& what, ErrorPlace place)
    : std::runtime_error(format_location(file, line, what)),
      file_(std::move(file)),
      line_(line),
      message_(what),
      place_(std::move(place)) {}

std::string option_name(const OptionNames& names, const std::string& field) {
  const auto it = names.find(field);
  return it == names.end() ? field : it->second;
}

}  // namespace taxopt
