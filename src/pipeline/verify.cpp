// The verify stage: every operation checked as written -- read back, axis ranges and travel,
// the deviation cone, collisions of the points and of the moves between them, clearances,
// the machine's dynamic limits -- and the report's rows (stages.hpp).
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "cl/cl_writer.hpp"
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

/// The F words of an operation's feed blocks as read back, against the programmed feeds
/// (OperationResult::FeedWords); none for an inverse-time program.
std::optional<OperationResult::FeedWords> written_feed_words(
    const Operationd& op, const PostedOperation& po,
    const std::vector<const GcodeMove*>& point_moves, LengthUnit units, const Machine& machine) {
  if (machine.gcode.feed_mode != FeedMode::UnitsPerMinute) return std::nullopt;
  OperationResult::FeedWords f;
  f.max_feed_ratio = machine.gcode.max_feed_ratio;
  f.lengthened_blocks = po.feed_ratio_blocks;
  const GcodeMove* last = nullptr;
  for (std::size_t i = 1; i < op.points.size() && i < point_moves.size(); ++i) {
    const GcodeMove* m = point_moves[i];
    const double programmed = op.points[i].feed_mm_per_min;
    if (!m || m == last || m->rapid || op.points[i].motion != Motion::Feed || !(programmed > 0.0)) {
      continue;
    }
    last = m;  // an arc's chord points share its block
    const double ratio = m->feed * mm_per_unit(units) / programmed;
    f.min_ratio = f.blocks ? std::min(f.min_ratio, ratio) : ratio;
    f.max_ratio = f.blocks ? std::max(f.max_ratio, ratio) : ratio;
    ++f.blocks;
  }
  return f;
}

double round_to(double v, int decimals) {
  const double s = std::pow(10.0, decimals);
  return std::round(v * s) / s;
}

/// The axes as written and read back, per point (deg, mm), and the input's (rounded as
/// written).
struct WrittenAxes {
  std::vector<double> a_w, c_w, a_in, c_in;
  std::vector<Vec3d> xyz_w;
};

/// Point i's row of the CSV: the point as posted, its axes as written (WrittenAxes).
void set_point_row(const CLPointd& posted, std::size_t i, const WrittenAxes& ax, PointRow& row) {
  row.index = i;
  row.line = posted.line;
  row.tip_mm = posted.tip_mm;
  row.axis = posted.axis;
  row.tilt_axis_deg = ax.a_w[i];
  row.c_deg = ax.c_w[i];
}

/// A rotary axis that turns more than half a turn between two CL points of a feed move (a
/// limited C unwinding there: an audit's C of [-200, 200] deg turned 356 deg inside a G1) sweeps
/// the tool round while it cuts, part or no part: a problem where the ball's centre leaves its
/// straight path by more than the 0.05 mm contact tolerance floor (a pass through the pole,
/// where C flips by 180 deg with the axis nearly vertical, stays within it).
void check_turns_in_cut(const Run& run, const OperationContext& o, const WrittenAxes& ax,
                        JobResult& res) {
  const Operationd& op = *o.op;
  const MachineKinematicsd& ac = run.machine.rotary;
  const double R = o.ball_radius_mm > 0.0 ? o.ball_radius_mm : 0.5 * op.tool.diameter_mm;
  std::size_t count = 0, first = 0;
  double first_turn = 0.0, first_off = 0.0;
  for (std::size_t i = 1; i < op.points.size(); ++i) {
    if (op.points[i].motion != Motion::Feed) continue;
    const double da = ax.a_w[i] - ax.a_w[i - 1], dc = ax.c_w[i] - ax.c_w[i - 1];
    if (std::max(std::abs(da), std::abs(dc)) <= 180.0) continue;
    const auto axis_at = [&](double s) {
      return ac.forward(
          Posed{deg_to_rad(ax.a_w[i - 1] + s * da), deg_to_rad(ax.c_w[i - 1] + s * dc)});
    };
    const Vec3d v0 = axis_at(0.0), v1 = axis_at(1.0);
    double off = 0.0;
    for (int q = 1; q < 16; ++q) {
      const double s = q / 16.0;
      off = std::max(off, (R * (axis_at(s) - ((1.0 - s) * v0 + s * v1))).norm());
    }
    if (off <= kContactToleranceFloorMm) continue;
    if (count++ == 0) first = i, first_turn = std::max(std::abs(da), std::abs(dc)), first_off = off;
  }
  if (count == 0) return;
  std::ostringstream os;
  os << "operation " << op.name << ": " << count << " feed move(s) where a rotary axis turns more "
     << "than half a turn, the first " << shown(first_turn) << " deg into CL line "
     << op.points[first].line << " (C's range [" << rad_to_deg(ac.c.min_rad) << ", "
     << rad_to_deg(ac.c.max_rad) << "] deg makes it unwind there): the tool sweeps round while "
     << "it cuts, the ball's centre up to " << shown(first_off)
     << " mm off its straight path; widen the range or make the CL file lift the tool there";
  add_finding(res, FindingCode::TurnInCut, o.index, op.points[first].line,
              format_location(run.tp.source, op.points[first].line, os.str()));
}

