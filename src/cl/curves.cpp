// Arcs (CIRCLE, MOVARC) and NURBS into points once the file is read (reader.hpp).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "cl/reader.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt::cl {
namespace {

/// The vote of one straight move on an arc's sense: +1 when it runs along the
/// counter-clockwise tangent (about n, at radius vector r), -1 against it, 0 undecided.
/// `strong` is cleared when the vote is less than clear-cut.
int tangent_vote(const Vec3d& move, const Vec3d& radius, const Vec3d& n, bool& strong) {
  // A CAM system writes a straight move into an arc along its tangent: the real files' votes
  // lie within 0.01 deg (SOLIDWORKS CAM, Creo, Fusion) or 3.6 deg (NX's long moves) of it. A
  // corner says nothing of the sense, even a shallow one: SOLIDWORKS CAM's boss outline meets
  // its straight moves at 12.6 deg, and counting those refused the file (issue 62).
  constexpr double kTangentCos = 0.99619;  // cos 5 deg
  constexpr double kClearCos = 0.99985;    // cos 1 deg
  const Vec3d in_plane = move - move.dot(n) * n;
  const Vec3d tangent = n.cross(radius - radius.dot(n) * n);
  const double m = move.norm(), p = in_plane.norm(), t = tangent.norm();
  if (m < 1e-9 || t < 1e-9 || p < 0.5 * m) return 0;  // a plunge or no move: says nothing
  const double c = in_plane.dot(tangent) / (p * t);
  if (std::abs(c) < kTangentCos) return 0;  // a corner: says nothing
  if (std::abs(c) < kClearCos) strong = false;
  return c > 0.0 ? 1 : -1;
}

}  // namespace

void Reader::count_curve_points(std::size_t n, const std::string& what, int line) {
  // A budget for what a few records may ask: every point costs about 1 kB through the run
  // (measured: four MOVARC records of 400 turns at r 1000 mm, 3.6e6 chords, took 3.9 GB and
  // 14 s from a 423-byte file). 1e6 curve points is a day of machining at 0.001 mm chords.
  constexpr std::size_t kCurvePointBudget = 1000000;
  curve_points_ += n;
  if (curve_points_ > kCurvePointBudget) {
    fail(line, what + ": the file's arcs, splines and drilling cycles up to here expand to " +
                   std::to_string(curve_points_) +
                   " points, more than the 1e6 taxopt posts from such records (about 1 GB to "
                   "run): a runaway ANGLE, TIMES, knot vector or peck?");
  }
}

double Reader::arc_sweep_rad(const PendingArc& c, const Vec3d& start, const Vec3d& end_mm) {
  const Vec3d s = start - c.centre, e = end_mm - c.centre;
  const Vec3d sp = s - s.dot(c.axis) * c.axis, ep = e - e.dot(c.axis) * c.axis;
  double phi = std::atan2(sp.cross(ep).dot(c.axis), sp.dot(ep));
  if (phi <= 1e-12) phi += Constants<double>::two_pi();
  return phi + Constants<double>::two_pi() * (c.turns - 1);
}

std::vector<Vec3d> Reader::arc_chords(const PendingArc& c, const Vec3d& start,
                                      const Vec3d& end_mm) {
  const Vec3d s = start - c.centre, e = end_mm - c.centre;
  const double hs = s.dot(c.axis), he = e.dot(c.axis);
  const Vec3d sp = s - hs * c.axis, ep = e - he * c.axis;
  const double rs = sp.norm(), re = ep.norm();
  const double tol = options_.arc_tolerance_mm;
  if (rs < 1e-9 || re < 1e-9) fail(c.line, "CIRCLE: start or end point lies on its axis");
  const double r_given = c.radius_mm > 0.0 ? c.radius_mm : rs;
  const double mismatch = std::max(std::abs(rs - r_given), std::abs(re - r_given));
  // As MOVARC's ends are held (check_movarcs): a CIRCLE is an arc, and an end GOTO off its
  // circle is no arc a CAM system wrote (a 5 mm miss was posted as a spiral from radius 10
  // to 15). The allowance covers the CL file's rounding of its numbers.
  const double allowed_mm = kArcEndTolerance * scale_;
  if (mismatch > allowed_mm + 1e-6 * r_given) {
    std::ostringstream os;
    os << "CIRCLE radius " << r_given << " mm but the arc's ends lie at " << rs << " and " << re
       << " mm from its axis (more than " << allowed_mm
       << " mm apart): not an arc; the end GOTO is not on the circle";
    fail(c.line, os.str());
  }
  // TIMES,n: n revolutions in all, the last one ending at the GOTO (docs/cl-files.md).
  const double phi = arc_sweep_rad(c, start, end_mm);
  const double r_max = std::max(rs, re);
  const double step = tol < r_max ? 2.0 * std::acos(1.0 - tol / r_max) : phi;
  const double segments = std::ceil(phi / step);
  if (segments > 1e6) fail(c.line, "CIRCLE needs more than 1e6 chords: radius or TIMES too large");
  const int n = std::max(1, static_cast<int>(segments));
  const Vec3d u = sp / rs, w = c.axis.cross(u);
  std::vector<Vec3d> out;
  for (int k = 1; k < n; ++k) {
    const double t = static_cast<double>(k) / n;
    const double th = phi * t, r = rs + (re - rs) * t;
    out.push_back(c.centre + (hs + (he - hs) * t) * c.axis +
                  r * (std::cos(th) * u + std::sin(th) * w));
  }
  return out;
}

