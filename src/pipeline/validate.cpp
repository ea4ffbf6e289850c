// The first stages: the options checked, the contexts of the operations, their contacts and
// the part's collision models (stages.hpp).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "geometry/contact_progress.hpp"
#include "pipeline/stages.hpp"
#include "taxopt/core/error.hpp"
#include "util/parallel.hpp"

namespace taxopt {

JobOptions resolved_options(const JobOptions& given, const Machine& machine) {
  JobOptions options = given;
  // The deviation cone: as given; without a part to check the axes against, no wider than a
  // controller's own orientation tolerance unless asked for.
  if (given.max_deviation_deg) {
    options.paper.max_deviation_deg = *given.max_deviation_deg;
  } else if (!given.part) {
    options.paper.max_deviation_deg =
        std::min(options.paper.max_deviation_deg, kNoPartMaxDeviationDeg);
  }
  // The machine's usual holder where the options name none.
  ToolOverrides& tool = options.tool;
  if (!tool.holder_radius_mm && machine.holder_radius_mm) {
    tool.holder_radius_mm = machine.holder_radius_mm;
    if (!tool.holder_length_mm) tool.holder_length_mm = machine.holder_length_mm;
    if (!tool.gauge_length_mm) tool.gauge_length_mm = machine.holder_gauge_length_mm;
  }
  options.shank_clearance_mm = given.shank_clearance_mm.value_or(
      machine.shank_clearance_mm.value_or(kDefaultShankClearanceMm));
  options.holder_clearance_mm = given.holder_clearance_mm.value_or(
      machine.holder_clearance_mm.value_or(kDefaultHolderClearanceMm));
  return options;
}

void check_options(const JobOptions& o) {
  const auto refuse = [&o](const std::string& field, const std::string& expected, double v) {
    throw InputError(o.name_of(field) + " must be " + expected + ", got " + pipeline::shown(v),
                     ErrorPlace{std::nullopt, std::nullopt, "JobOptions::" + field});
  };
  // `range` is the interval as the docs write it: "[0.01, 1e6] mm/min" (open below with "(").
  const auto within = [&](const std::string& field, const std::optional<double>& v, double lo,
                          double hi, const std::string& range) {
    if (!v) return;
    const bool open_low = range[0] == '(';
    if (open_low ? (*v > lo && *v <= hi) : (*v >= lo && *v <= hi)) return;
    refuse(field, "within " + range, *v);
  };
  if (!(o.global.jerk_weight_s2 >= 0.0) || !std::isfinite(o.global.jerk_weight_s2)) {
    refuse("global.jerk_weight_s2", "a number >= 0 (s^2)", o.global.jerk_weight_s2);
  }
  // One cone per run: plan_pass_global's own field serves callers of the optimiser alone;
  // run_job sets it from the run's, so a value given there would silently not apply.
  if (o.global.max_deviation_deg != GlobalOptions{}.max_deviation_deg) {
    throw InputError(
        "JobOptions::global.max_deviation_deg is not read by run_job: the run's deviation cone "
        "is " +
        o.name_of("max_deviation_deg") + " (empty: paper.max_deviation_deg); set that one");
  }
  within("max_deviation_deg", o.max_deviation_deg, 0.0, 90.0, "[0, 90] deg");
  within("paper.max_deviation_deg", o.paper.max_deviation_deg, 0.0, 90.0, "[0, 90] deg");
  // Below 0.1 deg the cap grids and C-space windows outgrow any memory budget (a 30 deg cone
  // at 0.1 deg is 300 x 300 cells a point) and their counts overflow an int.
  within("paper.grid_deg", o.paper.grid_deg, 0.1, 10.0, "[0.1, 10] deg");
  // A feed the G-code can write and a machine can run (as the CL reader's FEDRAT).
  within("feed_mm_per_min", o.feed_mm_per_min, 0.01, 1e6, "[0.01, 1e6] mm/min");
  within("default_feed_mm_per_min", o.default_feed_mm_per_min, 0.01, 1e6, "[0.01, 1e6] mm/min");
  // Beyond a millimetre a contact is no contact: the gouge and flute checks would be off.
  if (o.contact.tolerance_mm != 0.0) {
    within("contact.tolerance_mm", o.contact.tolerance_mm, 0.0, 1.0, "(0, 1] mm (0: the default)");
  }
  // A part tolerance that is still one (1 mm), clearances a machine keeps (50 mm is more than
  // any holder's): larger values turn the checks off or make them hang.
  within("part_tolerance_mm", o.part_tolerance_mm, 0.0, 1.0, "[0, 1] mm");
  // Beyond 60 deg off the normal a ball-end mill cuts with its side.
  within("min_tilt_deg", o.min_tilt_deg, 0.0, 60.0, "[0, 60] deg");
  if (o.work_offset_mm) {
    // A work offset within a hundred metres of the machine's zero (a longer one is a typo).
    for (int q = 0; q < 3; ++q) {
      within("work_offset_mm", std::optional<double>((*o.work_offset_mm)[q]), -1e5, 1e5,
             "[-1e5, 1e5] mm in each of X, Y, Z");
    }
  }
  within("shank_clearance_mm", o.shank_clearance_mm, 0.0, 50.0, "[0, 50] mm");
  within("holder_clearance_mm", o.holder_clearance_mm, 0.0, 50.0, "[0, 50] mm");
  // A tool is no larger than a metre: larger dimensions make the checks hang.
  const ToolOverrides& tool = o.tool;
  for (const auto& [field, v] : {std::make_pair("tool.ball_radius_mm", tool.ball_radius_mm),
                                 std::make_pair("tool.shank_radius_mm", tool.shank_radius_mm),
                                 std::make_pair("tool.flute_length_mm", tool.flute_length_mm),
                                 std::make_pair("tool.holder_radius_mm", tool.holder_radius_mm),
                                 std::make_pair("tool.holder_length_mm", tool.holder_length_mm),
                                 std::make_pair("tool.gauge_length_mm", tool.gauge_length_mm)}) {
    within(field, v, 0.0, 1000.0, "(0, 1000] mm");
  }
  within("spindle_rpm", o.spindle_rpm, 1.0, 2e5, "[1, 200000] rpm");
  if (o.tool_number && !(*o.tool_number >= 1 && *o.tool_number <= 99999)) {
    refuse("tool_number", "within [1, 99999]", *o.tool_number);
  }
  if (o.threads > 1024) {
    refuse("threads", "within [0, 1024] (0: all cores)", static_cast<double>(o.threads));
  }
}

}  // namespace taxopt

