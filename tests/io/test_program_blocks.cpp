// The program is planned as blocks before it is text (ProgramBlock::move, ::joints): every
// motion block the writer emits carries what it asks of the machine, and the text is that
// plan formatted. Read back as the verification reads it (read_gcode_moves), every dialect,
// mode, feed mode and unit gives the same blocks, the same axes, the same targets to the
// written decimals, the same F, and the joints the verification computes from the words.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "support.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;

namespace {

struct Case {
  std::string cl, machine;
  GcodeDialect dialect;
  LengthUnit units;
  FeedMode feed_mode;
  bool schedule;
  GcodeMode mode = GcodeMode::Tcp;
};

std::string describe(const Case& c) {
  return c.cl + " on " + c.machine + ", " + to_string(c.dialect) +
         (c.units == LengthUnit::Inch ? ", in" : ", mm") +
         (c.feed_mode == FeedMode::InverseTime ? ", G93" : "") + (c.schedule ? ", scheduled" : "") +
         (c.mode == GcodeMode::Machine ? ", machine mode" : "");
}

Toolpath toolpath_of(const std::string& cl) {
  if (cl == "sine.cls") {
    return read_cl_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls");
  }
  return test::read_real(cl);
}

/// One case posted (method none: the writer's blocks are the subject), its plan and its text
/// compared block by block. Returns the number of motion blocks compared.
std::size_t spindle_z_findings = 0;
std::size_t last_linearised = 0;  ///< the last case's linearised blocks  ///< findings naming the
                                  ///< block that takes the spindle to a Z

std::size_t check_case(const Case& c) {
  INFO(describe(c));
  Machine machine =
      read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/" + c.machine + ".toml");
  machine.gcode.dialect = c.dialect;
  machine.gcode.feed_mode = c.feed_mode;
  machine.gcode.mode = c.mode;
  machine.gcode.decimals = std::min(machine.gcode.decimals, max_decimals(c.dialect));
  if (c.dialect == GcodeDialect::Heidenhain || c.dialect == GcodeDialect::Siemens) {
    machine.gcode.program.header.clear();  // the files' own words are LinuxCNC's or Fanuc's
    machine.gcode.program.footer.clear();
  }
  const Toolpath tp = toolpath_of(c.cl);
  JobOptions options;
  options.method = Method::None;
  options.spindle_rpm = 8000.0;
  options.tool_number = 3;
  options.units_out = c.units;
  options.feed_schedule = c.schedule;
  // The work offset LinuxCNC's sample simulations start with (G54 at zero): the travel check
  // holds every block in machine coordinates.
  options.work_offset_mm = Vec3d::Zero();
  const JobResult res = run_job(tp, machine, options);
  const GcodeProgram& prog = res.gcode;
  REQUIRE_FALSE(prog.text.empty());
  const std::vector<GcodeMove> moves =
      read_gcode_moves(prog.text, "t", c.dialect, prog.verbatim_lines, machine.rotary.tilt_letter(),
                       prog.tool_calls);
  std::map<int, const ProgramBlock*> block_at;
  std::size_t planned = 0;
  for (const ProgramBlock& b : prog.blocks) {
    block_at[b.line] = &b;
    planned += b.move.has_value();
  }
  // One read-back move per planned move, on its line.
  REQUIRE(moves.size() == planned);
  last_linearised = prog.linearised_blocks;
  const double mm = mm_per_unit(c.units);
  const double linear_tol_mm = 0.5 * std::pow(10.0, -machine.gcode.decimals) * mm + 1e-9;
  const double angle_tol_deg = 0.5 * std::pow(10.0, -machine.gcode.decimals) + 1e-9;
  const GcodeMove* previous = nullptr;
  for (const GcodeMove& w : moves) {
    INFO("line " << w.line);
    const auto found = block_at.find(w.line);
    REQUIRE(found != block_at.end());
    const ProgramBlock& b = *found->second;
    REQUIRE(b.move);
    const PlannedMove& m = *b.move;
    CHECK(w.given == m.given);
    CHECK(w.retract == m.machine_frame);
    CHECK(w.rapid == (m.type == PlannedMove::Type::Rapid));
    CHECK(w.arc == (m.type == PlannedMove::Type::ArcClockwise ||
                    m.type == PlannedMove::Type::ArcCounterClockwise));
    const Vec3d& read_mm = m.machine_frame ? w.machine_mm : w.xyz_mm;
    for (int q = 0; q < 3; ++q) {
      if (m.given & (1u << q)) CHECK(std::abs(read_mm[q] - m.xyz_mm[q]) <= linear_tol_mm);
    }
    if (m.given & 0x8u) CHECK(std::abs(w.tilt_deg - m.tilt_deg) <= angle_tol_deg);
    if (m.given & 0x10u) CHECK(std::abs(w.c_deg - m.c_deg) <= angle_tol_deg);
    if (w.arc) {
      REQUIRE(previous);
      // The centre in the arc's plane: the start as written plus the offset, each rounded to
      // the decimals (a helix rises along the plane's axis).
      Vec3d miss = w.arc_centre_mm - (previous->xyz_mm + m.centre_offset_mm);
      miss[m.arc_axis] = 0.0;
      CHECK(miss.norm() <= 2.0 * std::sqrt(2.0) * linear_tol_mm);
      CHECK(std::abs(std::abs(w.arc_normal[m.arc_axis]) - 1.0) < 1e-12);
      CHECK((w.arc_normal[m.arc_axis] > 0.0) == (m.type == PlannedMove::Type::ArcCounterClockwise));
    }
    if (m.feed_per_min) {
      // The F in force is the plan's, to the last digit (the text is the plan formatted).
      CHECK(w.feed == *m.feed_per_min);
      CHECK(w.inverse_time == m.inverse_time);
    } else {
      CHECK(w.rapid);
    }
    // The joints: where the plan knows all five axes in the program's frame (every block that
    // reaches a point, and the way in once X Y Z are named), as the verification computes them
    // from the words read back; never on a move in machine coordinates.
    if (!w.positioning) CHECK(b.joints.has_value());
    if (w.retract) CHECK_FALSE(b.joints.has_value());
    if (b.joints) {
      const Posed pose{deg_to_rad(w.tilt_deg), deg_to_rad(w.c_deg)};
      const Vec3d xyz = joints_of_written_mm(machine, w.xyz_mm, pose);
      const JointPosition read = {xyz.x(), xyz.y(), xyz.z(), w.tilt_deg, w.c_deg};
      for (std::size_t j = 0; j < kJointCount; ++j)
        CHECK(std::abs((*b.joints)[j] - read[j]) < 1e-6);
    }
    previous = &w;
  }
  // A finding about a block names its line in the program as written (after a failed
  // verification, in the program marked NOT VERIFIED): a motion block, and the same line in
  // its message.
  for (const Finding& f : res.findings) {
    if (!f.gcode_line) continue;
    INFO(f.message);
    REQUIRE(*f.gcode_line >= 1);
    REQUIRE(static_cast<std::size_t>(*f.gcode_line) <= prog.blocks.size());
    const ProgramBlock& named = prog.blocks[static_cast<std::size_t>(*f.gcode_line - 1)];
    REQUIRE(named.move.has_value());
    // A block the message says takes the spindle to a Z is one that names that Z.
    const std::size_t to_z = f.message.find("takes the spindle to Z ");
    if (to_z != std::string::npos) {
      const double z_mm = std::stod(f.message.substr(to_z + 23));
      CHECK((named.move->given & 0x4u) != 0);
      CHECK(std::abs(named.move->xyz_mm.z() - z_mm) <= linear_tol_mm + 1e-3);
      ++spindle_z_findings;
    }
    const std::size_t at = f.message.find("G-code line ");
    if (at != std::string::npos) {
      CHECK(std::stoi(f.message.substr(at + 12)) == *f.gcode_line);
    }
  }
  return planned;
}

}  // namespace

