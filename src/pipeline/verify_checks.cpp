// The verification's checks of one operation as written (verify_checks.hpp).
#include "pipeline/verify_checks.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "pipeline/stages.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/kinematics/machine.hpp"
#include "taxopt/kinematics/metrics.hpp"
#include "util/parallel.hpp"
#include "util/parallel_select.hpp"

namespace taxopt::pipeline {

/// A guaranteed lower bound of the least distance between the part and the tool's bodies that
/// do not cut (shank and holder, past the flutes; the flutes touch the part at a contact by
/// design) over the CL points with axes `axes`, and the point where it occurs; empty when the
/// tool has no such bodies. The bodies grown by d in radius and at both ends hold every point
/// within d of them, so where the grown bodies miss the part the clearance is at least d (and
/// at most d sqrt 2). d comes from bisecting FCL collision queries (exact distances cost 5 ms to
/// 0.3 s a query on flat parts): at 32 spread points first, then only at the points whose
/// bodies, grown by that bound, touch the part. Capped at 10 mm, 5 um steps; the same result
/// whatever the thread count.
std::optional<std::pair<double, std::size_t>> clearance_bound(const CollisionModel& model,
                                                              const ToolModel& tool,
                                                              const Operationd& op,
                                                              const std::vector<Vec3d>& axes,
                                                              detail::StageProgress* progress) {
  constexpr double kCapMm = 10.0, kStepMm = 0.005;
  const std::size_t n = op.points.size();
  ToolModel above = tool;
  if (!above.bodies.empty()) above.bodies.erase(above.bodies.begin());
  if (above.bodies.empty() || n == 0) {
    if (progress) progress->advance(n);
    return std::nullopt;
  }
  const auto free_at = [&](std::size_t i, double d_mm) {
    ToolModel grown = above;
    for (ToolBody& b : grown.bodies) {
      b.radius_mm += d_mm;
      b.start_mm -= d_mm;
      b.end_mm += d_mm;
    }
    return !model.collides(grown, reference_point(op.points[i], tool.ball_radius_mm), axes[i]);
  };
  // The largest d in [0, hi] (to kStepMm) with the grown bodies free at point i.
  const auto bisect = [&](std::size_t i, double hi) {
    if (!free_at(i, 0.0)) return 0.0;
    if (free_at(i, hi)) return hi;
    double lo = 0.0;
    while (hi - lo > kStepMm) {
      const double mid = 0.5 * (lo + hi);
      (free_at(i, mid) ? lo : hi) = mid;
    }
    return lo;
  };
  using Least = std::pair<double, std::size_t>;
  const auto least_over = [&](const std::vector<std::size_t>& at, double hi) {
    return detail::parallel_reduce(
        0, at.size(), Least{hi, n},
        [&](std::size_t lo, std::size_t end, Least acc) {
          for (std::size_t j = lo; j != end; ++j) {
            if (progress) progress->check();  // a bisection is some 10 queries
            acc = std::min(acc, Least{bisect(at[j], hi), at[j]});
          }
          return acc;
        },
        [](const Least& a, const Least& b) { return std::min(a, b); });
  };
  std::vector<std::size_t> sample;
  for (std::size_t k = 0; k < 32; ++k) sample.push_back(k * (n - 1) / 31);
  sample.erase(std::unique(sample.begin(), sample.end()), sample.end());
  Least bound = least_over(sample, kCapMm);
  if (bound.second == n) bound.second = sample.front();  // every sample at the cap
  const std::vector<std::size_t> closer = detail::parallel_select(0, n, [&](std::size_t i) {
    const bool near = bound.first > 0.0 && !free_at(i, bound.first);
    if (progress) progress->advance();
    return near;
  });
  const Least found = least_over(closer, bound.first);
  return found.second == n ? bound : std::min(bound, found);
}

namespace {

/// A joint's worst rate and the point it belongs to.
struct Worst {
  double value = 0.0;
  std::size_t point = 0;
};
struct WorstRates {
  std::array<Worst, kJointCount> velocity{}, accel{}, jerk{};
};

/// The time of the written blocks into each feed point, s, from the F words read back (a
/// linearised move: its blocks, each at its own F).
std::vector<double> written_times_s(const PostedOperation& po,
                                    const std::vector<const GcodeMove*>& at,
                                    const std::vector<GcodeMove>& moves, LengthUnit units) {
  const std::size_t n = po.points.size();
  std::vector<double> written_s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) {
    if (po.points[i].motion != Motion::Feed || at[i] == at[i - 1]) continue;
    const std::ptrdiff_t from = move_index(moves, at[i - 1]), to = move_index(moves, at[i]);
    if (from >= 0 && to > from + 1) {
      for (std::ptrdiff_t j = from + 1; j <= to; ++j) {
        written_s[i] += block_time_s(moves[static_cast<std::size_t>(j - 1)],
                                     moves[static_cast<std::size_t>(j)], units);
      }
    } else {
      written_s[i] = block_time_s(*at[i - 1], *at[i], units);
    }
  }
  return written_s;
}

/// The joints' worst velocity, acceleration and jerk over the feed chains as written, each
/// chain from rest to rest: a linearised move is its blocks (machine mode), each at its own F
/// with its own joints, so that no block between the points is faster than the limits (a
/// machinist's review, tests/test_program.cpp); each rate belongs to its block's point.
WorstRates worst_rates(const PostedOperation& po, const std::vector<JointPosition>& joints,
                       const std::vector<const GcodeMove*>& at, const std::vector<GcodeMove>& moves,
                       LengthUnit units,
                       const std::function<JointPosition(const GcodeMove&)>& joint_of) {
  const std::vector<double> written_s = written_times_s(po, at, moves, units);
  WorstRates worst;
  for (const IndexRange& c : feed_chains(po.points)) {
    std::vector<JointPosition> q = {joints[c.begin - 1]};
    std::vector<double> t;
    std::vector<std::size_t> owner = {c.begin - 1};
    for (std::size_t i = c.begin; i < c.end; ++i) {
      const std::ptrdiff_t from = move_index(moves, at[i - 1]), to = move_index(moves, at[i]);
      if (at[i] != at[i - 1] && from >= 0 && to > from + 1) {
        for (std::ptrdiff_t j = from + 1; j <= to; ++j) {
          const GcodeMove& m = moves[static_cast<std::size_t>(j)];
          q.push_back(j == to ? joints[i] : joint_of(m));
          t.push_back(block_time_s(moves[static_cast<std::size_t>(j - 1)], m, units));
          owner.push_back(i);
        }
      } else {
        q.push_back(joints[i]);
        t.push_back(written_s[i]);
        owner.push_back(i);
      }
    }
    const JointRates jr = joint_rates(q, t);
    const auto keep = [](Worst& w, double v, std::size_t point) {
      if (v > w.value) w = Worst{v, point};
    };
    for (std::size_t j = 0; j < kJointCount; ++j) {
      keep(worst.velocity[j], jr.max_velocity_per_s[j],
           owner[std::min(owner.size() - 1, jr.velocity_at[j] + 1)]);
      keep(worst.accel[j], jr.max_accel_per_s2[j],
           owner[std::min(owner.size() - 1, jr.accel_at[j])]);
      keep(worst.jerk[j], jr.max_jerk_per_s3[j], owner[std::min(owner.size() - 1, jr.jerk_at[j])]);
    }
  }
  return worst;
}

}  // namespace