/// The written point `last` (its pose `written`) within the rotary axes' ranges (its row marked
/// at a range's end) and, its joints in machine coordinates, within the machine's linear travel.
void check_point_ranges(const Run& run, const OperationContext& o, const GcodeMove& last,
                        const Posed& written, const CLPointd& want, PointRow& row,
                        OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const Machine& machine = run.machine;
  // At a range's end (within 0.01 deg) or past it: the page's "limit reached".
  const auto at_limit = [](const RotaryAxis<double>& range, double v_rad) {
    const double near_rad = deg_to_rad(0.01);
    return !range.continuous &&
           (v_rad <= range.min_rad + near_rad || v_rad >= range.max_rad - near_rad);
  };
  if (at_limit(machine.rotary.tilt, written.tilt_rad) ||
      at_limit(machine.rotary.c, written.c_rad)) {
    row.mark(PointMark::AxisLimit);
  }
  if (!machine.rotary.tilt.contains(written.tilt_rad) ||
      !machine.rotary.c.contains(written.c_rad)) {
    if (r.verification.within_axis_limits) {
      add_finding(res, FindingCode::AxisRangeExceeded, o.index, want.line,
                  format_location(
                      run.tp.source, want.line,
                      "operation " + op.name + ": written " + machine.rotary.tilt_letter() + " " +
                          std::to_string(last.tilt_deg) + " / C " + std::to_string(last.c_deg) +
                          " deg is outside the machine's axis ranges"));
    }
    r.verification.within_axis_limits = false;
  }
  // The linear travel, in machine coordinates, where the machine file gives it: the
  // spindle's, the tool length above the tip (GcodeProgram::time_tool_length_mm), the work
  // offset added. Without a work offset the program's span is checked (ProgramChecks::travel).
  if (!machine.work_offset_mm) return;
  const Vec3d joints_mm = joints_of_written_mm(machine, last.xyz_mm, written) +
                          Vec3d(0.0, 0.0, res.gcode.time_tool_length_mm) + *machine.work_offset_mm;
  for (int q = 0; q < 3; ++q) {
    const std::optional<std::string> outside = outside_travel(machine, q, joints_mm[q]);
    if (!outside) continue;
    row.mark(PointMark::TravelExceeded);
    if (r.verification.within_axis_limits) {
      std::ostringstream os;
      os << "operation " << op.name << ": "
         << "XYZ"[q] << " would be " << joints_mm[q] << " mm in machine coordinates";
      if (q == 2 && res.gcode.time_tool_length_mm > 0.0) {
        os << " (the spindle, tool length " << res.gcode.time_tool_length_mm << " mm)";
      }
      os << " with the work offset "
         << "XYZ"[q] << " " << (*machine.work_offset_mm)[q] << " mm";
      os << *outside;
      add_finding(res, FindingCode::TravelExceeded, o.index, want.line,
                  format_location(run.tp.source, want.line, os.str()));
    }
    r.verification.within_axis_limits = false;
  }
}