Reader::ArcVotes Reader::vote_arcs() {
  ArcVotes v;
  // Which points end or start an arc: the moves into / out of them are not straight.
  std::vector<std::set<std::size_t>> ends(tp_.operations.size()), starts(ends.size());
  for (const auto& a : arcs_) {
    starts[static_cast<std::size_t>(a.op)].insert(a.start);
    ends[static_cast<std::size_t>(a.op)].insert(a.start + 1);
  }
  for (auto& a : arcs_) {
    const auto& pts = tp_.operations[static_cast<std::size_t>(a.op)].points;
    const auto o = static_cast<std::size_t>(a.op);
    const Vec3d s = pts[a.start].tip_mm, e = pts[a.start + 1].tip_mm;
    bool strong = true;
    int in = 0, out = 0;
    if (a.start > 0 && !ends[o].count(a.start)) {
      in = tangent_vote(s - pts[a.start - 1].tip_mm, s - a.centre, a.axis, strong);
    }
    if (a.start + 2 < pts.size() && !starts[o].count(a.start + 1)) {
      out = tangent_vote(pts[a.start + 2].tip_mm - e, e - a.centre, a.axis, strong);
    }
    a.evidence = (in != 0 && out != 0 && in != out) ? 0 : (in != 0 ? in : out);
    a.strong = strong && a.evidence != 0;
    a.tangent_both_ends = in != 0 && in == out;
    if (a.movarc) continue;  // its sense is written: it does not vote on the CIRCLEs'
    ++v.circles;
    if (a.evidence > 0) ++v.ccw;
    if (a.evidence < 0) ++v.cw;
  }
  return v;
}

std::string Reader::arc_lines(int sign) const {
  std::string out;
  int n = 0;
  for (const auto& a : arcs_) {
    if (a.evidence != sign || a.movarc) continue;
    if (n++ == 5) {
      out += ", ...";
      break;
    }
    out += (out.empty() ? "" : ", ") + std::to_string(a.line);
  }
  return out;
}

ArcDirection Reader::arc_convention(const ArcVotes& v) {
  auto& rd = tp_.reading;
  ArcDirection convention = options_.arc_direction;
  if (convention != ArcDirection::Auto) {
    rd.arc_convention_source = "option";
  } else {
    // Two CAM systems' structures whose CIRCLE senses differ: the file cannot say which.
    for (const DialectEvidence::Seen& s : dialects_seen_) {
      const DialectEvidence::Seen& first = dialects_seen_.front();
      if (documented_arc_direction(s.dialect) != documented_arc_direction(first.dialect)) {
        fail(arcs_.front().line,
             "CIRCLE: the file shows two CAM systems whose arcs run in opposite senses (line " +
                 std::to_string(first.line) + ": " + first.what + "; line " +
                 std::to_string(s.line) + ": " + s.what +
                 "): which sense its arcs have is not known; give " +
                 options_.name_of("arc_direction"));
      }
    }
    convention = documented_arc_direction(rd.dialect);
    if (convention == ArcDirection::Auto) {
      // Nothing documented for this CAM system: the file's own arcs must say it clearly.
      const int decided = v.ccw + v.cw;
      if (decided == 0) {
        convention = ArcDirection::CounterClockwise;
        notice(arcs_.front().line,
               "CIRCLE: the CAM system is not recognised and no arc's neighbouring moves "
               "decide its sense; APT's counter-clockwise about (i,j,k) is assumed "
               "(" +
                   options_.name_of("arc_direction") + " cw|ccw sets it)");
      } else if (std::max(v.ccw, v.cw) >= 0.8 * decided) {
        convention = v.ccw > v.cw ? ArcDirection::CounterClockwise : ArcDirection::Clockwise;
        rd.arc_convention_source = "tangents";
        notice(arcs_.front().line,
               std::string("CIRCLE: the CAM system is not recognised; ") +
                   std::to_string(std::max(v.ccw, v.cw)) + " of " + std::to_string(decided) +
                   " decidable arcs run " +
                   (convention == ArcDirection::Clockwise ? "clockwise" : "counter-clockwise") +
                   " about their axis by the tangents of the moves beside them, so every arc "
                   "is read so (" +
                   options_.name_of("arc_direction") + " cw|ccw sets it)");
      } else {
        fail(arcs_.front().line,
             "CIRCLE: the CAM system is not recognised and its arcs disagree: " +
                 std::to_string(v.ccw) + " run counter-clockwise (lines " + arc_lines(1) +
                 ") and " + std::to_string(v.cw) + " clockwise (lines " + arc_lines(-1) +
                 ") by the moves beside them; give " + options_.name_of("arc_direction"));
      }
    }
  }
  return convention;
}