void check_dynamic_limits(const Run& run, std::size_t op_index, const PostedOperation& po,
                          const std::vector<const GcodeMove*>& at,
                          const std::vector<GcodeMove>& moves, OperationResult& r, JobResult& res) {
  const Machine& machine = run.machine;
  const JobOptions& options = run.options;
  const bool scheduled = options.feed_schedule;
  const JointLimits check = scheduled ? effective_limits(machine) : machine.limits;
  const std::string& source = run.tp.source;
  const char tilt_letter = machine.rotary.tilt_letter();
  const WorstRates worst =
      worst_rates(po, written_joints(machine, at), at, moves, res.gcode_units,
                  [&](const GcodeMove& m) { return written_joints(machine, {&m}).front(); });
  const auto& velocity = worst.velocity;
  const auto& accel = worst.accel;
  const auto& jerk = worst.jerk;
  const char* at_feed = scheduled ? " at the scheduled feed" : " at the programmed feed";
  for (std::size_t j = 0; j < kJointCount; ++j) {
    const std::string unit = j < 3 ? "mm" : "deg";
    const std::string axis = "axis " + joint_name(static_cast<Joint>(j), tilt_letter);
    const auto describe = [&](const Worst& w, double limit, const char* what,
                              const std::string& per) {
      return format_location(source, po.points[w.point].line,
                             "operation " + po.name + ": " + axis + " " + what + " " +
                                 std::to_string(w.value) + " " + unit + per + at_feed +
                                 ", the machine allows " + std::to_string(limit));
    };
    if (check[j].max_velocity_per_s > 0.0 &&
        velocity[j].value > check[j].max_velocity_per_s * (1.0 + 1e-9)) {
      r.verification.within_dynamic_limits = false;
      add_finding(res, FindingCode::DynamicLimitExceeded, op_index,
                  po.points[velocity[j].point].line,
                  describe(velocity[j], check[j].max_velocity_per_s, "velocity", "/s"));
    }
    if (check[j].max_accel_per_s2 > 0.0 &&
        accel[j].value > check[j].max_accel_per_s2 * (1.0 + 1e-9)) {
      r.verification.within_dynamic_limits = false;
      add_finding(res, FindingCode::DynamicLimitExceeded, op_index, po.points[accel[j].point].line,
                  describe(accel[j], check[j].max_accel_per_s2, "acceleration", "/s^2"));
    }
    if (check[j].max_jerk_per_s3 > 0.0 && jerk[j].value > check[j].max_jerk_per_s3 * (1.0 + 1e-9)) {
      add_finding(res, FindingCode::JerkLimitExceeded, op_index, po.points[jerk[j].point].line,
                  describe(jerk[j], check[j].max_jerk_per_s3, "jerk", "/s^3") +
                      " (feed schedules bound velocity and acceleration, not jerk)");
    }
  }
  if (!r.verification.within_dynamic_limits && !scheduled) {
    add_finding(res, FindingCode::DynamicLimitExceeded, op_index, 0,
                "operation " + po.name + ": " + options.name_of("feed_schedule") +
                    " writes feeds within the machine's limits");
  }
}

