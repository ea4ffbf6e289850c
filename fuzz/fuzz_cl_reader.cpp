// Any input: the reader either returns a toolpath or throws InputError (never crashes, hangs
// or throws anything else); a toolpath it returns writes back to exactly the input.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const taxopt::Toolpath tp = taxopt::parse_cl(text, "fuzz.cls");
    // The round trip is exact except for line ends: a lone '\r' or mixed CRLF/LF files are
    // normalised to the file's dominant convention.
    if (text.find('\r') == std::string::npos && taxopt::format_cl(tp, tp.operations) != text) {
      std::abort();
    }
  } catch (const taxopt::InputError&) {
  }
  return 0;
}