void Reader::apply_arc_convention(ArcDirection convention, const ArcVotes& v) {
  auto& rd = tp_.reading;
  const char* dialect = to_string(rd.dialect);
  rd.arc_convention = convention;
  const int convention_sign = convention == ArcDirection::Clockwise ? -1 : 1;
  const int agree = convention_sign > 0 ? v.ccw : v.cw;
  const int contra = convention_sign > 0 ? v.cw : v.ccw;
  rd.arcs_contradicting = contra;
  const std::string sense =
      convention == ArcDirection::Clockwise ? "clockwise" : "counter-clockwise";
  if (contra > agree && rd.arc_convention_source == "documented") {
    fail(arcs_.front().line,
         "CIRCLE: " + std::to_string(contra) + " of " + std::to_string(contra + agree) +
             " decidable arcs (lines " + arc_lines(-convention_sign) + ") run against the " +
             sense + " sense " + dialect +
             " files use about (i,j,k), by the moves before and after them; if the file is "
             "right, give " +
             options_.name_of("arc_direction") + " cw|ccw");
  }
  if (rd.arc_convention_source == "option") option_against_tangents(convention, agree, contra);
  for (auto& a : arcs_) {
    if (a.movarc) continue;
    a.clockwise = convention == ArcDirection::Clockwise;
    // An arc whose neighbours all clearly contradict the convention is run their way.
    if (rd.arc_convention_source != "option" && a.evidence == -convention_sign && a.strong) {
      a.clockwise = !a.clockwise;
      ++rd.arcs_reversed;
      if (rd.reversed_arc_lines.size() < 20) rd.reversed_arc_lines.push_back(a.line);
    }
  }
  // The arcs the moves beside them do not decide run by the CAM system's convention: said,
  // with what named the system.
  if (rd.arc_convention_source == "documented" && rd.arcs_decidable < rd.arcs) {
    notice(arcs_.front().line,
           "CIRCLE: " + std::to_string(rd.arcs - rd.arcs_decidable) + " of " +
               std::to_string(rd.arcs) + " arcs have no neighbouring moves that decide their " +
               "sense; they run " + sense + ", the convention of " + dialect + " (" +
               rd.dialect_evidence + "; " + options_.name_of("arc_direction") + " cw|ccw sets it)");
  }
  if (rd.arcs_reversed > 0) {
    std::string lines;
    for (int l : rd.reversed_arc_lines) lines += (lines.empty() ? "" : ", ") + std::to_string(l);
    notice(rd.reversed_arc_lines.front(),
           std::to_string(rd.arcs_reversed) + " CIRCLE record(s) (lines " + lines +
               ") are run against the " + sense + " sense " + dialect +
               " files use: the moves before and after each of them run the other way "
               "(" +
               options_.name_of("arc_direction") + " cw|ccw applies one sense to every arc)");
  }
}

