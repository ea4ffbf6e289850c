// The program's blocks between and around the CL points: swept against the part, held to
// the machine's travel, read as a machinist reads them (stages.hpp).
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "pipeline/stages.hpp"
#include "pipeline/verify_checks.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/kinematics/machine.hpp"
#include "taxopt/kinematics/metrics.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {
namespace {

/// The operation each written line belongs to and what it is, from the writer's blocks
/// (GcodeProgram::blocks): a line of the program's start counts as the first operation's, one
/// of its end as the last's.
class BlockOwner {
 public:
  BlockOwner(const GcodeProgram& program, std::size_t operations)
      : blocks_(program.blocks), last_(operations > 0 ? operations - 1 : 0) {}
  std::size_t operator()(int line) const {
    const ProgramBlock* b = at(line);
    if (!b || !b->operation) return line <= first_line() ? 0 : last_;
    return std::min(*b->operation, last_);
  }
  /// What the block is, in words.
  std::string what(int line) const {
    const ProgramBlock* b = at(line);
    if (!b) return "a block";
    switch (b->kind) {
      case BlockKind::Retract: return "the retract";
      case BlockKind::TableTurn: return "the table's turn with the tool up";
      case BlockKind::Approach: return "the approach";
      case BlockKind::Point: return "the move to a CL point";
      case BlockKind::Linearised: return "a linearisation block";
      case BlockKind::Arc: return "an arc";
      case BlockKind::JointSafeRapid: return "a rapid at a joint-safe feed";
      case BlockKind::End: return "the program's end";
      default: return "a block";
    }
  }

 private:
  const ProgramBlock* at(int line) const {
    if (line < 1 || static_cast<std::size_t>(line) > blocks_.size()) return nullptr;
    return &blocks_[static_cast<std::size_t>(line - 1)];
  }
  int first_line() const {
    for (const ProgramBlock& b : blocks_) {
      if (b.operation) return b.line;
    }
    return 0;
  }
  const std::vector<ProgramBlock>& blocks_;
  std::size_t last_;
};

/// The program's own checks (check_program): each kind of breach counted, its first named.
class ProgramChecks {
 public:
  ProgramChecks(const Run& run, const std::vector<PostedOperation>& posted, const Written& w,
                JobResult& res)
      : machine_(run.machine),
        t_(run.machine.gcode.program),
        posted_(posted),
        w_(w),
        res_(res),
        op_of_(res.gcode, posted.size()),
        threshold_deg_(run.machine.gcode.program.index_threshold_deg + 1e-9) {}

  void run() {
    travel();
    const GcodeMove* prev = nullptr;
    for (const GcodeMove& m : w_.moves) {
      block_words(m, prev);
      approach(m, prev);
      prev = &m;
    }
    coolant();
    end_pose();
    for (const auto& [code, b] : breaches_) {
      add_finding(res_, code, b.operation, 0,
                  b.what + (b.count > 1 ? " (and " + std::to_string(b.count - 1) + " more)" : ""),
                  b.line);
    }
  }

 private:
  struct Breach {
    std::size_t count = 0;
    std::size_t operation = 0;
    int line = 0;
    std::string what;
  };

  void breach(FindingCode code, const GcodeMove& m, const std::string& what) {
    Breach& b = breaches_[code];
    if (b.count++ == 0) {
      b.operation = op_of_(m.line);
      b.line = m.line;
      b.what = "operation " + posted_[op_of_(m.line)].name + ": G-code line " +
               std::to_string(m.line) + " " + what;
    }
  }

