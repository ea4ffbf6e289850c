// Any input: a machine or an InputError, nothing else.
#include <cstdint>
#include <string>

#include "taxopt/core/error.hpp"
#include "taxopt/io/machine_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    taxopt::parse_machine_toml(std::string(reinterpret_cast<const char*>(data), size), "fuzz.toml");
  } catch (const taxopt::InputError&) {
  }
  return 0;
}
