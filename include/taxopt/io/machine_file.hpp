#pragma once
/// @file The machine file (TOML, CLI.md "Machine file"): kinematics, axis ranges and senses,
/// pivot, G-code settings.

#include <string>

#include "taxopt/kinematics/ac_machine.hpp"

namespace taxopt {

/// Controller dialect of the G-code. Only LinuxCNC is written in this version.
enum class GcodeDialect { LinuxCNC };
/// tcp: X Y Z are the tool tip in workpiece coordinates (the controller does TCP);
/// machine: X Y Z are the joint positions after the table rotation (CLI.md convention).
enum class GcodeMode { Tcp, Machine };
/// G94 units per minute, or G93 inverse time.
enum class FeedMode { UnitsPerMinute, InverseTime };

/// How G-code is written for a machine.
struct GcodeSettings {
  GcodeDialect dialect = GcodeDialect::LinuxCNC;
  GcodeMode mode = GcodeMode::Tcp;
  FeedMode feed_mode = FeedMode::UnitsPerMinute;
  /// Decimals of every coordinate and angle (0 to 8).
  int decimals = 4;
};

/// A machine: name, kinematics and how to write its G-code.
struct Machine {
  std::string name = "generic-ac-trt";
  std::string kinematics = "ac-table-table";
  ACMachined ac = default_ac_machine();
  GcodeSettings gcode;
};

/// The built-in machine of CLI.md: A in [-120, 120] deg, C continuous, LinuxCNC, TCP.
Machine default_machine();

/// Parses a machine file. Unknown keys, wrong types, missing sections, min > max are errors.
/// @throws InputError naming `source` and the line.
Machine parse_machine_toml(const std::string& text, const std::string& source);

/// Reads a machine file from disk. @throws InputError
Machine read_machine_file(const std::string& path);

}  // namespace taxopt