// [slow]: about 100 jobs (10 s in release): under the sanitizers the real files' case below
// covers the same writer.
TEST_CASE("program blocks: every motion block is its plan formatted, in every dialect and mode",
          "[io][gcode][blocks][slow]") {
  std::size_t compared = 0;
  for (const char* machine : {"linuxcnc-xyzac-trt", "haas-umc750", "generic-ac-trt", "paper-ac",
                              "linuxcnc-xyzbc-trt", "linuxcnc-max5"}) {
    for (GcodeDialect dialect : {GcodeDialect::LinuxCNC, GcodeDialect::Fanuc, GcodeDialect::Haas,
                                 GcodeDialect::Siemens, GcodeDialect::Heidenhain}) {
      for (LengthUnit units : {LengthUnit::Millimetre, LengthUnit::Inch}) {
        compared += check_case({"sine.cls", machine, dialect, units, FeedMode::UnitsPerMinute,
                                units == LengthUnit::Inch});
      }
    }
  }
  // Machine mode (table-table machines): the joints' words, with the blocks that keep the tip
  // on its line between points (linearisation).
  std::size_t linearised = 0;
  for (const char* machine : {"paper-ac", "generic-ac-trt", "linuxcnc-xyzbc-trt"}) {
    for (GcodeDialect dialect : {GcodeDialect::LinuxCNC, GcodeDialect::Fanuc, GcodeDialect::Haas,
                                 GcodeDialect::Siemens, GcodeDialect::Heidenhain}) {
      for (FeedMode feed_mode : {FeedMode::UnitsPerMinute, FeedMode::InverseTime}) {
        if (dialect == GcodeDialect::Heidenhain && feed_mode == FeedMode::InverseTime) continue;
        compared += check_case({"sine.cls", machine, dialect, LengthUnit::Millimetre, feed_mode,
                                feed_mode == FeedMode::InverseTime, GcodeMode::Machine});
        linearised += last_linearised;
      }
    }
  }
  CHECK(linearised > 0);
  // Inverse time (not on a TNC).
  for (GcodeDialect dialect :
       {GcodeDialect::LinuxCNC, GcodeDialect::Fanuc, GcodeDialect::Siemens}) {
    compared += check_case({"sine.cls", "generic-ac-trt", dialect, LengthUnit::Millimetre,
                            FeedMode::InverseTime, true});
  }
  CHECK(compared > 100000);
  // Some cases fail their verification (the LinuxCNC sample's 20 mm/s axes, its Z travel):
  // their programs are marked NOT VERIFIED, and the findings' lines must follow the marks.
  CHECK(spindle_z_findings > 0);
}