void Reader::option_against_tangents(ArcDirection convention, int agree, int contra) {
  const int sign = convention == ArcDirection::Clockwise ? -1 : 1;
  // Arcs the moves on both sides meet along their tangent the other way: the option turns each
  // into the long way round (a 45 deg lead-in arc a 315 deg loop), so each is named.
  std::vector<int> both;
  for (const auto& a : arcs_) {
    if (!a.movarc && a.tangent_both_ends && a.evidence == -sign) both.push_back(a.line);
  }
  if (contra <= agree && both.empty()) return;
  std::string text = "CIRCLE: " + options_.name_of("arc_direction") + " " +
                     std::string(to_string(convention)) + " is against the tangents of " +
                     std::to_string(contra) + " of " + std::to_string(contra + agree) +
                     " decidable arcs (lines " + arc_lines(-sign) + ")";
  if (!both.empty()) {
    text += "; " + std::to_string(both.size()) + " of them are tangent at both ends only " +
            (sign > 0 ? "clockwise" : "counter-clockwise") + " and run the long way round, lines";
    for (std::size_t k = 0; k < both.size() && k < 100; ++k) {
      text += (k ? ", " : " ") + std::to_string(both[k]);
    }
    if (both.size() > 100) text += ", ...";
  }
  notice(arcs_.front().line, text + "; applied as asked");
}

void Reader::expand_arcs() {
  auto& rd = tp_.reading;
  const ArcVotes votes = vote_arcs();
  if (votes.circles == 0) {
    // No CIRCLE to decide: the report still names the sense the file's arcs would have had.
    if (options_.arc_direction != ArcDirection::Auto) {
      rd.arc_convention = options_.arc_direction;
      rd.arc_convention_source = "option";
    } else if (documented_arc_direction(rd.dialect) != ArcDirection::Auto) {
      rd.arc_convention = documented_arc_direction(rd.dialect);
    }
  } else {
    rd.arcs = votes.circles;
    rd.arcs_decidable = votes.ccw + votes.cw;
    apply_arc_convention(arc_convention(votes), votes);
  }
  check_movarcs();
  insert_chords();
}

void Reader::check_movarcs() {
  for (auto& a : arcs_) {
    if (!a.movarc) continue;
    a.clockwise = false;
    const auto& pts = tp_.operations[static_cast<std::size_t>(a.op)].points;
    const Vec3d s = pts[a.start].tip_mm, e = pts[a.start + 1].tip_mm;
    const double sweep = arc_sweep_rad(a, s, e);
    const Vec3d sr = s - a.centre;
    const double r = (sr - sr.dot(a.axis) * a.axis).norm();
    // The written ANGLE has a few decimals: within 0.01 deg, or 0.002 mm along the arc.
    const double allowed = std::max(deg_to_rad(0.01), 0.002 / std::max(r, 1e-9));
    if (std::abs(sweep - a.declared_sweep_rad) > allowed) {
      std::ostringstream os;
      os << "MOVARC: ANGLE " << rad_to_deg(a.declared_sweep_rad) << " deg, but its end GOTO lies "
         << rad_to_deg(sweep) << " deg counter-clockwise about (i,j,k) from its start";
      fail(a.line, os.str());
    }
    // The end GOTO decides the sense where the clockwise reading of ANGLE would end elsewhere:
    // the two ends lie 2 r |sin ANGLE| apart (a Fusion arc after a 0.112 mm reversed move, a
    // cusp, ended 1.7e-6 mm from its counter-clockwise end and 1.22 mm from the other, and the
    // neighbouring moves' vote refused its file). Only where they meet (ANGLE 180 or 360 deg)
    // do the moves beside it say.
    const double ends_apart_mm = 2.0 * r * std::abs(std::sin(a.declared_sweep_rad));
    if (a.evidence < 0 && a.strong && ends_apart_mm <= 0.01) {
      fail(a.line,
           "MOVARC: the moves before and after it run clockwise about its axis, "
           "against the counter-clockwise sweep it writes");
    }
    ++tp_.reading.arcs;
  }
}