/// The flute length from the tip (mm, to 0.01) with which the shank, the tool's first body past
/// the flutes, no longer hits the part at point i with `axis`: the flutes as judged run on over
/// the shank's first x mm. Empty: the shank hits nowhere, or no length up to its end clears it.
/// With `known_mm` (a length from the tip) that already clears the point, that length.
static std::optional<double> flutes_clearing(const CollisionModel& model, const ToolModel& tool,
                                             const Operationd& op, std::size_t i, const Vec3d& axis,
                                             double known_mm = 0.0) {
  const std::size_t b = static_cast<std::size_t>(tool.flute_bodies);
  if (b >= tool.bodies.size() || b == 0 || static_cast<int>(b) == tool.holder_body) return {};
  const Vec3d centre = op.points[i].tip_mm + tool.ball_radius_mm * axis;
  const double s0 = tool.bodies[b].start_mm, s1 = tool.bodies[b].end_mm;
  if (!(s1 > s0)) return {};
  const auto clear_with = [&](double x) {
    ToolModel g = tool;
    g.bodies.erase(g.bodies.begin(), g.bodies.begin() + static_cast<long>(b));
    g.bodies.front().start_mm = s0 + x;
    ToolBody flutes = tool.bodies.front();
    flutes.start_mm = s0;
    flutes.end_mm = s0 + x;
    if (x > 0.0) g.bodies.insert(g.bodies.begin(), flutes);
    return !model.collides(g, centre, axis, false);
  };
  if (clear_with(0.0)) return {};
  const double known = known_mm - s0 - tool.ball_radius_mm;
  if (known > 0.0 && known < s1 - s0 && clear_with(known)) return known_mm;
  if (!clear_with(s1 - s0 - 1e-6)) return {};
  double lo = 0.0, hi = s1 - s0 - 1e-6;
  while (hi - lo > 0.01) {
    const double mid = 0.5 * (lo + hi);
    (clear_with(mid) ? hi : lo) = mid;
  }
  return hi + s0 + tool.ball_radius_mm;
}

