#pragma once
/// @file One run of taxopt as a library call: a read toolpath and a machine in, G-code,
/// metrics, verification and report data out. The CLI is a thin layer over run_job.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "taxopt/core/error.hpp"
#include "taxopt/core/export.hpp"
#include "taxopt/core/option_names.hpp"
#include "taxopt/core/stop.hpp"
#include "taxopt/core/toolpath.hpp"
#include "taxopt/core/version.hpp"
#include "taxopt/cspace/cspace.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/kinematics/machine.hpp"
#include "taxopt/kinematics/metrics.hpp"
#include "taxopt/kinematics/pose_planner.hpp"
#include "taxopt/plan/global_optimiser.hpp"
#include "taxopt/plan/paper_optimiser.hpp"

namespace taxopt {

/// Tool-axis method. `None` keeps the input axes (post-processing only).
enum class Method { None, Paper, Global };
/// "none", "paper", "global".
TAXOPT_API const char* to_string(Method method);

/// Clearances the shank (past the flutes) and the holder keep from the part when neither the
/// options nor the machine file give them, mm.
constexpr double kDefaultShankClearanceMm = 0.5;
constexpr double kDefaultHolderClearanceMm = 1.0;

/// Largest change of a tool axis without a part to check it against, deg: what a controller
/// smooths orientations by on its own, with no part model (Sinumerik's CYCLE832 examples
/// program OTOL = 1 deg for 5-axis finishing; docs/cli.md).
constexpr double kNoPartMaxDeviationDeg = 1.0;

/// Options of run_job, with the CLI's defaults.
struct JobOptions {
  Method method = Method::Paper;
  /// Feed for the metrics: overrides the file's feeds when given. When the file
  /// has no feed at all, it (or `default_feed_mm_per_min`) is also the feed written.
  std::optional<double> feed_mm_per_min;
  double default_feed_mm_per_min = 1000.0;
  /// The spindle speed (rpm) and tool number of an operation whose CL file gives none
  /// here; else the machine's (Machine::default_spindle_rpm, default_tool_number). With none
  /// of the three, run_job refuses such an operation (InputError): a program must call its tool and
  /// turn its spindle before it cuts.
  std::optional<double> spindle_rpm;
  std::optional<int> tool_number;
  /// Units of the G-code; empty: the CL file's.
  std::optional<LengthUnit> units_out;
  PosePlanOptions pose_options;
  /// The paper's optimiser (Method::Paper): deviation cone, candidate grid, segmenter and joint
  /// smoothing.
  PaperOptions paper;
  /// Method::Global (global_optimiser.hpp): its objective and jerk weight. Its cone is the run's
  /// (max_deviation_deg, else paper.max_deviation_deg): run_job refuses a global.max_deviation_deg
  /// of its own. It starts from the paper's axes.
  GlobalOptions global;
  /// The part (not owned); without it there is no contact recovery and no collision check,
  /// and the deviation cone shrinks to kNoPartMaxDeviationDeg unless `max_deviation_deg` is
  /// given (JobResult::safety_warnings says so).
  const Part* part = nullptr;
  /// The deviation cone, deg; overrides paper.max_deviation_deg. Empty: that
  /// one with a part, at most kNoPartMaxDeviationDeg without.
  std::optional<double> max_deviation_deg;
  ContactOptions contact;
  /// Tool dimensions overriding the CL file's (mm), for contact recovery and collision checks.
  ToolOverrides tool;
  /// Clearances the shank (past the flutes) and the holder keep from the part in every check
  /// in mm: the optimisers accept, and the verification
  /// passes, only axes where the grown bodies are free (docs/cli.md).
  /// Empty: the machine's (Machine::shank_clearance_mm, holder_clearance_mm), else
  /// kDefaultShankClearanceMm / ...HolderClearanceMm.
  std::optional<double> shank_clearance_mm, holder_clearance_mm;
  /// How far the flutes may reach into the part mesh without a collision: its chordal error
  /// in mm; empty: the contact tolerance (contact_tolerance_mm: max(0.05, the
  /// mesh's chordal error + the CL file's tolerance band)).
  std::optional<double> part_tolerance_mm;
  /// The least angle a method's axis keeps from the designed surface's normal at a contact
  /// in deg: at the ball's tip the cutting speed is zero, so a CAM system leads or
  /// tilts the tool off the normal. At each contact the bound is the lesser of this and the
  /// input's own angle there: no method brings the axis nearer the normal than the CAM did, and
  /// none is refused for an input that comes nearer than asked. Empty: the input's own least
  /// over the operation's touching feed points, rounded down to 0.1 deg, 10 deg at most (a
  /// larger tilt is the CAM's for reach or clearance), held where it is 1 deg at least (an
  /// input nearer the normal holds no lead); 0: no bound. Where no free axis keeps
  /// it a point gives it up (FindingCode::LeastTiltNotKept); the report
  /// (OperationResult::Cutting) names the points and moves below it.
  std::optional<double> min_tilt_deg;
  /// Where the program's zero sits in machine coordinates, mm; replaces
  /// Machine::work_offset_mm.
  std::optional<Vec3d> work_offset_mm;
  /// Rasterise the C-space of every contact point (cspace.hpp) and fill PointRow::free_cells
  /// (with a part only; costs about 10 ms a point at 2 deg, docs/benchmarks.md).
  bool count_free_cells = false;
  /// C-space maps per operation (with a part): the contact with the fewest free cells and
  /// the one whose axis changed most (0: none). Implies count_free_cells.
  bool cspace_maps = false;
  /// Write the scheduled feed of every feed move: the fastest the machine's
  /// limits allow, never above the programmed feed (feed_schedule.hpp). The dynamic limits
  /// are then checked at those feeds with the machine's effective limits (its own, else the
  /// defaults); otherwise at the programmed feeds, with the limits its file gives.
  bool feed_schedule = false;
  /// Receives progress and informational lines (the library never prints).
  std::function<void(const std::string&)> log;
  /// Receives the progress of the long stages ("contact recovery", "optimisation", "posting",
  /// "writing", "verification", in that order): items done of total, from 0 and once per whole
  /// percent up to done == total. Called from any of the job's threads, never concurrently. An
  /// exception it throws stops the job (as `stop` does) and is what run_job throws.
  std::function<void(const std::string& stage, std::size_t done, std::size_t total)> progress;
  /// Stops the job from another thread: run_job throws Cancelled, nothing is returned.
  StopSource stop;
  /// Worker threads of the job (its own task arena; other jobs and the caller's own TBB work
  /// are not limited by it); 0: all cores. The result does not depend on it.
  std::size_t threads = 0;
  /// How the caller names these fields in its messages (option_names.hpp): run_job's errors
  /// and findings that say which option to set name it so ("JobOptions::part" unless mapped).
  OptionNames option_names;
  /// `field` ("tool.ball_radius_mm") as the caller names JobOptions::field (option_names).
  std::string name_of(const std::string& field) const {
    return option_name(option_names, "JobOptions::" + field);
  }
};

/// Checks the options' values as run_job does first (each number within its documented
/// range: the cone, the grid, the feed, the tool's dimensions, the tolerances, the clearances,
/// the spindle speed, the tool number, the threads), without a toolpath or a machine: a caller
/// can check them before it reads any file. @throws InputError naming the field (as
/// options.option_names names it) and the value.
TAXOPT_API void check_options(const JobOptions& options);

/// What run_job proved about its output.
struct Verification {
  /// Largest distance between a written XYZ (mapped to the workpiece) and the intended tip.
  double roundtrip_max_mm = 0.0;
  /// Largest angle between FK(A, C) of the written values and the intended axis.
  double roundtrip_max_deg = 0.0;
  /// Collision-free by the part check; empty when no part was given (nothing checked).
  std::optional<bool> collision_free;
  /// Moves between consecutive CL points (sampled as the machine moves them, linear in its
  /// joints, at most 0.5 deg and 0.1 mm apart) where the tool hits the part; empty: not checked.
  std::optional<long> colliding_moves;
  /// The blocks of the program the operation's point and move checks do not cover (the
  /// approach, the descent and the XY move to it, index moves, retracts, the end moves: the
  /// blocks taxopt adds), swept against the part with the whole tool in the air as the
  /// controller runs them, and those where it hits (check_every_block); empty: not checked.
  std::optional<long> blocks_swept, colliding_blocks;
  /// Of those blocks, the ones whose end is not known relative to the part: a retract in
  /// machine coordinates (G53 and the like) and the blocks after it until one gives the tool's
  /// X Y Z in the workpiece again (the table's turn at the retract height, a descent): where
  /// they put the tool depends on the work offset and the tool length, which the program does
  /// not hold. Not checked; empty without a part.
  std::optional<long> blocks_not_checked;
  /// A guaranteed lower bound (true value within a factor sqrt 2 above it) of the least
  /// distance between the part and the tool's bodies that do not cut (shank and holder, past
  /// the flutes) at the written CL points, mm, capped at 10 mm; and the point where it
  /// occurs. Empty without a part or when the flutes reach the holder.
  std::optional<double> min_clearance_mm;
  /// Written CL points where the flutes reach deeper into the part than the part tolerance (a
  /// gouge of the cutter, told apart from collisions of the shank and holder); empty: not
  /// checked.
  std::optional<long> flute_gouge_points;
  std::size_t min_clearance_index = 0;
  bool within_axis_limits = true;
  /// Every written point's move runs with the tool length offset on, and in tcp mode with the
  /// controller's tool centre point control on (read back from the G-code).
  bool tool_length_active = true;
  /// Joint velocities and accelerations within the limits at the written feeds, as the
  /// controller moves (linear in the joints, from rest at each chain of feed moves): the
  /// machine's limits, or with JobOptions::feed_schedule the effective ones (true when none).
  bool within_dynamic_limits = true;
};

/// What fired at one CL point (PointRow::marks, the CSV's `findings`, the HTML page's markers):
/// a bit each. The move marks are of the move into the point.
enum class PointMark : std::uint32_t {
  PointCollision = 1u << 0,  ///< the shank or holder (or a ball in the air) hits the part here
  FluteGouge = 1u << 1,      ///< the flutes reach deeper than the part tolerance here
  MoveCollision = 1u << 2,   ///< the tool hits the part on the move into this point
  KeptCollision = 1u << 3,   ///< input axis kept: the optimised axes hit the part
  KeptPeakRate = 1u << 4,    ///< input axis kept: the optimised axes raised the pass's peak rate
  KeptJoin = 1u << 5,        ///< blended between kept and optimised axes
  NoFreeAxis = 1u << 6,      ///< no acceptable axis within the deviation cone
  AxisLimit = 1u << 7,       ///< the written tilt or C is at (within 0.01 deg) or past its range
  TravelExceeded = 1u << 8,  ///< the spindle leaves the linear travel here
  CFlip = 1u << 9,           ///< C turns by more than 90 deg on the move into this point (after)
  CFlipBefore = 1u << 10,    ///< the same with the input axes
  NotChecked = 1u << 11,     ///< no collision check judged the tool here (no part, or no model)
};
/// Every mark, in bit order.
inline constexpr PointMark kAllPointMarks[] = {
    PointMark::PointCollision, PointMark::FluteGouge,   PointMark::MoveCollision,
    PointMark::KeptCollision,  PointMark::KeptPeakRate, PointMark::KeptJoin,
    PointMark::NoFreeAxis,     PointMark::AxisLimit,    PointMark::TravelExceeded,
    PointMark::CFlip,          PointMark::CFlipBefore,  PointMark::NotChecked};
/// "point_collision", "flute_gouge", "move_collision", "kept_collision", "kept_peak_rate",
/// "kept_join", "no_free_axis", "axis_limit", "travel_exceeded", "c_flip", "c_flip_before",
/// "not_checked".
TAXOPT_API const char* to_string(PointMark mark);
/// The marks set in `marks`, in bit order, joined by `;` (the CSV's `findings`).
TAXOPT_API std::string point_marks_text(std::uint32_t marks);

/// Per-point values for the CSV (after optimisation).
struct PointRow {
  std::size_t index = 0;
  /// The CL file's line of this point.
  int line = 0;
  /// What fired here: PointMark bits.
  std::uint32_t marks = 0;
  void mark(PointMark m) { marks |= static_cast<std::uint32_t>(m); }
  bool has(PointMark m) const { return (marks & static_cast<std::uint32_t>(m)) != 0; }
  double arc_mm = 0.0;
  Vec3d tip_mm = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
  double tilt_axis_deg = 0.0, c_deg = 0.0;
  double omega_deg_s = 0.0, accel_deg_s2 = 0.0;
  /// The same per rotary axis (signed): the tilt axis (A or B) and C.
  double omega_tilt_deg_s = 0.0, omega_c_deg_s = 0.0;
  double accel_tilt_deg_s2 = 0.0, accel_c_deg_s2 = 0.0;
  /// Contact geometry, when a part was given and the ball touches it here: the designed
  /// surface's contact and normal (ContactPoint::surface_cc_mm, surface_normal), the input
  /// axis's tilt and yaw in its frame, the exact gap to the mesh, where the contact lies and
  /// the angle between the mesh's and the surface's normals.
  bool has_contact = false;
  Vec3d cc_mm = Vec3d::Zero(), normal = Vec3d::UnitZ();
  double tilt_deg = 0.0, yaw_deg = 0.0;
  double gap_mm = 0.0;
  SurfacePlace place = SurfacePlace::Smooth;
  double normal_uncertainty_deg = 0.0;
  /// The same with the input axes as the machine would have run them (the "before").
  double tilt_axis_before_deg = 0.0, c_before_deg = 0.0;
  double omega_before_deg_s = 0.0, accel_before_deg_s2 = 0.0;
  /// Where the ball touches: the written axis's angle from the designed surface's normal, and
  /// the ball's effective cutting diameter at the contact, 2 R sin(that angle), with the input
  /// axis (before) and the written one, mm (OperationResult::Cutting).
  double tilt_after_deg = 0.0;
  double cutting_diameter_before_mm = 0.0, cutting_diameter_mm = 0.0;
  /// A key point of the optimiser: an end of one of its intervals (segment boundary).
  bool key = false;
  /// Scheduled feed of the move into this point (the feed the machine can hold there, mm/min:
  /// programmed feed x programmed time / scheduled time), after and before; empty for rapids
  /// and the first point.
  std::optional<double> feed_mm_min, feed_before_mm_min;
  /// Free cells of the C-space grid at this contact (cell size PaperOptions::grid_deg, within
  /// the deviation cone of the input axis; each axis once), when JobOptions::count_free_cells asked
  /// for them.
  std::optional<std::size_t> free_cells;
};

/// Contact recovery summary of an operation.
struct ContactSummary {
  bool recovered = false;
  std::size_t touching = 0, in_air = 0, local_gouges = 0;
  double max_abs_gap_mm = 0.0;
  double tolerance_mm = 0.0;
  /// Touching points on a designed edge or corner (ContactPoint::place), where the ball rolls
  /// over a feature and no smooth normal holds.
  std::size_t edge_points = 0, corner_points = 0;
  /// The largest ContactPoint::normal_uncertainty_rad over the touching points on the smooth
  /// surface, deg: the facets' normals against the smooth ones.
  double max_normal_uncertainty_deg = 0.0;
};

/// The C-space grid of one contact point (the paper's fig. 10), with the input and output
/// axes as (tilt, yaw) in the contact's frame (T, K, N), tilt >= 0.
struct CSpaceMap {
  std::size_t index = 0;
  CSpaceGrid grid;
  double input_tilt_deg = 0.0, input_yaw_deg = 0.0;
  double output_tilt_deg = 0.0, output_yaw_deg = 0.0;
  /// The deviation cone the grid was computed in, deg.
  double max_deviation_deg = 30.0;
  /// Why this point was chosen ("fewest free cells", "largest axis change").
  std::string why;
};

/// The feed schedule of an operation at the machine's effective limits (feed_schedule.hpp).
struct FeedSummary {
  /// Feed moves at their scheduled feeds plus rapids on their joints' trapezoids, s: the
  /// operation's own cycle, what the methods compare. The move into an operation's first
  /// point (from the previous one) is not counted; the table's turn before it is table_turn_s.
  double cycle_time_s = 0.0;
  /// Its two parts, s: the feed moves at their scheduled feeds (each block's time as the
  /// controller runs it from the F word written), the rapids (retract, traverse, descent) on
  /// their joints' trapezoids. cycle_time_s = feed_time_s + rapid_time_s.
  double feed_time_s = 0.0, rapid_time_s = 0.0;
  /// The table turned with the tool up, A and C on their trapezoids: to the operation's first
  /// pose from the previous operation's last (the first: from home, A = C = 0), and for the
  /// last operation back home (gcode.end_pose "home"), s; the program's time adds it to the
  /// cycles (tests/controller: the global method's first turn of two whole turns took 24 s that the
  /// report did not show).
  double table_turn_s = 0.0;
  /// The part of rapid_time_s the rotary joints add: over the rapids, each one's time less the
  /// time of its linear joints alone, s. Between passes it is what turning the tool costs
  /// (the turn is spread over the rapids in the air where that is faster, air_turn.hpp).
  double transition_excess_s = 0.0;
  /// Share of the feed moves' tip path length where the schedule is below the programmed feed.
  double feed_limited_fraction = 0.0;
  /// Lowest scheduled feed, mm/min (0 when there is no feed move).
  double min_feed_mm_min = 0.0;
  /// Length of the feed moves' tip path, mm. With feed_reference "tip" the programmed feed
  /// applies to it, so new axes that swing the tip more lengthen the cycle even where no limit
  /// binds; with "cutter-path" (the default) each block keeps its input time instead.
  double feed_path_mm = 0.0;
  /// The joint ("X" ... "C") whose limits hold the feed down over the longest path, and
  /// whether its velocity or acceleration does; empty when the programmed feed holds.
  std::string limiting_axis, limiting_kind;
  /// Largest number of sweeps the scheduler needed on a chain of feed moves.
  int sweeps = 0;
};

/// A rotary axis's peak rate against the machine's limit for it: the machine limits each axis
/// on its own (a trunnion's tilt is far slower than its C), so a combined figure can fall while
/// one axis rises.
struct AxisShare {
  /// 'A' or 'B' (the tilt axis), or 'C'.
  char axis = 'C';
  /// "omega" (peak angular velocity) or "accel" (peak angular acceleration).
  std::string rate;
  /// The machine file's limit, deg/s or deg/s^2.
  double limit = 0.0;
  /// The peak of the input's axes and of the written program, each over the limit.
  double before = 0.0, after = 0.0;
};

/// The axis and rate whose peak comes nearest its limit (the larger of its before and after
/// share), among the limits the machine gives (Machine::limits; the defaults a schedule falls
/// back on are no machine's); empty where it gives none for A/B or C.
TAXOPT_API std::optional<AxisShare> worst_axis_share(const RotarySummary& before,
                                                     const RotarySummary& after,
                                                     const Machine& machine);

/// Result of one operation.
struct OperationResult {
  std::string name;
  std::size_t points = 0;
  /// Feed used for the metrics (the first feed move's), mm/min.
  double feed_mm_min = 0.0;
  /// The rotary rates of the input axes and of the program as the machine runs them: each
  /// feed move at the time the controller takes from the words written (tip path / F, the
  /// block's kept time, or with JobOptions::feed_schedule the scheduled one), the input's likewise.
  RotarySummary before, after;
  /// The axis whose peak rate comes nearest the machine's limit for it (worst_axis_share);
  /// empty where the machine gives no rotary limit.
  std::optional<AxisShare> worst_axis;
  /// The cutting conditions at the contacts (with a part and a ball): at the ball's tip the
  /// cutting speed is zero, so the angle between the axis and the designed surface's normal
  /// sets the effective cutting diameter 2 R sin(angle) and speed pi D n.
  struct Cutting {
    /// The least tilt measured against (JobOptions::min_tilt_deg, else the input's least
    /// rounded down to 0.1 deg, 10 deg at most), whether it was given, and whether the methods
    /// hold it (given and not 0; by default where it is 1 deg at least).
    double least_tilt_deg = 0.0;
    bool least_tilt_given = false;
    bool least_tilt_held = false;
    /// Touching feed points whose written axis is nearer the normal than the bound asked there
    /// (the least tilt, or the input's own angle where that is less; less kTiltAllowanceDeg):
    /// the points where no free axis keeps it (FindingCode::LeastTiltNotKept), and the first
    /// one's CL line.
    std::size_t points_below = 0;
    int first_line_below = 0;
    /// Feed moves between two touching points whose ends keep that bound but whose axis, as the
    /// machine turns it between them, passes nearer the normal (the axis goes from one side of
    /// the normal to the other within the move), and the first one's CL line (its end's).
    std::size_t moves_past_normal = 0;
    int first_line_past = 0;
    /// Over the touching feed points: the least angle from the normal, deg, and the effective
    /// cutting diameter's least and mean, mm; before (input axes) and after (written).
    double least_tilt_before_deg = 0.0, least_tilt_after_deg = 0.0;
    double least_diameter_before_mm = 0.0, mean_diameter_before_mm = 0.0;
    double least_diameter_after_mm = 0.0, mean_diameter_after_mm = 0.0;
    /// The spindle speed the diameters turn at (rpm; 0: the file gives none, no speed).
    double spindle_rpm = 0.0;
    std::size_t points = 0;
  };
  std::optional<Cutting> cutting;
  /// The paper's metric (eq. 16-18): the angles over the contact points' arc lengths at the
  /// metric feed. For comparison with the paper only: on a meshed part the contact points
  /// carry the facets, and no optimiser or guard judges by it.
  RotarySummary paper_before, paper_after;
  /// Feed schedules of the input axes and of the written G-code.
  FeedSummary feed_before, feed_after;
  /// CL points whose tool intersects the part (shank and holder above the ball; the ball too
  /// where it is in the air), with the input and with the output axes; empty: not checked.
  std::optional<long> colliding_before, colliding_after;
  double max_axis_change_deg = 0.0;
  int segments = 0;
  ContactSummary contact;
  Verification verification;
  /// Each stage's own wall time for this operation, s: contact recovery, the C-space raster
  /// (JobOptions::count_free_cells, cspace_maps), the optimiser with its guards, posting and
  /// writing (the write shared evenly), the verification without the raster.
  double time_contacts_s = 0.0, time_cspace_s = 0.0, time_optimise_s = 0.0, time_post_s = 0.0,
         time_verify_s = 0.0;
  /// With an optimiser: the points of the feed passes whose written axis is their input
  /// axis, by why. `collision`: the method's axes' points or moves hit the part; `peak_rate`:
  /// they raised a rotary axis's omega or a above the input's peak over the pass; `no_gain`:
  /// they gained nothing on the pass; `no_free_axis`: no acceptable axis within the cone;
  /// `method_choice`: the method chose the input's axis itself (the time objective's input
  /// plan, a fallback). `join_points` were blended between kept and optimised axes; `passes`
  /// are written whole with the input's axes.
  struct KeptInputPoints {
    std::size_t collision = 0, peak_rate = 0, no_gain = 0, no_free_axis = 0, method_choice = 0;
    std::size_t join_points = 0;
    std::size_t passes = 0, stretches = 0;
    std::size_t total() const {
      return collision + peak_rate + no_gain + no_free_axis + method_choice;
    }
  };
  std::optional<KeptInputPoints> kept_input_points;
  /// GlobalObjective::Time: the plan kept (paper, sum-squares, sum-squares-fine, time, input), its
  /// scheduled cycle and peak a, and the shortest plan's: within the tie band of the shortest
  /// cycle the smoothest plan wins (GlobalOptions::time_tie_band).
  struct TimeChoice {
    std::string plan, shortest_plan;
    double cycle_s = 0.0, peak_accel_deg_s2 = 0.0;
    double shortest_cycle_s = 0.0, shortest_peak_accel_deg_s2 = 0.0;
    double tie_band = 0.0;
  };
  std::optional<TimeChoice> time_choice;
  /// The F words of the operation's feed blocks as written (read back), against the feed the
  /// CL file programmed for each: the least and the largest ratio, over `blocks` blocks; the
  /// blocks GcodeSettings::max_feed_ratio lengthened (feed_reference "cutter-path": their F
  /// would have left the ratio to keep the input block's time). Empty for inverse time (G93).
  struct FeedWords {
    double min_ratio = 0.0, max_ratio = 0.0, max_feed_ratio = 0.0;
    std::size_t blocks = 0, lengthened_blocks = 0;
  };
  std::optional<FeedWords> feed_words;
  std::vector<PointRow> rows;
  /// With JobOptions::cspace_maps: the maps of the chosen points.
  std::vector<CSpaceMap> cspace_maps;
  /// The paper's metric over the mesh's own contacts (the facets' points), beside
  /// paper_before/after over the designed surface's: what the mesh's uncertainty alone makes
  /// of it. `paper_gain_claimed`: its peak a falls under both; where it does under one only,
  /// the reduction is the mesh's, not the method's, and the report does not claim it.
  RotarySummary paper_before_facets, paper_after_facets;
  bool paper_gain_claimed = false;
};

/// What a run found, by kind: programs test the code, people read the message.
enum class FindingCode {
  // Safety: what was not checked, or checked less, and could hurt a machine.
  NoPart,           ///< no part model: no collision check, a narrow deviation cone
  NoHolderModel,    ///< the holder is not checked against the part
  NoSafeRetract,    ///< gcode.safe_retract = "none"
  NoLinearisation,  ///< machine mode without linearisation
  NoToolModel,      ///< with a part, an operation with no tool geometry: nothing of it checked
  NoCoolant,        ///< neither the CL file nor the machine file asks for coolant
  NoWorkOffset,     ///< a machine with travel, no work offset: only the program's span checked
  // Warnings: the output is sound; something the user should know.
  NotABallMill,       ///< an operation's tool is no ball-end mill: its input axes are kept
  LocalGouge,         ///< a concave radius below the ball radius at contact points (eq. 19)
  InputAxesKept,      ///< the guard kept the input axes over passes or stretches
  MissingFeed,        ///< feed moves without a feed: the fallback feed is used
  JerkLimitExceeded,  ///< a joint's jerk above its limit (velocity and acceleration hold)
  LongerCycle,        ///< at the machine's limits the new axes take longer than the input's
  ClFileNote,         ///< what the CL reader noted (a record skipped, a frame applied, ...)
  TcpJointLimit,      ///< LinuxCNC tcp: a rapid its planner moves drives a joint past its limit
  FeedInAir,          ///< feed points in the air between touching points of their pass
  MeshSlivers,        ///< zero-area faces of the part's file dropped (no surface lost)
  PartTolerance,      ///< the part tolerance is not the larger contact tolerance given
  AxisRateRose,       ///< a rotary axis's peak omega or a above the input's (and why)
  LeastTiltNotKept,   ///< no free axis in the cone keeps the least tilt from the normal there
  // Problems: the output is not to be used (JobResult::ok() is false).
  NoFreeAxis,            ///< no acceptable axis within the deviation cone at a point
  UnreachablePose,       ///< no pose within the machine's axis ranges
  AxisRangeExceeded,     ///< a written rotary value outside its range
  TurnInCut,             ///< a rotary turns over 180 deg in a feed move: the tool sweeps round
  TravelExceeded,        ///< a written linear joint outside its travel
  DynamicLimitExceeded,  ///< a joint's velocity or acceleration above its limit
  ToolLengthOffsetOff,   ///< a move written without the tool length offset (or TCP) in force
  ReadBackMismatch,      ///< the G-code read back is not what was meant
  DeviationExceeded,     ///< an output axis outside the deviation cone
  PointCollision,        ///< CL points whose tool hits the part
  MoveCollision,         ///< moves where the tool hits the part between CL points
  // The program as a machinist checks it, on the read-back (a machinist's review,
  // tests/test_program.cpp).
  NoToolCalled,         ///< a move with no tool called (T .. M6, a TNC's tool call)
  SpindleOff,           ///< a feed move with the spindle stopped
  CoolantMismatch,      ///< an operation starts with other coolant than the CL file asks
  IndexWithoutRetract,  ///< without a part: a rapid turns the table more than the threshold
  DiagonalApproach,     ///< a rapid leaves the retract height diagonally (not XY, then Z)
  EndPoseNotHome,       ///< end_pose "home": the program ends away from the rotaries' home
};
/// "no_part", "no_free_axis", ...: the report's `findings[].code`.
TAXOPT_API const char* to_string(FindingCode code);

enum class Severity { Safety, Warning, Problem };
/// "safety", "warning", "problem".
TAXOPT_API const char* to_string(Severity severity);

/// One finding: its kind, its severity, where (an operation's index into the toolpath, a CL
/// line and a line of the written G-code, each when known) and a message for display.
struct Finding {
  FindingCode code;
  Severity severity;
  std::optional<std::size_t> operation;
  /// 1-based line of the CL file; 0: no CL line (a finding about the program or its blocks).
  int line = 0;
  std::string message;
  /// 1-based line of the written G-code the finding is about (a block the writer added, a
  /// controller limit met at a block), when it is about one.
  std::optional<int> gcode_line;
};

/// Result of run_job. `ok()` is false when the output could not be made safe: `problems`
/// says why (one line each, with the CL line); the G-code is then not to be used.
struct TAXOPT_API JobResult {
  std::vector<OperationResult> operations;
  /// Everything below as structured findings, in the order found.
  std::vector<Finding> findings;
  /// The findings' messages by severity (display; the same order).
  std::vector<std::string> problems;
  /// What was not checked and could hurt a machine (no part, no holder model), shown first.
  std::vector<std::string> safety_warnings;
  std::vector<std::string> warnings;
  /// True when some finding has this code.
  bool has(FindingCode code) const;
  /// The tool axes were checked against a part (collision_free and colliding_* mean something).
  bool collision_checked = false;
  GcodeProgram gcode;
  std::string out_cls;
  LengthUnit gcode_units = LengthUnit::Millimetre;
  /// The machine's tilt axis letter, 'A' (A/C) or 'B' (B/C): the plots' titles name it. The
  /// axis's value is PointRow::tilt_axis_deg (PointRow::tilt_deg is the tool's tilt against the
  /// surface normal, another angle); the CSV's column keeps the name A_deg (docs/cli.md).
  char tilt_letter = 'A';
  bool ok() const { return problems.empty(); }
};

/// A part mesh as run_job takes it (JobOptions::part): in mm and in the frame the CL reader
/// posts the points in. `mesh` is in `mesh_units` and in the CL file's own coordinates: an
/// inch CL file's part may be in inches (the CLI's convention: the CL file's units) or in mm;
/// where the reader moved the points into an MSYS frame (ClReadOptions::apply_msys), the mesh
/// moves with them. Where the points are posted as written in the MCS an MSYS names (the
/// default), the mesh may be in that MCS or in absolute coordinates: the frame in which the
/// ball (of `ball_radius_mm`, else the file's ball-end tool) touches the mesh at more of the
/// sampled feed points is taken, and `note` says which and why. @throws InputError when the
/// file's applied MSYS records name different frames (one mesh cannot be in all of them), when
/// the mesh fits the points in neither frame or in both alike (MeshFrame below says which),
/// or when a vertex is not finite.
TAXOPT_API TriangleMesh part_mesh_for(const Toolpath& toolpath, TriangleMesh mesh,
                                      LengthUnit mesh_units, std::string* note = nullptr,
                                      std::optional<double> ball_radius_mm = std::nullopt);

/// Which frame a part mesh is in where the CL points are posted in the MCS an MSYS names
/// (part_mesh_for): judged from where the ball touches it (Auto; refused where both frames
/// fit the sampled points alike: a tie is no evidence), that MCS, or absolute coordinates
/// (moved into the MCS).
enum class MeshFrame { Auto, Mcs, Absolute };

/// part_mesh_for with the mesh's frame given (`frame`) rather than judged.
TAXOPT_API TriangleMesh part_mesh_for(const Toolpath& toolpath, TriangleMesh mesh,
                                      LengthUnit mesh_units, MeshFrame frame,
                                      std::string* note = nullptr,
                                      std::optional<double> ball_radius_mm = std::nullopt);

/// Tool dimensions as a user gives them, in one length unit (the CLI: the CL file's).
struct ToolDimensions {
  LengthUnit units = LengthUnit::Millimetre;
  std::optional<double> ball_radius, shank_radius, flute_length, holder_radius, holder_length,
      gauge_length;
};
/// The same in mm, as JobOptions::tool takes them (check_options checks them there, each
/// within (0, 1000] mm).
TAXOPT_API ToolOverrides tool_overrides(const ToolDimensions& given);

/// Runs the job. @throws InputError (taxopt/core/error.hpp; InputError::place() says the
/// operation, point and field) for input the boundary refuses (check_options, validate(const
/// Machine&), every point, tool and part), options that cannot apply (a method this build
/// lacks) and a part that does not fit the CL file (no point touches it, or a ball cuts into
/// it: the CL line is named); Cancelled (taxopt/core/stop.hpp) when JobOptions::stop was
/// requested. Outcomes (out of limits, failed verification) are in JobResult::problems.
TAXOPT_API JobResult run_job(const Toolpath& toolpath, const Machine& machine,
                             const JobOptions& options);

/// The options a run applies, all defaults made explicit: the deviation cone (as given, else
/// the paper's default with a part and at most kNoPartMaxDeviationDeg without one), the
/// machine file's holder where the options name none (its radius, length and gauge length),
/// and the clearances (as given, else the machine file's [checks], else the defaults). run_job
/// runs with these; the report records them.
TAXOPT_API JobOptions resolved_options(const JobOptions& given, const Machine& machine);

/// The tool axes and machine poses of a run without G-code, for a post-processor that writes
/// its own program: the stages of run_job up to posting (the options checked, the contacts, the
/// method's axes with their guards, the machine's poses with the turns between passes), the
/// same axes and poses run_job writes. Nothing here is verified as written (no read-back, no
/// FCL check of the output, no dynamic limits): run_job does that.
struct TAXOPT_API AxisPlan {
  /// Per operation: the points with the planned axes and tips (the ball centres where the CL
  /// file put them; feeds as posted) and per point the machine's pose; empty when a pose is
  /// unreachable (a finding with FindingCode::UnreachablePose names the line).
  std::vector<PostedOperation> operations;
  /// Per operation and point, the contacts (empty without a part or for a tool not a ball).
  std::vector<std::vector<ContactPoint>> contacts;
  /// What the stages found (as JobResult::findings).
  std::vector<Finding> findings;
  /// No finding of severity Problem.
  bool ok() const;
};
/// @throws InputError as run_job.
TAXOPT_API AxisPlan plan_axes(const Toolpath& toolpath, const Machine& machine,
                              const JobOptions& options);

/// What a report records of the run itself, so that it can be reproduced (given by the
/// caller: the library does not know its command line or clock).
struct RunInfo {
  /// The command line as typed (arguments quoted where the shell needs it).
  std::string command_line;
  /// When the run started, UTC, ISO 8601 ("2026-11-24T06:30:00Z").
  std::string started_utc;
  /// The machine file's path and the SHA-256 of its bytes; empty: the built-in machine.
  std::string machine_file, machine_sha256;
  /// The part mesh's path, when one was given.
  std::string part_file;
};

/// JSON report (CLI.md): the input, the machine, the run (RunInfo), the options the run applied
/// (resolved_options of the ones given) and every operation's tool model are recorded too; a null
/// value comes with its reason
/// (`null_reasons`); numbers are written with 12 significant digits at most, never -0.
TAXOPT_API std::string report_json(const JobResult& result, const Toolpath& toolpath,
                                   const Machine& machine, const JobOptions& options,
                                   const RunInfo& run = {});

/// Per-point CSV (CLI.md column names).
TAXOPT_API std::string points_csv(const JobResult& result);

/// A quantity before the run's method and after it (the written program).
template <class T>
struct BeforeAfter {
  T before{};
  T after{};
};

/// One operation's summary, the numbers the CLI's table prints and the HTML page's summary
/// shows (each chooses its columns and formats): one place that reads them off the
/// OperationResult, so that the two never say different things.
struct SummaryRow {
  std::string operation;
  std::size_t points = 0;
  /// The rotary rates as the machine runs the program (OperationResult::before, after):
  /// combined (the paper's sqrt(tilt^2 + C^2)) and per axis.
  BeforeAfter<double> peak_omega_deg_s, peak_accel_deg_s2, rms_accel_deg_s2;
  BeforeAfter<double> peak_omega_tilt_deg_s, peak_omega_c_deg_s;
  BeforeAfter<double> peak_accel_tilt_deg_s2, peak_accel_c_deg_s2;
  /// The machine's tilt axis letter ('A' or 'B').
  char tilt_letter = 'A';
  /// The axis nearest its machine limit (OperationResult::worst_axis); empty: no limits given.
  std::optional<AxisShare> worst_axis;
  /// The ball's least effective cutting diameter at the contacts, mm (OperationResult::
  /// Cutting); empty: no contacts.
  std::optional<BeforeAfter<double>> least_cutting_diameter_mm;
  BeforeAfter<long> c_jumps;
  /// Colliding points; empty: not checked for this operation.
  std::optional<BeforeAfter<long>> colliding_points;
  /// Moves of the written program that collide; empty: not checked.
  std::optional<long> colliding_moves;
  /// Points where the guard kept the input's axes; empty: no guard ran.
  std::optional<std::size_t> input_axes_kept;
  double max_axis_change_deg = 0.0;
  /// Feed time and cycle time of the program (feed blocks; with rapids and dwells).
  BeforeAfter<double> feed_time_s, cycle_time_s;
  /// What the operation took to compute: contacts, C-space, optimisation, post, verification.
  double compute_s = 0.0;
};

/// The summary of every operation of a run, in order.
TAXOPT_API std::vector<SummaryRow> summary_rows(const JobResult& result);

}  // namespace taxopt