void Reader::insert_chords() {
  std::vector<std::vector<const PendingArc*>> by_op(tp_.operations.size());
  for (const auto& a : arcs_) by_op[static_cast<std::size_t>(a.op)].push_back(&a);
  for (std::size_t o = 0; o < by_op.size(); ++o) {
    if (by_op[o].empty()) continue;
    auto& pts = tp_.operations[o].points;
    std::vector<CLPointd> out;
    std::vector<std::size_t> after(pts.size(), 0);  // out's size after point i's own entry
    std::size_t next = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      out.push_back(pts[i]);
      after[i] = out.size();
      while (next < by_op[o].size() && by_op[o][next]->start == i) {
        PendingArc a = *by_op[o][next++];
        if (a.clockwise) a.axis = -a.axis;
        const CLPointd& end = pts[i + 1];
        const std::vector<Vec3d> chords = arc_chords(a, pts[i].tip_mm, end.tip_mm);
        ArcRun run;
        run.start = out.size() - 1;
        run.end = run.start + chords.size() + 1;
        run.centre_mm = a.centre;
        run.normal = a.axis;
        run.start_tip_mm = pts[i].tip_mm;
        run.sweep_rad = arc_sweep_rad(a, pts[i].tip_mm, end.tip_mm);
        tp_.operations[o].arcs.push_back(run);
        points_ += chords.size();
        if (points_ > 20000000) fail(a.line, "more than 2e7 CL points: the file cannot be posted");
        count_curve_points(chords.size(), a.movarc ? "MOVARC" : "CIRCLE", a.line);
        for (const Vec3d& q : chords) {
          check_reach(q, "CIRCLE", a.line);
          CLPointd p = end;
          p.tip_mm = q;
          p.motion = Motion::Feed;
          p.line = a.line;
          p.record = a.record;
          out.push_back(p);
        }
      }
    }
    for (ProgramEvent& e : tp_.operations[o].events) {
      if (e.before_point > 0) e.before_point = after[e.before_point - 1];
    }
    pts = std::move(out);
  }
}

void Reader::index_records() {
  for (auto& r : tp_.records) {
    r.op = -1;
    r.first_point = -1;
    r.point_count = 0;
  }
  for (std::size_t o = 0; o < tp_.operations.size(); ++o) {
    const auto& pts = tp_.operations[o].points;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (pts[i].record < 0) continue;
      auto& r = tp_.records[static_cast<std::size_t>(pts[i].record)];
      if (r.first_point < 0) r.first_point = static_cast<int>(i);
      r.op = static_cast<int>(o);
      ++r.point_count;
    }
  }
}

std::vector<double> Reader::clamped_knots(const PendingSpline& sp, int p,
                                          const std::string& what) const {
  double prev = 0.0;
  for (double k : sp.knots) {
    if (k < prev || k > 1.0 + 1e-9) {
      fail(sp.line, what + ": knots must rise from 0 to 1");
    }
    prev = k;
  }
  // The list follows the p + 1 zeros and ends with the last 1: a 0 in it, or a 1 before its
  // end, would give an end knot more than p + 1 times (no clamped B-spline).
  for (std::size_t i = 0; i + 1 < sp.knots.size(); ++i) {
    if (!(sp.knots[i] > 0.0 && sp.knots[i] < 1.0)) {
      fail(sp.line, what + ": knot " + std::to_string(i + 1) +
                        " repeats an end knot (0 or 1) beyond the degree + 1 times");
    }
  }
  if (std::abs(sp.knots.back() - 1.0) > 1e-6) fail(sp.line, what + ": the last knot must be 1");
  std::vector<double> U(static_cast<std::size_t>(p + 1), 0.0);
  U.insert(U.end(), sp.knots.begin(), sp.knots.end() - 1);
  U.insert(U.end(), static_cast<std::size_t>(p + 1), 1.0);
  for (std::size_t i = static_cast<std::size_t>(p + 1);
       i + static_cast<std::size_t>(p + 1) < U.size(); ++i) {
    std::size_t mult = 1;
    while (i + mult < U.size() && U[i + mult] == U[i]) ++mult;
    if (U[i] < 1.0 && mult > static_cast<std::size_t>(p)) {
      fail(sp.line, what + ": an inner knot repeats more than the degree");
    }
  }
  return U;
}