/// Point i as read back: the tool length and TCP on, the round trip, within the axes' ranges
/// and the machine's travel; its row's place.
void check_point_written(const Run& run, const OperationContext& o, const PostedOperation& po,
                         const GcodeMove* last, std::size_t i, WrittenAxes& ax, OperationResult& r,
                         JobResult& res) {
  const Operationd& op = *o.op;
  const Machine& machine = run.machine;
  const int decimals = machine.gcode.decimals;
  // Where TCP is asked for, the controller's must be on, with the tool length offset
  // (LinuxCNC's kinematics steer the spindle nose without it); in machine mode the offset.
  const bool tcp_mode = machine.gcode.mode == GcodeMode::Tcp;
  if (!last->length_offset || (tcp_mode && !last->tcp)) {
    if (r.verification.tool_length_active) {
      add_finding(res, FindingCode::ToolLengthOffsetOff, o.index, op.points[i].line,
                  "operation " + op.name + ": G-code line " + std::to_string(last->line) +
                      " moves with " +
                      (!last->length_offset ? std::string("the tool length offset off")
                                            : std::string("tool centre point control off")) +
                      " (the written program must switch it on before the operation's first move)");
    }
    r.verification.tool_length_active = false;
  }
  ax.a_w[i] = last->tilt_deg;
  ax.xyz_w[i] = last->xyz_mm;
  ax.c_w[i] = last->c_deg;
  if (!o.input_poses.empty()) {
    ax.a_in[i] = round_to(rad_to_deg(o.input_poses[i].tilt_rad), decimals);
    ax.c_in[i] = round_to(rad_to_deg(o.input_poses[i].c_rad), decimals);
  }
  const Posed written{deg_to_rad(last->tilt_deg), deg_to_rad(last->c_deg)};
  const Vec3d axis = machine.rotary.forward(written);
  const Vec3d tip = tip_of_written_mm(machine, last->xyz_mm, written);
  const CLPointd& want = po.points[i];
  r.verification.roundtrip_max_mm =
      std::max(r.verification.roundtrip_max_mm, (tip - want.tip_mm).norm());
  r.verification.roundtrip_max_deg =
      std::max(r.verification.roundtrip_max_deg, rad_to_deg(angle_between(axis, want.axis)));
  check_point_ranges(run, o, *last, written, want, r.rows[i], r, res);
  r.max_axis_change_deg =
      std::max(r.max_axis_change_deg, rad_to_deg(angle_between(op.points[i].axis, want.axis)));
  set_point_row(want, i, ax, r.rows[i]);
}

/// The round trip held to the written decimals' rounding, and that rounding to a finishing
/// tolerance.
void check_round_trip(const Run& run, const OperationContext& o, const PostedOperation& po,
                      OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const Machine& machine = run.machine;
  const int decimals = machine.gcode.decimals;
  // The round trip may differ from the intent only by the rounding of the written
  // decimals: half a unit of the last decimal per word, mapped to mm and to the axis angle;
  // in machine mode the angle rounding also moves the mapped point by its lever arm.
  const double half_unit = 0.5 * std::pow(10.0, -decimals);
  const double ang_tol = std::sqrt(2.0) * half_unit + 1e-9;
  double lever_mm = 0.0;
  if (machine.gcode.mode == GcodeMode::Machine) {
    for (const auto& p : po.points) {
      lever_mm =
          std::max(lever_mm,
                   (p.tip_mm - machine.rotary.c_axis_point_mm).norm() +
                       (machine.rotary.c_axis_point_mm - machine.rotary.tilt_axis_point_mm).norm());
    }
  }
  // 10 nm for the arithmetic of unit conversions (a Fusion inch file's arc missed by 3 nm).
  const double pos_tol = std::sqrt(3.0) * half_unit * mm_per_unit(res.gcode_units) +
                         2.0 * lever_mm * deg_to_rad(ang_tol) + 1e-5;
  // The rounding itself must keep the tips within a finishing tolerance: `decimals = 0` wrote
  // G1 X0 Y4 Z8 for GOTO/0,3.555,8.4996 and the round trip "held" within its 0.87 mm.
  constexpr double kProgramToleranceMm = 0.005;
  if (pos_tol > kProgramToleranceMm) {
    add_finding(res, FindingCode::ReadBackMismatch, k, 0,
                "operation " + op.name + ": gcode.decimals = " + std::to_string(decimals) +
                    " rounds the written tips by up to " + std::to_string(pos_tol) +
                    " mm, more than the " + std::to_string(kProgramToleranceMm) +
                    " mm a finishing program holds (write more decimals)");
  } else if (r.verification.roundtrip_max_mm > pos_tol) {
    add_finding(res, FindingCode::ReadBackMismatch, k, 0,
                "operation " + op.name + ": G-code read back is " +
                    std::to_string(r.verification.roundtrip_max_mm) +
                    " mm from the intended tips (rounding allows " + std::to_string(pos_tol) + ")");
  }
  if (r.verification.roundtrip_max_deg > ang_tol) {
    add_finding(res, FindingCode::ReadBackMismatch, k, 0,
                "operation " + op.name + ": G-code read back is " +
                    std::to_string(r.verification.roundtrip_max_deg) +
                    " deg from the intended axes (rounding allows " + std::to_string(ang_tol) +
                    ")");
  }
}