namespace taxopt::pipeline {
namespace {

/// An operation's tool as the CL reader makes one (a tool built in code has not been read): every
/// size finite, none negative, within the tool options' bound (1000 mm), the corner radius at
/// most half the diameter, and a tool said to be described (from_file) with a diameter. A
/// negative diameter was taken as "no tool geometry" and the job ran unchecked.
void check_tool(const Toolpath& tp, std::size_t k) {
  const Operationd& op = tp.operations[k];
  const Tool& t = op.tool;
  const auto refuse = [&](const std::string& field, const std::string& what) {
    throw InputError(tp.source, op.points.empty() ? 0 : op.points.front().line,
                     "operation " + op.name + ": " + field + " " + what,
                     ErrorPlace{k, std::nullopt, field});
  };
  for (const auto& [field, v] : {std::make_pair("diameter_mm", t.diameter_mm),
                                 std::make_pair("corner_radius_mm", t.corner_radius_mm),
                                 std::make_pair("flute_length_mm", t.flute_length_mm),
                                 std::make_pair("gauge_length_mm", t.gauge_length_mm)}) {
    if (!(v >= 0.0 && v <= 1000.0)) {
      refuse(std::string("Operation::tool.") + field, shown(v) + ", expected within [0, 1000] mm");
    }
  }
  if (!(t.taper_rad >= 0.0 && t.taper_rad < deg_to_rad(90.0))) {
    refuse("Operation::tool.taper_rad", shown(t.taper_rad) + ", expected within [0, pi/2)");
  }
  if (t.from_file && !(t.diameter_mm > 0.0)) {
    refuse("Operation::tool.from_file",
           "says the tool is described, and its diameter_mm is " + shown(t.diameter_mm) +
               " (set the diameter, or from_file false for no geometry)");
  }
  if (t.corner_radius_mm > 0.5 * t.diameter_mm * (1.0 + 1e-6)) {
    refuse("Operation::tool.corner_radius_mm",
           shown(t.corner_radius_mm) + " exceeds half the diameter " + shown(t.diameter_mm));
  }
}

/// Every point as the CL reader makes them (a toolpath built in code has not been read): a
/// finite tip within reach, a unit axis (as the reader normalises it: a point taxopt changed
/// silently would be posted where the caller did not put it), a finite feed >= 0.
void check_points(const Toolpath& tp) {
  if (point_count(tp) == 0) {
    throw InputError(tp.source, 0, "no CL point in any operation: there is nothing to post");
  }
  for (std::size_t k = 0; k < tp.operations.size(); ++k) {
    const Operationd& op = tp.operations[k];
    check_tool(tp, k);
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      const CLPointd& p = op.points[i];
      std::string field = "CLPoint::tip_mm";
      const auto refuse = [&](const std::string& what) {
        std::ostringstream os;
        os << "operation " << op.name << ", point " << i << ": " << what;
        throw InputError(tp.source, p.line, os.str(), ErrorPlace{k, i, field});
      };
      if (!p.tip_mm.allFinite() || p.tip_mm.cwiseAbs().maxCoeff() > kMaxCoordinateMm) {
        std::ostringstream os;
        os << "tip (" << p.tip_mm.x() << ", " << p.tip_mm.y() << ", " << p.tip_mm.z()
           << ") mm is not a finite point within +-1e6 mm";
        refuse(os.str());
      }
      const double length = p.axis.norm();
      field = "CLPoint::axis";
      if (!std::isfinite(length) || std::abs(length - 1.0) > 1e-9) {
        std::ostringstream os;
        // Digits enough to show how far off unit it is (issue 64.3: "has length 1" for 1+1e-7).
        os.precision(12);
        os << "tool axis (" << p.axis.x() << ", " << p.axis.y() << ", " << p.axis.z()
           << ") has length " << length
           << ", expected a unit vector (normalise it; within 1e-6 of unit, float round-off, it "
              "is normalised)";
        refuse(os.str());
      }
      field = "CLPoint::feed_mm_per_min";
      if (!(p.feed_mm_per_min >= 0.0 && p.feed_mm_per_min <= 1e6)) {
        refuse("feed " + shown(p.feed_mm_per_min) +
               " mm/min, expected within [0, 1e6] (0: none given)");
      }
    }
  }
}

}  // namespace