/// What hits at point i (axis `axis`): the first body of the judged `tool` past the flutes
/// that meets the part, how far its real body (`real_tool`) stays from it (or that it enters
/// it), and, for the shank, the flute length that would clear it when one does: the words a
/// refusal gives (tests/test_paper_method.cpp).
std::string what_hits(const CollisionModel& model, const ToolModel& tool,
                      const ToolModel& real_tool, const Operationd& op, std::size_t i,
                      const Vec3d& axis, bool in_air, const JobOptions& options) {
  const Vec3d centre = op.points[i].tip_mm + tool.ball_radius_mm * axis;
  const std::size_t first = static_cast<std::size_t>(tool.flute_bodies);
  for (std::size_t b = first; b < tool.bodies.size(); ++b) {
    ToolModel one = tool;
    one.bodies = {tool.bodies[b]};
    if (!model.collides(one, centre, axis, false)) continue;
    const bool holder = static_cast<int>(b) == tool.holder_body;
    const char* name = holder ? "holder" : "shank";
    const double clearance = tool.bodies[b].radius_mm - real_tool.bodies[b].radius_mm;
    // The real body grown by d stays free for d below its distance from the part.
    const auto free_grown = [&](double d) {
      ToolModel g = real_tool;
      g.bodies = {real_tool.bodies[b]};
      g.bodies[0].radius_mm += d;
      if (holder) g.bodies[0].start_mm -= d;
      return !model.collides(g, centre, axis, false);
    };
    std::ostringstream os;
    os.precision(3);
    os << std::fixed;
    if (!free_grown(0.0)) {
      os << "the " << name << " itself enters the part";
    } else {
      double lo = 0.0, hi = clearance;
      while (hi - lo > 0.001) {
        const double mid = 0.5 * (lo + hi);
        (free_grown(mid) ? lo : hi) = mid;
      }
      os << "the " << name << " comes " << lo << " mm from the part (its clearance " << clearance
         << " mm)";
    }
    if (!holder && b == first && tool.bodies[b].end_mm > tool.bodies[b].start_mm) {
      if (const std::optional<double> flutes = flutes_clearing(model, tool, op, i, axis)) {
        os << "; flutes of " << *flutes << " mm from the tip ("
           << options.name_of("tool.flute_length_mm") << ") would clear it here";
      } else {
        os << "; no flute length up to the gauge length clears it here";
      }
    }
    return os.str();
  }
  return in_air ? "the ball, in the air, meets the part" : "";
}

/// One refusal, one remedy: the flute length that clears the shank at every point of `hits`
/// it can clear (the longest of theirs), in mm and in the CL file's units, so that the next run
/// does not stop at the next point; empty where no shank hit is cleared by longer flutes.
static std::string flutes_for_every_point(const Run& run, const OperationContext& o,
                                          const ToolModel& tool,
                                          const std::vector<std::size_t>& hits,
                                          const std::vector<Vec3d>& axes) {
  double longest = 0.0;
  std::size_t cleared = 0;
  for (std::size_t i : hits) {
    if (const std::optional<double> f =
            flutes_clearing(*run.collision, tool, *o.op, i, axes[i], longest)) {
      longest = std::max(longest, *f);
      ++cleared;
    }
  }
  if (cleared < 2) return "";
  std::ostringstream os;
  os.precision(3);
  os << std::fixed << "; flutes of " << longest << " mm from the tip";
  if (run.tp.units == LengthUnit::Inch) {
    os.precision(4);
    os << " (" << longest / kMmPerInch << " in, the CL file's unit)";
  }
  os << " would clear the shank at all " << cleared << " of these points it can clear ("
     << run.options.name_of("tool.flute_length_mm") << ")";
  return os.str();
}

/// The points `at` of an operation that collide, `what` they hit, the first's detail.
void point_collision_finding(const Run& run, const OperationContext& o,
                             const std::vector<std::size_t>& at, const std::string& what,
                             const std::string& first_detail, JobResult& res) {
  if (at.empty()) return;
  const Operationd& op = *o.op;
  std::string lines;
  for (std::size_t j = 0; j < at.size() && j < 10; ++j) {
    lines += (j ? ", " : "") + std::to_string(op.points[at[j]].line);
  }
  if (at.size() > 10) lines += ", ...";
  add_finding(res, FindingCode::PointCollision, o.index, op.points[at.front()].line,
              format_location(run.tp.source, op.points[at.front()].line,
                              "operation " + op.name + ": " + std::to_string(at.size()) +
                                  " CL points " + what + ", at lines " + lines +
                                  (first_detail.empty()
                                       ? std::string()
                                       : "; at line " + std::to_string(op.points[at.front()].line) +
                                             " " + first_detail)));
}

