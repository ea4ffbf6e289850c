// The verify stage: every operation checked as written -- read back, axis ranges and travel,
// the deviation cone, collisions of the points and of the moves between them, clearances,
// the machine's dynamic limits -- and the report's rows (stages.hpp).
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
          for (std::size_t j = lo; j != end; ++j)
            acc = std::min(acc, Least{bisect(at[j], hi), at[j]});
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

/// Checks the joints' velocity, acceleration and jerk at the written feeds against `check`
/// (0: no limit), as the controller moves: block times from the F words read back, each
/// chain of feed moves from rest to rest. Velocity and acceleration beyond a limit are
/// problems, jerk a warning (the schedule does not bound it).
void check_dynamic_limits(OperationResult& r, const PostedOperation& po,
                          const std::vector<JointPosition>& joints,
                          const std::vector<const GcodeMove*>& at,
                          const std::vector<GcodeMove>& moves, JobResult& res,
                          const std::string& source, const JointLimits& check, bool scheduled,
                          char tilt_letter, std::size_t op_index,
                          const std::function<JointPosition(const GcodeMove&)>& joint_of) {
  const std::size_t n = po.points.size();
  std::vector<double> written_s(n, 0.0);
  const auto index_of = [&](const GcodeMove* m) { return move_index(moves, m); };
  for (std::size_t i = 1; i < n; ++i) {
    if (po.points[i].motion != Motion::Feed || at[i] == at[i - 1]) continue;
    // A linearised move: the blocks between the points, each at its own F.
    const std::ptrdiff_t from = index_of(at[i - 1]), to = index_of(at[i]);
    if (from >= 0 && to > from + 1) {
      for (std::ptrdiff_t j = from + 1; j <= to; ++j) {
        written_s[i] += block_time_s(moves[static_cast<std::size_t>(j - 1)],
                                     moves[static_cast<std::size_t>(j)], res.gcode_units);
      }
    } else {
      written_s[i] = block_time_s(*at[i - 1], *at[i], res.gcode_units);
    }
  }
  struct Worst {
    double value = 0.0;
    std::size_t point = 0;
  };
  std::array<Worst, kJointCount> velocity{}, accel{}, jerk{};
  for (const IndexRange& c : feed_chains(po.points)) {
    // The chain as written: a linearised move is its blocks (machine mode), each at its own F
    // with its own joints, so that no block between the points is faster than the limits
    // (a machinist's review, tests/test_program.cpp); `owner` maps a block back to its point.
    std::vector<JointPosition> q = {joints[c.begin - 1]};
    std::vector<double> t;
    std::vector<std::size_t> owner = {c.begin - 1};
    for (std::size_t i = c.begin; i < c.end; ++i) {
      const std::ptrdiff_t from = index_of(at[i - 1]), to = index_of(at[i]);
      if (at[i] != at[i - 1] && from >= 0 && to > from + 1) {
        for (std::ptrdiff_t j = from + 1; j <= to; ++j) {
          const GcodeMove& m = moves[static_cast<std::size_t>(j)];
          q.push_back(j == to ? joints[i] : joint_of(m));
          t.push_back(block_time_s(moves[static_cast<std::size_t>(j - 1)], m, res.gcode_units));
          owner.push_back(i);
        }
      } else {
        q.push_back(joints[i]);
        t.push_back(written_s[i]);
        owner.push_back(i);
      }
    }
    const JointRates jr = joint_rates(q, t);
    for (std::size_t j = 0; j < kJointCount; ++j) {
      const auto keep = [](Worst& w, double v, std::size_t point) {
        if (v > w.value) w = Worst{v, point};
      };
      keep(velocity[j], jr.max_velocity_per_s[j],
           owner[std::min(owner.size() - 1, jr.velocity_at[j] + 1)]);
      keep(accel[j], jr.max_accel_per_s2[j], owner[std::min(owner.size() - 1, jr.accel_at[j])]);
      keep(jerk[j], jr.max_jerk_per_s3[j], owner[std::min(owner.size() - 1, jr.jerk_at[j])]);
    }
  }
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
    add_finding(
        res, FindingCode::DynamicLimitExceeded, op_index, 0,
        "operation " + po.name + ": --feed-schedule writes feeds within the machine's limits");
  }
}

