#pragma once
/// @file A LinuxCNC configuration (INI and the HAL files it names) turned into a taxopt
/// machine file: `taxopt machine --from-linuxcnc-ini FILE` (docs/cli.md).

#include <string>
#include <vector>

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

/// Reads a LinuxCNC INI (and the files it #INCLUDEs) of a machine whose [KINS] KINEMATICS is
/// xyzac-trt-kins or xyzbc-trt-kins (table-table: A or B, and C, sense -1), maxkins
/// (head-table B/C) or 5axiskins (head-head B/C; both B sense -1, C +1): [TRAJ] LINEAR_UNITS,
/// [AXIS_*] MIN_LIMIT, MAX_LIMIT, MAX_VELOCITY, MAX_ACCELERATION within the axis's joint's,
/// and the kinematics' pins (the table's x-/y-/z-rot-point and offsets; a head's
/// pivot-length, which must be set) by `setp`, or `sets` on the signal a `net` joins them to,
/// in the [HAL] HALCMD lines and the HALFILEs beside the INI ([SECTION]KEY substituted). The
/// retract goes to Z's MAX_LIMIT. @throws InputError naming the file and line (another
/// kinematics, a missing axis, a value that is no number, a head's pivot length not set).
ImportedMachine machine_from_linuxcnc_ini(const std::string& ini_path);

}  // namespace taxopt