/// The written axes within this of the input's count as kept, rad (a pose's forward
/// kinematics round-trip is good to about 1e-15).
constexpr double kKeptAxisRad = 1e-9;

/// A rise of an axis's peak rate over the input's below this share is the rounding of the
/// written words (the guards hold the plan's rates to the input's exactly).
constexpr double kRiseShare = 1e-3;

/// The reasons of the kept points, in words.
std::string kept_reasons(const OperationResult::KeptInputPoints& kept) {
  std::string out;
  const auto add = [&](std::size_t count, const char* what) {
    if (count == 0) return;
    if (!out.empty()) out += "; ";
    out += std::to_string(count) + " " + what;
  };
  add(kept.collision, "where the method's axes swept the tool through the part");
  add(kept.peak_rate,
      "where the method's axes raised a rotary axis's omega or a above the input's");
  add(kept.no_gain, "where the method's axes gained nothing on the pass");
  add(kept.no_free_axis, "with no acceptable axis within the cone");
  add(kept.method_choice, "where the method itself chose the input's axes");
  return out;
}

/// Why point i kept its input axis, as the method's own guards say: the last guard that gave
/// the point back its reference (global against the paper's, the paper's against the input).
KeptWhy kept_why(const OptimisedOperation& opt, std::size_t i) {
  for (const StretchGuardResult* g : {&opt.global_guard, &opt.guard}) {
    if (i < g->why.size() && g->why[i] != KeptWhy::None && g->why[i] != KeptWhy::Join) {
      return g->why[i];
    }
  }
  return KeptWhy::None;
}

/// The points of the feed passes whose written axis is their input axis, by why; and the cone
/// proved on what is written. The counts come from the axes written, whatever method and
/// fallback chose them: a guard's count of what it kept is not what a later stage wrote.
void kept_points(const Run& run, const OperationContext& o, const PostedOperation& po,
                 OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  r.segments = static_cast<int>(o.optimised->intervals);
  const OptimisedOperation& opt = *o.optimised;
  OperationResult::KeptInputPoints kept;
  std::vector<char> no_free(op.points.size(), 0);
  for (std::size_t i : opt.no_free_axis) {
    no_free[i] = 1;
    r.rows[i].mark(PointMark::NoFreeAxis);
  }
  for (const IndexRange& pass : feed_passes(op)) {
    std::size_t kept_here = 0;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      const KeptWhy why = kept_why(opt, i);
      if (why == KeptWhy::None && i < opt.guard.why.size() && opt.guard.why[i] == KeptWhy::Join) {
        r.rows[i].mark(PointMark::KeptJoin);
        ++kept.join_points;
      }
      // The written axis is the input's: within the round-off of a pose's forward kinematics.
      if (angle_between(po.points[i].axis, op.points[i].axis) > kKeptAxisRad) continue;
      ++kept_here;
      if (no_free[i]) {
        ++kept.no_free_axis;
      } else if (why == KeptWhy::Collision) {
        ++kept.collision;
        r.rows[i].mark(PointMark::KeptCollision);
      } else if (why == KeptWhy::PeakRate) {
        ++kept.peak_rate;
        r.rows[i].mark(PointMark::KeptPeakRate);
      } else if (why == KeptWhy::NoGain) {
        ++kept.no_gain;
      } else {
        ++kept.method_choice;
      }
    }
    if (kept_here == pass.size()) ++kept.passes;
  }
  kept.stretches = opt.guard.stretches + opt.global_guard.stretches;
  if (kept.total() > 0) {
    add_finding(res, FindingCode::InputAxesKept, k, 0,
                "operation " + op.name + ": " + std::to_string(kept.total()) +
                    " points keep their input axes as written (" + std::to_string(kept.passes) +
                    " whole passes): " + kept_reasons(kept));
  }
  r.kept_input_points = kept;
  r.time_choice = opt.time_choice;
  // The optimiser keeps every axis within the cone; this proves it on what is written.
  const double allowed = run.options.paper.max_deviation_deg + 1e-6;
  if (r.max_axis_change_deg > allowed) {
    add_finding(res, FindingCode::DeviationExceeded, k, 0,
                "operation " + op.name + ": an output axis is " +
                    std::to_string(r.max_axis_change_deg) + " deg from its input axis, more than " +
                    run.options.name_of("max_deviation_deg"));
  }
}

