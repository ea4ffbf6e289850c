// Any input, in each dialect's reader: moves or an InputError, nothing else.
#include <cstdint>
#include <string>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (taxopt::GcodeDialect d :
       {taxopt::GcodeDialect::LinuxCNC, taxopt::GcodeDialect::Fanuc, taxopt::GcodeDialect::Siemens,
        taxopt::GcodeDialect::Heidenhain, taxopt::GcodeDialect::Haas}) {
    for (char tilt : {'A', 'B'}) {
      try {
        taxopt::read_gcode_moves(text, "fuzz.ngc", d, {}, tilt);
      } catch (const taxopt::InputError&) {
      }
    }
  }
  return 0;
}
