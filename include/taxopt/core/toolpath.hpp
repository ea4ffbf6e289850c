#pragma once
/// @file Cutter-location data: points, operations, tools and the record list that lets a CL
/// file be written back with every record it had.
///
/// All lengths inside taxopt are millimetres; the reader converts inch files and the writers
/// convert back, so that a name ending in `_mm` is always true.

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/types.hpp"

namespace taxopt {

/// Length unit of a file (CL input, G-code output).
enum class LengthUnit { Millimetre, Inch };

/// Millimetres in one `unit`.
inline double mm_per_unit(LengthUnit unit) { return unit == LengthUnit::Inch ? kMmPerInch : 1.0; }
/// "mm" or "in".
TAXOPT_API const char* to_string(LengthUnit unit);

/// The CAM system a CL file comes from, as the reader recognises it by its records and
/// comments (docs/cl-files.md lists the markers and what each dialect's records mean).
enum class ClDialect { Generic, SiemensNx, MakinoFfcam, Catia, SolidworksCam, Creo };
/// "generic-apt", "siemens-nx", "makino-ffcam", "catia-v5", "solidworks-cam", "creo".
TAXOPT_API const char* to_string(ClDialect dialect);

/// Sense in which a CIRCLE record's arc runs about its axis (i,j,k), looking from the tip of
/// (i,j,k) down onto the arc's plane. `Auto`: the dialect's documented convention, checked
/// against the tangents of the moves before and after each arc.
enum class ArcDirection { Auto, Clockwise, CounterClockwise };
/// "auto", "cw", "ccw".
TAXOPT_API const char* to_string(ArcDirection direction);

/// What the reader made of the motion records of a file: how arcs were read and why, and how
/// much motion splines, drilling cycles and frames contributed. The report carries it.
struct ClReadSummary {
  ClDialect dialect = ClDialect::Generic;
  /// The sense applied to CIRCLE records (never Auto), and where it comes from:
  /// "documented" (the dialect's), "tangents" (the file's own arcs decided it), "option".
  ArcDirection arc_convention = ArcDirection::CounterClockwise;
  std::string arc_convention_source = "documented";
  /// CIRCLE records; those whose neighbouring straight moves decide their sense; those whose
  /// tangents contradict the convention; and of these, the ones run in their tangents' sense.
  int arcs = 0, arcs_decidable = 0, arcs_contradicting = 0, arcs_reversed = 0;
  /// CL lines of the reversed arcs (the first 20).
  std::vector<int> reversed_arc_lines;
  /// NX NURBS records evaluated, and the points they became.
  int splines = 0, spline_points = 0;
  /// Hole positions inside CYCLE/... CYCLE/OFF expanded into their drilling moves.
  int cycle_holes = 0;
  /// MSYS records whose frame moved the coordinates that follow (non-identity, applied).
  int msys_applied = 0;
  /// Motion records read: GOTO, FROM, GODLTA, GOHOME.
  int motion_records = 0;
  /// Where `dialect` comes from: the first record of the CAM system's own structure ("line 1:
  /// NX CLSF's TOOL PATH record"); empty for a generic file.
  std::string dialect_evidence;
};

/// A frame a file's coordinates were given in (NX MSYS): a point p of the file is
/// rotation * q + origin_mm for the point q taxopt works with.
struct ClFrame {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3d origin_mm = Vec3d::Zero();
  int line = 0;
};

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
struct TAXOPT_API Tool {
  int number = 0;
  std::string name;
  double diameter_mm = 0.0;
  double corner_radius_mm = 0.0;
  double flute_length_mm = 0.0;
  /// The tool's length below the holder as the CL file gives it (LOADTL's LENGTH), mm; 0 when
  /// it gives none. The tool model's gauge length where neither ToolOverrides nor the machine
  /// file's holder gives one.
  double gauge_length_mm = 0.0;
  /// True when the file described this tool (TLDATA or CUTTER); false for the default.
  bool from_file = false;
  /// A tapered ball-end mill (APT CUTTER with r > d/2): the half angle of the cone tangent to
  /// the ball, rad; 0 for a cylindrical tool. diameter_mm is then the ball's (2 r).
  double taper_rad = 0.0;

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

/// A CIRCLE of the CL file as taxopt read it: the arc runs from point `start` to point `end`
/// of its operation (the points between are its chords), counter-clockwise about `normal`
/// (already turned for the file's sense) through `sweep_rad` (more than 2 pi for TIMES),
/// about `centre_mm`, the tip at `start` being `start_tip_mm` when it was read. The G-code
/// writer keeps it as G2/G3 where the axes allow (gcode.hpp).
struct ArcRun {
  std::size_t start = 0, end = 0;
  Vec3d centre_mm = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  double sweep_rad = 0.0;
  Vec3d start_tip_mm = Vec3d::Zero();
};

/// Coolant as a CL file asks for it (COOLNT/ON|FLOOD, MIST, OFF).
enum class ClCoolant { Off, Flood, Mist };

/// What a CL file asks of the program between two moves (docs/cl-files.md): written where it
/// stands, before the block of point `before_point` of its operation (after the last point
/// when it equals the point count).
struct ProgramEvent {
  /// Comment: text for the operator (an INSERT record's prose), written as a comment.
  enum class Kind { Stop, OptionalStop, Dwell, Spindle, Coolant, Comment };
  Kind kind = Kind::Stop;
  std::size_t before_point = 0;
  double dwell_s = 0.0;
  /// Spindle: the speed from here on, rpm; 0 stops it.
  double spindle_rpm = 0.0;
  bool spindle_clockwise = true;
  ClCoolant coolant = ClCoolant::Off;
  /// 1-based line of the record in the CL file.
  int line = 0;
  /// Comment: its text, printable ASCII.
  std::string text;
};

/// One machining operation (an NX `TOOL PATH` block, or the moves of one tool).
template <class S>
struct Operation {
  std::string name;
  Tool tool;
  double spindle_rpm = 0.0;
  bool spindle_clockwise = true;
  std::vector<CLPoint<S>> points;
  /// The CIRCLE arcs among the points, in order (ArcRun).
  std::vector<ArcRun> arcs;
  /// Coolant the CL file asks for at the operation's start; empty: the file says nothing (the
  /// machine file's default applies).
  std::optional<ClCoolant> coolant;
  /// Stops, dwells, spindle and coolant changes inside the operation, in order.
  std::vector<ProgramEvent> events;
  /// The band the CAM system kept its path within about the part surface, mm: the largest
  /// INTOL / OUTTOL / TOLER (part surface) in force over the operation's points; empty where
  /// the file gives none. It adds to the part mesh's chordal error in the default contact
  /// tolerance (contact_tolerance_mm).
  std::optional<double> cam_tolerance_mm;
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

/// A record of the source file, kept for the round trip (JobResult::out_cls).
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
  /// The record whose motion this one is part of (a KNOT or CNTRL of a NURBS), else -1: it is
  /// left out where the owner is written as new GOTOs.
  int owner = -1;
  /// Index in Toolpath::frames of the frame its coordinates are in (-1: taxopt's own).
  int frame = -1;
};

/// A CL file in memory: operations to optimise, plus every record for the round trip.
struct Toolpath {
  std::string source;
  /// Units of the file (coordinates inside are always mm).
  LengthUnit units = LengthUnit::Millimetre;
  /// Line end used by the file ("\n" or "\r\n") and whether its last line ended with one.
  std::string line_end = "\n";
  bool final_line_end = true;
  /// The file began with a UTF-8 byte-order mark (stripped for reading, kept for writing).
  bool byte_order_mark = false;
  std::vector<ClRecord> records;
  std::vector<Operationd> operations;
  /// Non-fatal findings of the reader (skipped lines, assumptions), one line each.
  std::vector<std::string> warnings;
  /// Findings a user must see even without -v: how the reader decided what the file means
  /// where it could not be read literally (arcs taken by their tangents, MSYS applied, arc
  /// sense from evidence), one line each with the file and line.
  std::vector<std::string> notices;
  /// Major words of records the reader kept but did not interpret (display, comments,
  /// machine words: none bears motion), with their counts.
  std::map<std::string, int> skipped_records;
  /// The part of skipped_records that the user skipped by name (ClReadOptions::skip_records).
  std::map<std::string, int> skipped_by_option;
  ClReadSummary reading;
  /// Frames of MSYS records that were applied (ClRecord::frame).
  std::vector<ClFrame> frames;
  /// Non-identity MSYS frames the file names but whose coordinates were posted as written
  /// (the default: NX writes CLSF coordinates in the MCS already). part_mesh_for decides from
  /// them in which frame a part mesh lies.
  std::vector<ClFrame> declared_frames;
};

/// Number of CL points over all operations.
TAXOPT_API std::size_t point_count(const Toolpath& toolpath);

}  // namespace taxopt
