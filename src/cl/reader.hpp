#pragma once
/// @file The APT / NX CLSF reader's state and its record readers, one file per family:
/// reader.cpp (the file, its units, the record table), motion_records.cpp (GOTO, GODLTA,
/// GOHOME, CIRCLE, MOVARC, NURBS, TLAXIS, MSYS, MULTAX, CYCLE), curves.cpp (arcs and NURBS
/// into points after reading), state_records.cpp (units, feed, tool, spindle, coolant,
/// tolerances, modes), event_records.cpp (stops, dwells, text, operations). The traps it
/// survives are listed in docs/cl-files.md; each has a test.

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cl/cl_words.hpp"
#include "cl/lexer.hpp"
#include "taxopt/io/cl_file.hpp"

namespace taxopt::cl {
/// How far an arc's end may lie off its circle, in the CL file's unit (mm or inch): the
/// rounding of its numbers (MOVARC's and CIRCLE's ends alike).
constexpr double kArcEndTolerance = 0.002;

/// A CIRCLE whose end GOTO has been read: its chords go between points `start` and
/// `start + 1` of operation `op` once the file's arc sense is decided.
struct PendingArc {
  int op = -1;
  std::size_t start = 0;
  Vec3d centre = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
  double radius_mm = 0.0;  // 0: from the start point
  int turns = 1;           // TIMES,n: n revolutions in all
  int record = -1;
  int line = 0;
  /// What the straight moves before and after say: +1 counter-clockwise about `axis`,
  /// -1 clockwise, 0 undecided; and whether every deciding side is unambiguous.
  int evidence = 0;
  bool strong = false;
  /// Both sides vote, the same way: the arc is tangent at both ends in that sense only.
  bool tangent_both_ends = false;
  bool clockwise = false;
  /// MOVARC (Fusion / HSM): counter-clockwise about `axis` through `declared_sweep_rad`, as
  /// written; it takes no part in deciding the CIRCLE sense.
  bool movarc = false;
  double declared_sweep_rad = 0.0;
};

struct CircleRecord {
  Vec3d centre, axis;
  double radius_mm = 0.0;
  int turns = 1;
  int record = -1;
  int line = 0;
  bool movarc = false;
  double declared_sweep_rad = 0.0;
};

/// NX NURBS/ + KNOT/ + CNTRL/ records being collected.
struct PendingSpline {
  int record = -1;
  int line = 0;
  Motion motion = Motion::Feed;
  std::vector<double> knots;
  std::vector<Eigen::Vector4d> control;  // x, y, z (mm), weight
};

/// A drilling cycle in force (CYCLE/kind,... up to CYCLE/OFF).
struct DrillCycle {
  std::string kind;
  int line = 0;
  double depth_mm = 0.0, rapid_to_mm = 0.0, retract_to_mm = 0.0;
  double first_peck_mm = 0.0, next_peck_mm = 0.0;
  double feed_mm_per_min = 0.0;
  bool feed_out = false;  // bore, ream, tap: the tool leaves the hole at the feed
};

/// One record as its reader gets it: its word, its fields, their text, its index in
/// Toolpath::records and its line.
struct ClRecordArgs {
  const std::string& major;
  const std::vector<std::string>& args;
  const std::string& text;
  int index;
  int line;
};

/// What may follow a LOADTL's tool number, as CAM systems write it: ADJUST,h (NX's LOAD/TOOL)
/// or OSETNO,h (Creo) -- the length offset register; LENGTH,l (the tool's length, in the file's
/// unit); IN,p (the magazine pocket: the T word is the tool number, so it is read and not
/// written). Fusion's APT post writes them by position: LOADTL/t, p, l, h.
struct LoadtlWords {
  std::optional<double> register_, length;
};

class Reader {
 public:
  Reader(const std::string& source, const ClReadOptions& options)
      : source_(source), options_(options) {}
  Toolpath run(const std::string& input);

