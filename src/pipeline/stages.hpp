#pragma once
// The stages of a run (run_job, plan_axes in job.hpp), each a function with values in and out:
//
//   validate -> operation contexts -> contacts (and the part's collision models)
//            -> plan (the method's axes per operation) -> post (the machine's poses)
//            -> write (G-code, read back, feed schedules) -> verify (per operation)
//
// Each stage reads the Run (input, machine, validated options, collision models) and the
// OperationContexts, adds what it works out to them, and records its findings in the
// JobResult. The helpers here are shared by more than one stage; a stage's own live in its
// source file (src/pipeline/*.cpp).

#include <chrono>
#include <cstddef>
#include <deque>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "controller/block_time.hpp"
#include "controller/linuxcnc_planner.hpp"
#include "plan/stretch_guard.hpp"
#include "taxopt/cspace/collision.hpp"
#include "taxopt/cspace/cspace.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/job.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"
#include "util/progress.hpp"

namespace taxopt::pipeline {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

template <class T>
std::vector<T> slice(const std::vector<T>& v, std::size_t begin, std::size_t end) {
  return std::vector<T>(v.begin() + static_cast<long>(begin), v.begin() + static_cast<long>(end));
}

// ---- What every stage reads ---------------------------------------------------------------

/// One run: the input, the machine, the options as validated, and the part's two collision
/// models, built once per run beside contact recovery: the occlusion map's tree (cspace.hpp),
/// which the optimisers and the guard ask, and FCL's, the independent reference every output
/// is verified with. Both empty without a part.
struct Run;

struct Run {
  const Toolpath& tp;
  const Machine& machine;
  JobOptions options;
  /// The feed of feed moves without one: --feed, else the default, mm/min.
  double fallback_feed_mm_per_min = 0.0;
  std::optional<CollisionModel> collision;
  std::optional<CSpaceRasteriser> checker;
  const PartCheck* planner_check() const { return checker ? &*checker : nullptr; }
  /// The same tree, for colliding_moves to clear runs of a move's samples at once.
  const CSpaceRasteriser* clearance_bounds() const { return checker ? &*checker : nullptr; }
  /// Operations whose plan the verification refused (a point or move hit the part) in a first
  /// run; run_job plans them again, falling back to the other method's plan (the global
  /// method's for the paper's, the paper's for the global method's), else the input's axes
  /// where those are free (plan.cpp).
  std::set<std::size_t> refused_operations = {};
  /// The tool number and spindle speed of operations whose CL file gives none: the options',
  /// else the machine file's [defaults] (validate refuses an operation that needs one of them
  /// when neither gives it).
  std::optional<int> fallback_tool = {};
  std::optional<double> fallback_spindle_rpm = {};
};

/// The axes of one operation after the paper's optimiser, and what it did.
struct OptimisedOperation {
  std::vector<Vec3d> axes;
  std::size_t intervals = 0, repairs = 0, smoothed_joints = 0, sharp_joints = 0;
  /// Stretches near the pole A = 0 whose C was re-planned (pole_passage.hpp).
  std::size_t pole_stretches = 0;
  /// Key points (ends of the optimiser's intervals), indices into the operation, ascending.
  std::vector<std::size_t> keys;
  /// What the guard after the paper's optimiser gave back their input axes.
  StretchGuardResult guard;
  /// Points with no acceptable axis within the cone (they keep their input axis).
  std::vector<std::size_t> no_free_axis;
  /// --method global: per point the pose it chose (branch, C on the pole), for plan_poses;
  /// empty otherwise. Passes refined by it, and given back the paper's axes by its guard.
  std::vector<std::optional<Posed>> preferred;
  std::size_t global_passes = 0;
  /// What the guard after --method global gave back the paper's axes.
  StretchGuardResult global_guard;
  /// --objective time: which plan won and by how much.
  std::optional<OperationResult::TimeChoice> time_choice;
};

/// One operation through the stages: what is worked out once (ball radius, tool model, feeds)
/// and what each stage adds to it.
struct OperationContext {
  std::size_t index = 0;
  const Operationd* op = nullptr;
  /// The override, else the file's; 0: not a ball-end mill (no contacts, no new axes).
  double ball_radius_mm = 0.0;
  /// The feed of each point the kinematic metrics use: --feed, else the file's, else the
  /// fallback, mm/min.
  std::vector<double> metric_feed_mm_per_min;
  // contacts: per point (empty without a part or a ball), and what they came to.
  std::vector<ContactPoint> contacts;
  ContactSummary contact;
  /// The tool as built from the file and the overrides, and as the checks judge it (with the
  /// margins); built once, where the contacts were recovered.
  std::optional<ToolModel> real_tool, tool;
  /// The tool with its flutes held to kInputDepthAllowanceMm (the other margins as `tool`'s):
  /// where the input's flutes clear the part by it, a new axis's must too.
  std::optional<ToolModel> strict_tool;
  /// The least tilt from the designed surface's normal a method keeps (JobOptions::
  /// min_tilt_deg, else the input's least over its touching feed points rounded down to
  /// 0.1 deg), whether it was given, and per point the bound (the lesser of it and the input's
  /// own angle there; 0 where the ball does not touch, or where no free axis keeps it: those
  /// points are least_tilt_relaxed). Set by the plan stage.
  double least_tilt_deg = 0.0;
  bool least_tilt_given = false, least_tilt_held = false;
  std::vector<double> least_tilt_rad;
  std::vector<std::size_t> least_tilt_relaxed;
  // plan: the method's axes (none: empty).
  std::optional<OptimisedOperation> optimised;
  // post: the input axes as the machine would have run them (the "before"; empty where they
  // cannot be posed).
  std::vector<Posed> input_poses;
  double contacts_s = 0.0, optimise_s = 0.0, post_s = 0.0;
  const ToolModel* judged_tool() const { return tool ? &*tool : nullptr; }
};

/// An operation's feed schedule: per point the scheduled time of the move into it (0 for
/// rapids and the first point), the feed it reaches, and the summary.
struct OperationSchedule {
  std::vector<double> time_s;
  std::vector<std::optional<double>> feed_mm_min;
  FeedSummary summary;
  /// Per point reached by a linearised move (Linearised): its blocks' scheduled times, adding
  /// up to time_s; empty elsewhere.
  std::vector<std::vector<double>> block_time_s;
};

/// The blocks a linearised feed move into a point is written as (machine mode): the joints at
/// the end of each block but the last (the point's own), and each block's share of the move's
/// time at the programmed feed (adding up to 1). Empty: one block.
struct Linearised {
  std::vector<JointPosition> joints;
  std::vector<double> share;
};

/// One written position on the way between two points (a linearisation block): X Y Z as
/// written (machine or tip by the mode), A and C in degrees.
struct WayPoint {
  Vec3d xyz = Vec3d::Zero();
  double tilt_deg = 0.0, c_deg = 0.0;
};

/// What the write stage gives the checks: the program read back, per operation and point the
/// move that put the machine there (a chord point inside a G2/G3 block: the point of the arc
/// at its angle) and the linearisation blocks on the way into it, and the feed schedules of
/// the written path and of the input axes. Not copyable: point_moves point into moves and
/// on_arcs (a move keeps them where they are).
struct Written {
  Written() = default;
  Written(const Written&) = delete;
  Written& operator=(const Written&) = delete;
  Written(Written&&) = default;
  Written& operator=(Written&&) = default;
  std::vector<GcodeMove> moves;
  std::deque<GcodeMove> on_arcs;
  std::vector<std::vector<const GcodeMove*>> point_moves;
  std::vector<std::vector<std::vector<WayPoint>>> way_points;
  std::vector<OperationSchedule> schedule_after, schedule_before;
  /// Per operation and point, the time of the move into it as the controller runs the program
  /// (0 for rapids and the first point): the programmed time of the words written (tip path /
  /// F, or the block's kept time), with --feed-schedule the scheduled one; the input's the same
  /// way. The report's rotary rates are computed with them.
  std::vector<std::vector<double>> time_into_after, time_into_before;
  /// Per read-back move, the machine's linear joints at its end referred to the spindle (the
  /// tip's plus the tool length along the machine's Z, GcodeProgram::time_tool_length_mm), as
  /// program_time follows them; empty before the first retract (where the machine stands is
  /// not known there). check_program holds them to the machine's travel.
  std::vector<std::optional<Vec3d>> spindle_mm;
  /// Per read-back move, the joints at its end referred to the tip (X Y Z mm in machine
  /// coordinates, A C deg) where every one of them is known (a block has set each since the
  /// start), and whether the controller ran it with TCP (the tip on a straight line in the
  /// workpiece; else the joints on a straight line): check_every_block sweeps the tool along
  /// each block so.
  std::vector<std::optional<JointPosition>> joints_after;
  std::vector<char> tip_linear;
  double write_s = 0.0;
};

// ---- The stages -----------------------------------------------------------------------------

/// Checks the options (InputError in the library's words) and records what will not be
/// checked (no part, no holder, no safe retract, no linearisation) and the CL file's notes.
Run validate(const Toolpath& tp, const Machine& machine, const JobOptions& given, JobResult& res);

/// The first feed move of an operation that starts without a spindle speed and whose CL file
/// turns the spindle on before none of its feed moves; empty when it needs no speed from
/// elsewhere.
std::optional<std::size_t> needs_spindle_speed(const Operationd& op);

/// One context per operation: ball radius and metric feeds.
std::vector<OperationContext> operation_contexts(const Run& run);

/// With a part: the contacts of every ball-end operation (a gouging CL point or an operation
/// that never touches the part: InputError naming the line), the judged tools, and the part's
/// collision models, built beside them.
void recover_contacts(Run& run, std::vector<OperationContext>& ops, JobResult& res);

/// The method's axes for every ball-end operation (--method paper/global), guarded.
void plan_operations(const Run& run, std::vector<OperationContext>& ops, JobResult& res);

/// The machine's poses of the planned axes (and of the input axes, for the "before"); the
/// turns between passes spread over the rapids in the air. Empty when a pose is unreachable
/// (a problem finding names the line).
std::optional<std::vector<PostedOperation>> post_operations(const Run& run,
                                                            std::vector<OperationContext>& ops,
                                                            JobResult& res);

/// Writes the program, reads it back, schedules the written and the input path at the
/// machine's limits; with --feed-schedule writes it again at the scheduled feeds.
/// The program's header comments: the version, method, source and machine, and every NOT
/// CHECKED item of the run so far (the program travels without its report).
std::vector<std::string> program_comments(const Run& run, const JobResult& res);
/// After a failed verification: the program's text again with the failed checks named in its
/// header (a program written only with --force must say it was not verified).
void mark_unverified(const Run& run, const std::vector<PostedOperation>& posted, JobResult& res);
Written write_program(const Run& run, const std::vector<OperationContext>& ops,
                      std::vector<PostedOperation>& posted, JobResult& res);

/// Reads res.gcode.text back into `w` again (its moves, the points' moves, the machine's state
/// after each block) as write_program does: a program changed after writing (the tests' tampered
/// programs; the same number of lines) is then verified as it stands.
void read_program_again(const Run& run, const std::vector<PostedOperation>& posted, Written& w,
                        JobResult& res);

/// Verifies every operation as written (read back, axis ranges, deviation, collisions of the
/// points and moves, clearances, dynamic limits), fills the report rows and the CL output.
void verify_operations(const Run& run, const std::vector<OperationContext>& ops,
                       const std::vector<PostedOperation>& posted, const Written& written,
                       JobResult& res);

/// Every motion block of the program read back that the operations' own checks do not sweep
/// (the approach, the descent and the XY move to it, index moves, the retracts and the end
/// moves: the blocks taxopt adds), swept against the part as the controller runs it (the tip
/// on a straight line with TCP, else the joints), with the whole tool in the air; a hit is a
/// problem (MoveCollision) naming the G-code line. Verification::blocks_swept and
/// colliding_blocks per operation. Without a part nothing is checked (NOT CHECKED says so).
void check_every_block(const Run& run, const std::vector<OperationContext>& ops,
                       const std::vector<PostedOperation>& posted, const Written& w,
                       JobResult& res);

/// The program as a machinist checks it, on the read-back (verify_operations runs
/// it): a tool called and the spindle turning before anything moves at feed, the coolant the
/// CL file asks for at each operation's start, no turn of the table by more than the index
/// threshold in a rapid below the retract without a part model to check the move, the
/// approach from the retract XY first and then down, and the rotary axes home at the end
/// (end_pose "home"). The first breach of each kind is a finding, with how many there are.
void check_program(const Run& run, const std::vector<PostedOperation>& posted, const Written& w,
                   JobResult& res);

// ---- Shared by the stages -----------------------------------------------------------------

/// The index of `m` in `moves` (a point's move read back), -1 when it is not one of them (a
/// chord point's copy on its arc, Written::on_arcs).
std::ptrdiff_t move_index(const std::vector<GcodeMove>& moves, const GcodeMove* m);
/// Where the spindle's `v_mm` on linear axis `q` (machine coordinates) lies outside the
/// machine's travel by more than 1e-6 mm (the written decimals' rounding): the words for it
/// (", outside the machine's travel [min, max] mm"); empty within it. The one travel rule of
/// the points' check (verify_operation) and the other blocks' (check_program).
std::optional<std::string> outside_travel(const Machine& machine, int q, double v_mm);

/// Records a finding, and its message by severity (JobResult's display lists).
/// `line`: the CL line (0: none); `gcode_line`: the written G-code's, for a finding about a block.
void add_finding(JobResult& res, FindingCode code, std::optional<std::size_t> operation, int line,
                 const std::string& message, std::optional<int> gcode_line = std::nullopt);

/// Ball radius of an operation's tool: the override, else the file's (0: not a ball-end mill).
double ball_radius_mm(const Operationd& op, const JobOptions& options);
/// Why an operation with no ball radius is left alone.
std::string not_a_ball(const Operationd& op, const JobOptions& options);
/// Where the file names an MSYS frame that was posted as written (the default) and point p's
/// axis no pose reaches: the option that takes the coordinates into that frame, when the axis
/// moved into it is one the machine reaches (NX's MSYS with its Z pointing down); else empty.
std::string msys_remedy(const Run& run, const CLPointd& p);
/// The margins the collision checks judge the tool's bodies by (ToolMargins).
/// How far nearer the normal than the least tilt a written axis may come and still count as
/// keeping it, deg: the round-off of the written words' angles (a 4-decimal A/C and the
/// normals' arithmetic), not a tolerance.
constexpr double kTiltAllowanceDeg = 0.01;

/// The cutting conditions at an operation's contacts (cutting.cpp).
void cutting_conditions(const OperationContext& o, const PostedOperation& po, OperationResult& r,
                        const StopSource& stop);

/// A rotary axis moving slower than this is still, as the promise "no axis faster than the
/// input's" reads: where the input holds an axis still, a method may move it this little (a
/// pole passage's C, the rounding of the written words) but no more. deg/s and deg/s^2.
constexpr double kStillOmegaDegS = 0.1;
constexpr double kStillAccelDegS2 = 1.0;

/// How much deeper than the input's a new axis may put the flutes into the part, mm: the
/// arithmetic of the checks (FCL's distances on a mesh), not a tolerance. The part tolerance
/// bounds the input's own axes; a method's axes are held to the input's depth where the input
/// clears the part (OperationPlanInputs::input_clear).
constexpr double kInputDepthAllowanceMm = 0.001;
double part_tolerance_mm(const JobOptions& options, const Operationd& op);
std::string part_tolerance_source(const JobOptions& options, const Operationd& op);
ToolMargins margins_of(const JobOptions& options, const Operationd& op);

/// A number for a message, as a stream writes it (6 significant digits).
std::string shown(double v);
/// Point whose path length the metrics measure: the ball centre for a ball-end mill.
Vec3d reference_point(const CLPointd& p, double ball_radius_mm);
/// The tip that keeps the ball centre of `p` where it is with the tool along `axis`.
Vec3d tip_for_axis(const CLPointd& p, double ball_radius_mm, const Vec3d& axis);
/// The feed of each point that the kinematic metrics use: --feed, else the file's, else
/// `fallback_mm_min`.
std::vector<double> metric_feeds_of(const Operationd& op, const JobOptions& options,
                                    double fallback_mm_min);
/// The metric feeds of a pass's moves: the move from point i to i + 1 runs at point i + 1's.
std::vector<double> pass_feeds(const std::vector<double>& metric_feed, const IndexRange& pass);
/// The path lengths of a pass's moves between the ball centres (the tips elsewhere): what the
/// machine's timing follows whatever the axes (the centre does not move when the axis turns),
/// free of the mesh's facets. The optimisers' segment lengths.
std::vector<double> segment_lengths_mm(const Operationd& op, double ball_radius_mm,
                                       const IndexRange& pass);
/// The paper's L_i of a pass (eq. 16-18): between contact points where both ends touch, else
/// between ball centres. Only the paper's metric (OperationResult::paper_before/after) uses
/// them: on a mesh a contact point sticks on a facet or jumps between facets while the ball
/// moves on, so they carry the tessellation.
/// The designed surface's contacts (ContactPoint::surface_cc_mm), or with `facets` the
/// mesh's own (cc_mm).
std::vector<double> contact_lengths_mm(const Operationd& op,
                                       const std::vector<ContactPoint>& contacts,
                                       double ball_radius_mm, const IndexRange& pass,
                                       bool facets = false);
using controller::BlockTiming;
using controller::kept_block_times_s;
using controller::kept_time_s;
/// The timing of `op`'s blocks on `machine` with the metric feeds: under "cutter-path" the
/// input's block times with its axes as the machine runs them (planned from no start pose).
BlockTiming block_timing(const Operationd& op, const Machine& machine,
                         const PosePlanOptions& pose_options,
                         const std::vector<double>& metric_feed);
/// The time of each move from point i to i + 1 in `range` (range.size() - 1 of them) as the
/// controller takes it from the written words (BlockTiming), with the tool along `poses` (of
/// the whole operation) and the ball centres where the CL file has them: the program's own
/// timing, as the report measures it.
std::vector<double> move_times_s(const Operationd& op, double ball_radius_mm,
                                 const MachineKinematicsd& ac, const std::vector<Posed>& poses,
                                 const BlockTiming& timing, const IndexRange& range);
/// Rotary kinematics of every pass of an operation for the axis angles tilt_deg, c_deg of its
/// points, each move taking `time_into_s` (per point, the move into it: the program's own
/// timing); fills the rows' omega and accel (before or after) when given.
RotarySummary summarise_timed(const Operationd& op, const std::vector<double>& tilt_deg,
                              const std::vector<double>& c_deg,
                              const std::vector<double>& time_into_s,
                              std::vector<PointRow>* rows = nullptr, bool rows_before = false);
/// The paper's metric (eq. 16-18 over contact_lengths_mm at the metric feeds): the paper's
/// comparison, never the headline; fills the rows' arc lengths when given.
RotarySummary summarise_paper(const Operationd& op, const std::vector<ContactPoint>& contacts,
                              double ball_radius_mm, const std::vector<double>& tilt_deg,
                              const std::vector<double>& c_deg,
                              const std::vector<double>& metric_feed,
                              std::vector<PointRow>* rows = nullptr, bool facets = false);
/// Joint positions (X Y Z mm, A C deg) of tips and poses, in machine coordinates.
std::vector<JointPosition> joints_of(const MachineKinematicsd& ac,
                                     const std::vector<Vec3d>& tips_mm,
                                     const std::vector<Posed>& poses);
/// The chains of feed moves of an operation: runs [begin, end) of points i >= 1 reached by a
/// feed move; a chain's joints are those of points begin - 1 .. end - 1.
std::vector<IndexRange> feed_chains(const std::vector<CLPointd>& points);
/// The feed schedule of one operation's points at `limits`. With `via` (per point), a
/// linearised move is scheduled block by block, so that none of its blocks exceeds a limit
/// (tests/test_program.cpp: scheduled on the points alone, a block ran X at 32 mm/s against 20).
/// With `tcp_poses` (tcp mode: the controller interpolates the tip and A, C, and the joints follow
/// through the kinematics), no feed block is shorter than its joints' velocity limits allow
/// along it (joint_velocity_rate_per_s, measured on LinuxCNC's motion controller).
OperationSchedule schedule_operation(const std::vector<CLPointd>& points,
                                     const std::vector<JointPosition>& joints,
                                     const std::vector<double>& programmed_s,
                                     const JointLimits& limits, const MachineKinematicsd& ac,
                                     const std::vector<Linearised>* via = nullptr,
                                     const std::vector<Posed>* tcp_poses = nullptr,
                                     const StopSource* stop = nullptr);
/// The points with every feed move's feed set (`fallback_feed` where the file gives none).
std::vector<CLPointd> posted_feeds(const Operationd& op, double fallback_feed);
/// Per point, whether the move into it is a rapid (the first point counts as one).
std::vector<bool> rapid_into_of(const Operationd& op);
/// Indices of the points of `op` whose tool collides, for axes `axes`, sorted.
std::vector<std::size_t> colliding_points(const PartCheck& model, const ToolModel& tool,
                                          const Operationd& op, const std::vector<Vec3d>& axes,
                                          const std::vector<ContactPoint>& contacts,
                                          detail::StageProgress* progress = nullptr,
                                          const std::vector<char>* only = nullptr);
/// Index i of every move from point i-1 to point i during which the tool hits the part, with
/// the machine moving linearly in its joints between the values written (`xyz_w` as written,
/// `tilt_deg`/`c_deg`, through the blocks `between` where given). Samples at most 0.5 deg and
/// 0.1 mm apart, each judged by `model`. Between two contact points only the bodies above the
/// ball are checked (the ball's path between contacts is the CAM system's chord tolerance);
/// where either end is in the air, the ball too. With `bounds` (a tree of the same part), runs
/// of samples whose bodies, grown by the most they move over the run, miss the part are clear
/// without a query each: the same verdicts, about one query a move (move_sweep.cpp).
std::vector<std::size_t> colliding_moves(
    const PartCheck& model, const ToolModel& tool, const Machine& machine,
    const std::vector<Vec3d>& xyz_w, const std::vector<double>& tilt_deg,
    const std::vector<double>& c_deg, const std::vector<ContactPoint>& contacts,
    detail::StageProgress* progress = nullptr,
    const std::vector<std::vector<WayPoint>>* between = nullptr,
    const std::vector<char>* only = nullptr, const CSpaceRasteriser* bounds = nullptr);
/// Joint positions as written: the words read back (in tcp mode mapped to the joints).
std::vector<JointPosition> written_joints(const Machine& machine,
                                          const std::vector<const GcodeMove*>& at);
/// The findings of LinuxCNC's TCP planner on the written program's `blocks`
/// (GcodeProgram::tcp_joint_peaks, in `res.gcode`): a joint velocity past a limit held (the
/// machine file's, or with `scheduled` the effective ones) from a stated start a problem, the
/// rest a warning with its remedy (tcp_findings.cpp). `stop` is looked at as the blocks are
/// followed.
void tcp_joint_findings(const Machine& machine, const JointLimits& limits, bool scheduled,
                        const std::vector<controller::TcpBlock>& blocks, JobResult& res,
                        const StopSource* stop = nullptr);
/// The turn between two passes spread over the rapids of the chain in the air
/// (plan_global.cpp); `stop`, where given, looked at as the chains and their checks go.
void spread_turns_in_air(const Operationd& op, const std::vector<ContactPoint>& contacts,
                         double ball_radius_mm, const PartCheck* model, const ToolModel& tool,
                         const Machine& machine, double max_deviation_rad, PostedOperation& po,
                         const StopSource* stop = nullptr);

}  // namespace taxopt::pipeline
