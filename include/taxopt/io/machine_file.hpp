#pragma once
/// @file The machine file (TOML, CLI.md "Machine file"): kinematics, axis ranges and senses,
/// pivot, G-code settings, read into a Machine (kinematics/machine.hpp).

#include <string>

#include "taxopt/core/export.hpp"
#include "taxopt/kinematics/machine.hpp"

namespace taxopt {

/// Parses a machine file. Unknown keys, wrong types, missing sections, min > max are errors.
/// @throws InputError naming `source` and the line.
TAXOPT_API Machine parse_machine_toml(const std::string& text, const std::string& source);

/// Reads a machine file from disk. @throws InputError
TAXOPT_API Machine read_machine_file(const std::string& path);

}  // namespace taxopt
