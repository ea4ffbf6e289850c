#pragma once
/// @file The program template's blocks (the machine file's gcode.header, footer, tool_change,
/// tcp_on, tcp_off, work_offset), checked by what they do.

#include <string>
#include <vector>

#include "taxopt/kinematics/machine.hpp"

namespace taxopt {

/// The template's lists of blocks by their key (gcode.<key> in a machine file): the machine
/// file's reader and validate(Machine) check the same lists.
struct TemplateList {
  const char* key;
  std::vector<std::string> ProgramTemplate::*blocks;
};
inline const TemplateList kTemplateLists[] = {{"header", &ProgramTemplate::header},
                                              {"footer", &ProgramTemplate::footer},
                                              {"tool_change", &ProgramTemplate::tool_change},
                                              {"tcp_on", &ProgramTemplate::tcp_on},
                                              {"tcp_off", &ProgramTemplate::tcp_off}};

/// What a tool change template must do: the program is checked for the tool it calls.
inline constexpr const char* kToolChangeCallsTool =
    "must call the tool by \"{tool}\" (\"T{tool} M6\")";

/// A program name of letters, digits, '_' and '-' only: a TNC's is a file name (written into
/// its begin block, where a line break would start a block), the others' go into a comment.
bool program_name_characters_ok(const std::string& name);

/// Why `block` may not stand in the template key `what` ("gcode.header", ...) of a `dialect`
/// program; empty where it may. A block of the template is written as it is and stepped over
/// by the read-back, so it is checked by what it does, against an allowlist
/// (tests/test_bad_input.cpp, tests/io/test_machine_file.cpp): machine-specific M codes (an
/// unlock, a kinematics switch such as LinuxCNC's M428), dwell and path-control codes (G4 P,
/// G40, G61, G61.1, G64 P Q, G80; Fanuc G5.1 Q and G8 P; Haas G187 P E; Sinumerik FFWON, SOFT,
/// G642, COMPCAD, CYCLE832(...) ...), and comments. Everything else is refused: a word that
/// moves an axis, a G code outside the list (motion, units, planes, frames such as G10 L2, G7,
/// G59.3, G30, G95, G96), the spindle, coolant, tool, H and D offsets, F and S, the program end
/// (M2, M30), subprogram calls (M98, G65, an O word; in the tool change only: the machine's own
/// macro), expressions and parameters ([, #, =), "%" and an unclosed comment. Per key:
/// `tool_change` must call T{tool} (and may hold M6); `work_offset` holds one work offset code
/// (G54 ... G59.3, G54.1 P, Sinumerik G505 ... G599); a `footer` block may home the rotary axes
/// (`G91 G28 B0. C0.`: G28 with rotary words of 0 only) and restore `G90`.
std::string template_block_problem(const std::string& block, const std::string& what,
                                   GcodeDialect dialect, bool footer);

}  // namespace taxopt