/// What hits at point i (axis `axis`): the first body of the judged `tool` past the flutes
/// that meets the part, how far its real body (`real_tool`) stays from it (or that it enters
/// it), and, for the shank, the flute length that would clear it when one does: the words a
/// refusal gives (tests/test_paper_method.cpp).
std::string what_hits(const CollisionModel& model, const ToolModel& tool,
                      const ToolModel& real_tool, const Operationd& op, std::size_t i,
                      const Vec3d& axis, bool in_air) {
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
      // Longer flutes (the flute body as judged) over the shank's first x mm.
      const double s0 = tool.bodies[b].start_mm, s1 = tool.bodies[b].end_mm;
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
      if (clear_with(s1 - s0 - 1e-6)) {
        double lo = 0.0, hi = s1 - s0 - 1e-6;
        while (hi - lo > 0.01) {
          const double mid = 0.5 * (lo + hi);
          (clear_with(mid) ? hi : lo) = mid;
        }
        os << "; flutes of " << hi + s0 + tool.ball_radius_mm
           << " mm from the tip (--flute-length) would clear it here";
      } else {
        os << "; no flute length up to the gauge length clears it here";
      }
    }
    return os.str();
  }
  return in_air ? "the ball, in the air, meets the part" : "";
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
    // Told apart: the flutes reaching deeper than the part tolerance (a gouge of the cutter)
    // and the bodies that never cut (shank, holder, a ball in the air) within their margins.
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
      if (at.empty()) return;
      std::string lines;
      for (std::size_t j = 0; j < at.size() && j < 10; ++j) {
        lines += (j ? ", " : "") + std::to_string(op.points[at[j]].line);
      }
      if (at.size() > 10) lines += ", ...";
      add_finding(
          res, FindingCode::PointCollision, k, op.points[at.front()].line,
          format_location(run.tp.source, op.points[at.front()].line,
                          "operation " + op.name + ": " + std::to_string(at.size()) +
                              " CL points " + what + ", at lines " + lines +
                              (first_detail.empty()
                                   ? std::string()
                                   : "; at line " + std::to_string(op.points[at.front()].line) +
                                         " " + first_detail)));
    };
    const std::string hit_detail =
        hits.empty()
            ? std::string()
            : what_hits(
                  *run.collision, tool, real_tool, op, hits.front(), out_axes[hits.front()],
                  o.contacts.empty() || o.contacts[hits.front()].state != ContactState::Touching);
    report(hits,
           "where the tool hits the part (the shank or holder within its clearance, or a "
           "ball in the air)",
           hit_detail);
    const double flute_tolerance_mm = margins_of(run.options, op).flute_tolerance_mm;
    report(gouges, "where the flutes reach into the part deeper than the part tolerance " +
                       shown(flute_tolerance_mm) + " mm (" +
                       (run.options.part_tolerance_mm
                            ? std::string("as given")
                            : contact_tolerance_source(*run.options.part, run.options.contact,
                                                       op.cam_tolerance_mm)) +
                       "; a gouge; --part-tolerance)");
    if (hits.empty() && gouges.empty()) {
      report(after, "where the tool hits the part");  // never: the bodies are the same
    }
  } else {
    r.verification.flute_gouge_points = 0;
  }
  const auto moves_hit = colliding_moves(*run.collision, tool, machine, xyz_w, a_w, c_w, o.contacts,
                                         &checking, &w.way_points[k]);
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
  const std::vector<std::size_t> moves = colliding_moves(
      *run.collision, tool, run.machine, xyz_w, a_w, c_w, above, nullptr, &w.way_points[k]);
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
      return std::pair<double, double>(rad_to_deg(angle_between(c.normal, v)),
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

/// One operation verified as written.
OperationResult verify_operation(const Run& run, const OperationContext& o,
                                 const PostedOperation& po, const Written& w, std::size_t n_posted,
                                 detail::StageProgress& checking, JobResult& res) {
  const Operationd& op = *o.op;
  const std::size_t k = o.index;
  const Machine& machine = run.machine;
  const JobOptions& options = run.options;
  const int decimals = machine.gcode.decimals;
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
  // Read back: the A/C values actually written, and what they mean in the workpiece.
  std::vector<double> a_w(op.points.size()), c_w(op.points.size());
  std::vector<Vec3d> xyz_w(op.points.size());
  std::vector<double> a_in(op.points.size()), c_in(op.points.size());
  r.rows.resize(op.points.size());
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    const GcodeMove* last = w.point_moves[k][i];
    // Where TCP is asked for, the controller's must be on, with the tool length offset
    // (LinuxCNC's kinematics steer the spindle nose without it); in machine mode the offset.
    const bool tcp_mode = machine.gcode.mode == GcodeMode::Tcp;
    if (!last->length_offset || (tcp_mode && !last->tcp)) {
      if (r.verification.tool_length_active) {
        add_finding(
            res, FindingCode::ToolLengthOffsetOff, k, op.points[i].line,
            "operation " + op.name + ": G-code line " + std::to_string(last->line) +
                " moves with " +
                (!last->length_offset ? std::string("the tool length offset off")
                                      : std::string("tool centre point control off")) +
                " (the written program must switch it on before the operation's first move)");
      }
      r.verification.tool_length_active = false;
    }
    a_w[i] = last->a_deg;
    xyz_w[i] = last->xyz_mm;
    c_w[i] = last->c_deg;
    if (!o.input_poses.empty()) {
      a_in[i] = round_to(rad_to_deg(o.input_poses[i].a_rad), decimals);
      c_in[i] = round_to(rad_to_deg(o.input_poses[i].c_rad), decimals);
    }
    const Posed written{deg_to_rad(last->a_deg), deg_to_rad(last->c_deg)};
    const Vec3d axis = machine.ac.forward(written);
    const Vec3d tip = tip_of_written_mm(machine, last->xyz_mm, written);
    const CLPointd& want = po.points[i];
    r.verification.roundtrip_max_mm =
        std::max(r.verification.roundtrip_max_mm, (tip - want.tip_mm).norm());
    r.verification.roundtrip_max_deg =
        std::max(r.verification.roundtrip_max_deg, rad_to_deg(angle_between(axis, want.axis)));
    // At a range's end (within 0.01 deg) or past it: the page's "limit reached".
    const auto at_limit = [](const RotaryAxis<double>& range, double v_rad) {
      const double near_rad = deg_to_rad(0.01);
      return !range.continuous &&
             (v_rad <= range.min_rad + near_rad || v_rad >= range.max_rad - near_rad);
    };
    if (at_limit(machine.ac.a, written.a_rad) || at_limit(machine.ac.c, written.c_rad)) {
      r.rows[i].mark(PointMark::AxisLimit);
    }
    if (!machine.ac.a.contains(written.a_rad) || !machine.ac.c.contains(written.c_rad)) {
      if (r.verification.within_axis_limits) {
        add_finding(res, FindingCode::AxisRangeExceeded, k, want.line,
                    format_location(
                        run.tp.source, want.line,
                        "operation " + op.name + ": written " + machine.ac.tilt_letter() + " " +
                            std::to_string(last->a_deg) + " / C " + std::to_string(last->c_deg) +
                            " deg is outside the machine's axis ranges"));
      }
      r.verification.within_axis_limits = false;
    }
    // The linear travel, in machine coordinates, where the machine file gives it: the
    // spindle's, the tool length above the tip (GcodeProgram::time_tool_length_mm).
    const Vec3d joints_mm = joints_of_written_mm(machine, last->xyz_mm, written) +
                            Vec3d(0.0, 0.0, res.gcode.time_tool_length_mm);
    for (int q = 0; q < 3; ++q) {
      const auto& range = machine.linear_range[static_cast<std::size_t>(q)];
      if (range.contains(joints_mm[q])) continue;
      r.rows[i].mark(PointMark::TravelExceeded);
      if (r.verification.within_axis_limits) {
        std::ostringstream os;
        os << "operation " << op.name << ": "
           << "XYZ"[q] << " would be " << joints_mm[q] << " mm in machine coordinates";
        if (q == 2 && res.gcode.time_tool_length_mm > 0.0) {
          os << " (the spindle, tool length " << res.gcode.time_tool_length_mm << " mm)";
        }
        os << ", outside the machine's travel [" << range.min_mm << ", " << range.max_mm << "] mm";
        add_finding(res, FindingCode::TravelExceeded, k, want.line,
                    format_location(run.tp.source, want.line, os.str()));
      }
      r.verification.within_axis_limits = false;
    }
    r.max_axis_change_deg =
        std::max(r.max_axis_change_deg, rad_to_deg(angle_between(op.points[i].axis, want.axis)));
    PointRow& row = r.rows[i];
    row.index = i;
    row.line = want.line;
    row.tip_mm = want.tip_mm;
    row.axis = want.axis;
    row.a_deg = a_w[i];
    row.c_deg = c_w[i];
  }
  // The round trip may differ from the intent only by the rounding of the written
  // decimals: half a unit of the last decimal per word, mapped to mm and to the axis angle;
  // in machine mode the angle rounding also moves the mapped point by its lever arm.
  const double half_unit = 0.5 * std::pow(10.0, -decimals);
  const double ang_tol = std::sqrt(2.0) * half_unit + 1e-9;
  double lever_mm = 0.0;
  if (machine.gcode.mode == GcodeMode::Machine) {
    for (const auto& p : po.points) {
      lever_mm =
          std::max(lever_mm, (p.tip_mm - machine.ac.c_axis_point_mm).norm() +
                                 (machine.ac.c_axis_point_mm - machine.ac.a_axis_point_mm).norm());
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
  r.contact = o.contact;
  r.time_contacts_s = o.contacts_s;
  r.time_optimise_s = o.optimise_s;
  if (o.optimised) {
    r.segments = static_cast<int>(o.optimised->intervals);
    // Why points kept their input axes: the paper's guard, else no free axis in the cone.
    const OptimisedOperation& opt = *o.optimised;
    OperationResult::KeptInputPoints kept;
    kept.passes = opt.guard.whole_passes;
    kept.stretches = opt.guard.stretches;
    std::vector<KeptWhy> why = opt.guard.why;
    why.resize(op.points.size(), KeptWhy::None);
    for (std::size_t i : opt.no_free_axis) {
      if (why[i] == KeptWhy::None) ++kept.no_free_axis;
      r.rows[i].mark(PointMark::NoFreeAxis);
    }
    for (std::size_t i = 0; i < why.size(); ++i) {
      if (why[i] == KeptWhy::Collision) r.rows[i].mark(PointMark::KeptCollision);
      if (why[i] == KeptWhy::PeakRate) r.rows[i].mark(PointMark::KeptPeakRate);
      if (why[i] == KeptWhy::Join) r.rows[i].mark(PointMark::KeptJoin);
    }
    for (const KeptWhy kw : why) {
      kept.collision += kw == KeptWhy::Collision;
      kept.peak_rate += kw == KeptWhy::PeakRate;
      kept.join_points += kw == KeptWhy::Join;
    }
    r.kept_input_points = kept;
    r.time_choice = opt.time_choice;
    // The optimiser keeps every axis within the cone; this proves it on what is written.
    const double allowed = options.paper.max_deviation_deg + 1e-6;
    if (r.max_axis_change_deg > allowed) {
      add_finding(res, FindingCode::DeviationExceeded, k, 0,
                  "operation " + op.name + ": an output axis is " +
                      std::to_string(r.max_axis_change_deg) +
                      " deg from its input axis, more than --max-deviation");
    }
  }
  if (run.collision && r.contact.recovered) {
    check_collisions(run, o, po, w, xyz_w, a_w, c_w, checking, r, res);
  } else if (run.collision && !(o.ball_radius_mm > 0.0) && op.tool.from_file &&
             op.tool.diameter_mm > 0.0) {
    check_shank_and_holder(run, o, po, w, xyz_w, a_w, c_w, r, res);
  }
  if (!r.verification.collision_free) {
    for (PointRow& row : r.rows) row.mark(PointMark::NotChecked);
  }
  if (!o.contacts.empty()) {
    for (std::size_t i = 0; i < op.points.size(); ++i) {
      const ContactPoint& c = o.contacts[i];
      if (c.state != ContactState::Touching) continue;
      PointRow& row = r.rows[i];
      row.has_contact = true;
      row.cc_mm = c.cc_mm;
      row.normal = c.normal;
      row.tilt_deg = rad_to_deg(c.tilt_rad);
      row.yaw_deg = rad_to_deg(c.yaw_rad);
    }
    if ((options.count_free_cells || options.cspace_maps) && run.checker &&
        o.ball_radius_mm > 0.0) {
      cspace_rows(run, o, checking, r);
    }
  }
  // The rates as the machine runs the program: each move at the time the controller gives the
  // words written (Written::time_into_after), the input's likewise; the paper's eq. 16-18 over
  // the contacts beside them, for the paper's comparison.
  r.before = summarise_timed(op, a_in, c_in, w.time_into_before[k], &r.rows, true);
  r.paper_before =
      summarise_paper(op, o.contacts, o.ball_radius_mm, a_in, c_in, o.metric_feed_mm_per_min);
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    r.rows[i].a_before_deg = a_in[i];
    r.rows[i].c_before_deg = c_in[i];
  }
  if (o.optimised) {
    for (std::size_t i : o.optimised->keys) r.rows[i].key = true;
  }
  r.after = summarise_timed(op, a_w, c_w, w.time_into_after[k], &r.rows);
  r.paper_after = summarise_paper(op, o.contacts, o.ball_radius_mm, a_w, c_w,
                                  o.metric_feed_mm_per_min, &r.rows);
  r.feed_after = w.schedule_after[k].summary;
  r.feed_before = w.schedule_before[k].summary;
  // A longer cycle is worth a warning above 0.1 % and 10 ms (below that it is rounding and the
  // schedule's own resolution: a run saw warnings for 2e-7 s); it names what grew.
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
  for (std::size_t i = 0; i < op.points.size(); ++i) {
    r.rows[i].feed_mm_min = w.schedule_after[k].feed_mm_min[i];
    r.rows[i].feed_before_mm_min = w.schedule_before[k].feed_mm_min[i];
  }
  r.feed_words = written_feed_words(op, po, w.point_moves[k], res.gcode_units, machine);
  check_dynamic_limits(r, po, written_joints(machine, w.point_moves[k]), w.point_moves[k], w.moves,
                       res, run.tp.source,
                       options.feed_schedule ? effective_limits(machine) : machine.limits,
                       options.feed_schedule, machine.ac.tilt_letter(), k,
                       [&](const GcodeMove& m) { return written_joints(machine, {&m}).front(); });
  // The checks' own time: this operation's verification without its C-space raster.
  r.time_verify_s = std::max(0.0, seconds_since(t_verify) - r.time_cspace_s);
  return r;
}

/// The operation a block of the program belongs to: the first whose last point is at or after
/// it (the approach to its first point is its own, the moves after the last point the last's).
/// The operation each written line belongs to and what it is, from the writer's blocks
/// (GcodeProgram::blocks): a line of the program's start counts as the first operation's, one
/// of its end as the last's.
class BlockOwner {
 public:
  BlockOwner(const GcodeProgram& program, std::size_t operations)
      : blocks_(program.blocks), last_(operations > 0 ? operations - 1 : 0) {}
  std::size_t operator()(int line) const {
    const ProgramBlock* b = at(line);
    if (!b || b->operation < 0) return line <= first_line() ? 0 : last_;
    return std::min(static_cast<std::size_t>(b->operation), last_);
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
      if (b.operation >= 0) return b.line;
    }
    return 0;
  }
  const std::vector<ProgramBlock>& blocks_;
  std::size_t last_;
};

}  // namespace