/// The colliding points `after` told apart: the flutes reaching deeper than the part tolerance
/// (a gouge of the cutter) and the bodies that never cut (shank, holder, a ball in the air)
/// within their margins; each marked on its row and reported.
void tell_point_collisions(const Run& run, const OperationContext& o,
                           const std::vector<std::size_t>& after,
                           const std::vector<Vec3d>& out_axes, OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const ToolModel& real_tool = *o.real_tool;
  const ToolModel& tool = *o.tool;
  ToolModel flutes = tool, rest = tool;
  flutes.bodies.resize(static_cast<std::size_t>(tool.flute_bodies));
  rest.bodies.erase(rest.bodies.begin(), rest.bodies.begin() + tool.flute_bodies);
  std::vector<std::size_t> gouges, hits;
  for (std::size_t i : after) {
    const Vec3d centre = op.points[i].tip_mm + tool.ball_radius_mm * out_axes[i];
    const bool in_air = o.contacts.empty() || o.contacts[i].state != ContactState::Touching;
    if (!flutes.bodies.empty() && run.collision->collides(flutes, centre, out_axes[i], false)) {
      gouges.push_back(i);
    }
    if (run.collision->collides(rest, centre, out_axes[i], in_air)) hits.push_back(i);
  }
  r.verification.flute_gouge_points = static_cast<long>(gouges.size());
  for (std::size_t i : gouges) r.rows[i].mark(PointMark::FluteGouge);
  for (std::size_t i : hits) r.rows[i].mark(PointMark::PointCollision);
  if (hits.empty() && gouges.empty()) {
    for (std::size_t i : after) r.rows[i].mark(PointMark::PointCollision);
  }
  const auto report = [&](const std::vector<std::size_t>& at, const std::string& what,
                          const std::string& first_detail = std::string()) {
    point_collision_finding(run, o, at, what, first_detail, res);
  };
  const std::string hit_detail =
      hits.empty()
          ? std::string()
          : what_hits(
                *run.collision, tool, real_tool, op, hits.front(), out_axes[hits.front()],
                o.contacts.empty() || o.contacts[hits.front()].state != ContactState::Touching,
                run.options);
  report(hits,
         "where the tool hits the part (the shank or holder within its clearance, or a "
         "ball in the air)",
         hit_detail + flutes_for_every_point(run, o, tool, hits, out_axes));
  const double flute_tolerance_mm = margins_of(run.options, op).flute_tolerance_mm;
  report(gouges, "where the flutes reach into the part deeper than the part tolerance " +
                     shown(flute_tolerance_mm) + " mm (" + part_tolerance_source(run.options, op) +
                     "; a gouge; " + run.options.name_of("part_tolerance_mm") + ")");
  if (hits.empty() && gouges.empty()) {
    report(after, "where the tool hits the part");  // never: the bodies are the same
  }
}