namespace {

/// The part tolerance is its own number: where --contact-tolerance is given and the part
/// tolerance is not, say what the flutes are held to (the tolerance the contact tolerance would
/// have been, not the one given), so that nobody reads a contact tolerance as a gouge budget.
void part_tolerance_note(const Toolpath& tp, const JobOptions& given, JobResult& res) {
  if (!given.part || given.part_tolerance_mm || !(given.contact.tolerance_mm > 0.0)) return;
  // Said once, for the first operation it concerns (the others differ only by the CL file's
  // tolerance band, which the report's tool and checks give per operation).
  for (std::size_t k = 0; k < tp.operations.size(); ++k) {
    const Operationd& op = tp.operations[k];
    const double part_mm = part_tolerance_mm(given, op);
    if (part_mm >= given.contact.tolerance_mm) continue;
    add_finding(res, FindingCode::PartTolerance, std::nullopt, 0,
                "the part tolerance stays " + shown(part_mm) + " mm (" +
                    part_tolerance_source(given, op) + "; operation " + op.name +
                    "), not the contact tolerance " + shown(given.contact.tolerance_mm) +
                    " mm given (" + given.name_of("contact.tolerance_mm") +
                    "): no part of the tool but the ball may reach deeper into the part; " +
                    given.name_of("part_tolerance_mm") + " sets it");
    return;
  }
}

/// What the run leaves unchecked or unwritten by the machine's and the part's set-up: no part,
/// no holder model, slivers dropped from the mesh, no safe retract, no coolant, no
/// linearisation; and the CL file's own notes.
void setup_findings(const Toolpath& tp, const Machine& machine, const JobOptions& given,
                    const JobOptions& options, JobResult& res) {
  if (!given.part) {
    std::ostringstream os;
    const auto name = [&given](const char* field) { return given.name_of(field); };
    os << "no part (" << name("part") << "): the tool and holder are not checked against the part";
    if (given.method != Method::None) {
      os << "; each tool axis stays within " << options.paper.max_deviation_deg
         << " deg of its input";
      if (given.max_deviation_deg && *given.max_deviation_deg > kNoPartMaxDeviationDeg) {
        os << " as " << name("max_deviation_deg") << " asks, unchecked: give " << name("part")
           << " to check it";
      } else {
        os << " (" << name("max_deviation_deg") << " widens it, unchecked)";
      }
    }
    add_finding(res, FindingCode::NoPart, std::nullopt, 0, os.str());
  } else if (!options.tool.holder_radius_mm) {
    add_finding(res, FindingCode::NoHolderModel, std::nullopt, 0,
                "no holder model (" + given.name_of("tool.holder_radius_mm") + ", " +
                    given.name_of("tool.holder_length_mm") +
                    "): the holder is not checked against the part, only the tool");
  }
  part_tolerance_note(tp, given, res);
  if (given.part && given.part->mesh().dropped_degenerate_faces > 0) {
    const TriangleMesh& m = given.part->mesh();
    std::ostringstream os;
    os << "part mesh: " << m.dropped_degenerate_faces
       << " zero-area faces (slivers) dropped, the first at (" << m.first_degenerate_mm.x() << ", "
       << m.first_degenerate_mm.y() << ", " << m.first_degenerate_mm.z()
       << ") in the mesh file's coordinates: they cover no surface, so the part's shape is "
          "whole";
    add_finding(res, FindingCode::MeshSlivers, std::nullopt, 0, os.str());
  }
  const bool travel = std::any_of(machine.linear_range.begin(), machine.linear_range.end(),
                                  [](const Machine::LinearRange& r) { return r.bounded(); });
  if (travel && !machine.work_offset_mm) {
    add_finding(res, FindingCode::NoWorkOffset, std::nullopt, 0,
                "no work offset (" + given.name_of("work_offset_mm") + ", " +
                    option_name(given.option_names, "Machine::work_offset_mm") +
                    "): where the program's zero "
                    "sits in machine coordinates is not known, so only the program's span is "
                    "held to the machine's travel");
  }
  if (machine.gcode.program.retract == SafeRetract::None) {
    add_finding(res, FindingCode::NoSafeRetract, std::nullopt, 0,
                option_name(given.option_names, "Machine::gcode.program.retract") +
                    " is none: no retract before an operation's "
                    "first move nor after the last, and the table turns where the tool stands");
  }
  {
    // Coolant: where neither the CL file (COOLNT) nor the machine file (gcode.coolant) asks for
    // any, the program runs dry; said, not assumed (a real NX program's post wrote M8, taxopt
    // nothing, silently).
    bool asked = machine.gcode.program.coolant != Coolant::None;
    for (const Operationd& op : tp.operations) {
      asked = asked || op.coolant.has_value();
      for (const ProgramEvent& e : op.events) {
        asked = asked || e.kind == ProgramEvent::Kind::Coolant;
      }
    }
    if (!asked && !tp.operations.empty()) {
      add_finding(res, FindingCode::NoCoolant, std::nullopt, 0,
                  "no coolant: neither the CL file (COOLNT) nor " +
                      option_name(given.option_names, "Machine::gcode.program.coolant") +
                      " asks for any, so the program turns none on");
    }
  }
  if (machine.gcode.mode == GcodeMode::Machine &&
      !(machine.gcode.program.linearise_tolerance_mm > 0.0)) {
    add_finding(
        res, FindingCode::NoLinearisation, std::nullopt, 0,
        option_name(given.option_names, "Machine::gcode.program.linearise_tolerance_mm") +
            " is 0: the tip leaves the straight line "
            "between points where the table turns (the moves are checked as the joints run)");
  }
  for (const std::string& w : tp.warnings) {
    add_finding(res, FindingCode::ClFileNote, std::nullopt, 0, w);
  }
}

/// The tool and the spindle speed: the CL file's, else the options', else the machine file's
/// [defaults]; never guessed (tests/test_program.cpp: a program that feeds with the spindle
/// off). An operation that needs one and has none is refused, naming the option.
void tool_and_spindle_fallbacks(const Run& run, JobResult& res) {
  const Toolpath& tp = run.tp;
  // Each named as the caller names it (JobOptions::option_names): the CLI's "--tool-number"
  // and "the machine file's [defaults] tool_number", a library's own field otherwise.
  const auto source_of = [&](bool option, const char* field) {
    return option ? run.options.name_of(field)
                  : option_name(run.options.option_names, std::string("Machine::default_") + field);
  };
  for (std::size_t k = 0; k < tp.operations.size(); ++k) {
    const Operationd& op = tp.operations[k];
    const int line = op.points.empty() ? 0 : op.points.front().line;
    if (op.tool.number <= 0) {
      if (!run.fallback_tool) {
        throw InputError(tp.source, line,
                         "operation " + op.name +
                             ": the CL file calls no tool (no LOADTL or TOOL number): give " +
                             run.options.name_of("tool_number") + ", or " +
                             source_of(false, "tool_number"));
      }
      add_finding(res, FindingCode::ClFileNote, k, line,
                  "operation " + op.name + ": no tool number in the CL file: T" +
                      std::to_string(*run.fallback_tool) + " from " +
                      source_of(run.options.tool_number.has_value(), "tool_number"));
    }
    const std::optional<std::size_t> first_feed = needs_spindle_speed(op);
    if (!first_feed) continue;
    if (!run.fallback_spindle_rpm) {
      throw InputError(tp.source, op.points[*first_feed].line,
                       "operation " + op.name +
                           ": feed moves without a spindle speed (no SPINDL before them, or "
                           "the spindle off: SPINDL/OFF or a speed of 0): give " +
                           run.options.name_of("spindle_rpm") + ", or " +
                           source_of(false, "spindle_rpm"));
    }
    add_finding(res, FindingCode::ClFileNote, k, op.points[*first_feed].line,
                "operation " + op.name + ": no spindle speed in the CL file: S" +
                    shown(*run.fallback_spindle_rpm) + " from " +
                    source_of(run.options.spindle_rpm.has_value(), "spindle_rpm"));
  }
}

}  // namespace

