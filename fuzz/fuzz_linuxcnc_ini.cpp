// Any INI (and HAL file, after a line "%%HAL%%"): a machine file that reads back, or an
// InputError, nothing else.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "taxopt/core/error.hpp"
#include "support/linuxcnc_ini.hpp"
#include "taxopt/io/machine_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = [] {
    const auto d =
        std::filesystem::temp_directory_path() / ("taxopt-fuzz-ini-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  std::string ini(reinterpret_cast<const char*>(data), size), hal;
  const std::size_t at = ini.find("%%HAL%%\n");
  if (at != std::string::npos) {
    hal = ini.substr(at + 8);
    ini.erase(at);
  }
  std::ofstream(dir / "m.ini", std::ios::binary) << ini;
  std::ofstream(dir / "m.hal", std::ios::binary) << hal;
  taxopt::ImportedMachine imported;
  try {
    imported = taxopt::machine_from_linuxcnc_ini((dir / "m.ini").string());
  } catch (const taxopt::InputError&) {
    return 0;
  }
  // What the importer writes is a machine file taxopt reads.
  try {
    taxopt::parse_machine_toml(imported.toml, "imported.toml");
  } catch (const taxopt::InputError&) {
    __builtin_trap();
  }
  return 0;
}