  /// Every block's end within the machine's travel, the spindle's position (the approach, the
  /// index moves, the retracts too: a LinuxCNC program whose approach left Z's travel by the
  /// tool's length stopped there with a soft-limit error, measured on LinuxCNC's motion
  /// controller). The CL points' own blocks are checked with their points (verify_operation,
  /// with the same tool length): here the blocks between them.
  void travel() {
    const std::vector<GcodeMove>& moves = w_.moves;
    std::set<const GcodeMove*> at_points;
    for (const auto& op_moves : w_.point_moves) at_points.insert(op_moves.begin(), op_moves.end());
    const std::optional<Vec3d>& offset = machine_.work_offset_mm;
    for (std::size_t k = 0; k < moves.size() && k < w_.spindle_mm.size(); ++k) {
      if (!w_.spindle_mm[k]) continue;
      // Without a work offset only a retract's Z is in machine coordinates.
      if (offset ? at_points.count(&moves[k]) > 0 : !moves[k].retract) continue;
      for (int q = offset ? 0 : 2; q < 3; ++q) {
        const double v = (*w_.spindle_mm[k])[q] + (offset ? (*offset)[q] : 0.0);
        const std::optional<std::string> outside = outside_travel(machine_, q, v);
        if (!outside) continue;
        std::ostringstream os;
        os << "takes the spindle to "
           << "XYZ"[q] << " " << v << " mm in machine coordinates (tool length "
           << res_.gcode.time_tool_length_mm << " mm";
        if (offset)
          os << ", work offset "
             << "XYZ"[q] << " " << (*offset)[q] << " mm";
        os << ")" << *outside;
        breach(FindingCode::TravelExceeded, moves[k], os.str());
      }
    }
    if (!offset) span();
  }

  /// Without a work offset: the program's span in each linear joint (every block in the
  /// program's frame, the retracts aside) within the machine's travel's; where it is not, no
  /// work offset fits the program.
  void span() {
    const std::vector<GcodeMove>& moves = w_.moves;
    for (int q = 0; q < 3; ++q) {
      const Machine::LinearRange& range = machine_.linear_range[static_cast<std::size_t>(q)];
      if (!std::isfinite(range.min_mm) || !std::isfinite(range.max_mm)) continue;
      std::optional<std::size_t> lo, hi;
      for (std::size_t k = 0; k < moves.size() && k < w_.spindle_mm.size(); ++k) {
        if (!w_.spindle_mm[k] || moves[k].retract) continue;
        const double v = (*w_.spindle_mm[k])[q];
        if (!lo || v < (*w_.spindle_mm[*lo])[q]) lo = k;
        if (!hi || v > (*w_.spindle_mm[*hi])[q]) hi = k;
      }
      if (!lo) continue;
      const double low = (*w_.spindle_mm[*lo])[q], high = (*w_.spindle_mm[*hi])[q];
      if (high - low <= range.max_mm - range.min_mm + 1e-6) continue;
      std::ostringstream os;
      os << "and G-code line " << moves[*hi].line << " span the spindle's "
         << "XYZ"[q] << " over " << high - low << " mm (" << low << " to " << high
         << " mm from the program's zero), more than the machine's travel [" << range.min_mm << ", "
         << range.max_mm << "] mm: no work offset fits the program";
      breach(FindingCode::TravelExceeded, moves[*lo], os.str());
    }
  }

  /// The tool, the spindle and the feed a block runs with, and a table turned in a rapid
  /// below the retract.
  void block_words(const GcodeMove& m, const GcodeMove* prev) {
    const PostedOperation& po = posted_[op_of_(m.line)];
    if (!m.retract) {
      if (m.tool <= 0) {
        breach(FindingCode::NoToolCalled, m, "moves with no tool called (T with M6)");
      } else if (po.tool.number > 0 && m.tool != po.tool.number && !m.positioning) {
        breach(FindingCode::NoToolCalled, m,
               "runs tool " + std::to_string(m.tool) + " where the operation's is " +
                   std::to_string(po.tool.number));
      }
    }
    // A rapid written at a joint-safe feed (LinuxCNC, tcp) cuts nothing: a rapid still.
    const bool joint_safe_rapid = std::binary_search(res_.gcode.joint_safe_rapids.begin(),
                                                     res_.gcode.joint_safe_rapids.end(), m.line);
    if (!m.rapid && !m.spindle_on && !joint_safe_rapid) {
      breach(FindingCode::SpindleOff, m, "moves at feed with the spindle stopped");
    }
    if (!m.rapid && !(m.feed > 0.0)) {
      // A feed that rounds to F0 at gcode.feed_decimals: no controller runs it (rs274: "Cannot
      // do g1 with zero feed rate").
      breach(FindingCode::ReadBackMismatch, m,
             "moves at feed F0 (the feed rounds to zero at gcode.feed_decimals)");
    }
    if (prev && m.rapid && !m.positioning && !prev->positioning && !po.swept_moves_checked &&
        t_.retract != SafeRetract::None &&
        std::max(std::abs(m.tilt_deg - prev->tilt_deg), std::abs(m.c_deg - prev->c_deg)) >
            threshold_deg_) {
      breach(FindingCode::IndexWithoutRetract, m,
             "turns the table by more than " + shown(t_.index_threshold_deg) +
                 " deg in a rapid below the retract, with no part model to check the move");
    }
  }