Run validate(const Toolpath& tp, const Machine& machine, const JobOptions& given, JobResult& res) {
  // The options were checked where the job entered the library (in_job_arena).
  taxopt::validate(machine);
  check_points(tp);
  JobOptions options = resolved_options(given, machine);
  res.collision_checked = given.part != nullptr;
  res.tilt_letter = machine.rotary.tilt_letter();
  setup_findings(tp, machine, given, options, res);
  res.gcode_units = options.units_out.value_or(tp.units);
  const double fallback = options.feed_mm_per_min.value_or(options.default_feed_mm_per_min);
  Run run{tp, machine, std::move(options), fallback, std::nullopt, std::nullopt};
  run.fallback_tool =
      run.options.tool_number ? run.options.tool_number : machine.default_tool_number;
  run.fallback_spindle_rpm =
      run.options.spindle_rpm ? run.options.spindle_rpm : machine.default_spindle_rpm;
  tool_and_spindle_fallbacks(run, res);
  return run;
}

std::optional<std::size_t> needs_spindle_speed(const Operationd& op) {
  std::size_t first_feed = op.points.size();
  for (std::size_t i = 0; i < op.points.size() && first_feed == op.points.size(); ++i) {
    if (op.points[i].motion == Motion::Feed) first_feed = i;
  }
  if (first_feed == op.points.size() || op.spindle_rpm > 0.0) return std::nullopt;
  for (const ProgramEvent& e : op.events) {
    if (e.kind == ProgramEvent::Kind::Spindle && e.spindle_rpm > 0.0 &&
        e.before_point <= first_feed) {
      return std::nullopt;
    }
  }
  return first_feed;
}