namespace {

/// Rational B-spline point at t (de Boor on homogeneous coordinates).
Vec3d spline_point(const std::vector<double>& U, const std::vector<Eigen::Vector4d>& P, int p,
                   double t) {
  const int n = static_cast<int>(P.size()) - 1;
  // The knot span of t: the last k in [p, n] with U[k] <= t, by bisection (a walk from p made
  // reading one NURBS quadratic in its knots: 40k knots 8.2 s).
  const auto first_above = std::upper_bound(U.begin() + p + 1, U.begin() + n + 1, t);
  const int k = static_cast<int>(first_above - U.begin()) - 1;
  std::vector<Eigen::Vector4d> d(static_cast<std::size_t>(p + 1));
  for (int j = 0; j <= p; ++j) {
    const Eigen::Vector4d& c = P[static_cast<std::size_t>(j + k - p)];
    d[static_cast<std::size_t>(j)] << c.head<3>() * c[3], c[3];
  }
  for (int r = 1; r <= p; ++r) {
    for (int j = p; j >= r; --j) {
      const double lo = U[static_cast<std::size_t>(j + k - p)];
      const double hi = U[static_cast<std::size_t>(j + 1 + k - r)];
      const double alpha = hi > lo ? (t - lo) / (hi - lo) : 0.0;
      d[static_cast<std::size_t>(j)] = (1.0 - alpha) * d[static_cast<std::size_t>(j - 1)] +
                                       alpha * d[static_cast<std::size_t>(j)];
    }
  }
  const Eigen::Vector4d& h = d[static_cast<std::size_t>(p)];
  return h.head<3>() / h[3];
}

/// A NURBS curve (knots U, weighted control points P, degree p) sampled within a chordal
/// tolerance.
struct SplineSampler {
  const std::vector<double>& U;
  const std::vector<Eigen::Vector4d>& P;
  int p;
  double tol_mm;
  std::vector<Vec3d> out;

  /// The curve from t0 (at a) to t1 (at b), halved while it strays from the chord; false
  /// past 1e6 points.
  bool piece(double t0, const Vec3d& a, double t1, const Vec3d& b, int depth) {
    const Vec3d chord = b - a;
    const double len = chord.norm();
    double dev = 0.0;
    for (double f : {0.25, 0.5, 0.75}) {
      const Vec3d q = spline_point(U, P, p, t0 + f * (t1 - t0)) - a;
      const double along = len > 0.0 ? q.dot(chord) / len : 0.0;
      dev = std::max(dev, len > 0.0 ? (q - along * chord / len).norm() : q.norm());
    }
    if (dev > tol_mm && depth < 40) {
      const double tm = 0.5 * (t0 + t1);
      const Vec3d mpt = spline_point(U, P, p, tm);
      return piece(t0, a, tm, mpt, depth + 1) && piece(tm, mpt, t1, b, depth + 1);
    }
    if (out.size() >= 1000000) return false;
    out.push_back(b);
    return true;
  }

  /// The whole curve from `start`: each knot span in 4 pieces, then halved.
  bool curve(const Vec3d& start) {
    Vec3d a = start;
    double t0 = 0.0;
    for (std::size_t i = static_cast<std::size_t>(p); i + 1 < U.size(); ++i) {
      if (!(U[i + 1] > U[i])) continue;
      for (int k = 1; k <= 4; ++k) {
        const double t1 = U[i] + (U[i + 1] - U[i]) * k / 4.0;
        const Vec3d b = spline_point(U, P, p, t1);
        if (!piece(t0, a, t1, b, 0)) return false;
        a = b;
        t0 = t1;
      }
    }
    return true;
  }
};

}  // namespace

void Reader::finish_spline() {
  PendingSpline sp = std::move(*spline_);
  spline_.reset();
  const std::string what = "NURBS at line " + std::to_string(sp.line);
  if (sp.control.empty() || sp.knots.empty()) fail(sp.line, "NURBS without KNOT and CNTRL");
  const Vec3d start = last_point("NURBS", sp.line).tip_mm;
  const int m = static_cast<int>(sp.control.size());
  const int p = m + 1 - static_cast<int>(sp.knots.size());
  if (p < 1 || p > 9) {
    fail(sp.line, what + ": " + std::to_string(sp.knots.size()) + " knots and " +
                      std::to_string(m) +
                      " control points do not fit NX's layout (degree = control points + 1 - "
                      "knots, from 1 to 9)");
  }
  const std::vector<double> U = clamped_knots(sp, p, what);
  std::vector<Eigen::Vector4d> P;
  P.emplace_back(start.x(), start.y(), start.z(), 1.0);
  P.insert(P.end(), sp.control.begin(), sp.control.end());
  SplineSampler sampler{U, P, p, options_.arc_tolerance_mm, {}};
  if (!sampler.curve(start)) fail(sp.line, what + " needs more than 1e6 points");
  const std::vector<Vec3d>& out = sampler.out;
  count_curve_points(out.size(), what, sp.line);
  for (const Vec3d& q : out) add_point(q, sp.motion, sp.record, sp.line);
  ++tp_.reading.splines;
  tp_.reading.spline_points += static_cast<int>(out.size());
}

}  // namespace taxopt::cl