  /// Down from the retract height: XY first (alone, or with Z at the clearance height in the
  /// positioning block that names X, Y and Z but not the angles), then straight down, or under
  /// TCP along the tool axis (as CAM links an approach: the writer comes down so where the
  /// axis is not vertical).
  void approach(const GcodeMove& m, const GcodeMove* prev) {
    if (m.retract) {
      after_retract_ = true;
      xy_set_ = false;
      return;
    }
    if (!after_retract_) return;
    const bool gives_xy = (m.given & 3u) != 0, gives_z = (m.given & 4u) != 0;
    const bool turns = prev && (m.tilt_deg != prev->tilt_deg || m.c_deg != prev->c_deg);
    const bool positioning_xyz = (m.given & 0x1fu) == 0x7u && m.positioning && !xy_set_;
    if (gives_z && !gives_xy && !xy_set_ && !turns) {
      // Straight down (or up) to the clearance height, where it is: not the way in yet.
    } else if ((gives_xy && !gives_z) || positioning_xyz) {
      xy_set_ = true;
      xy_[0] = m.xyz_mm.x();
      xy_[1] = m.xyz_mm.y();
    } else if (gives_z) {
      const auto along_axis = [&] {
        if (!prev || !m.tcp || !prev->tcp) return false;
        const Vec3d d = m.xyz_mm - prev->xyz_mm;
        if (d.norm() < 1e-9) return false;
        const Vec3d axis =
            machine_.rotary.forward(Posed{deg_to_rad(m.tilt_deg), deg_to_rad(m.c_deg)});
        return std::abs(d.normalized().dot(axis)) > std::cos(1e-3);
      };
      if (!xy_set_ || ((m.xyz_mm.x() != xy_[0] || m.xyz_mm.y() != xy_[1]) && !along_axis()) ||
          turns) {
        breach(FindingCode::DiagonalApproach, m,
               "leaves the retract height otherwise than XY first, then down");
      }
      after_retract_ = false;
    }
  }

  /// The coolant at each operation's first point: the CL file's (its last change before that
  /// point), else the machine file's.
  void coolant() {
    const auto code_of = [](ClCoolant c) {
      return c == ClCoolant::Flood ? 8 : c == ClCoolant::Mist ? 7 : 0;
    };
    for (std::size_t k = 0; k < posted_.size(); ++k) {
      const PostedOperation& po = posted_[k];
      if (w_.point_moves[k].empty()) continue;
      int want = po.coolant                     ? code_of(*po.coolant)
                 : t_.coolant == Coolant::Flood ? 8
                 : t_.coolant == Coolant::Mist  ? 7
                                                : 0;
      for (const ProgramEvent& e : po.events) {
        if (e.kind == ProgramEvent::Kind::Coolant && e.before_point == 0) want = code_of(e.coolant);
      }
      const GcodeMove& first = *w_.point_moves[k].front();
      if (first.coolant != want) {
        breach(FindingCode::CoolantMismatch, first,
               "starts with coolant " +
                   std::string(first.coolant == 0   ? "off"
                               : first.coolant == 7 ? "M7"
                                                    : "M8") +
                   " where " +
                   std::string(want == 0   ? "off"
                               : want == 7 ? "M7 (mist)"
                                           : "M8 (flood)") +
                   " is asked (CL file COOLNT, else the machine file's gcode.coolant)");
      }
    }
  }

