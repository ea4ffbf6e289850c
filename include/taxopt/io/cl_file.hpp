#pragma once
/// @file Reading and writing APT / NX CLSF cutter-location files.

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/option_names.hpp"
#include "taxopt/core/toolpath.hpp"

namespace taxopt {

/// Options of the CL reader.
struct ClReadOptions {
  /// Units of the file; when empty: UNITS/UNIT record, else inch if a feed is IPM/IPR,
  /// else millimetres.
  std::optional<LengthUnit> units;
  /// Largest distance between a CIRCLE arc and the chords taxopt replaces it by, mm.
  double arc_tolerance_mm = 0.001;
  /// Largest accepted | |(i,j,k)| - 1 | of a tool axis; the axis is then normalised.
  double axis_length_tolerance = 1e-3;
  /// Sense of CIRCLE arcs. Auto: the dialect's documented sense; an arc
  /// whose neighbouring moves contradict it on every side they decide is run in their sense
  /// (a notice says which); when most decidable arcs contradict it, reading stops (exit 2).
  /// An explicit sense is applied to every arc as given.
  ArcDirection arc_direction = ArcDirection::Auto;
  /// Apply NX MSYS frames. Off by default: NX writes CLSF coordinates
  /// in the MCS already and MSYS only says where that MCS lies (the production NX post for
  /// the Haas UMC-750 writes them unchanged: tests/data/real-post). On: the coordinates after
  /// an MSYS record are taken as absolute and moved into its MCS, in which the G-code is posted.
  bool apply_msys = false;
  /// Peck drilling: after each peck the tool rapids back down to this far above the depth
  /// reached, then feeds on, mm. 0.254 mm (0.010 in) is LinuxCNC 2.9's G83 (rs274ngc's
  /// G83_RAPID_DELTA, "how far above hole bottom for rapid return").
  double peck_clearance_mm = 0.254;
  /// Record words to skip (upper case): words the reader does not know, or
  /// knows as information, a program event or a refused word that leaves the motion as it is
  /// (cl_words.hpp, ClWord::skippable). Skipping a motion, state or frame word is refused.
  std::set<std::string> skip_records;
  /// How the caller names these fields in its messages (option_names.hpp): the reader's
  /// errors and notices that say which option to set name it so.
  OptionNames option_names;
  /// `field` ("skip_records") as the caller names ClReadOptions::field (option_names).
  std::string name_of(const std::string& field) const {
    return option_name(option_names, "ClReadOptions::" + field);
  }
};

/// Parses CL text. `source` names the file in errors and warnings.
/// @throws InputError with the file and line of the first malformed record.
TAXOPT_API Toolpath parse_cl(const std::string& text, const std::string& source,
                             const ClReadOptions& options = {});

/// Reads a CL file from disk. @throws InputError (unreadable file, malformed record).
TAXOPT_API Toolpath read_cl_file(const std::string& path, const ClReadOptions& options = {});

/// Writes a toolpath back as CL text in the file's own units and line ends. Every record of
/// `original` is written as it was, except the motion records whose points differ in
/// `operations` (same shape as original.operations): those are written as new GOTOs.
/// A CIRCLE whose arc points changed is written as the GOTOs of its chords.
TAXOPT_API std::string format_cl(const Toolpath& original,
                                 const std::vector<Operationd>& operations);

/// Writes operations as a new NX CLSF text in millimetres (TOOL PATH, TLDATA, SPINDL, FEDRAT,
/// RAPID, GOTO/x,y,z,i,j,k on every point, END-OF-PATH), as `taxopt generate` does.
TAXOPT_API std::string format_new_cl(const std::vector<Operationd>& operations);

}  // namespace taxopt
