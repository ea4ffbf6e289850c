#pragma once
/// @file The program writer's state and stages (program_writer.cpp: the program and its
/// operations; point_blocks.cpp: the blocks that reach the CL points), internal to the library.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gcode/dialect.hpp"
#include "taxopt/core/stop.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt::gcode {

/// write_gcode looking at `stop` as it goes (a few milliseconds of work apart), and
/// read_gcode_moves the same: a job's stop is honoured inside them.
GcodeProgram write_program(const std::vector<PostedOperation>& operations, const Machine& machine,
                           LengthUnit units, const std::vector<std::string>& comments,
                           const StopSource* stop);
std::vector<GcodeMove> read_moves(const std::string& text, const std::string& source,
                                  GcodeDialect dialect, const std::vector<int>& verbatim_lines,
                                  char tilt_letter,
                                  const std::vector<std::pair<int, int>>& tool_calls,
                                  const StopSource* stop);

/// Writes one program. The stages: the program's start, per operation its start (retract,
/// tool, spindle, coolant, table turn, length and TCP on), its points (events, arcs, index
/// moves, approaches, rapids, feed blocks) and its end, then the program's end. Every line is
/// recorded with its kind and origin (GcodeProgram::blocks).
class ProgramWriter {
 public:
  ProgramWriter(const std::vector<PostedOperation>& operations, const Machine& machine,
                LengthUnit units)
      : ops_(operations),
        machine_(machine),
        g_(machine.gcode),
        scale_(1.0 / mm_per_unit(units)),
        d_(g_.decimals),
        fd_(feed_decimals(g_)),
        max_fd_(max_feed_decimals(g_.dialect)),
        dialect_(g_, units),
        tcp_(g_.mode == GcodeMode::Tcp),
        // LinuxCNC plans a tcp rapid in the program's axes: where that would run a joint over
        // its velocity limit, the rapid is a feed block at a joint-safe feed
        // (joint_safe_rate_per_s).
        joint_safe_(tcp_ && dialect_.rules().tcp_planned_in_program_axes()),
        retracts_(g_.program.retract != SafeRetract::None),
        limits_(effective_limits(machine)),
        retract_z_(dialect_.number(g_.program.retract_z_mm * scale_, d_)),
        // The tilt axis's word: A or B (ac_machine.hpp).
        tilt_word_(std::string(" ") + machine.rotary.tilt_letter()) {}
  /// The program; `stop`, where given, is looked at every few hundred points.
  GcodeProgram write(const std::vector<std::string>& comments, const StopSource* stop = nullptr) {
    stop_ = stop;
    // About a block a feed point, a few around each rapid (retract, turn, approach) and 60
    // characters a block: reserved, not grown by doubling (a program of 143,840 points held
    // 1.5 times its blocks while they grew).
    std::size_t blocks = 256;
    for (const PostedOperation& op : ops_) {
      for (const CLPointd& p : op.points) blocks += p.motion == Motion::Rapid ? 8 : 1;
    }
    prog_.blocks.reserve(blocks);
    prog_.text.reserve(60 * blocks);
    program_start(comments);
    for (std::size_t k = 0; k < ops_.size(); ++k) operation(k);
    program_end();
    return std::move(prog_);
  }