  void end_pose() {
    const GcodeMove& last = w_.moves.back();
    // A continuous C is home at any whole turn (the writer takes the nearest).
    const bool c_home =
        machine_.rotary.c.continuous ? std::fmod(last.c_deg, 360.0) == 0.0 : last.c_deg == 0.0;
    if (t_.end_pose == EndPose::Home && t_.retract != SafeRetract::None &&
        (last.tilt_deg != 0.0 || !c_home)) {
      breach(FindingCode::EndPoseNotHome, last,
             "ends with the rotary axes at " + shown(last.tilt_deg) + " / " + shown(last.c_deg) +
                 " deg, not at their home (gcode.end_pose)");
    }
  }

  const Machine& machine_;
  const ProgramTemplate& t_;
  const std::vector<PostedOperation>& posted_;
  const Written& w_;
  JobResult& res_;
  const BlockOwner op_of_;
  const double threshold_deg_;
  std::map<FindingCode, Breach> breaches_;
  bool after_retract_ = false, xy_set_ = false;
  double xy_[2] = {0.0, 0.0};
};

}  // namespace

void check_program(const Run& run, const std::vector<PostedOperation>& posted, const Written& w,
                   JobResult& res) {
  if (w.moves.empty() || posted.empty()) return;
  ProgramChecks(run, posted, w, res).run();
}

namespace {

/// The blocks the operations' own checks sweep already (colliding_moves): a feed move into a
/// point with its linearisation blocks, a rapid written as one block; and the blocks that end
/// at a contact point.
struct PointBlocks {
  std::vector<char> swept, touching_end;
};

PointBlocks point_blocks(const std::vector<OperationContext>& ops,
                         const std::vector<PostedOperation>& posted, const Written& w) {
  const std::vector<GcodeMove>& moves = w.moves;
  PointBlocks out{std::vector<char>(moves.size(), 0), std::vector<char>(moves.size(), 0)};
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const OperationContext& o = ops[k];
    const std::vector<const GcodeMove*>& at = w.point_moves[k];
    for (std::size_t i = 0; i < at.size(); ++i) {
      const std::ptrdiff_t to = move_index(moves, at[i]);
      if (to < 0) continue;
      if (!o.contacts.empty() && o.contacts[i].state == ContactState::Touching) {
        out.touching_end[static_cast<std::size_t>(to)] = 1;
      }
      if (i == 0 || !o.judged_tool()) continue;
      const std::ptrdiff_t from = move_index(moves, at[i - 1]);
      if (from < 0 || to <= from) continue;
      if (posted[k].points[i].motion == Motion::Feed || to == from + 1) {
        for (std::ptrdiff_t j = from + 1; j <= to; ++j) out.swept[static_cast<std::size_t>(j)] = 1;
      }
    }
  }
  return out;
}

/// The tool in the air: the ball counts as a body too, within the flutes' tolerance of the part
/// (a block that ends at a contact point touches it there by design).
ToolModel air_tool(const ToolModel& tool, double flute_tolerance_mm) {
  ToolModel air = tool;
  air.ball_radius_mm =
      std::max(0.5 * tool.ball_radius_mm, tool.ball_radius_mm - flute_tolerance_mm);
  return air;
}

/// How far apart a sweep samples the tool along its path: no more than half the thinnest
/// body's radius (a wall the body could pass between two samples is thinner than the body is
/// wide), at least 0.05 mm.
double sweep_step_mm(const ToolModel& tool) {
  double thinnest = tool.ball_radius_mm > 0.0 ? tool.ball_radius_mm : 1.0;
  for (const ToolBody& b : tool.bodies) thinnest = std::min(thinnest, b.radius_mm);
  return std::max(0.05, 0.5 * thinnest);
}