void check_program(const Run& run, const std::vector<PostedOperation>& posted, const Written& w,
                   JobResult& res) {
  const Machine& machine = run.machine;
  const ProgramTemplate& t = machine.gcode.program;
  const std::vector<GcodeMove>& moves = w.moves;
  if (moves.empty() || posted.empty()) return;
  const BlockOwner op_of(res.gcode, posted.size());
  struct Breach {
    std::size_t count = 0;
    int line = 0;
    std::string what;
  };
  std::map<FindingCode, Breach> breaches;
  const auto breach = [&](FindingCode code, const GcodeMove& m, const std::string& what) {
    Breach& b = breaches[code];
    if (b.count++ == 0) {
      b.line = m.line;
      b.what = "operation " + posted[op_of(m.line)].name + ": G-code line " +
               std::to_string(m.line) + " " + what;
    }
  };
  const double threshold_deg = t.index_threshold_deg + 1e-9;
  bool after_retract = false, xy_set = false;
  double xy[2] = {0.0, 0.0};
  const GcodeMove* prev = nullptr;
  // Every block's end within the machine's travel, the spindle's position (the approach, the
  // index moves, the retracts too: a LinuxCNC program whose approach left Z's travel by the
  // tool's length stopped there with a soft-limit error, measured on LinuxCNC's motion controller).
  // The CL points' own blocks are checked with their points (verify_operation, with the same
  // tool length): here the blocks between them.
  std::set<const GcodeMove*> at_points;
  for (const auto& op_moves : w.point_moves) at_points.insert(op_moves.begin(), op_moves.end());
  for (std::size_t k = 0; k < moves.size() && k < w.spindle_mm.size(); ++k) {
    if (!w.spindle_mm[k] || at_points.count(&moves[k])) continue;
    for (int q = 0; q < 3; ++q) {
      const auto& range = machine.linear_range[static_cast<std::size_t>(q)];
      const double v = (*w.spindle_mm[k])[q];
      if (range.contains(v) || std::abs(v - std::clamp(v, range.min_mm, range.max_mm)) < 1e-6) {
        continue;
      }
      std::ostringstream os;
      os << "takes the spindle to "
         << "XYZ"[q] << " " << v << " mm in machine coordinates (tool length "
         << res.gcode.time_tool_length_mm << " mm), outside the machine's travel [" << range.min_mm
         << ", " << range.max_mm << "] mm";
      breach(FindingCode::TravelExceeded, moves[k], os.str());
    }
  }
  for (const GcodeMove& m : moves) {
    const PostedOperation& po = posted[op_of(m.line)];
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
    const bool joint_safe_rapid = std::binary_search(res.gcode.joint_safe_rapids.begin(),
                                                     res.gcode.joint_safe_rapids.end(), m.line);
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
        t.retract != SafeRetract::None &&
        std::max(std::abs(m.a_deg - prev->a_deg), std::abs(m.c_deg - prev->c_deg)) >
            threshold_deg) {
      breach(FindingCode::IndexWithoutRetract, m,
             "turns the table by more than " + shown(t.index_threshold_deg) +
                 " deg in a rapid below the retract, with no part model to check the move");
    }
    if (m.retract) {
      after_retract = true;
      xy_set = false;
    } else if (after_retract) {
      const bool gives_xy = (m.given & 3u) != 0, gives_z = (m.given & 4u) != 0;
      const bool turns = prev && (m.a_deg != prev->a_deg || m.c_deg != prev->c_deg);
      if (gives_z && !gives_xy && !xy_set && !turns) {
        // Straight down (or up) to the clearance height, where it is: not the way in yet.
      } else if (gives_xy && !gives_z) {
        xy_set = true;
        xy[0] = m.xyz_mm.x();
        xy[1] = m.xyz_mm.y();
      } else if (gives_z) {
        // Down from there: straight down, or under TCP along the tool axis (as CAM links an
        // approach: the writer comes down so where the axis is not vertical).
        const auto along_axis = [&] {
          if (!prev || !m.tcp || !prev->tcp) return false;
          const Vec3d d = m.xyz_mm - prev->xyz_mm;
          if (d.norm() < 1e-9) return false;
          const Vec3d axis = machine.ac.forward(Posed{deg_to_rad(m.a_deg), deg_to_rad(m.c_deg)});
          return std::abs(d.normalized().dot(axis)) > std::cos(1e-3);
        };
        if (!xy_set || ((m.xyz_mm.x() != xy[0] || m.xyz_mm.y() != xy[1]) && !along_axis()) ||
            (prev && (m.a_deg != prev->a_deg || m.c_deg != prev->c_deg))) {
          breach(FindingCode::DiagonalApproach, m,
                 "leaves the retract height otherwise than XY first, then down");
        }
        after_retract = false;
      }
    }
    prev = &m;
  }
  // The coolant at each operation's first point: the CL file's (its last change before that
  // point), else the machine file's.
  const auto code_of = [](ClCoolant c) {
    return c == ClCoolant::Flood ? 8 : c == ClCoolant::Mist ? 7 : 0;
  };
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const PostedOperation& po = posted[k];
    if (w.point_moves[k].empty()) continue;
    int want = po.coolant                    ? code_of(*po.coolant)
               : t.coolant == Coolant::Flood ? 8
               : t.coolant == Coolant::Mist  ? 7
                                             : 0;
    for (const ProgramEvent& e : po.events) {
      if (e.kind == ProgramEvent::Kind::Coolant && e.before_point == 0) want = code_of(e.coolant);
    }
    const GcodeMove& first = *w.point_moves[k].front();
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
  if (t.end_pose == EndPose::Home && t.retract != SafeRetract::None &&
      (moves.back().a_deg != 0.0 || moves.back().c_deg != 0.0)) {
    breach(FindingCode::EndPoseNotHome, moves.back(),
           "ends with the rotary axes at " + shown(moves.back().a_deg) + " / " +
               shown(moves.back().c_deg) + " deg, not at their home (gcode.end_pose)");
  }
  for (const auto& [code, b] : breaches) {
    add_finding(res, code, std::nullopt, 0,
                b.what + (b.count > 1 ? " (and " + std::to_string(b.count - 1) + " more)" : ""));
  }
}