/// The collisions of an operation's points and moves as written (FCL, the reference), told
/// apart by body, and the clearance of the bodies that do not cut.
void check_collisions(const Run& run, const OperationContext& o, const PostedOperation& po,
                      const Written& w, const std::vector<Vec3d>& xyz_w,
                      const std::vector<double>& a_w, const std::vector<double>& c_w,
                      detail::StageProgress& checking, OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const Machine& machine = run.machine;
  // Judged with the margins; the clearance is measured from the real bodies.
  const ToolModel& real_tool = *o.real_tool;
  const ToolModel& tool = *o.tool;
  std::vector<Vec3d> in_axes, out_axes;
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    in_axes.push_back(op.points[i].axis);
    out_axes.push_back(po.points[i].axis);
  }
  // The input's count is information, not a check of the output: where the axes changed,
  // the planner's check (which agrees with FCL) counts it; what is written is checked with
  // FCL (where they did not change, the one count is that check).
  const bool same_axes = in_axes == out_axes;
  const PartCheck& counter =
      run.checker && !same_axes ? static_cast<const PartCheck&>(*run.checker) : *run.collision;
  const auto before = colliding_points(counter, tool, op, in_axes, o.contacts, &checking);
  if (same_axes) checking.advance(op.points.size());
  const auto after =
      same_axes ? before
                : colliding_points(*run.collision, tool, op, out_axes, o.contacts, &checking);
  r.colliding_before = static_cast<long>(before.size());
  r.colliding_after = static_cast<long>(after.size());
  r.verification.collision_free = after.empty();
  if (!after.empty()) {
    tell_point_collisions(run, o, after, out_axes, r, res);
  } else {
    r.verification.flute_gouge_points = 0;
  }
  const auto moves_hit =
      colliding_moves(*run.collision, tool, machine, xyz_w, a_w, c_w, o.contacts, &checking,
                      &w.way_points[k], nullptr, run.clearance_bounds());
  r.verification.colliding_moves = static_cast<long>(moves_hit.size());
  for (std::size_t i : moves_hit) r.rows[i].mark(PointMark::MoveCollision);
  if (const auto least = clearance_bound(*run.collision, real_tool, op, out_axes, &checking)) {
    r.verification.min_clearance_mm = least->first;
    r.verification.min_clearance_index = least->second;
  }
  if (!moves_hit.empty()) {
    r.verification.collision_free = false;
    const std::size_t i = moves_hit.front();
    add_finding(res, FindingCode::MoveCollision, k, op.points[i].line,
                format_location(run.tp.source, op.points[i].line,
                                "operation " + op.name + ": " + std::to_string(moves_hit.size()) +
                                    " moves where the tool hits the part between CL points as the "
                                    "machine moves it, "
                                    "first from line " +
                                    std::to_string(op.points[i - 1].line) + " to line " +
                                    std::to_string(op.points[i].line)));
  }
}

/// An operation whose tool is no ball end (flat, bull nose) with a part: no contact model, so
/// its flutes are not judged, but its shank and holder, which never cut, are checked at every
/// point and along every move as written, with their clearances (tests/test_bad_input.cpp: the demo
/// with a corner radius of 1 mm was posted with 330 shank collisions at exit 0).
void check_shank_and_holder(const Run& run, const OperationContext& o, const PostedOperation& po,
                            const Written& w, const std::vector<Vec3d>& xyz_w,
                            const std::vector<double>& a_w, const std::vector<double>& c_w,
                            OperationResult& r, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  ToolModel tool;
  try {
    tool =
        ToolModel::shank_and_holder(op.tool, run.options.tool).judged(margins_of(run.options, op));
  } catch (const InputError& e) {
    throw InputError(run.tp.source, op.points.empty() ? 0 : op.points.front().line,
                     "operation " + op.name + ": " + e.message());
  }
  if (tool.bodies.empty()) return;  // the flutes reach the holder face: nothing above them
  // Every point counts as touching: the check is of the bodies above the flutes only.
  std::vector<ContactPoint> above(op.points.size());
  for (ContactPoint& c : above) c.state = ContactState::Touching;
  std::vector<Vec3d> axes;
  for (const CLPointd& p : po.points) axes.push_back(p.axis);
  const std::vector<std::size_t> hits =
      colliding_points(*run.collision, tool, op, axes, above, nullptr);
  const std::vector<std::size_t> moves =
      colliding_moves(*run.collision, tool, run.machine, xyz_w, a_w, c_w, above, nullptr,
                      &w.way_points[k], nullptr, run.clearance_bounds());
  r.colliding_before = r.colliding_after = static_cast<long>(hits.size());
  r.verification.colliding_moves = static_cast<long>(moves.size());
  r.verification.collision_free = hits.empty() && moves.empty();
  for (std::size_t i : hits) r.rows[i].mark(PointMark::PointCollision);
  for (std::size_t i : moves) r.rows[i].mark(PointMark::MoveCollision);
  const std::string what = tool.holder_body >= 0 ? "shank or holder" : "shank";
  if (!hits.empty()) {
    std::string lines;
    for (std::size_t j = 0; j < hits.size() && j < 10; ++j) {
      lines += (j ? ", " : "") + std::to_string(op.points[hits[j]].line);
    }
    if (hits.size() > 10) lines += ", ...";
    add_finding(res, FindingCode::PointCollision, k, op.points[hits.front()].line,
                format_location(run.tp.source, op.points[hits.front()].line,
                                "operation " + op.name + ": " + std::to_string(hits.size()) +
                                    " CL points where the " + what +
                                    " of the (not ball-end) tool hits the part within its "
                                    "clearance, at lines " +
                                    lines));
  }
  if (!moves.empty()) {
    const std::size_t i = moves.front();
    add_finding(res, FindingCode::MoveCollision, k, op.points[i].line,
                format_location(run.tp.source, op.points[i].line,
                                "operation " + op.name + ": " + std::to_string(moves.size()) +
                                    " moves where the " + what +
                                    " of the (not ball-end) tool hits the part, first from "
                                    "line " +
                                    std::to_string(op.points[i - 1].line) + " to line " +
                                    std::to_string(op.points[i].line)));
  }
}