/// Whether block j (its end known) hits the part as the machine moves it, sampled at most
/// 0.5 deg of either rotary axis and half the thinnest body apart.
bool block_collides(const Run& run, const OperationContext& o, const Written& w, std::size_t j,
                    bool touching_end, double flute_tolerance_mm) {
  const Machine& machine = run.machine;
  constexpr std::size_t kA = static_cast<std::size_t>(Joint::Tilt);
  constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
  const ToolModel& tool = *o.tool;
  const double R = tool.ball_radius_mm;
  const ToolModel air = air_tool(tool, flute_tolerance_mm);
  // A block whose start is not known (the first after a retract in machine
  // coordinates): its end, where the tool stands.
  const JointPosition& q1 = *w.joints_after[j];
  const JointPosition& q0 = w.joints_after[j - 1] ? *w.joints_after[j - 1] : q1;
  const Posed p0{deg_to_rad(q0[kA]), deg_to_rad(q0[kC])};
  const Posed p1{deg_to_rad(q1[kA]), deg_to_rad(q1[kC])};
  const Vec3d m0(q0[0], q0[1], q0[2]), m1(q1[0], q1[1], q1[2]);
  const Vec3d t0 = machine.rotary.from_machine_mm(m0, p0),
              t1 = machine.rotary.from_machine_mm(m1, p1);
  const bool tip_linear = w.tip_linear[j] != 0;
  // Steps: 0.5 deg of either rotary axis, and along the path sweep_step_mm.
  const double step_mm = sweep_step_mm(tool);
  const double travel = std::max((t1 - t0).norm(), (m1 - m0).norm());
  const int steps = static_cast<int>(std::ceil(std::max(
      {std::abs(q1[kA] - q0[kA]) / 0.5, std::abs(q1[kC] - q0[kC]) / 0.5, travel / step_mm, 1.0})));
  for (int s = 1; s <= steps; ++s) {
    const double u = static_cast<double>(s) / steps;
    const Posed pose{p0.tilt_rad + u * (p1.tilt_rad - p0.tilt_rad),
                     p0.c_rad + u * (p1.c_rad - p0.c_rad)};
    const Vec3d tip = tip_linear ? Vec3d(t0 + u * (t1 - t0))
                                 : machine.rotary.from_machine_mm(m0 + u * (m1 - m0), pose);
    const Vec3d axis = machine.rotary.forward(pose);
    // The block's end at a contact point: the flutes judged as at every CL point.
    const bool at_contact = s == steps && touching_end;
    if (run.collision->collides(at_contact ? tool : air, tip + R * axis, axis, !at_contact)) {
      return true;
    }
  }
  return false;
}

/// A retract in machine coordinates along Z alone (G53 Z, G28 Z, SUPA Z, M91) from a known
/// pose: the tool goes straight along machine +Z; where it stops depends on the work offset and
/// the tool length, but beyond the part's bounding box along that direction nothing is left to
/// hit. Whether it hits the part on the way, sampled as block_collides samples.
bool retract_collides(const Run& run, const OperationContext& o, const Written& w, std::size_t j,
                      const Vec3d& box_lo, const Vec3d& box_hi, double flute_tolerance_mm) {
  const Machine& machine = run.machine;
  const JointPosition& q = *w.joints_after[j - 1];
  const Posed pose{deg_to_rad(q[static_cast<std::size_t>(Joint::Tilt)]),
                   deg_to_rad(q[static_cast<std::size_t>(Joint::C)])};
  const Vec3d m0(q[0], q[1], q[2]);
  const Vec3d t0 = machine.rotary.from_machine_mm(m0, pose);
  const Vec3d up = (machine.rotary.from_machine_mm(m0 + Vec3d::UnitZ(), pose) - t0).normalized();
  const Vec3d axis = machine.rotary.forward(pose);
  const ToolModel& tool = *o.tool;
  const double R = tool.ball_radius_mm;
  double length = 2.0 * R, widest = R;
  for (const ToolBody& b : tool.bodies) {
    length = std::max(length, b.end_mm + R);
    widest = std::max(widest, b.radius_mm);
  }
  // The farthest the part reaches along `up`, and the tool's lowest point along it.
  double part_top = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < 8; ++c) {
    const Vec3d corner((c & 1) ? box_hi.x() : box_lo.x(), (c & 2) ? box_hi.y() : box_lo.y(),
                       (c & 4) ? box_hi.z() : box_lo.z());
    part_top = std::max(part_top, corner.dot(up));
  }
  const double tool_low = std::min(t0.dot(up), (t0 + length * axis).dot(up)) - widest;
  const double rise = part_top - tool_low;
  if (!(rise > 0.0)) return false;
  const ToolModel air = air_tool(tool, flute_tolerance_mm);
  const int steps = static_cast<int>(std::ceil(rise / sweep_step_mm(tool)));
  for (int s = 1; s <= steps; ++s) {
    const Vec3d tip = t0 + (rise * s / steps) * up;
    if (run.collision->collides(air, tip + R * axis, axis, true)) return true;
  }
  return false;
}

