#pragma once
// Helpers shared by the tests: temporary folders, running the CLI and rs274, and CL files of
// heightfield parts made on the fly (parts no test was tuned on: seeded random shapes).
#include <functional>
#include <optional>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "taxopt/core/types.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt::test {

/// A fresh empty directory under the system temp folder, removed at destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
};

std::string read_file(const std::string& path);
void write_file(const std::string& path, const std::string& content);
/// `text` with the first `from` replaced by `to`; `from` must be there (REQUIRE).
std::string replaced_once(std::string text, const std::string& from, const std::string& to);
bool file_exists(const std::string& path);
std::string real_data(const std::string& name);

/// The records a user must skip by name to post a real file (docs/cl-files.md, "The real
/// files"): the SOLIDWORKS CAM files' INSERT (tool-holder text) and CUTCOM/LEFT; the words of
/// the shot-peening machine in the CATIA file.
std::vector<std::string> real_skips(const std::string& name);
/// The same as CLI flags (" --skip-record W ..."), with the tool number and spindle speed the
/// NX files lack (as the production post for them wrote).
std::string real_flags(const std::string& name);
/// The real file's text; in the peening file its SPINDLE/CLW20 records made comments (a state
/// taxopt refuses by name: the file as it is cannot be posted), so that its CATIA traps can be
/// read.
std::string real_text(const std::string& name);
/// The path of a copy of real_text in `dir` (the file itself where nothing was taken out).
std::string real_path(const std::string& name, const std::string& dir);
/// A real file read as a user who decided its real_skips reads it (real_text).
Toolpath read_real(const std::string& name, ClReadOptions options = {});

/// The lines of a text (without their line ends), and the index (0-based) of the first line
/// holding `what` at or after `from` (npos when none).
std::vector<std::string> lines_of(const std::string& text);
std::size_t line_of(const std::vector<std::string>& lines, const std::string& what,
                    std::size_t from = 0);

/// Result of a command: exit code, stdout and stderr.
struct RunResult {
  int code = -1;
  std::string out;
  std::string err;
};
/// Runs a shell command line.
RunResult run(const std::string& command);
/// Runs the taxopt CLI with the given arguments (already quoted as needed).
RunResult run_taxopt(const std::string& args);
/// The generator's small sine (5 passes of 20 mm, 3 mm wide) as g.cls and g.stl in `t`: the
/// part the joint and program tests post; its exit code (0 when written).
int generate_small_sine(const TempDir& t);
/// Occurrences of `what` in `text` (overlapping ones too).
std::size_t count_of(const std::string& text, const std::string& what);
/// True when LinuxCNC's rs274 is installed.
bool have_rs274();

/// One canonical move printed by rs274 (program units, degrees).
struct CanonMove {
  bool feed = false;
  double x = 0, y = 0, z = 0, a = 0, b = 0, c = 0;
  /// Feed rate in force (SET_FEED_RATE: rs274 turns a G93 word into units or degrees per
  /// minute of the move) and whether the program is in inverse time (G93).
  double feed_rate = 0;
  bool inverse_time = false;
  /// An ARC_FEED (G2/G3): x y z are its end; arc_length_mm its length from the move before
  /// (program units despite the name's unit when the program is in inches).
  bool arc = false;
  double arc_length = 0;
  /// The tool length offset in force (USE_TOOL_LENGTH_OFFSET's Z), program units.
  double tool_length = 0;
  /// The kinematics last switched to by the stubbed M428 (1, TCP) / M429 (0, identity);
  /// -1 before either.
  int kins = -1;
  /// The machine's state at the move as rs274's canonical calls set it: the spindle turning
  /// (START_SPINDLE_* at a speed above 0, until STOP_SPINDLE_TURNING), the tool in it
  /// (CHANGE_TOOL; 0 before), the coolant (FLOOD_ON or MIST_ON).
  bool spindle_on = false;
  int tool = 0;
  bool coolant = false;
};
/// How rs274 is run: the tool length of every tool in its table (mm), and a LinuxCNC INI file (its
/// folder copied, so that its remaps and subroutines are found).
struct Rs274Options {
  double tool_length = 0.0;
  std::string ini;
  /// Replace the configuration's remapped M428/M429/M430 by stubs that only say they ran
  /// (LinuxCNC's own read a HAL pin, which rs274 alone does not have).
  bool stub_switchkins = false;
};
/// Runs `rs274 -g` on a G-code file (with a tool table holding tools 1-99); code is its exit.
/// `moves` are the moves of the program's points: the safe retracts and the table turns
/// before an operation's first point (GcodeMove::positioning, by taxopt's reader of the same
/// file) are left out; `all_moves`, when given, receives every move.
RunResult run_rs274(const std::string& ngc_path, std::vector<CanonMove>& moves,
                    const Rs274Options& options = {}, std::vector<CanonMove>* all_moves = nullptr);