std::vector<OperationContext> operation_contexts(const Run& run) {
  std::vector<OperationContext> ops(run.tp.operations.size());
  for (std::size_t k = 0; k < ops.size(); ++k) {
    OperationContext& o = ops[k];
    o.index = k;
    o.op = &run.tp.operations[k];
    o.ball_radius_mm = ball_radius_mm(*o.op, run.options);
    o.metric_feed_mm_per_min = metric_feeds_of(*o.op, run.options, run.fallback_feed_mm_per_min);
  }
  return ops;
}

namespace {

/// An operation that is no ball-end mill: what is not checked of it.
void not_a_ball_findings(const Run& run, const OperationContext& o, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  if (!(op.tool.from_file && op.tool.diameter_mm > 0.0)) {
    // Said as what was not checked (the program's header, stderr's NOT CHECKED lines): the
    // run was "ok" with every point not checked, and only the holder named.
    add_finding(res, FindingCode::NoToolModel, k, op.points.empty() ? 0 : op.points.front().line,
                "operation " + op.name +
                    " has no tool geometry (no TLDATA or CUTTER, or not a mill): none of its "
                    "moves is checked against the part (" +
                    run.options.name_of("tool.ball_radius_mm") + " gives it a ball)");
  }
  add_finding(res, FindingCode::NotABallMill, k, op.points.empty() ? 0 : op.points.front().line,
              not_a_ball(op, run.options) +
                  (op.tool.from_file && op.tool.diameter_mm > 0.0
                       ? ", no contact recovery: its flutes are not checked against the part, "
                         "its shank and holder are"
                       : ", no contact recovery and no collision check"));
}

/// The box of points, mm.
Eigen::AlignedBox3d box_of(const std::vector<Vec3d>& points) {
  Eigen::AlignedBox3d box;
  for (const Vec3d& p : points) box.extend(p);
  return box;
}

/// Whether the part's box scaled by `scale` about the origin holds the feed points' box (with
/// `margin_mm`) and is no more than three times its size: the part in other units.
bool fits_scaled(const Eigen::AlignedBox3d& part, const Eigen::AlignedBox3d& path, double scale,
                 double margin_mm) {
  Eigen::AlignedBox3d scaled(part.min() * scale, part.max() * scale);
  const double size = scaled.diagonal().norm();
  scaled.min().array() -= margin_mm;
  scaled.max().array() += margin_mm;
  return scaled.contains(path) && size <= 3.0 * path.diagonal().norm();
}

/// A finishing operation touches the part along its passes: one whose feed points touch it at
/// fewer than one in ten, most of them farther than the ball's diameter from it, was made for
/// another part, or the part is in other units (a plane's mesh in inches read as mm: 9 of
/// 1,350 points touched, the rest up to 76 mm off, and the run passed). A floor left with stock
/// is not that (the Haas course job's ROTARY_FLOOR: 339 of 4,847 touch, none 1.04 mm off).
/// Refused, with the two extents and the units that would explain them where the part in the
/// other unit would hold the feed points.
void off_part_check(const Run& run, const OperationContext& o) {
  const Operationd& op = *o.op;
  std::size_t feed = 0, touching = 0, far = 0;
  std::vector<Vec3d> tips;
  double worst_mm = 0.0;
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    if (op.points[i].motion != Motion::Feed) continue;
    ++feed;
    tips.push_back(op.points[i].tip_mm);
    const ContactPoint& c = o.contacts[i];
    if (c.state == ContactState::Touching) ++touching;
    if (c.state != ContactState::InAir) continue;
    worst_mm = std::max(worst_mm, c.gap_mm);
    if (c.gap_mm > 2.0 * o.ball_radius_mm) ++far;
  }
  if (feed < 10 || 10 * touching >= feed || 2 * far <= feed) return;
  const Eigen::AlignedBox3d path = box_of(tips), part = box_of(run.options.part->mesh().vertices);
  const double margin_mm = 2.0 * o.ball_radius_mm + 1.0;
  std::string units = ": wrong part or wrong units?";
  const std::string option = option_name(run.options.option_names, "part_mesh_for::mesh_units");
  if (fits_scaled(part, path, 25.4, margin_mm)) {
    units = ": the part in inches read as mm? (" + option + " in reads it so)";
  } else if (fits_scaled(part, path, 1.0 / 25.4, margin_mm)) {
    units = ": the part in mm read as inches? (" + option + " mm reads it so)";
  }
  throw InputError(run.tp.source, op.points.front().line,
                   "operation " + op.name + ": " + std::to_string(touching) + " of " +
                       std::to_string(feed) + " feed points touch the part, the others up to " +
                       shown(worst_mm) + " mm off it; the part spans " +
                       shown(part.diagonal().norm()) + " mm, the feed points " +
                       shown(path.diagonal().norm()) + " mm" + units);
}