/// The free cells of every contact's C-space (--count-free-cells) and the maps of the most
/// constrained contact and the most turned one (--cspace-maps).
void cspace_rows(const Run& run, const OperationContext& o, detail::StageProgress& checking,
                 OperationResult& r) {
  const Operationd& op = *o.op;
  const JobOptions& options = run.options;
  const CSpaceRasteriser* rasteriser = &*run.checker;
  const auto t0 = Clock::now();
  const double R = o.ball_radius_mm;
  const ToolModel& tool = *o.tool;
  CSpaceOptions cs;
  // The grid's cell must divide 180 deg: the nearest such to --grid.
  cs.cell_deg = 180.0 / std::max(1.0, std::round(180.0 / options.paper.grid_deg));
  cs.max_deviation_deg = options.paper.max_deviation_deg;
  detail::parallel_for(std::size_t(0), op.points.size(), [&](std::size_t i) {
    const ContactPoint& c = o.contacts[i];
    checking.advance();
    if (c.state != ContactState::Touching) return;
    const CSpaceGrid g =
        rasteriser->free_axes(tool, c, reference_point(op.points[i], R), op.points[i].axis, cs);
    r.rows[i].free_cells = g.free_count() / 2;  // the grid holds every axis twice
  });
  if (options.cspace_maps) {
    // The most constrained contact, and the one whose axis the optimiser turned most.
    std::optional<std::size_t> fewest, turned;
    double most_deg = -1.0;
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      if (!r.rows[i].free_cells) continue;
      if (!fewest || *r.rows[i].free_cells < *r.rows[*fewest].free_cells) fewest = i;
      const double dev = rad_to_deg(angle_between(op.points[i].axis, r.rows[i].axis));
      if (dev > most_deg) most_deg = dev, turned = i;
    }
    const auto tilt_yaw = [](const ContactPoint& c, const Vec3d& v) {
      return std::pair<double, double>(rad_to_deg(angle_between(c.surface_normal, v)),
                                       rad_to_deg(std::atan2(v.dot(c.side), v.dot(c.feed_dir))));
    };
    for (const auto& [at, why] :
         {std::pair<std::optional<std::size_t>, const char*>{fewest, "fewest free cells"},
          {turned, "largest axis change"}}) {
      if (!at) continue;
      if (!r.cspace_maps.empty() && r.cspace_maps.back().index == *at) continue;
      const ContactPoint& c = o.contacts[*at];
      CSpaceMap map;
      map.index = *at;
      map.why = why;
      map.max_deviation_deg = cs.max_deviation_deg;
      map.grid = rasteriser->free_axes(tool, c, reference_point(op.points[*at], R),
                                       op.points[*at].axis, cs);
      std::tie(map.input_tilt_deg, map.input_yaw_deg) = tilt_yaw(c, op.points[*at].axis);
      std::tie(map.output_tilt_deg, map.output_yaw_deg) = tilt_yaw(c, r.rows[*at].axis);
      r.cspace_maps.push_back(std::move(map));
    }
  }
  r.time_cspace_s += seconds_since(t0);
}

}  // namespace taxopt::pipeline
