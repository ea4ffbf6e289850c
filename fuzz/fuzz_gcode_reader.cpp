// Any input: moves or an InputError, nothing else.
#include <cstdint>
#include <string>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    taxopt::read_gcode_moves(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ngc");
  } catch (const taxopt::InputError&) {
  }
  return 0;
}