void check_every_block(const Run& run, const std::vector<OperationContext>& ops,
                       const std::vector<PostedOperation>& posted, const Written& w,
                       JobResult& res) {
  const std::vector<GcodeMove>& moves = w.moves;
  if (!run.collision || moves.empty() || posted.empty() || res.operations.size() != posted.size())
    return;
  const BlockOwner op_of(res.gcode, posted.size());
  // The blocks the operations' own checks sweep already (colliding_moves): a feed move into a
  // point with its linearisation blocks, a rapid written as one block. Every other block (the
  // approach, the descent and the XY move to it, an index move's retract, turn and way back,
  // the retract at the end and the unwinding) is swept here, with the whole tool in the air.
  std::vector<char> swept(moves.size(), 0);
  std::vector<char> touching_end(moves.size(), 0);
  for (std::size_t k = 0; k < posted.size(); ++k) {
    const OperationContext& o = ops[k];
    const std::vector<const GcodeMove*>& at = w.point_moves[k];
    for (std::size_t i = 0; i < at.size(); ++i) {
      const std::ptrdiff_t to = move_index(moves, at[i]);
      if (to < 0) continue;
      if (!o.contacts.empty() && o.contacts[i].state == ContactState::Touching) {
        touching_end[static_cast<std::size_t>(to)] = 1;
      }
      if (i == 0 || !o.judged_tool()) continue;
      const std::ptrdiff_t from = move_index(moves, at[i - 1]);
      if (from < 0 || to <= from) continue;
      if (posted[k].points[i].motion == Motion::Feed || to == from + 1) {
        for (std::ptrdiff_t j = from + 1; j <= to; ++j) swept[static_cast<std::size_t>(j)] = 1;
      }
    }
  }
  struct Hit {
    std::size_t count = 0;
    std::size_t move = 0;  // the first block that hits
  };
  std::vector<Hit> hits(posted.size());
  std::vector<std::size_t> candidates;
  std::vector<long> unknown(posted.size(), 0);
  for (std::size_t j = 1; j < moves.size(); ++j) {
    if (swept[j]) continue;
    const OperationContext& o = ops[op_of(moves[j].line)];
    if (!o.judged_tool()) continue;
    if (w.joints_after[j]) {
      candidates.push_back(j);
    } else {
      ++unknown[op_of(moves[j].line)];
    }
  }
  const Machine& machine = run.machine;
  constexpr std::size_t kA = static_cast<std::size_t>(Joint::A);
  constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
  std::vector<double> flute_tolerance_mm(ops.size(), 0.0);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    flute_tolerance_mm[k] = margins_of(run.options, *ops[k].op).flute_tolerance_mm;
  }
  const std::vector<std::size_t> hit =
      detail::parallel_select(0, candidates.size(), [&](std::size_t c) {
        const std::size_t j = candidates[c];
        const std::size_t k = op_of(moves[j].line);
        const OperationContext& o = ops[k];
        const ToolModel& tool = *o.tool;
        const double R = tool.ball_radius_mm;
        // In the air the ball counts as a body too, within the flutes' tolerance of the part
        // (a block that ends at a contact point touches it there by design).
        ToolModel air = tool;
        air.ball_radius_mm = std::max(0.5 * R, R - flute_tolerance_mm[k]);
        // A block whose start is not known (the first after a retract in machine
        // coordinates): its end, where the tool stands.
        const JointPosition& q1 = *w.joints_after[j];
        const JointPosition& q0 = w.joints_after[j - 1] ? *w.joints_after[j - 1] : q1;
        const Posed p0{deg_to_rad(q0[kA]), deg_to_rad(q0[kC])};
        const Posed p1{deg_to_rad(q1[kA]), deg_to_rad(q1[kC])};
        const Vec3d m0(q0[0], q0[1], q0[2]), m1(q1[0], q1[1], q1[2]);
        const Vec3d t0 = machine.ac.from_machine_mm(m0, p0),
                    t1 = machine.ac.from_machine_mm(m1, p1);
        const bool tip_linear = w.tip_linear[j] != 0;
        // Steps: 0.5 deg of either rotary axis, and along the path no more than half the
        // thinnest body's radius (a wall the body could pass between two samples is thinner
        // than the body is wide).
        double thinnest = R > 0.0 ? R : 1.0;
        for (const ToolBody& b : tool.bodies) thinnest = std::min(thinnest, b.radius_mm);
        const double step_mm = std::max(0.05, 0.5 * thinnest);
        const double travel = std::max((t1 - t0).norm(), (m1 - m0).norm());
        const int steps = static_cast<int>(
            std::ceil(std::max({std::abs(q1[kA] - q0[kA]) / 0.5, std::abs(q1[kC] - q0[kC]) / 0.5,
                                travel / step_mm, 1.0})));
        for (int s = 1; s <= steps; ++s) {
          const double u = static_cast<double>(s) / steps;
          const Posed pose{p0.a_rad + u * (p1.a_rad - p0.a_rad),
                           p0.c_rad + u * (p1.c_rad - p0.c_rad)};
          const Vec3d tip = tip_linear ? Vec3d(t0 + u * (t1 - t0))
                                       : machine.ac.from_machine_mm(m0 + u * (m1 - m0), pose);
          const Vec3d axis = machine.ac.forward(pose);
          // The block's end at a contact point: the flutes judged as at every CL point.
          const bool at_contact = s == steps && touching_end[j];
          if (run.collision->collides(at_contact ? tool : air, tip + R * axis, axis, !at_contact)) {
            return true;
          }
        }
        return false;
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
  for (std::size_t j : candidates) ++res.operations[op_of(moves[j].line)].verification.blocks_swept;
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
                    (m.retract ? " in machine coordinates" : "") + ")");
  }
}

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
  // Every block the program holds, whoever wrote it, swept against the part.
  check_every_block(run, ops, posted, written, res);
  // The program as a whole after its points: a point's own finding names its CL line first.
  check_program(run, posted, written, res);
  res.out_cls = format_cl(run.tp, out_ops);
}

}  // namespace taxopt::pipeline