TEST_CASE("program blocks: real CL files' arcs, index moves and operations, as planned",
          "[io][gcode][blocks]") {
  std::size_t arcs = 0;
  for (const char* cl : {"creopost-profilfraesen.ncl", "mech491-project2-multiop.cls",
                         "taxopt-fusion-style-movarc.apt"}) {
    for (GcodeDialect dialect :
         {GcodeDialect::LinuxCNC, GcodeDialect::Fanuc, GcodeDialect::Haas, GcodeDialect::Siemens}) {
      for (LengthUnit units : {LengthUnit::Millimetre, LengthUnit::Inch}) {
        check_case({cl, "haas-umc750", dialect, units, FeedMode::UnitsPerMinute, false});
      }
    }
  }
  // The arcs are there to be compared (G2/G3 on the Haas in its own dialect).
  Machine machine =
      read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/haas-umc750.toml");
  JobOptions options;
  options.method = Method::None;
  options.spindle_rpm = 8000.0;
  options.tool_number = 3;
  const JobResult res = run_job(test::read_real("creopost-profilfraesen.ncl"), machine, options);
  for (const ProgramBlock& b : res.gcode.blocks) {
    arcs += b.move && b.move->type != PlannedMove::Type::Rapid &&
            b.move->type != PlannedMove::Type::Linear;
  }
  CHECK(arcs > 0);
}
