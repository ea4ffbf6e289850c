#pragma once
/// @file G-code for an A/C machine (LinuxCNC dialect), and a reader of that subset used to
/// verify every written file by reading it back.

#include <optional>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/toolpath.hpp"
#include "taxopt/kinematics/machine.hpp"

namespace taxopt {

/// An operation ready to be posted: its points (tips, axes, feeds, motions) and the machine
/// pose of every point.
struct PostedOperation {
  std::string name;
  Tool tool;
  double spindle_rpm = 0.0;
  bool spindle_clockwise = true;
  std::vector<CLPointd> points;
  std::vector<Posed> poses;
  /// Optional, per point: the time of the feed move into it at the programmed feed, s
  /// (FeedReference::CutterPath: the input block's, within GcodeSettings::max_feed_ratio);
  /// absent: programmed_block_times_s.
  std::vector<double> programmed_time_s;
  /// Optional, per point: the time of the feed move into it, s, from a feed schedule
  /// (feed_schedule.hpp); 0 or absent: the programmed time. Never shorter than that.
  std::vector<double> block_time_s;
  /// The CL file's arcs among the points (ArcRun). Where the written A and C stay put over an
  /// arc, its plane is the written XY, XZ or YZ plane and the feeds are units per minute and
  /// not scheduled, the arc is written as G2/G3 blocks of at most 180 deg each (not in the
  /// Heidenhain dialect); else as its chords.
  std::vector<ArcRun> arcs;
  /// Coolant the CL file asks for at the start (Operation::coolant); empty: the machine file's.
  std::optional<ClCoolant> coolant;
  /// Stops, dwells, spindle and coolant changes where they stand (Operation::events).
  std::vector<ProgramEvent> events;
  /// The part model's highest point in the workpiece (its bounding box's top), mm: the
  /// approach's clearance height stands above it as above the operation's tips (ProgramTemplate::
  /// approach_clearance_mm); empty without a part.
  std::optional<double> part_top_z_mm = {};
  /// The moves are checked against a part model, swept (the verification's move check): the
  /// turns of the table stay in the air; false: a rapid turning more than the machine's
  /// index threshold is an index move (up, turn, XY, down).
  bool swept_moves_checked = false;
  /// Optional, per point reached by a linearised move (machine mode): the scheduled time of
  /// each of its blocks, s (adding up to block_time_s); used where the count matches the
  /// blocks written, else the point's time is shared in proportion to the blocks' lengths.
  std::vector<std::vector<double>> linearised_time_s = {};
  /// The blocks of programmed_time_s that the feed ratio lengthened (their input block's time
  /// would have needed an F above max_feed_ratio times the programmed feed).
  std::size_t feed_ratio_blocks = 0;
};

/// Where an approach under TCP comes down to before the last leg along the tool axis to
/// `tip_mm`: on the axis at the clearance height where the axis rises within 60 deg of the
/// vertical, else `safe_distance_mm` along it (below the clearance height: the writer comes
/// straight down to it first).
TAXOPT_API Vec3d approach_tip_mm(const Vec3d& tip_mm, const Vec3d& axis, double clearance_z_mm,
                                 double safe_distance_mm);

/// Time of one feed move at `feed_mm_per_min`, s, as a controller times it under TCP: the tip
/// distance over the feed, or the rotary distance (deg) over the feed read as deg/min when
/// only A and C turn (1e-9 of either at the least: a move too small to time still takes time).
TAXOPT_API double programmed_move_time_s(const Vec3d& from_tip_mm, const Posed& from,
                                         const Vec3d& to_tip_mm, const Posed& to,
                                         double feed_mm_per_min);

/// Time of the feed move into each point at its programmed feed, s, as a controller times it
/// under TCP: the tip distance over the feed, or the rotary distance (deg) over the feed read
/// as deg/min when only A and C turn. 0 for the first point, rapids and feed moves without a
/// feed; a feed move too small to time (below 1e-9 mm and deg) gets 1e-9 over its feed.
TAXOPT_API std::vector<double> programmed_block_times_s(const std::vector<CLPointd>& points,
                                                        const std::vector<Posed>& poses);

/// A joint's peak velocity and acceleration, per second (mm for X Y Z, deg for A C), and the
/// G-code lines where they occur (0: none).
struct JointPeak {
  double velocity_per_s = 0.0, accel_per_s2 = 0.0;
  int velocity_line = 0, accel_line = 0;
};

/// What a written line is for (GcodeProgram::blocks).
enum class BlockKind {
  Start,    ///< program start, comments, modal set-up, work offset, template header
  Retract,  ///< the safe retract to the machine's Z (an operation's start, an index move, the end)
  ToolChange,      ///< the tool change (and the set-up again after a template's)
  Spindle,         ///< S M3/M4, M5 between operations
  Coolant,         ///< M7, M8, M9 between operations
  TableTurn,       ///< A and C turned with the tool up
  LengthTcp,       ///< tool length offset and tool centre point control on or off
  Approach,        ///< the way down from the retract: clearance height, XY, along the axis
  Point,           ///< the block reaching a CL point (rapid or feed), G93 after a first feed block
  Linearised,      ///< machine mode: a block between two points keeping the tip on the line
  Arc,             ///< a G2/G3 block of a CL arc
  JointSafeRapid,  ///< LinuxCNC tcp mode: a rapid written at a joint-safe feed
  Dwell,           ///< G4 P0 between a joint-safe rapid and a feed block
  Event,           ///< the CL file's stop, dwell, spindle or coolant change
  End,             ///< the home turn, the park, the footer, M2/M30
};

/// A motion block as the writer plans it, before its dialect writes it: what the block asks
/// of the machine. The block's text is this, formatted (the dialect's motion word, the axes'
/// words to the program's decimals and units, I J K, F where it changes); read back
/// (read_gcode_moves), each block gives the axes `given` says and lands where the move says,
/// to the written decimals (tests/io/test_program_blocks.cpp, every dialect and mode).
struct PlannedMove {
  enum class Type { Rapid, Linear, ArcClockwise, ArcCounterClockwise };
  Type type = Type::Rapid;
  /// The words name machine coordinates: the safe retract and the end's park (G53, G28,
  /// SUPA, M91). Fanuc's retract is a reference return (G91 G28 Z0.): its target Z is the
  /// machine's reference point, 0 here, as read_gcode_moves reads it.
  bool machine_frame = false;
  /// Which of X Y Z, the tilt axis, C (bits 0 to 4, as GcodeMove::given) the block names.
  unsigned given = 0;
  /// The targets of the axes named, unrounded: X Y Z in mm in the block's frame (the
  /// program's: with tool centre point control the tip in the workpiece, in machine mode the
  /// machine's X Y Z; else the machine's), the rotary axes in deg.
  Vec3d xyz_mm = Vec3d::Zero();
  double tilt_deg = 0.0, c_deg = 0.0;
  /// An arc: the axis normal to its plane (0 X: G19, 1 Y: G18, 2 Z: G17) and its centre's
  /// offset from its start (the previous block's end as written), mm.
  int arc_axis = 2;
  Vec3d centre_offset_mm = Vec3d::Zero();
  /// The F in force for the block (written where it changes, always under G93), as the
  /// program states it: the program's length unit (or deg where only the rotary axes turn)
  /// per minute, or 1/min under inverse time (G93), with `feed_decimals` decimals. Empty on a
  /// rapid.
  std::optional<double> feed_per_min;
  int feed_decimals = 0;
  bool inverse_time = false;
};

/// One written line, its kind and where it comes from.
struct ProgramBlock {
  int line = 0;  ///< 1-based line of GcodeProgram::text
  BlockKind kind = BlockKind::Start;
  /// Index of its operation; empty: the program's start or end.
  std::optional<std::size_t> operation;
  /// CL point it leads to (an arc's: its last); empty: none.
  std::optional<std::size_t> point;
  /// A motion block's plan (empty: a block that moves no axis: modes, tool, spindle,
  /// coolant, comments, dwells, a template's verbatim lines).
  std::optional<PlannedMove> move;
  /// The machine's joints at the block's end (X Y Z mm, the tilt axis and C deg: JointPosition,
  /// as joints_of_written_mm takes them from the words, the work offset zero) where the
  /// program has named all five axes in its own frame since the last move in machine
  /// coordinates; empty elsewhere (the way back in after a retract until X Y Z are given).
  std::optional<JointPosition> joints;
};

/// Written G-code and where each point went.
struct GcodeProgram {
  std::string text;
  /// Every line of `text`, in order, with its kind and origin: the writer's plan of the
  /// program, which the verification and the time model read with the blocks read back.
  std::vector<ProgramBlock> blocks;
  /// emitted[k][i]: 1-based G-code line of point i of operation k; 0 when the point was not
  /// written because it repeats the previous block exactly (nothing would move) or an index
  /// move passed over it (passed_over); minus the
  /// line of the G2/G3 block the point lies on when it is a chord point inside that block.
  std::vector<std::vector<int>> emitted;
  /// CL arcs written as G2/G3 (in arc_blocks blocks), and those left to their chords.
  std::size_t arcs_kept = 0, arcs_chorded = 0, arc_blocks = 0;
  /// Machine mode: blocks written between points to keep the tip on the straight line
  /// (linearisation); they belong to no point.
  std::size_t linearised_blocks = 0;
  /// Rapids written as index moves (retract, turn, XY, down; ProgramTemplate).
  std::size_t index_moves = 0;
  /// passed_over[k]: the points of operation k no block reaches: rapids after an index move's
  /// turning one up to the next feed, which the tool, up at the retract, has no need to pass
  /// (the move turns to the last of them and comes down there). Their emitted line is 0.
  std::vector<std::vector<std::size_t>> passed_over;
  /// LinuxCNC tcp mode: rapids written as feed moves at a joint-safe feed
  /// (joint_safe_rate_per_s), their lines.
  std::vector<int> joint_safe_rapids;
  /// The program's time as the controller runs it (pipeline: program_time), s: every block
  /// from the end of the first retract (where the machine stands before it is not known) to
  /// the end, the feed blocks at their scheduled times, every rapid (approach, retract, table
  /// turn, index move) rest to rest on the trapezoids of the space the controller plans it in:
  /// the program's axes with TCP on (LinuxCNC plans X Y Z A C, measured, measured on LinuxCNC's
  /// motion controller), the joints otherwise. A retract's length takes the tool length offset as
  /// the tool's gauge length (time_tool_length_mm) and the work offset as zero. 0 before it is
  /// computed.
  double time_s = 0.0;
  int time_from_line = 0;
  double time_tool_length_mm = 0.0;
  /// LinuxCNC in tcp mode: the joints (X Y Z A C) as its planner moves them where it
  /// accelerates at the axes' limits: on the rapids (and the rapids written at a joint-safe
  /// feed), rest to rest, and on the feed blocks that start a chain from rest or end it at rest;
  /// each a straight line in the program's axes (tip X Y Z, A, C) at the path velocity and
  /// acceleration within every axis's limit, the joints through the kinematics, filtered as the
  /// controller test filters the commanded joints (central differences over 10 ms). Empty
  /// otherwise (measured only on LinuxCNC; machine-mode blocks are planned in the joints). The
  /// blends inside a chain are not modelled; a chain's first block LinuxCNC blends
  /// parabolically with the next (one of the two turns A or C) at half its acceleration, as
  /// it runs it; on a first block of X Y Z alone the peak is a bound (LinuxCNC may blend it
  /// parabolically too).
  std::vector<JointPeak> tcp_joint_peaks;
  /// Where a joint passes its acceleration limit in tcp_joint_peaks (the joint's own,
  /// Machine::joint_accel_limit): the largest share of the axes' acceleration limits
  /// (LinuxCNC's [AXIS_*] MAX_ACCELERATION) at which the same model keeps every joint within
  /// it, rounded down to 0.001; 0 where none down to 0.05 does. Empty where no joint passes.
  std::optional<double> tcp_axis_accel_scale;
  /// Lines of the program template written as they are (header, footer, a tool change or
  /// kinematics switch of the machine file's): the reader steps over them.
  std::vector<int> verbatim_lines;
  /// The template's tool changes among them: line, tool number.
  std::vector<std::pair<int, int>> tool_calls;
};

/// Linearisation of a machine-mode feed move from (from_tip_mm, from) to (to_tip_mm, to):
/// the fractions of the move, 0 first and 1 last, at which blocks are written so that, with
/// the joints moving linearly between them (A and C at the same fractions of their change,
/// the tip on the straight line there), the tip stays within `tolerance_mm` of the straight
/// line. {0, 1} when it does already or the tolerance is 0 (off).
TAXOPT_API std::vector<double> linearise_fractions(const MachineKinematicsd& machine,
                                                   const Vec3d& from_tip_mm, const Posed& from,
                                                   const Vec3d& to_tip_mm, const Posed& to,
                                                   double tolerance_mm);

/// A rapid in tcp mode: LinuxCNC with its kinematics on plans G0 in the program's axes (X Y Z
/// of the tip, A, C), each at its own limits, and the joints follow through the kinematics,
/// faster than their limits where the table turns (measured on LinuxCNC's motion controller:
/// joints at 42 mm/s against 20). The rate along the move (fraction of it per second) that
/// keeps every joint's velocity within its limit, from the joints' largest rate of change
/// along the move (sampled in steps of at most 0.25 deg of turn, up to 2^20 of them, less 0.1 % and
/// the step's turn in rad for what falls between them); nullopt when the axes' own limits keep them
/// there already. Where A and C are held, the rate that keeps the joints' straight lines (the tip's
/// line turned with the table) within their limits: an approach's leg along a tilted tool axis is
/// the spindle's Z alone, an XY rapid with the table turned moves joints X and Y both.
TAXOPT_API std::optional<double> joint_safe_rate_per_s(const MachineKinematicsd& ac,
                                                       const JointLimits& limits,
                                                       const Vec3d& from_tip_mm, const Posed& from,
                                                       const Vec3d& to_tip_mm, const Posed& to);

/// The same bound for any tcp move, with the joint that sets it: the largest rate along the
/// move (fraction per second, the tip on its line and A, C in proportion, as a tcp controller
/// interpolates a block) at which the linear joints, which follow through the kinematics and
/// not linearly, stay within their velocity limits. Infinite (and X) when no joint moves or A
/// and C stay (the joints then move linearly, as the schedule's chords say). A
/// feed schedule made on the joints at the points alone (their chords) misses this where the
/// table turns within a block.
TAXOPT_API std::pair<double, Joint> joint_velocity_rate_per_s(
    const MachineKinematicsd& ac, const JointLimits& limits, const Vec3d& from_tip_mm,
    const Posed& from, const Vec3d& to_tip_mm, const Posed& to);

/// Writes G-code. Feed moves need a positive feed. `comments` go into the header.
/// @param units units of the output (G20/G21); coordinates inside are mm.
TAXOPT_API GcodeProgram write_gcode(const std::vector<PostedOperation>& operations,
                                    const Machine& machine, LengthUnit units,
                                    const std::vector<std::string>& comments);

/// One motion block read back from G-code (millimetres and degrees).
struct GcodeMove {
  bool rapid = false;
  Vec3d xyz_mm = Vec3d::Zero();
  double tilt_deg = 0.0;
  double c_deg = 0.0;
  /// F word in force: units/min (G94) or 1/min (G93), in the file's units.
  double feed = 0.0;
  bool inverse_time = false;
  int line = 0;
  /// A G2/G3 block: it runs from the previous move's XYZ counter-clockwise about
  /// `arc_normal` (+ or - the plane's axis: G3 or G2) around `arc_centre_mm`, to xyz_mm.
  bool arc = false;
  Vec3d arc_centre_mm = Vec3d::Zero();
  Vec3d arc_normal = Vec3d::UnitZ();
  /// A move in machine coordinates (the safe retract: G53, G28, SUPA, M91), one with an
  /// axis whose workpiece position is not known since (the table turned before the first
  /// point), or one on the way back in after a retract before the block that gives X, Y, Z
  /// and both rotary axes together (the table turn, the positioning at the clearance height,
  /// the descent): it belongs to no point, and xyz_mm holds the last known values.
  bool positioning = false;
  /// The tool length offset is on (G43/G43.4 H, Sinumerik D1..., a TNC's tool call), and the
  /// controller's tool centre point control (LinuxCNC: its kinematics, always; Fanuc G43.4,
  /// Sinumerik TRAORI, TNC M128).
  bool length_offset = false;
  bool tcp = false;
  /// A move in machine coordinates (the dialect's retract: G53, G28, SUPA, M91).
  bool retract = false;
  /// Such a move's target in machine coordinates, mm, for the axes it gives (`given`); Fanuc's
  /// reference return (G28) goes to the machine's reference point instead: zero here.
  Vec3d machine_mm = Vec3d::Zero();
  /// Which of X Y Z A C (bits 0 to 4) the block gives.
  unsigned given = 0;
  /// The machine's state at the block, as the program set it: the tool in the spindle (T with
  /// M6, a TNC's tool call, a template's tool change; 0: none), the spindle (S with M3/M4;
  /// M5, M2, M30 stop it), the coolant (7 mist, 8 flood, 0 off after M9).
  int tool = 0;
  bool spindle_on = false;
  double spindle_rpm = 0.0;
  int coolant = 0;
};

/// The point of the arc of `to` (a G2/G3 move starting at `from_mm`) at the same angle as
/// `near_mm`, clamped to the arc; and the arc's length from its start to there, mm.
TAXOPT_API Vec3d point_on_arc(const Vec3d& from_mm, const GcodeMove& to, const Vec3d& near_mm);
TAXOPT_API double arc_length_mm(const Vec3d& from_mm, const GcodeMove& to);

/// Time the controller takes for the feed move `to` from `from` (both read back, `units` the
/// program's): under G94 the XYZ distance over F, or the rotary distance (deg) over F when
/// only A and C move; under G93 one over F minutes.
TAXOPT_API double block_time_s(const GcodeMove& from, const GcodeMove& to, LengthUnit units);

/// Reads the motion blocks of G-code in the subset taxopt writes for `dialect` (G0/G1, G2/G3
/// with incremental I J K in G17/G18/G19 (not Heidenhain),
/// G90, G93/G94, X Y Z A C F, comments; units G20/G21, Sinumerik G700/G710, Heidenhain
/// G70/G71; Fanuc's %, O, G43.4/G43 H, G49; Sinumerik's TRAORI, ORIAXES, TRAFOOF, D; the
/// Heidenhain ISO program blocks, N numbers and "*"). @throws InputError on anything outside.
/// `verbatim_lines` (GcodeProgram::verbatim_lines) are stepped over. The safe retracts
/// (LinuxCNC `G53 G0 Z`, Fanuc `G91 G28 Z0.` + `G90`, Sinumerik `G0 SUPA Z D0`, TNC
/// `G00 Z M91`) and the end's park of X Y (`G53 G0 X Y` on LinuxCNC, Fanuc, Haas) are read as
/// positioning moves. Haas as Fanuc, with G234 H (tool centre point control). The tilt axis's word
/// is `tilt_letter` (A, or B on a B/C machine; GcodeMove::tilt_deg holds it); the other is refused.
/// `tool_calls` (GcodeProgram::tool_calls) are the verbatim lines that change the tool.
TAXOPT_API std::vector<GcodeMove> read_gcode_moves(
    const std::string& text, const std::string& source,
    GcodeDialect dialect = GcodeDialect::LinuxCNC, const std::vector<int>& verbatim_lines = {},
    char tilt_letter = 'A', const std::vector<std::pair<int, int>>& tool_calls = {});

}  // namespace taxopt
