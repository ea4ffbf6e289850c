#pragma once
/// @file Cutter-location data: points, operations, tools and the record list that lets a CL
/// file be written back with every record it had.
///
/// All lengths inside taxopt are millimetres; the reader converts inch files and the writers
/// convert back, so that a name ending in `_mm` is always true.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "taxopt/core/types.hpp"

namespace taxopt {

/// Length unit of a file (CL input, G-code output).
enum class LengthUnit { Millimetre, Inch };

/// Millimetres in one `unit`.
inline double mm_per_unit(LengthUnit unit) { return unit == LengthUnit::Inch ? kMmPerInch : 1.0; }
/// "mm" or "in".
const char* to_string(LengthUnit unit);

/// How the machine reaches a CL point from the one before it.
enum class Motion { Rapid, Feed };

/// One cutter location: tool tip and unit tool axis (from tip towards the spindle).
template <class S>
struct CLPoint {
  Vec3<S> tip_mm = Vec3<S>::Zero();
  Vec3<S> axis = Vec3<S>::UnitZ();
  /// Programmed feed of the move that ends here, mm/min; 0 when the file gave none.
  S feed_mm_per_min = S(0);
  Motion motion = Motion::Feed;
  /// 1-based line of the record in the source file (0 for points made by taxopt).
  int line = 0;
  /// Index of the owning record in Toolpath::records (-1 when none).
  int record = -1;
};
using CLPointd = CLPoint<double>;

/// Cutting tool as far as a CL file describes it (TLDATA/MILL or APT CUTTER), plus the
/// parts above the flutes that taxopt needs for collision checks (filled from options).
struct Tool {
  int number = 0;
  std::string name;
  double diameter_mm = 0.0;
  double corner_radius_mm = 0.0;
  double flute_length_mm = 0.0;
  /// True when the file described this tool (TLDATA or CUTTER); false for the default.
  bool from_file = false;

  /// A ball-end mill of the given diameter and flute length (mm): corner radius d / 2.
  static Tool ball_end_mill(double diameter_mm, double flute_length_mm);

  /// A ball-end mill: corner radius equal to half the diameter (within 1e-6 relative).
  bool is_ball() const;
  /// Ball radius R for a ball-end mill, 0 otherwise.
  double ball_radius_mm() const { return is_ball() ? 0.5 * diameter_mm : 0.0; }
};

/// A range [begin, end) of point indices inside an operation.
struct IndexRange {
  std::size_t begin = 0;
  std::size_t end = 0;
  std::size_t size() const { return end - begin; }
};

/// One machining operation (an NX `TOOL PATH` block, or the moves of one tool).
template <class S>
struct Operation {
  std::string name;
  Tool tool;
  double spindle_rpm = 0.0;
  bool spindle_clockwise = true;
  std::vector<CLPoint<S>> points;
};
using Operationd = Operation<double>;

/// Passes of an operation: maximal runs of feed moves, each with the point they start from
/// (the end of the rapid before them, or the operation's first point). Ranges of fewer than
/// two points are left out: they hold no move.
template <class S>
std::vector<IndexRange> feed_passes(const Operation<S>& op) {
  std::vector<IndexRange> out;
  const auto& pts = op.points;
  std::size_t i = 0;
  while (i < pts.size()) {
    // A pass starts at point i when point i+1 is a feed move.
    if (i + 1 < pts.size() && pts[i + 1].motion == Motion::Feed) {
      std::size_t e = i + 1;
      while (e < pts.size() && pts[e].motion == Motion::Feed) ++e;
      out.push_back({i, e});
      i = e;  // point e (if any) is a rapid target: it may start the next pass
    } else {
      ++i;
    }
  }
  return out;
}

/// Kind of a record of a CL file.
enum class RecordKind {
  Record,     ///< a record with a major word (GOTO, FEDRAT, ...)
  Comment,    ///< `$$` comment (with its continuation lines)
  NotRecord,  ///< a line that is no record (listing header or trailer), skipped
  Blank,      ///< an empty line
};

/// A record of the source file, kept for the round trip (`--out-cls`).
struct ClRecord {
  RecordKind kind = RecordKind::Record;
  /// Major word, upper case, inner blanks folded ("GOTO", "TOOL PATH"); empty unless Record.
  std::string major;
  /// The physical lines as they were in the file, joined by "\n", without line ends.
  std::string text;
  /// 1-based line of the first physical line.
  int line = 0;
  /// Operation and the points this record produced (GOTO/FROM: one; CIRCLE: the points
  /// taxopt inserted along the arc).
  int op = -1;
  int first_point = -1;
  int point_count = 0;
};

/// A CL file in memory: operations to optimise, plus every record for the round trip.
struct Toolpath {
  std::string source;
  /// Units of the file (coordinates inside are always mm).
  LengthUnit units = LengthUnit::Millimetre;
  /// Line end used by the file ("\n" or "\r\n") and whether its last line ended with one.
  std::string line_end = "\n";
  bool final_line_end = true;
  std::vector<ClRecord> records;
  std::vector<Operationd> operations;
  /// Non-fatal findings of the reader (skipped lines, assumptions), one line each.
  std::vector<std::string> warnings;
  /// Major words the reader did not interpret, with their counts (kept for the round trip).
  std::map<std::string, int> unknown_records;
};

/// Number of CL points over all operations.
std::size_t point_count(const Toolpath& toolpath);

}  // namespace taxopt