/// The contacts' rows, and the C-space rows where asked.
void contact_rows(const Run& run, const OperationContext& o, detail::StageProgress& checking,
                  OperationResult& r) {
  const Operationd& op = *o.op;
  const JobOptions& options = run.options;
  if (!o.contacts.empty()) {
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      detail::look_at_stop(&options.stop, i, detail::kPointStride);
      const ContactPoint& c = o.contacts[i];
      if (c.state != ContactState::Touching) continue;
      PointRow& row = r.rows[i];
      row.has_contact = true;
      row.cc_mm = c.surface_cc_mm;
      row.normal = c.surface_normal;
      row.tilt_deg = rad_to_deg(c.tilt_rad);
      row.yaw_deg = rad_to_deg(c.yaw_rad);
      row.gap_mm = c.gap_mm;
      row.place = c.place;
      row.normal_uncertainty_deg = rad_to_deg(c.normal_uncertainty_rad);
    }
    if ((options.count_free_cells || options.cspace_maps) && run.checker &&
        o.ball_radius_mm > 0.0) {
      cspace_rows(run, o, checking, r);
    }
  }
}

/// A longer cycle is worth a warning above 0.1 % and 10 ms (below that it is rounding and the
/// schedule's own resolution: a run saw warnings for 2e-7 s); it names what grew.
void longer_cycle_finding(const Machine& machine, const OperationContext& o,
                          const OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const double grew_s = r.feed_after.cycle_time_s - r.feed_before.cycle_time_s;
  if (o.optimised && grew_s > std::max(0.01, 1e-3 * r.feed_before.cycle_time_s)) {
    const auto part = [](const char* what, double before, double after) {
      std::ostringstream os;
      os.precision(3);
      os << std::fixed << what << (*what ? " " : "") << before << " -> " << after << " s";
      return os.str();
    };
    std::string grew;
    const auto add = [&grew](const std::string& p) { grew += (grew.empty() ? "" : ", ") + p; };
    if (r.feed_after.feed_time_s > r.feed_before.feed_time_s + 1e-3) {
      add(part("feed moves", r.feed_before.feed_time_s, r.feed_after.feed_time_s) +
          (machine.gcode.feed_reference == FeedReference::Tip
               ? " (feed_reference \"tip\": the programmed feed applies to the new tips' path, " +
                     std::to_string(r.feed_after.feed_path_mm) + " mm against " +
                     std::to_string(r.feed_before.feed_path_mm) + " mm)"
               : std::string(" (the machine's limits hold the new axes back more; limiting "
                             "axis ") +
                     (r.feed_after.limiting_axis.empty() ? "none" : r.feed_after.limiting_axis) +
                     ")"));
    }
    if (r.feed_after.rapid_time_s > r.feed_before.rapid_time_s + 1e-3) {
      add(part("rapids", r.feed_before.rapid_time_s, r.feed_after.rapid_time_s) +
          (r.feed_after.transition_excess_s > r.feed_before.transition_excess_s + 1e-3
               ? " (of which the table's turns between passes " +
                     part("", r.feed_before.transition_excess_s, r.feed_after.transition_excess_s) +
                     ")"
               : std::string()));
    }
    std::ostringstream total;
    total.precision(3);
    total << std::fixed << r.feed_after.cycle_time_s << " s against the input's "
          << r.feed_before.cycle_time_s << " s";
    add_finding(res, FindingCode::LongerCycle, k, 0,
                "operation " + op.name + ": at the machine's limits the new axes take " +
                    total.str() + ": " + grew);
  }
}