/// Length of the path rs274 moves the tool from its first move's end on (arcs by their
/// length), program units; `arcs` receives the number of ARC_FEEDs when given.
double path_length(const std::vector<CanonMove>& moves, std::size_t* arcs = nullptr);

/// A heightfield z = f(x, y) with its gradient.
struct Heightfield {
  std::string name;
  std::function<double(double, double)> z;
  std::function<Vec3d(double, double)> normal;  // unit, upward
};
/// A wall 30 mm high rising across y = 24 mm (a logistic step 0.6 mm wide) beside a flat floor:
/// a path along x near it leans the shank or holder into it.
Heightfield wall_heightfield();
/// Seeded random heightfields of the kinds a CAM user meets: a steep flank, a bump, a wall;
/// their concave radii stay above 3 mm, so a 3 mm ball can follow them without gouging.
std::vector<Heightfield> random_heightfields(std::mt19937& rng);

/// Ground truth of a generated CL file: tip and axis of every GOTO in file order.
struct GeneratedCl {
  std::string text;
  std::vector<Vec3d> tips_mm;
  std::vector<Vec3d> axes;
  std::vector<bool> rapid;
  /// True contact point of each feed GOTO (the heightfield point), and the ball centre of
  /// every GOTO, mm.
  std::vector<Vec3d> cc_mm;
  std::vector<Vec3d> centres_mm;
};
/// Writes one GOTO (after RAPID when `rapid`) of a generated NX CLSF to `os` and records its
/// ground truth in `g`: tip, axis, contact point `cc_mm` and ball centre `centre_mm`.
void append_goto(GeneratedCl& g, std::ostream& os, const Vec3d& tip_mm, const Vec3d& axis,
                 bool rapid, const Vec3d& cc_mm, const Vec3d& centre_mm);

/// The writer's plan of `prog` (GcodeProgram::blocks) against its text and the blocks read
/// back: one entry per line in order, every point's line a block that leads to that point,
/// every motion read back a motion block, the linearisation blocks counted.
void check_blocks(const GcodeProgram& prog, GcodeDialect dialect, char tilt_letter = 'A');

/// The message of the InputError `f` throws, "" when it throws none (other exceptions pass).
std::string input_error_of(const std::function<void()>& f);

/// Nearest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5): written
/// here, independent of CGAL and FCL.
Vec3d closest_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);
/// Nearest point of a mesh to p, by every triangle (brute force).
Vec3d brute_nearest(const TriangleMesh& m, const Vec3d& p);

/// A closed profile in the xz plane (clockwise seen from +y) extruded along y over [y0, y1] in
/// `rows` rows: each profile segment a quad of two triangles per row, the ends closed by fans
/// from the profile's centroid; outward normals.
TriangleMesh extruded_profile(const std::vector<Eigen::Vector2d>& profile_xz, double y0, double y1,
                              int rows);

/// The heightfield over [x0, x1] x [y0, y1] as a triangle mesh with the given spacing.
TriangleMesh heightfield_mesh(const Heightfield& hf, double spacing_mm, double x0 = -10.0,
                              double x1 = 60.0, double y0 = -10.0, double y1 = 60.0);

/// Raster passes along x over `hf` with a ball-end mill of radius r_mm; the axis is the
/// surface normal tilted by tilt_deg in the plane of motion (a lead angle, about N x T). Each
/// pass starts with a rapid to 20 mm above its first tip and ends with a rapid to 20 mm above
/// its last one, along the axis; with `clearance_z_mm` given, the rapids between passes go up
/// to that height first, as a CAM system's clearance plane. NX CLSF in mm.
GeneratedCl raster_cl(const Heightfield& hf, double r_mm, double tilt_deg, int passes,
                      double step_mm, double y0, double y1, double x0, double x1,
                      std::optional<double> clearance_z_mm = std::nullopt);

}  // namespace taxopt::test
