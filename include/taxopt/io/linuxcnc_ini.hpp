#pragma once
/// @file A LinuxCNC configuration (INI and the HAL files it names) turned into a taxopt
/// machine file: `taxopt machine --from-linuxcnc-ini FILE` (docs/cli.md).

#include <string>
#include <vector>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// A machine file made from a LinuxCNC configuration, and what was assumed on the way.
struct ImportedMachine {
  /// The machine file (TOML); it reads back with parse_machine_toml.
  std::string toml;
  /// What the configuration did not say and was taken as a default (one line each).
  std::vector<std::string> assumptions;
  /// The configuration's files read: the INI and the HAL files it names.
  std::vector<std::string> files_read;
};

/// Reads a LinuxCNC INI of an xyzac-trt-kins machine: [KINS] KINEMATICS, [TRAJ] LINEAR_UNITS,
/// [AXIS_X|Y|Z|A|C] MIN_LIMIT, MAX_LIMIT, MAX_VELOCITY, MAX_ACCELERATION, and the kinematics'
/// pins (x-rot-point, y-rot-point, z-rot-point, y-offset, z-offset) set by `setp` or by
/// `sets` on the signal a `net` joins them to, in the [HAL] HALCMD lines and in the HALFILEs
/// beside the INI. A is the kinematics' A (sense -1, as C); the retract goes to Z's
/// MAX_LIMIT. @throws InputError naming the file and line (another kinematics, a missing
/// axis, a value that is no number).
TAXOPT_API ImportedMachine machine_from_linuxcnc_ini(const std::string& ini_path);

}  // namespace taxopt