/// A ball cutting into the part at point i beyond the tolerance: refused, naming the point; as
/// a flipped axis where the ball on the axis turned round touches the part (an axis from tip
/// into the part, the ball then inside it, was reported as 0.051 mm of cut).
[[noreturn]] void gouge_error(const Run& run, const OperationContext& o, std::size_t i,
                              double tolerance_mm) {
  const Operationd& op = *o.op;
  const Part& part = *run.options.part;
  const CLPointd& p = op.points[i];
  const ContactPoint& c = o.contacts[i];
  // A flipped axis: the ball's centre lies inside the part (behind its nearest face) and the
  // ball on the axis turned round touches it from outside.
  const auto outside = [&](const Vec3d& centre, double* gap_mm) {
    const Part::Closest q = part.closest(centre);
    const auto& f = part.mesh().faces[static_cast<std::size_t>(q.face)];
    const auto& v = part.mesh().vertices;
    const Vec3d n = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]);
    if (gap_mm) *gap_mm = q.distance_mm - o.ball_radius_mm;
    return (centre - q.point).dot(n) > 0.0;
  };
  double flipped_gap_mm = 0.0;
  const bool flipped = !outside(Vec3d(p.tip_mm + o.ball_radius_mm * p.axis), nullptr) &&
                       outside(Vec3d(p.tip_mm - o.ball_radius_mm * p.axis), &flipped_gap_mm) &&
                       std::abs(flipped_gap_mm) <= tolerance_mm;
  const std::string at = "operation " + op.name + ", point " + std::to_string(i) + ": ";
  if (flipped) {
    std::ostringstream os;
    os << at << "the tool axis (" << p.axis.x() << ", " << p.axis.y() << ", " << p.axis.z()
       << ") points into the part: the ball on it cuts " << shown(-c.gap_mm)
       << " mm in, on the axis turned round it touches (a flipped axis: the axis runs from the "
          "tip to the spindle)";
    throw InputError(run.tp.source, p.line, os.str(), ErrorPlace{o.index, i, "CLPoint::axis"});
  }
  throw InputError(
      run.tp.source, p.line,
      at + "the ball cuts " + shown(-c.gap_mm) +
          " mm into the part, more than the contact tolerance " + shown(tolerance_mm) + " mm (" +
          contact_tolerance_source(part, run.options.contact, op.cam_tolerance_mm) + "; " +
          run.options.name_of("contact.tolerance_mm") + "); wrong part, wrong tool or wrong units?",
      ErrorPlace{o.index, i, "CLPoint::tip_mm"});
}