 private:
  // --- emitting lines, each with its kind and origin -------------------------------------
  int raw(const std::string& s, BlockKind kind);
  int line(const std::string& s, BlockKind kind) { return raw(dialect_.block(s), kind); }
  void lines(const std::vector<std::string>& v, BlockKind kind);
  /// Blocks of the template, written as they are: the reader steps over them.
  void verbatim(const std::vector<std::string>& v, BlockKind kind);
  // --- motion blocks: planned, then written ---------------------------------------------
  /// A move of `type` to (xyz, pose): all five axes named.
  PlannedMove move_to(PlannedMove::Type type, const Vec3d& xyz, const Posed& pose) const;
  /// A rapid naming the linear axes in `given` (bits 0 to 2) at `xyz`.
  PlannedMove rapid_linear(unsigned given, const Vec3d& xyz) const;
  /// A rapid of the rotary axes alone.
  PlannedMove rapid_rotary(double tilt_deg, double c_deg) const;
  /// `m` at the F the feed planning wrote, `f`.
  void set_feed(PlannedMove& m, const std::string& f) const;
  /// The block's words: its motion word, the axes named, I J K, F where it changes.
  std::string motion_text(const PlannedMove& m);
  /// Writes a motion block (`modal` words before it); an operation's first that
  /// `takes_prefix` carries Fanuc's length and TCP words. The block keeps its plan and, where
  /// the program has named all five axes in its frame, the joints there.
  int motion(const PlannedMove& m, BlockKind kind, bool takes_prefix = true,
             const std::string& modal = std::string());
  /// The dialect's safe retract to machine Z, and the end's park of X and Y.
  void retract();
  void park(const std::array<double, 2>& xy_mm);
  /// The dialect's `blocks` of a move in machine coordinates, the first carrying `m`.
  void machine_frame_move(const std::vector<std::string>& blocks, PlannedMove m, BlockKind kind);
  // --- words -----------------------------------------------------------------------------
  Vec3d rounded(const Vec3d& v) const;
  /// `v_mm` as its words read back in the program's unit, mm.
  Vec3d rounded_mm(const Vec3d& v_mm) const;
  Vec3d out_xyz(const Vec3d& tip, const Posed& pose) const;
  std::string angle_words(const Posed& pose) const;
  std::string xyz_words(const Vec3d& xyz) const;
  static std::string spindle_words(double rpm, bool clockwise);
  static std::string coolant_code(ClCoolant c);
  /// Coolant as the CL file asks (COOLNT), else as the machine file's default.
  std::string coolant_of(const PostedOperation& o) const;
  /// " F" and the feed where it changes (always under G93).
  std::string feed_word(const std::string& f);
  // --- the program -----------------------------------------------------------------------
  void program_start(const std::vector<std::string>& comments);
  void program_end();
  // --- an operation ----------------------------------------------------------------------
  void operation(std::size_t k);
  /// Safe start: up to the retract height, the tool, the spindle and the coolant, the table
  /// turned to the first pose with the tool up, then the tool length and TCP on.
  void operation_start();
  void tool_change(int tool);
  /// Under tool centre point control the retract height can lie above the axes' range in the
  /// workpiece frame: LinuxCNC's sample (Z to 120, its limit) with the table tilted 19 deg
  /// refused the XY move there ("would exceed Z's positive limit", measured on its motion
  /// controller). So the tool first comes straight down to a clearance height, the operation's
  /// highest tip plus approach_clearance_mm, then XY, then down. Not on Fanuc, whose G43.4
  /// comes on with the block down: before it, Z would place the spindle nose. With a part
  /// model the clearance height stands above the part too (its highest point in the
  /// workpiece, PostedOperation::part_top_z_mm), not only above the operation's tips: an
  /// operation low on a tall part came down inside it (a Haas part's approach at Z1.5987 in,
  /// its top at Z3.0).
  double clearance_z_mm(const PostedOperation& op) const;
  /// Left running into the next operation where it starts with the same tool, spindle and
  /// coolant (before its first point: its events may change them after that). The spindle and
  /// coolant words left running from the operation before (empty: stopped) spare a stop and a
  /// restart between operations (a machinist's read of a real NX program: 11 pointless M5 /
  /// S M3 pairs in 12 operations).
  void operation_end(const PostedOperation* next);
  /// The file's stops, dwells, spindle and coolant changes before point i.
  void events_before(std::size_t i);
  void event(const ProgramEvent& e);
  /// The table turned with the tool up (after the retract), to `pose`.
  void turn_table(const Posed& pose);
  void length_and_tcp_on();
  void length_and_tcp_off();
  // --- the points ------------------------------------------------------------------------
  /// Point i starts the next CL arc: written as G2/G3 when it can be (true), else counted as
  /// left to its chords. An arc with an event inside it is left to its chords, so that the
  /// event stands where the file put it.
  bool arc_at(std::size_t i);
  /// The programmed time of the arc's chords, s (each block's given time, else its own at the
  /// programmed feed), and whether every given time is the block's own; nullopt where the arc
  /// cannot be one block run (a rapid, a turn of A or C, a schedule, a change of feed).
  std::optional<std::pair<double, bool>> arc_programmed_s(const ArcRun& run,
                                                          const std::string& pose_words) const;
  /// A CL arc in the output frame: its centre, its plane's normal (one of the frame's axes,
  /// `axis`, else no arc), radius, the direction to its start, its end, and the heights of its
  /// ends along the normal (a helix rises).
  struct OutputArc {
    Vec3d centre, normal, towards_start, end;
    int axis = -1;
    double radius = 0.0, start_height = 0.0, end_height = 0.0;
  };
  /// The arc `run` in the output frame where its points lie on one circle in a plane of the
  /// frame; empty elsewhere.
  std::optional<OutputArc> output_arc(const ArcRun& run) const;
  /// One G2/G3 block of an arc (at most half a turn): its end and its centre's offset from its
  /// start as written, mm.
  struct ArcPiece {
    Vec3d to, offset_mm;
  };
  /// The arc's blocks; empty where a block's rounded words would give two radii a controller
  /// refuses.
  std::optional<std::vector<ArcPiece>> arc_pieces(const ArcRun& run, const OutputArc& arc) const;
  /// Writes the arc `run` as G2/G3 blocks when it can be (PostedOperation::arcs); false: it
  /// is left to its chords.
  bool write_arc(const ArcRun& run);
  void advance_to(const Vec3d& xyz, const Posed& pose, const Vec3d& tip);
  /// The block (or blocks) that reach point i.
  void point(std::size_t i);
  /// An index move: a rapid that turns the table by more than the threshold goes up to the
  /// retract, turns there and comes down XY first (docs/gcode-dialects.md "Index moves").
  /// With a part model the turns stay in the air: the check verifies their swept moves.
  /// Rapids that follow the turning one up to the next feed (a CAM system's reorientation in
  /// steps: Creo wrote 11, which made 8 index cycles) are passed over: one cycle turns to the
  /// last of them and comes down there. Returns that point's index (i when nothing turns).
  std::size_t index_move_if_turning(std::size_t i);
  /// The way down from the retract height to point `p`: under TCP straight down to the
  /// clearance height, XY to above the point on its axis, then along the axis (as CAM links an
  /// approach: a tool tilted 90 deg that came straight down in the workpiece's Z swept through
  /// a wall); in machine mode the machine's Z is the tool axis already. Not on Fanuc, whose TCP
  /// comes on with the block down from the retract height (straight down to the point).
  void approach(const CLPointd& p, const Posed& pose, const Vec3d& xyz);
  /// The blocks of a machine-mode move from the last point to (tip, pose) between its ends
  /// (linearise_fractions): the fractions at which they stand.
  std::vector<double> linearised(const Vec3d& tip, const Posed& pose) const;
  Posed pose_at(const Posed& pose, double t) const;
  /// A rapid to point i; true when it was written as a joint-safe feed block (the point is
  /// done), false when the rapid block is written and the point's bookkeeping follows.
  bool rapid(std::size_t i, const Vec3d& xyz, const std::string& words);
  /// A rapid as a feed block at the rate that keeps the joints within their limits: F is the
  /// tip's distance (the rotary one when only A and C turn) per minute, or under G93 the
  /// block's inverse time; eight significant digits, rounded down: slower, never faster.
  void joint_safe_rapid(std::size_t i, const Vec3d& xyz, const std::string& words,
                        double rate_per_s);
  /// `m` as a feed block at `f` in place of a rapid: a dwell after a feed block (no blend into
  /// it), the comment that says what it is where a run of them starts, the block, listed in
  /// joint_safe_rapids; its line.
  int joint_safe_block(PlannedMove m, const std::string& f, BlockKind kind, bool takes_prefix);
  /// The F word of a joint-safe block: `rate_per_s` of the block a second as F (the tip's
  /// distance, the rotary one when only A and C turn, per minute; under G93 the inverse time),
  /// eight significant digits, rounded down.
  std::string joint_safe_feed(double tip_mm, double rot_deg, double rate_per_s) const;
  /// The joints after the block `m` from `q` (joints_): the words it gives, the rest held (the
  /// tip in the table's frame with TCP on, the linear joints without); empty where TCP is off
  /// and the block names a linear axis.
  std::optional<JointPosition> joints_after(const JointPosition& q, const PlannedMove& m) const;
  /// Whether TCP is on now: between length_and_tcp_on and length_and_tcp_off, and always on
  /// LinuxCNC without a kinematics switch.
  bool tcp_in_force() const;
  /// Whether the controller plans a block in the program's axes now (LinuxCNC with TCP on).
  bool tcp_planned_now() const;
  /// The F of a joint-safe feed block for the rapid `m` (joint_safe_feed): where the controller
  /// plans it in the program's axes (tcp_planned_now), the joints are known (joints_) and at
  /// the rapid's rate some joint would pass its velocity limit; empty otherwise. The tip moves
  /// on its line in the table's frame, the rotary axes in proportion (a turn alone keeps the
  /// tip put while the joints swing round it).
  std::optional<std::string> joint_safe_f(const PlannedMove& m) const;
  /// joint_safe_f for a linear block from a start the program does not state (the first
  /// positioning: X and Y stand wherever the machine stood) with the rotary axes stated and
  /// held: its direction is not known, so the F holds every joint within its limit whichever
  /// way the block goes; empty where the rapid does so (or under G93, whose F needs the
  /// block's length).
  std::optional<std::string> joint_safe_f_any_direction(const PlannedMove& m) const;
  /// A rapid block (an approach's, a table turn), or the joint-safe feed block in its place
  /// (joint_safe_f), with the comment that says what it is; its line.
  int rapid_block(PlannedMove m, BlockKind kind, bool takes_prefix = true);
  /// A turn of the rotary axes alone: an index's table turn, the end's turn home.
  void rotary_turn(const Posed& to, BlockKind kind);
  /// The block reaching point i, and the state after it.
  void finish_point(std::size_t i, const Vec3d& xyz, const std::string& words,
                    const PlannedMove& block, bool restore_inverse_time);
  /// The feed block (machine mode: blocks) reaching point i.
  void feed(std::size_t i, const Vec3d& xyz, const std::string& words);
  struct FeedBlock {
    double programmed_min, time_min;
    bool scheduled;
  };
  /// TCP: the tip moves at F (where only A and C turn, they do, in deg/min: feed_word.hpp).
  /// Its distance over the block time is the programmed feed unless the programmed time is
  /// another path's (FeedReference::CutterPath).
  std::string tcp_feed(std::size_t i, double programmed_min) const;
  /// Point i's block time at its programmed feed (the posted operation's, else its own), min.
  double programmed_minutes(std::size_t i) const;
  /// Whether point i's block keeps its programmed time: no schedule, or one no limit slowed.
  bool keeps_programmed_time(std::size_t i) const;
  /// Whether the block after point `i` runs no faster than it: none, a rapid, or a block at
  /// the same programmed feed that no limit slowed (ramps come after such blocks only).
  bool next_not_faster(std::size_t i) const;
  /// F of a joint-space block (machine mode, inverse time, a schedule) from `from` to `to`
  /// that takes `minutes`.
  std::string joint_feed(const Vec3d& from, const Posed& from_pose, const Vec3d& to,
                         const Posed& to_pose, double minutes, bool scheduled,
                         bool may_hold = false);
  /// Machine mode: where the joints moving linearly would take the tip off the straight line
  /// by more than the tolerance, blocks in between keep it on. Writes them and returns the F
  /// of the last (the point's own block).
  std::string linearised_feed(std::size_t i, const Vec3d& xyz, const FeedBlock& fb);
  // --- the program's settings --------------------------------------------------------------
  const std::vector<PostedOperation>& ops_;
  const Machine& machine_;
  const GcodeSettings& g_;
  const double scale_;
  const int d_, fd_, max_fd_;
  Dialect dialect_;
  const bool tcp_, joint_safe_, retracts_;
  const JointLimits limits_;
  const std::string retract_z_, tilt_word_;
  const StopSource* stop_ = nullptr;
  // --- the program so far ------------------------------------------------------------------
  GcodeProgram prog_;
  /// Where the program stands in its own frame as written (X Y Z mm, the tilt axis and C deg,
  /// rounded as the words read); empty: not named since the last move in machine coordinates.
  std::array<std::optional<double>, 5> at_;
  /// The machine's joints referred to the tip after the last block (JointPosition), where the
  /// program has stated them: a retract to machine Z keeps X, Y and the rotary axes and puts
  /// the tip the tool's gauge length below the retract height (the work offset taken as zero,
  /// as the program's time model does).
  std::optional<JointPosition> joints_;
  int line_no_ = 0;
  int current_tool_ = -1;
  std::string last_feed_;
  /// The scheduled feed of the last joint-feed block before rounding (joint_feed).
  double last_asked_ = -1.0;
  std::string running_spindle_, running_coolant_;
  // --- the operation being written ---------------------------------------------------------
  const PostedOperation* op_ = nullptr;
  std::optional<std::size_t> op_index_, point_;
  std::string spindle_, coolant_;  ///< the words in force (empty: stopped, off)
  std::size_t next_event_ = 0, arc_cursor_ = 0;
  /// Fanuc's length and TCP words for the operation's (or index move's) first motion block.
  std::string prefix_;
  /// The rotary words of the first block after TCP came on (write_arc).
  std::string tcp_angles_;
  bool approach_ = false, descend_ = false;
  double clearance_z_mm_ = 0.0;
  std::vector<int> emitted_;
  /// Points of this operation an index move passed over (index_move_if_turning), and the
  /// point it comes down to.
  std::vector<std::size_t> passed_over_;
  std::size_t index_target_ = 0;
  std::vector<double> own_times_;
  std::string last_words_;
  Vec3d prev_xyz_ = Vec3d::Zero(), prev_tip_ = Vec3d::Zero();
  Posed prev_pose_;
  bool have_prev_ = false;
  /// The last block written is a feed block (not a joint-safe rapid), or a joint-safe rapid.
  bool last_feed_block_ = false, last_joint_safe_ = false;
  /// The dialect's or the switch's TCP is on (length_and_tcp_on to length_and_tcp_off).
  bool tcp_switched_on_ = false;
};

}  // namespace taxopt::gcode