/// Read back: the A/C values actually written, and what they mean in the workpiece; each
/// point's row. Rapids an index move passed over (GcodeProgram::passed_over): no block reaches
/// them, so nothing of theirs is read back to check; their rows and axes are the plan's (the
/// rates run over feed passes, which start at the point the move came down to).
WrittenAxes read_back_points(const Run& run, const OperationContext& o, const PostedOperation& po,
                             const Written& w, OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const std::size_t n = op.points.size();
  WrittenAxes ax;
  ax.a_w.resize(n);
  ax.c_w.resize(n);
  ax.xyz_w.resize(n);
  ax.a_in.resize(n);
  ax.c_in.resize(n);
  r.rows.resize(n);
  std::vector<char> passed(n, 0);
  if (k < res.gcode.passed_over.size()) {
    for (const std::size_t i : res.gcode.passed_over[k]) passed[i] = 1;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!passed[i]) {
      check_point_written(run, o, po, w.point_moves[k][i], i, ax, r, res);
      continue;
    }
    const int decimals = run.machine.gcode.decimals;
    ax.a_w[i] = round_to(rad_to_deg(po.poses[i].tilt_rad), decimals);
    ax.c_w[i] = round_to(rad_to_deg(po.poses[i].c_rad), decimals);
    ax.xyz_w[i] = written_xyz_mm(run.machine, po.points[i].tip_mm, po.poses[i]);
    set_point_row(po.points[i], i, ax, r.rows[i]);
  }
  return ax;
}

/// The rates as the machine runs the program: each move at the time the controller gives the
/// words written (Written::time_into_after), the input's likewise; the paper's eq. 16-18 over
/// the contacts beside them, for the paper's comparison, on the exact contacts and on the
/// facets'.
void rates(const OperationContext& o, const Written& w, const WrittenAxes& ax, OperationResult& r) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  r.before = summarise_timed(op, ax.a_in, ax.c_in, w.time_into_before[k], &r.rows, true);
  r.paper_before =
      summarise_paper(op, o.contacts, o.ball_radius_mm, ax.a_in, ax.c_in, o.metric_feed_mm_per_min);
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    r.rows[i].tilt_axis_before_deg = ax.a_in[i];
    r.rows[i].c_before_deg = ax.c_in[i];
  }
  if (o.optimised) {
    for (std::size_t i : o.optimised->keys) r.rows[i].key = true;
  }
  r.after = summarise_timed(op, ax.a_w, ax.c_w, w.time_into_after[k], &r.rows);
  r.paper_after = summarise_paper(op, o.contacts, o.ball_radius_mm, ax.a_w, ax.c_w,
                                  o.metric_feed_mm_per_min, &r.rows);
  r.paper_before_facets = summarise_paper(op, o.contacts, o.ball_radius_mm, ax.a_in, ax.c_in,
                                          o.metric_feed_mm_per_min, nullptr, true);
  r.paper_after_facets = summarise_paper(op, o.contacts, o.ball_radius_mm, ax.a_w, ax.c_w,
                                         o.metric_feed_mm_per_min, nullptr, true);
  r.paper_gain_claimed =
      r.paper_after.max_accel_deg_s2 < r.paper_before.max_accel_deg_s2 &&
      r.paper_after_facets.max_accel_deg_s2 < r.paper_before_facets.max_accel_deg_s2;
}

/// A rotary axis whose peak omega or a the method raised above the input's, said with its axis
/// and why: the guards hold every pass whose input is free to the input's peaks per axis, so a
/// rise is where the input's own axes hit the part (the method's avoid it) or no pose of the
/// input's could be planned.
void axis_rise_finding(const Run& run, const OperationContext& o, const OperationResult& r,
                       JobResult& res) {
  std::string rose;
  const auto check = [&](char letter, const char* rate, double before, double after) {
    const double still = std::string(rate) == "omega" ? kStillOmegaDegS : kStillAccelDegS2;
    if (!(after > std::max(before * (1.0 + kRiseShare), still))) return;
    std::ostringstream os;
    os << (rose.empty() ? "" : ", ") << letter << "'s peak " << rate << " " << before << " -> "
       << after;
    rose += os.str();
  };
  const char tilt = run.machine.rotary.tilt_letter();
  check(tilt, "omega", r.before.tilt.max_omega_deg_s, r.after.tilt.max_omega_deg_s);
  check(tilt, "a", r.before.tilt.max_accel_deg_s2, r.after.tilt.max_accel_deg_s2);
  check('C', "omega", r.before.c.max_omega_deg_s, r.after.c.max_omega_deg_s);
  check('C', "a", r.before.c.max_accel_deg_s2, r.after.c.max_accel_deg_s2);
  if (rose.empty()) return;
  const std::string why =
      r.colliding_before && *r.colliding_before > 0
          ? "the input's axes hit the part at " + std::to_string(*r.colliding_before) +
                " points, and the method's axes that avoid it turn faster there"
          : "no pass's input was both free and posable for the guard to hold it to";
  add_finding(res, FindingCode::AxisRateRose, o.index, 0,
              "operation " + o.op->name + ": " + rose + " (deg/s, deg/s^2): " + why);
}

