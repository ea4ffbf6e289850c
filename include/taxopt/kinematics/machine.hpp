#pragma once
/// @file The machine a run is for (CLI.md "Machine file"): its kinematics, axis ranges and
/// senses, pivot, dynamic limits, G-code settings, the holder and clearances it usually runs
/// with. Read from a machine file by io/machine_file.hpp; the stages use it from here.

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"

namespace taxopt {

/// Controller dialect of the G-code (docs/gcode-dialects.md): LinuxCNC (rs274-checked),
/// Fanuc 30i/31i-B5 (G43.4), Siemens Sinumerik 840D (TRAORI), Heidenhain TNC in ISO mode
/// (M128).
/// Haas: the Next Generation Control of a Haas 5-axis mill (UMC series): Fanuc-like, with
/// G234 tool centre point control (docs/gcode-dialects.md).
enum class GcodeDialect { LinuxCNC, Fanuc, Siemens, Heidenhain, Haas };
/// "linuxcnc", "fanuc", "siemens", "heidenhain", "haas".
TAXOPT_API const char* to_string(GcodeDialect dialect);
/// Every dialect taxopt writes, in the order of GcodeDialect.
TAXOPT_API std::vector<GcodeDialect> gcode_dialects();
/// The dialect writes G93 inverse time (a TNC's ISO mode has none).
TAXOPT_API bool has_inverse_time(GcodeDialect dialect);
/// tcp: X Y Z are the tool tip in workpiece coordinates (the controller does TCP);
/// machine: X Y Z are the joint positions after the table rotation (CLI.md convention).
enum class GcodeMode { Tcp, Machine };
/// G94 units per minute, or G93 inverse time.
enum class FeedMode { UnitsPerMinute, InverseTime };
/// What the programmed feed is the speed of, once taxopt has turned the tool axes.
/// cutter-path: of the cut, as the CAM system programmed it: every feed block takes the time
/// the input block takes at its feed (its tip distance over the feed), so the ball centre and
/// the contact point, which do not move when the axis turns, run at the programmed speed and
/// the chip load is unchanged; the F word follows the new tip (or joint) distance.
/// tip: of the new tool tip: F is the programmed feed, and a longer tip path takes longer.
enum class FeedReference { CutterPath, Tip };

/// Coolant switched on for every operation (off after it): none, flood (M8) or mist (M7).
enum class Coolant { None, Flood, Mist };

/// The retract before an operation's first move and after the program's last: to a Z height
/// in machine coordinates in the dialect's own way (LinuxCNC G53, Fanuc G28 reference return,
/// Sinumerik SUPA, Heidenhain M91), or none (the user takes care of it; a warning says so).
enum class SafeRetract { MachineZ, None };

/// Where the program leaves the rotary axes: home (0, 0), turned there after the last retract,
/// so that a continuous C ends within one turn of its home and the next program starts from a
/// known table; or none (the footer homes them, e.g. Haas `G91 G28 B0. C0.`, or the user).
enum class EndPose { Home, None };

/// What a program holds besides its moves; empty strings and lists take the dialect's
/// defaults (docs/gcode-dialects.md "Program template").
struct ProgramTemplate {
  /// Program name (Heidenhain %NAME, a comment elsewhere); "" -> "TAXOPT".
  std::string name;
  /// Fanuc program number O1..O9999.
  int number = 1000;
  /// Work offset block after the set-up ("G54"); "" -> the dialect's (G54; none on a TNC,
  /// whose active preset is used); "none" -> none.
  std::string work_offset;
  Coolant coolant = Coolant::None;
  /// Blocks written as they are: after the set-up, before the program end.
  std::vector<std::string> header, footer;
  /// The tool change; "{tool}" is replaced by the tool number; empty -> the dialect's.
  std::vector<std::string> tool_change;
  /// Blocks before TCP is switched on and after it is off (a kinematics switch such as
  /// LinuxCNC's M428 / M429 of its switchkins configurations).
  std::vector<std::string> tcp_on, tcp_off;
  SafeRetract retract = SafeRetract::MachineZ;
  /// The machine Z of the retract, mm (LinuxCNC, Sinumerik, Heidenhain; Fanuc's G28 goes to
  /// its reference point).
  double retract_z_mm = 0.0;
  /// Machine mode: the largest distance the tip may leave the straight line between two
  /// points while the joints move linearly; longer moves are split (linearisation), mm.
  double linearise_tolerance_mm = 0.01;
  /// LinuxCNC: how far the controller's blending may round the path off the programmed points,
  /// mm: `G64 P<tolerance> Q0` after the set-up (without it LinuxCNC blends "at the best speed
  /// possible, no matter how far away from the programmed point", its G-code reference; Q0:
  /// no naive-CAM merging of the 5-axis blocks). 0: exact path, `G61`. Default 0.01 mm, as the
  /// linearisation's: the path stays within the finishing tolerances of the CAM systems.
  double blend_tolerance_mm = 0.01;
  /// A rapid that turns a rotary axis by more than this (written deg) inside an operation is
  /// an index move: tool up to the retract, the table turned there, XY at that height, then
  /// down (docs/gcode-dialects.md "Index moves"); with a part model, whose check verifies the
  /// swept moves, the turns stay in the air.
  double index_threshold_deg = 1.0;
  /// Tcp mode (not Fanuc): after the retract and the TCP switch the tool comes straight down
  /// to the operation's highest tip plus this, mm, before it moves XY (docs/gcode-dialects.md
  /// "The approach"). CAM systems' clearance heights are of this order above the stock.
  double approach_clearance_mm = 10.0;
  EndPose end_pose = EndPose::Home;
  /// Where the program parks X and Y at its end, in machine coordinates, mm (after the retract
  /// and the rotaries' home, as a machinist brings the table to the door: Haas posts write
  /// G53 Y0); empty: where the last retract leaves them.
  std::optional<std::array<double, 2>> end_park_xy_mm;
};

/// How G-code is written for a machine.
struct GcodeSettings {
  GcodeDialect dialect = GcodeDialect::LinuxCNC;
  GcodeMode mode = GcodeMode::Tcp;
  FeedMode feed_mode = FeedMode::UnitsPerMinute;
  FeedReference feed_reference = FeedReference::CutterPath;
  /// feed_reference "cutter-path": a block keeps its input block's time (its F is the new tip
  /// path over that time), but never at an F above this many times the programmed feed; where
  /// the new tip path would need more, the block takes longer (the contact point runs slower
  /// than programmed there, never faster). Below the programmed feed there is no bound: a low
  /// F over a short tip path keeps the contact at its programmed speed.
  double max_feed_ratio = 2.0;
  /// Decimals of every coordinate and angle (0 to max_decimals(dialect)).
  int decimals = 4;
  /// Decimals of a units-per-minute F word; -1: the dialect's (feed_decimals()).
  int feed_decimals = -1;
  /// The program template (docs/gcode-dialects.md "Program template").
  ProgramTemplate program;
};

/// The most decimals a controller takes for positions and angles: LinuxCNC 8, Fanuc 4
/// (IS-C, 0.0001 mm), Siemens 8, Heidenhain TNC ISO 4 (0.0001 mm), Haas 4.
TAXOPT_API int max_decimals(GcodeDialect dialect);
/// Decimals of an F word the controller takes: Heidenhain TNC ISO 3; the others 15 (no
/// limit of theirs is known to taxopt; a feed schedule writes 8 significant digits).
TAXOPT_API int max_feed_decimals(GcodeDialect dialect);
/// The F decimals written: settings.feed_decimals, else the least of max(decimals, 3) and the
/// dialect's.
TAXOPT_API int feed_decimals(const GcodeSettings& settings);

/// The kinematics names a machine file and Machine::kinematics take: "ac-table-table",
/// "bc-table-table", "ac-head-table", "bc-head-table", "ac-head-head", "bc-head-head" (the
/// tilt axis's letter, then where the tilt and C are: docs/kinematics.md).
inline constexpr const char* kKinematicsNames =
    "ac-table-table, bc-table-table, ac-head-table, bc-head-table, ac-head-head, bc-head-head";
/// The tilt axis and layout a kinematics name stands for; false for a name not in
/// kKinematicsNames.
TAXOPT_API bool kinematics_layout(const std::string& name, TiltAxis& tilt, RotaryLayout& layout);

/// A machine: name, kinematics and how to write its G-code.
/// Where a machine file's [pivot] places the rotary axes (Machine::pivot_frame).
enum class PivotFrame {
  /// In the workpiece's coordinates: relative to the program's zero (CLI.md's [pivot]).
  Workpiece,
  /// In machine coordinates, as a controller's kinematics hold them (LinuxCNC's rot-point
  /// pins): with a work offset the axes lie at the pivot less the offset in the workpiece.
  Machine
};

struct Machine {
  std::string name = "generic-ac-trt";
  std::string kinematics = "ac-table-table";
  MachineKinematicsd rotary = default_machine_kinematics();
  /// Velocity, acceleration and jerk limits of X Y Z (mm) and A C (deg) as the machine file
  /// gives them; 0: not given (effective_limits fills in the defaults).
  JointLimits limits{};
  /// The joints' own acceleration limits (mm/s^2 for X Y Z, deg/s^2 for A C) where a
  /// controller plans the program's axes and lets the joints follow: LinuxCNC with TCP on
  /// holds X Y Z A C to its [AXIS_*] limits (`limits`) and the joints to nothing, so its
  /// [JOINT_n] MAX_ACCELERATION may be above them ([axes.*] joint_max_accel_*). 0: the axis's
  /// own. They judge GcodeProgram::tcp_joint_peaks only (joint_accel_limit).
  std::array<double, kJointCount> joint_max_accel_per_s2{};
  /// Travel of X, Y, Z in machine coordinates (the machine-mode convention of CLI.md), mm:
  /// [axes.X] min_mm/max_mm; unbounded where the file gives none.
  struct LinearRange {
    double min_mm = -std::numeric_limits<double>::infinity();
    double max_mm = std::numeric_limits<double>::infinity();
    bool contains(double v_mm) const { return v_mm >= min_mm && v_mm <= max_mm; }
    bool bounded() const { return std::isfinite(min_mm) || std::isfinite(max_mm); }
  };
  std::array<LinearRange, 3> linear_range;
  /// [checks]: the clearances the shank and holder keep from the part (mm), where the command
  /// line gives none; empty: taxopt's defaults (JobOptions).
  std::optional<double> shank_clearance_mm, holder_clearance_mm;
  /// [holder]: the machine's usual holder (mm), used where the command line names none:
  /// radius_mm, length_mm and the tool's gauge_length_mm (tip to holder face).
  std::optional<double> holder_radius_mm, holder_length_mm, holder_gauge_length_mm;
  /// [defaults]: the spindle speed (rpm) and tool number of an operation whose CL file gives
  /// none and where JobOptions gives none (JobOptions::spindle_rpm, tool_number).
  std::optional<double> default_spindle_rpm;
  std::optional<int> default_tool_number;
  /// [setup] work_offset_mm, or JobOptions::work_offset_mm: where the program's zero sits in
  /// machine coordinates with the rotary axes at home (the work offset a machinist sets, G54's
  /// X Y Z), mm. The travel checks hold every block to the machine's travel with it; empty: not
  /// known, and the program's span alone is held to the travel's.
  std::optional<Vec3d> work_offset_mm;
  /// [pivot] frame: the frame rotary.c_axis_point_mm and tilt_axis_point_mm are given in.
  /// Machine: run_job moves them into the workpiece's by the work offset (the joints are then
  /// the controller's, which rotates the work offset with the table: LinuxCNC's G54 in its
  /// TCP kinematics, measured on its controller); without a work offset the two coincide.
  PivotFrame pivot_frame = PivotFrame::Workpiece;
  GcodeSettings gcode;
  /// A head machine's pivot ([pivot] head_pivot_length): from the tilt axis to the spindle's
  /// gauge line, mm (0 where the tilt axis crosses it, as LinuxCNC's max5); a head machine
  /// must give it, a table-table machine has none (validate). run_job adds the tool's gauge length
  /// (JobOptions::tool.gauge_length_mm, else the machine's holder_gauge_length_mm, else none) into
  /// rotary.head_length_mm for its joint model: the travel, the rapids' and the controller's times.
  std::optional<double> head_pivot_length_mm;
};

/// X Y Z as the G-code writes the tip `tip_mm` at `pose`: the tip itself (tcp mode) or the
/// machine's joints (machine mode, the convention of cli.md).
inline Vec3d written_xyz_mm(const Machine& machine, const Vec3d& tip_mm, const Posed& pose) {
  return machine.gcode.mode == GcodeMode::Machine ? machine.rotary.to_machine_mm(tip_mm, pose)
                                                  : tip_mm;
}
/// The tip that written X Y Z `xyz_mm` mean at `pose` (the inverse of written_xyz_mm).
inline Vec3d tip_of_written_mm(const Machine& machine, const Vec3d& xyz_mm, const Posed& pose) {
  return machine.gcode.mode == GcodeMode::Machine ? machine.rotary.from_machine_mm(xyz_mm, pose)
                                                  : xyz_mm;
}
/// The machine's linear joints for written X Y Z at `pose`, whatever the mode.
inline Vec3d joints_of_written_mm(const Machine& machine, const Vec3d& xyz_mm, const Posed& pose) {
  return machine.gcode.mode == GcodeMode::Machine ? xyz_mm
                                                  : machine.rotary.to_machine_mm(xyz_mm, pose);
}

/// Limits of a typical mid-size A/C trunnion machine, used where the machine file gives
/// none: X Y Z 500 mm/s (30 m/min) and 3000 mm/s^2; A 150 deg/s (25 rpm) and 1000 deg/s^2;
/// C 240 deg/s (40 rpm) and 1500 deg/s^2; no jerk limit.
TAXOPT_API JointLimits default_joint_limits();

/// The machine's limits where its file gives them, else default_joint_limits().
TAXOPT_API JointLimits effective_limits(const Machine& machine);

/// Joint `j`'s own acceleration limit: machine.joint_max_accel_per_s2 where given, else the
/// axis's (`effective`, from effective_limits).
inline double joint_accel_limit(const Machine& machine, const JointLimits& effective,
                                std::size_t j) {
  return machine.joint_max_accel_per_s2[j] > 0.0 ? machine.joint_max_accel_per_s2[j]
                                                 : effective[j].max_accel_per_s2;
}

/// The built-in machine of CLI.md: A in [-120, 120] deg, C continuous, LinuxCNC, TCP.
TAXOPT_API Machine default_machine();

/// The built-in machine with the kinematics `kinematics` (kKinematicsNames: "bc-table-table",
/// "ac-head-head", ...): its name, tilt axis (rotary.tilt_about) and layout (rotary.layout)
/// set from that one name, the tilt axis's range [-120, 120] deg, C continuous, LinuxCNC, TCP;
/// a head machine's pivot length, mm, given (none for a table-table machine). Change what
/// differs on your machine (senses, ranges, limits, dialect) after:
/// `Machine m = make_machine("bc-head-head", 250.0); m.rotary.tilt.sense = -1;`
/// @throws InputError for a name not in kKinematicsNames, a head machine without its pivot
/// length or a table-table machine with one.
TAXOPT_API Machine make_machine(const std::string& kinematics,
                                std::optional<double> head_pivot_length_mm = std::nullopt);

/// Checks a machine made in code as the machine file's reader checks a file: the kinematics
/// name against its tilt axis, the rotary ranges (min <= max, no NaN) and senses, the limits
/// (finite, >= 0; 0: not given), the linear travel, the pivots (finite), the G-code settings
/// (decimals and F decimals within the dialect's, inverse time where the dialect writes it,
/// the feed ratio, the tolerances, the end pose and park within the ranges). run_job calls it
/// before any work. @throws InputError naming the field and what was expected.
TAXOPT_API void validate(const Machine& machine);

}  // namespace taxopt