 private:
  [[noreturn]] void fail(int line, const std::string& what) const;
  void notice(int line, const std::string& what);
  /// The file's length unit (docs/cl-files.md, "Units"): --units, else the first UNITS/UNIT
  /// record, else inches when a feed is IPM/IPR, else mm. A change of unit is refused; feed
  /// words and --units that contradict the file's unit are said (not behind -v).
  void determine_units(const std::vector<LogicalLine>& lines);
  struct UnitEvidence;
  UnitEvidence unit_evidence(const std::vector<LogicalLine>& lines) const;
  void units_record(const LogicalLine& ll, const std::string& major, const std::string& args,
                    UnitEvidence& e) const;
  void notice_units(const UnitEvidence& e);
  std::vector<double> numbers(const std::vector<std::string>& args, std::size_t from,
                              std::size_t to, const std::string& major, int line) const;
  Operationd& current_op();
  /// A tool change outside a TOOL PATH block starts a new operation once the current one
  /// has moved.
  void tool_changed();
  Vec3d parse_axis(const std::vector<double>& v, std::size_t at, const std::string& major,
                   int line) const;
  /// A point of the file (in its units and frame) in taxopt's millimetres and MCS.
  Vec3d to_mcs_point(const Vec3d& p) const;
  /// A direction of the file in the MCS.
  Vec3d to_mcs_vector(const Vec3d& v) const;
  void add_point(const Vec3d& tip_mm, Motion motion, int record, int line);
  /// Coordinates beyond any machine (1e6 mm = 1 km) are a broken file, not a program.
  void check_reach(const Vec3d& p_mm, const std::string& major, int line) const;
  /// The largest CAM tolerance taken (INTOL, OUTTOL, TOLER), mm: a finishing path's band.
  static constexpr double kMaxCamToleranceMm = 1.0;
  const CLPointd& last_point(const std::string& major, int line);
  /// The angle an arc turns from `start` to `end`, counter-clockwise about `c.axis` (already
  /// turned for the sense), with TIMES' extra revolutions.
  static double arc_sweep_rad(const PendingArc& c, const Vec3d& start, const Vec3d& end_mm);
  /// Chords of an arc from `start` to `end` (exclusive of both), counter-clockwise about
  /// `c.axis` (already turned for the sense), within the chordal tolerance.
  std::vector<Vec3d> arc_chords(const PendingArc& c, const Vec3d& start, const Vec3d& end_mm);
  /// Decides the sense of every arc (the file's convention, checked against the tangents of
  /// the straight moves beside each arc) and inserts their chords.
  void expand_arcs();
  /// The CIRCLEs' votes: each arc's sense by the tangents of the moves beside it (its
  /// evidence, strong where both agree clearly), counted over the CIRCLEs (a MOVARC's sense is
  /// written: it does not vote).
  struct ArcVotes {
    int ccw = 0, cw = 0, circles = 0;
  };
  ArcVotes vote_arcs();
  /// The CIRCLEs' lines (the first five) whose evidence is `sign`.
  std::string arc_lines(int sign) const;
  /// The sense the file's CIRCLEs run about their axis: the option's, else the CAM system's
  /// documented one, else the tangents' where they agree (80 %); refused where they do not,
  /// or where the file shows two CAM systems of opposite senses.
  ArcDirection arc_convention(const ArcVotes& votes);
  /// Each CIRCLE's sense: the convention, reversed where its neighbours all clearly contradict
  /// it (not against an option); a documented convention most arcs contradict is refused.
  void apply_arc_convention(ArcDirection convention, const ArcVotes& votes);
  /// With the sense given by option: a notice where it runs against the decidable arcs
  /// (`agree`, `contra`), naming each arc tangent at both ends only the other way.
  void option_against_tangents(ArcDirection convention, int agree, int contra);
  /// MOVARC's sense and sweep are written: the GOTO must end the arc ANGLE deg on, and the
  /// moves beside it must not clearly run the other way.
  void check_movarcs();
  /// Inserts the chords of every arc, operation by operation; events keep their place (an
  /// event before an arc's end GOTO stands before the arc).
  void insert_chords();
  /// Records' operation and point ranges from the points (after arcs were inserted and empty
  /// operations dropped).
  void index_records();
  /// Evaluates the NURBS collected since its NURBS record into points within the chordal
  /// tolerance. NX's layout (docs/cl-files.md): the current point is the first control
  /// point, the CNTRL records the others; KNOT lists the knots after the p + 1 zeros and the
  /// last of the p + 1 ones, so the degree is p = (CNTRL count + 1) - (KNOT count).
  void finish_spline();
  /// The clamped knot vector of `sp` of degree p (p + 1 zeros, its knots, p + 1 ones), its
  /// knots checked.
  std::vector<double> clamped_knots(const PendingSpline& sp, int p, const std::string& what) const;
  void handle(const LogicalLine& ll);
  /// A feed word's value: FEDRAT/f, /{MMPM|IPM|PERMIN|MMPR|IPR|PERREV},f or /f,unit, in
  /// mm/min at the spindle speed in force (0 for a feed per revolution with none). With
  /// `per_rev_mm`, a feed per revolution is also given there (mm/rev; 0 for one per minute)
  /// and one with no spindle speed yet is no warning: the state holds it until SPINDL.
  double feed_of(const std::vector<std::string>& args, std::size_t from, const std::string& major,
                 int line, double* per_rev_mm = nullptr);
  /// A feed in mm/min a program can write and a machine run, else a failure naming `major`.
  double bounded_feed(double mm_per_min, const std::string& major, int line);
  void start_cycle(const std::vector<std::string>& args, int line);
  /// The moves of a drilling cycle at a hole whose top is `top`: in at the retract height, down
  /// to the rapid plane, feed to depth in pecks (back to the rapid plane between them), out.
  void drill_hole(const Vec3d& top, int record, int line);
  void skipped(const std::string& major) { ++tp_.skipped_records[major]; }
  /// Refuses an operation whose median feed per revolution is no milling feed where the other
  /// unit's reading is one (a file in the other unit than it says).
  void check_feed_per_revolution(const Operationd& op) const;
  /// Counts `n` points an arc, spline or drilling hole (at `line`) expands to against the
  /// file's budget of 1e6.
  void count_curve_points(std::size_t n, const std::string& what, int line);
  void interpret(const std::string& major, const std::string& args_text, int index, int line);
  /// The record words and their readers (the word table, cl_words.cpp, says what each means).
  using RecordReader = void (Reader::*)(const ClRecordArgs&);
  static const std::map<std::string, RecordReader>& record_readers() {
    static const std::map<std::string, RecordReader> readers = {
        {"GOTO", &Reader::goto_record},    {"FROM", &Reader::goto_record},
        {"GODLTA", &Reader::godlta},       {"GOHOME", &Reader::gohome},
        {"CIRCLE", &Reader::circle},       {"MOVARC", &Reader::movarc},
        {"TLAXIS", &Reader::tlaxis},       {"NURBS", &Reader::nurbs},
        {"RAPID", &Reader::rapid},         {"FEDRAT", &Reader::fedrat},
        {"MSYS", &Reader::msys},           {"MULTAX", &Reader::multax},
        {"CYCLE", &Reader::cycle},         {"TLDATA", &Reader::tldata},
        {"CUTTER", &Reader::cutter},       {"LOADTL", &Reader::load_tool},
        {"TOOLNO", &Reader::toolno},       {"LOAD", &Reader::load_tool},
        {"SPINDL", &Reader::spindl},       {"SPINDLE", &Reader::spindl},
        {"COOLNT", &Reader::coolnt},       {"CUTCOM", &Reader::cutcom},
        {"SET", &Reader::set_mode},        {"INTOL", &Reader::tolerance},
        {"OUTTOL", &Reader::tolerance},    {"TOLER", &Reader::tolerance},
        {"MODE", &Reader::mode},           {"MACHIN", &Reader::machin},
        {"STOP", &Reader::stop},           {"OPSTOP", &Reader::stop},
        {"DELAY", &Reader::delay},         {"INSERT", &Reader::insert},
        {"FINI", &Reader::fini},           {"END", &Reader::fini},
        {"TOOL PATH", &Reader::tool_path}, {"END-OF-PATH", &Reader::end_of_path},
    };
    return readers;
  }
  /// GOTO/, FROM/
  void goto_record(const ClRecordArgs& r);
  /// GODLTA/
  void godlta(const ClRecordArgs& r);
  /// GOHOME/
  void gohome(const ClRecordArgs& r);
  /// CIRCLE/
  void circle(const ClRecordArgs& r);
  /// MOVARC/
  void movarc(const ClRecordArgs& r);
  /// TLAXIS/
  void tlaxis(const ClRecordArgs& r);
  /// NURBS/
  void nurbs(const ClRecordArgs& r);
  /// RAPID/
  void rapid(const ClRecordArgs&);
  /// FEDRAT/
  void fedrat(const ClRecordArgs& r);
  /// MSYS/
  void msys(const ClRecordArgs& r);
  /// MULTAX/
  void multax(const ClRecordArgs& r);
  /// CYCLE/
  void cycle(const ClRecordArgs& r);
  /// TLDATA/
  void tldata(const ClRecordArgs& r);
  /// CUTTER/
  void cutter(const ClRecordArgs& r);
  /// LOADTL/, LOAD/
  void load_tool(const ClRecordArgs& r);
  /// A CIRCLE or MOVARC read: its end GOTO comes next.
  void pend_circle(CircleRecord c, int index, int line);
  /// TOOLNO/n[,d]: CATIA's announcement of the tool its LOADTL loads next (number, diameter).
  void toolno(const ClRecordArgs& r);
  /// SPINDL/, SPINDLE/
  void spindl(const ClRecordArgs& r);
  /// COOLNT/
  void coolnt(const ClRecordArgs& r);
  /// CUTCOM/
  void cutcom(const ClRecordArgs& r);
  /// SET/
  void set_mode(const ClRecordArgs& r);
  /// INTOL/, OUTTOL/, TOLER/
  void tolerance(const ClRecordArgs& r);
  /// MODE/
  void mode(const ClRecordArgs& r);
  /// MACHIN/
  void machin(const ClRecordArgs& r);
  /// STOP/, OPSTOP/
  void stop(const ClRecordArgs& r);
  /// DELAY/
  void delay(const ClRecordArgs& r);
  /// INSERT/
  void insert(const ClRecordArgs& r);
  /// FINI/, END/
  void fini(const ClRecordArgs& r);
  /// TOOL PATH/
  void tool_path(const ClRecordArgs& r);
  /// END-OF-PATH/
  void end_of_path(const ClRecordArgs&);
  /// SPINDL/[speed][,RPM|SFM|SMM][,CLW|CCLW] or /OFF or /ON: the spindle from here on.
  void spindle(const std::vector<std::string>& args, int line);
  /// A spindle or coolant change: the operation's own setting before its first point, an
  /// event where it stands after (none before any operation: current_op copies the state).
  void state_change(const ProgramEvent& e, int line);
  /// An INSERT that holds a program stop or end: written as the stop (its notes as a comment
  /// before it) and true, refused where it is not alone, false where `text` holds none.
  bool insert_stop(const std::string& text, const std::string& shown, int line);
  /// An event before the operation's next point.
  void add_event(ProgramEvent e, int line);
  /// What follows a LOADTL's tool number at args[at] (state_records.cpp); `positional` takes
  /// Fusion's LOADTL/t, p, l, h.
  LoadtlWords loadtl_words(const std::vector<std::string>& args, std::size_t at, bool positional,
                           int line, const std::string& shown);
  /// APT's CUTTER/d,r,e,f,a,b,h with r > d/2: a tapered ball-end mill of ball radius r whose
  /// flanks, at b from the axis, are tangent to the ball (e = 0, f = r, a = 0); d is the
  /// diameter where the flank line meets the tip plane, 2 r (1 - sin b) / cos b.
  void tapered_ball(const std::vector<double>& v, int line);
  void set_tool(double d, double r, double length, int line);
  std::string source_;
  ClReadOptions options_;
  Toolpath tp_;
  double scale_ = 1.0;
  int op_ = -1;
  int frame_ = -1;
  bool in_block_ = false;
  std::string pending_name_;
  Tool tool_;
  /// The last TOOLNO not yet loaded: its tool number, diameter (mm, 0: not given) and line.
  struct AnnouncedTool {
    int number = 0;
    double diameter_mm = 0.0;
    int line = 0;
  };
  std::optional<AnnouncedTool> announced_tool_;
  double spindle_rpm_ = 0.0;
  bool spindle_cw_ = true;
  Vec3d axis_ = Vec3d::UnitZ();
  bool rapid_next_ = false;
  double feed_mm_per_min_ = 0.0;
  /// A feed per revolution in force (mm/rev; 0: the feed is per minute) and its FEDRAT's line:
  /// the feed per minute follows every SPINDL (APT's MMPR/IPR: the feed is the spindle's).
  double feed_per_rev_mm_ = 0.0;
  int feed_line_ = 0;
  /// The CAM's tolerances of the part surface in force (INTOL, OUTTOL, TOLER), file units.
  double inside_tolerance_ = 0.0, outside_tolerance_ = 0.0;
  bool tolerance_given_ = false;
  std::optional<CircleRecord> pending_circle_;
  /// The circle the last GOTO ended an arc on, and whether the last record was a GOTO: a
  /// Pro/CLfile GOTO continues with a point a line and no `$`, each on that circle.
  std::optional<CircleRecord> last_arc_circle_;
  bool after_goto_ = false, goto_continued_ = false;
  std::vector<PendingArc> arcs_;
  std::optional<PendingSpline> spline_;
  std::optional<DrillCycle> cycle_;
  std::optional<std::pair<Vec3d, Vec3d>> home_;
  std::size_t points_ = 0;
  /// Every CAM system whose structure the file shows (detect_dialect), in order.
  std::vector<DialectEvidence::Seen> dialects_seen_;
  /// Points the file's arcs, splines and drilling cycles expanded to so far
  /// (count_curve_points).
  std::size_t curve_points_ = 0;
  double last_rpm_ = 0.0;
  std::optional<ClCoolant> coolant_;
  /// The coolant COOLNT/ON turns on: the last FLOOD or MIST, else flood.
  ClCoolant chosen_coolant_ = ClCoolant::Flood;
  int finished_line_ = 0;    // line of FINI / END
  int multax_off_line_ = 0;  // line of the MULTAX/OFF in force
};

}  // namespace taxopt::cl