/// One operation verified as written.
OperationResult verify_operation(const Run& run, const OperationContext& o,
                                 const PostedOperation& po, const Written& w, std::size_t n_posted,
                                 detail::StageProgress& checking, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const Machine& machine = run.machine;
  const auto t_verify = Clock::now();
  OperationResult r;
  r.name = op.name;
  r.points = op.points.size();
  r.time_post_s = o.post_s + w.write_s / static_cast<double>(n_posted);
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    if (op.points[i].motion == Motion::Feed) {
      r.feed_mm_min = o.metric_feed_mm_per_min[i];
      break;
    }
  }
  WrittenAxes ax = read_back_points(run, o, po, w, r, res);
  check_round_trip(run, o, po, r, res);
  check_turns_in_cut(run, o, ax, res);
  r.contact = o.contact;
  r.time_contacts_s = o.contacts_s;
  r.time_optimise_s = o.optimise_s;
  if (o.optimised) kept_points(run, o, po, r, res);
  if (run.collision && r.contact.recovered) {
    check_collisions(run, o, po, w, ax.xyz_w, ax.a_w, ax.c_w, checking, r, res);
  } else if (run.collision && !(o.ball_radius_mm > 0.0) && op.tool.from_file &&
             op.tool.diameter_mm > 0.0) {
    check_shank_and_holder(run, o, po, w, ax.xyz_w, ax.a_w, ax.c_w, r, res);
  }
  if (!r.verification.collision_free) {
    for (PointRow& row : r.rows) row.mark(PointMark::NotChecked);
  }
  contact_rows(run, o, checking, r);
  cutting_conditions(o, po, r, run.options.stop);
  rates(o, w, ax, r);
  r.worst_axis = worst_axis_share(r.before, r.after, machine);
  if (o.optimised) axis_rise_finding(run, o, r, res);
  r.feed_after = w.schedule_after[k].summary;
  r.feed_before = w.schedule_before[k].summary;
  longer_cycle_finding(machine, o, r, res);
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    r.rows[i].feed_mm_min = w.schedule_after[k].feed_mm_min[i];
    r.rows[i].feed_before_mm_min = w.schedule_before[k].feed_mm_min[i];
  }
  r.feed_words = written_feed_words(op, po, w.point_moves[k], res.gcode_units, machine);
  checking.check();
  check_dynamic_limits(run, k, po, w.point_moves[k], w.moves, r, res);
  // The checks' own time: this operation's verification without its C-space raster.
  r.time_verify_s = std::max(0.0, seconds_since(t_verify) - r.time_cspace_s);
  return r;
}

}  // namespace

void verify_operations(const Run& run, const std::vector<OperationContext>& ops,
                       const std::vector<PostedOperation>& posted, const Written& written,
                       JobResult& res) {
  const JobOptions& options = run.options;
  // Progress of the checks: per point, its pose before and after and the move into it, and
  // its C-space cells.
  const bool rasters = (options.count_free_cells || options.cspace_maps) && run.checker;
  std::size_t check_items = 0;
  for (const OperationContext& o : ops) {
    const std::size_t n = o.op->points.size();
    if (run.collision && o.contact.recovered) check_items += 4 * n;
    if (rasters && !o.contacts.empty()) check_items += n;
  }
  detail::StageProgress checking(options.progress, "verification", check_items, options.stop);
  std::vector<Operationd> out_ops = run.tp.operations;
  for (std::size_t k = 0; k < posted.size(); ++k) {
    res.operations.push_back(
        verify_operation(run, ops[k], posted[k], written, posted.size(), checking, res));
    for (std::size_t i = 0; i < posted[k].points.size(); ++i) {
      out_ops[k].points[i].axis = posted[k].points[i].axis;
      out_ops[k].points[i].tip_mm = posted[k].points[i].tip_mm;
    }
  }
  // Every block the program holds swept against the part, then the program as a whole (a
  // point's own finding names its CL line first); beside them the new CL file.
  std::string out_cls;
  detail::parallel_invoke(
      [&] {
        check_every_block(run, ops, posted, written, res);
        check_program(run, posted, written, res);
      },
      [&] { out_cls = cl::format_cl(run.tp, out_ops, &options.stop); });
  res.out_cls = std::move(out_cls);
}

}  // namespace taxopt::pipeline