/// The part's bounding box, mm (empty: lo above hi, without a part).
std::pair<Vec3d, Vec3d> part_box(const Run& run) {
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity());
  Vec3d hi = -lo;
  if (run.options.part) {
    for (const Vec3d& v : run.options.part->mesh().vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
  }
  return {lo, hi};
}

}  // namespace

void check_every_block(const Run& run, const std::vector<OperationContext>& ops,
                       const std::vector<PostedOperation>& posted, const Written& w,
                       JobResult& res) {
  const std::vector<GcodeMove>& moves = w.moves;
  if (!run.collision || moves.empty() || posted.empty() || res.operations.size() != posted.size())
    return;
  const BlockOwner op_of(res.gcode, posted.size());
  // Every block the operations' own checks do not sweep (the approach, the descent and the XY
  // move to it, an index move's retract, turn and way back, the retract at the end and the
  // unwinding) is swept here, with the whole tool in the air.
  const PointBlocks points = point_blocks(ops, posted, w);
  struct Hit {
    std::size_t count = 0;
    std::size_t move = 0;  // the first block that hits
  };
  std::vector<Hit> hits(posted.size());
  std::vector<std::size_t> candidates;
  std::vector<long> unknown(posted.size(), 0);
  // The part's bounding box: a retract along machine Z is swept until the tool clears it.
  const std::pair<Vec3d, Vec3d> box = part_box(run);
  const auto up_from_known = [&](std::size_t j) {
    return moves[j].retract && (moves[j].given & 0x7u) == 0x4u && w.joints_after[j - 1] &&
           run.options.part;
  };
  for (std::size_t j = 1; j < moves.size(); ++j) {
    if (points.swept[j]) continue;
    const OperationContext& o = ops[op_of(moves[j].line)];
    if (!o.judged_tool()) continue;
    if (w.joints_after[j] || up_from_known(j)) {
      candidates.push_back(j);
    } else {
      ++unknown[op_of(moves[j].line)];
    }
  }
  std::vector<double> flute_tolerance_mm(ops.size(), 0.0);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    flute_tolerance_mm[k] = margins_of(run.options, *ops[k].op).flute_tolerance_mm;
  }
  const std::vector<std::size_t> hit =
      detail::parallel_select(0, candidates.size(), [&](std::size_t c) {
        const std::size_t j = candidates[c];
        const std::size_t k = op_of(moves[j].line);
        if (up_from_known(j)) {
          return retract_collides(run, ops[k], w, j, box.first, box.second, flute_tolerance_mm[k]);
        }
        return block_collides(run, ops[k], w, j, points.touching_end[j] != 0,
                              flute_tolerance_mm[k]);
      });
  for (std::size_t c : hit) {
    const std::size_t j = candidates[c];
    Hit& h = hits[op_of(moves[j].line)];
    if (h.count++ == 0) h.move = j;
  }
  for (std::size_t k = 0; k < posted.size(); ++k) {
    res.operations[k].verification.blocks_swept = 0;
    res.operations[k].verification.blocks_not_checked = unknown[k];
  }
  for (std::size_t j : candidates) {
    std::optional<long>& count = res.operations[op_of(moves[j].line)].verification.blocks_swept;
    count = *count + 1;
  }
  for (std::size_t k = 0; k < posted.size(); ++k) {
    OperationResult& r = res.operations[k];
    r.verification.colliding_blocks = static_cast<long>(hits[k].count);
    if (!hits[k].count) continue;
    r.verification.collision_free = false;
    const GcodeMove& m = moves[hits[k].move];
    add_finding(res, FindingCode::MoveCollision, k, 0,
                "operation " + posted[k].name + ": " + std::to_string(hits[k].count) +
                    " blocks the program adds between CL points (approach, retract, index or "
                    "end moves) where the tool hits the part as the machine moves it, first G-code "
                    "line " +
                    std::to_string(m.line) + " (" + op_of.what(m.line) + ", " +
                    (m.rapid ? "a rapid" : "a feed block") +
                    (m.retract ? " in machine coordinates" : "") + ")",
                m.line);
  }
}

}  // namespace taxopt::pipeline