/// The contacts' summary; a ball cutting into the part beyond the contact tolerance, or an
/// operation that feeds and touches it nowhere, is refused (wrong part, tool or units).
void summarise_contacts(const Run& run, OperationContext& o) {
  const Operationd& op = *o.op;
  ContactSummary& cs = o.contact;
  bool any_feed = false;
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    const ContactPoint& c = o.contacts[i];
    any_feed = any_feed || op.points[i].motion == Motion::Feed;
    if (c.state == ContactState::Gouging) gouge_error(run, o, i, cs.tolerance_mm);
    if (c.state == ContactState::Touching) {
      ++cs.touching;
      cs.max_abs_gap_mm = std::max(cs.max_abs_gap_mm, std::abs(c.gap_mm));
      if (c.local_gouge) ++cs.local_gouges;
      if (c.place == SurfacePlace::Edge) ++cs.edge_points;
      if (c.place == SurfacePlace::Corner) ++cs.corner_points;
      cs.max_normal_uncertainty_deg =
          std::max(cs.max_normal_uncertainty_deg, rad_to_deg(c.normal_uncertainty_rad));
    } else {
      ++cs.in_air;
    }
  }
  if (any_feed && cs.touching == 0) {
    throw InputError(
        run.tp.source, op.points.front().line,
        "operation " + op.name + ": no CL point touches the part (wrong part or wrong units?)");
  }
  off_part_check(run, o);
}

/// Feed points off the part between points of their pass that touch it: the ball cuts air at
/// feed there -- a pass lifting over a gap, or points made for another part.
void feed_in_air_finding(const OperationContext& o, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  std::size_t feed_in_air = 0, worst = 0;
  for (const IndexRange& pass : feed_passes(op)) {
    std::size_t first = pass.end, last = pass.begin;
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      if (o.contacts[i].state != ContactState::Touching) continue;
      first = std::min(first, i);
      last = i;
    }
    for (std::size_t i = first + 1; i < last; ++i) {
      if (o.contacts[i].state != ContactState::InAir || op.points[i].motion != Motion::Feed)
        continue;
      if (!feed_in_air || o.contacts[i].gap_mm > o.contacts[worst].gap_mm) worst = i;
      ++feed_in_air;
    }
  }
  if (feed_in_air) {
    add_finding(
        res, FindingCode::FeedInAir, k, op.points[worst].line,
        "operation " + op.name + ": " + std::to_string(feed_in_air) +
            " feed points in the air between points of their pass that touch the part, "
            "the ball up to " +
            shown(o.contacts[worst].gap_mm) + " mm off it (point " + std::to_string(worst) +
            (op.points[worst].line > 0 ? ", CL line " + std::to_string(op.points[worst].line)
                                       : std::string()) +
            "): a pass lifting over a gap at feed, or points made for another part");
  }
}

/// The contacts of one ball-end operation and their summary.
void recover_operation(const Run& run, OperationContext& o, JobResult& res,
                       detail::StageProgress& progress) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const auto t0 = Clock::now();
  if (!(o.ball_radius_mm > 0.0)) {
    not_a_ball_findings(run, o, res);
    progress.advance(op.points.size());  // nothing to recover: its points are done
    return;
  }
  const Part& part = *run.options.part;
  o.contacts = detail::recover_contacts(part, op, o.ball_radius_mm, run.options.contact, &progress);
  ContactSummary& cs = o.contact;
  cs.recovered = true;
  cs.tolerance_mm = contact_tolerance_mm(part, run.options.contact, op.cam_tolerance_mm);
  summarise_contacts(run, o);
  feed_in_air_finding(o, res);
  if (cs.local_gouges) {
    add_finding(res, FindingCode::LocalGouge, k, 0,
                "operation " + op.name + ": " + std::to_string(cs.local_gouges) +
                    " contact points where a concave radius is below the ball radius "
                    "(local gouge, eq. 19)");
  }
  o.contacts_s = seconds_since(t0);
}

}  // namespace

void recover_contacts(Run& run, std::vector<OperationContext>& ops, JobResult& res) {
  if (!run.options.part) return;
  const auto recover_all = [&] {
    // Counted in points, each as it is done: a one-operation job's bar went from 0 to 1.
    std::size_t points = 0;
    for (const OperationContext& o : ops) points += o.op->points.size();
    detail::StageProgress progress(run.options.progress, "contact recovery", points,
                                   run.options.stop);
    for (OperationContext& o : ops) recover_operation(run, o, res, progress);
  };
  // FCL's model takes ~2 s at 800k triangles on one thread: built beside the contacts.
  detail::parallel_invoke(recover_all, [&] {
    // Each looks at the stop as it builds (FCL's and the rasteriser's trees are one call each,
    // up to 2 s at 800k triangles): a stop ends the job within milliseconds, not after them.
    detail::parallel_invoke(
        [&] { run.collision.emplace(run.options.part->mesh(), run.options.stop); },
        [&] { run.checker.emplace(run.options.part->mesh(), run.options.stop); });
  });
  for (OperationContext& o : ops) {
    if (!o.contact.recovered) continue;
    o.real_tool = ToolModel::ball_end(o.op->tool, run.options.tool);
    const ToolMargins margins = margins_of(run.options, *o.op);
    o.tool = o.real_tool->judged(margins);
    ToolMargins strict = margins;
    strict.flute_tolerance_mm = std::min(margins.flute_tolerance_mm, kInputDepthAllowanceMm);
    o.strict_tool = o.real_tool->judged(strict);
  }
}

}  // namespace taxopt::pipeline
