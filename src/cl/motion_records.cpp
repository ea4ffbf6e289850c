// The CL records that move the tool or set where it moves (reader.hpp).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "cl/reader.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt::cl {

Vec3d Reader::to_mcs_point(const Vec3d& p) const {
  const Vec3d mm = p * scale_;
  if (frame_ < 0) return mm;
  const ClFrame& f = tp_.frames[static_cast<std::size_t>(frame_)];
  return f.rotation.transpose() * (mm - f.origin_mm);
}

Vec3d Reader::to_mcs_vector(const Vec3d& v) const {
  if (frame_ < 0) return v;
  return tp_.frames[static_cast<std::size_t>(frame_)].rotation.transpose() * v;
}

void Reader::add_point(const Vec3d& tip_mm, Motion motion, int record, int line) {
  if (++points_ > 20000000) fail(line, "more than 2e7 CL points: the file cannot be posted");
  check_reach(tip_mm, tp_.records[static_cast<std::size_t>(record)].major, line);
  auto& op = current_op();
  CLPointd p;
  p.tip_mm = tip_mm;
  p.axis = axis_;
  if (motion == Motion::Feed && feed_per_rev_mm_ > 0.0 && !(feed_mm_per_min_ > 0.0)) {
    fail(line, "a feed move at a feed per revolution (FEDRAT, line " + std::to_string(feed_line_) +
                   ") with no spindle speed in force: its feed per minute is unknown (SPINDL "
                   "before it)");
  }
  p.feed_mm_per_min = feed_mm_per_min_;
  p.motion = motion;
  p.line = line;
  p.record = record;
  tp_.records[static_cast<std::size_t>(record)].frame = frame_;
  op.points.push_back(p);
  if (tolerance_given_) {
    const double band_mm = std::max(inside_tolerance_, outside_tolerance_) * scale_;
    op.cam_tolerance_mm = std::max(op.cam_tolerance_mm.value_or(0.0), band_mm);
  }
}

void Reader::check_reach(const Vec3d& p_mm, const std::string& major, int line) const {
  if (p_mm.cwiseAbs().maxCoeff() > kMaxCoordinateMm) {
    std::ostringstream os;
    os << major << ": point (" << p_mm.x() << ", " << p_mm.y() << ", " << p_mm.z()
       << ") mm lies beyond +-1e6 mm: not a machinable coordinate";
    fail(line, os.str());
  }
}

const CLPointd& Reader::last_point(const std::string& major, int line) {
  auto& op = current_op();
  if (op.points.empty()) fail(line, major + " has no start point (no GOTO or FROM before it)");
  return op.points.back();
}

void Reader::start_cycle(const std::vector<std::string>& args, int line) {
  DrillCycle c;
  c.kind = upper(args[0]);
  c.line = line;
  static const std::set<std::string> kinds = {"DRILL",  "FACE", "DEEP", "DEEP2",
                                              "BRKCHP", "BORE", "REAM"};
  if (c.kind == "TAP") {
    // A tap goes in and out at the feed of its pitch with the spindle reversing at the
    // bottom (the dialects' G84); posted as a feed in and out with the spindle turning
    // forward both ways, it would strip the thread.
    fail(line,
         "CYCLE/TAP: a tapping cycle is not posted (it needs the dialect's tapping cycle, "
         "pitch and spindle reversal); post the holes with the CAM system's own post");
  }
  if (!kinds.count(c.kind)) {
    fail(line, "CYCLE/" + c.kind +
                   ": drilling cycle not interpreted (DRILL, FACE, DEEP, DEEP2, BRKCHP, BORE, "
                   "REAM are)");
  }
  c.feed_out = c.kind == "BORE" || c.kind == "REAM" || c.kind == "TAP";
  bool depth = false;
  std::vector<std::string> feed_words;
  for (std::size_t k = 1; k < args.size(); ++k) {
    const std::string w = upper(args[k]);
    double v = 0.0;
    const auto value = [&]() {
      if (k + 1 >= args.size() || !parse_number(args[k + 1], v)) {
        fail(line, "CYCLE/" + c.kind + ": " + w + " expects a number after it");
      }
      ++k;
      return v;
    };
    if (w == "FEDTO") {
      c.depth_mm = value() * scale_;
      depth = true;
    } else if (w == "RAPTO") {
      c.rapid_to_mm = value() * scale_;
    } else if (w == "RTRCTO") {
      c.retract_to_mm = value() * scale_;
    } else if (w == "1STPECK") {
      c.first_peck_mm = value() * scale_;
    } else if (w == "SUBPECK" || w == "STEP") {
      c.next_peck_mm = value() * scale_;
    } else if (w == "DWELL") {
      value();  // time at the bottom: no motion
    } else if (w == "MMPM" || w == "IPM" || w == "PERMIN" || w == "MMPR" || w == "IPR" ||
               w == "PERREV") {
      feed_words = {args[k], std::to_string(value())};
      c.feed_mm_per_min = feed_of(feed_words, 0, "CYCLE/" + c.kind, line);
    } else {
      fail(line, "CYCLE/" + c.kind + ": '" + args[k] +
                     "' not interpreted (FEDTO, RAPTO, RTRCTO, 1STPECK, SUBPECK, DWELL and a "
                     "feed word are; APT's positional form is not)");
    }
  }
  if (!depth || !(c.depth_mm > 0.0)) fail(line, "CYCLE/" + c.kind + " needs FEDTO,depth > 0");
  if (c.feed_mm_per_min <= 0.0) c.feed_mm_per_min = feed_mm_per_min_;
  const bool pecks = c.kind == "DEEP" || c.kind == "DEEP2" || c.kind == "BRKCHP";
  if (pecks && !(c.first_peck_mm > 0.0)) c.first_peck_mm = c.depth_mm;
  if (pecks && !(c.next_peck_mm > 0.0)) c.next_peck_mm = c.first_peck_mm;
  if (!pecks) c.first_peck_mm = c.next_peck_mm = c.depth_mm;
  if (c.depth_mm / c.next_peck_mm > 1e4) fail(line, "CYCLE: more than 1e4 pecks");
  cycle_ = c;
}

void Reader::drill_hole(const Vec3d& top, int record, int line) {
  const DrillCycle& c = *cycle_;
  const Vec3d u = axis_;
  const double clear = std::max(c.retract_to_mm, c.rapid_to_mm);
  const double saved_feed = feed_mm_per_min_;
  const std::size_t points_before = points_;
  add_point(top + clear * u, Motion::Rapid, record, line);
  add_point(top + c.rapid_to_mm * u, Motion::Rapid, record, line);
  feed_mm_per_min_ = c.feed_mm_per_min;
  double reached = 0.0;
  while (reached < c.depth_mm - 1e-9) {
    const double next =
        std::min(c.depth_mm, reached + (reached == 0.0 ? c.first_peck_mm : c.next_peck_mm));
    if (reached > 0.0) {
      // Back to the rapid plane, then down to a clearance above the depth reached (a rapid
      // onto the chips at the very depth would strike them).
      add_point(top + c.rapid_to_mm * u, Motion::Rapid, record, line);
      const double back = std::max(reached - options_.peck_clearance_mm, -c.rapid_to_mm);
      add_point(top - back * u, Motion::Rapid, record, line);
    }
    add_point(top - next * u, Motion::Feed, record, line);
    reached = next;
  }
  add_point(top + clear * u, c.feed_out ? Motion::Feed : Motion::Rapid, record, line);
  feed_mm_per_min_ = saved_feed;
  // A hole is one GOTO: its pecks count against what the file's few records may ask.
  count_curve_points(points_ - points_before, "CYCLE", line);
  ++tp_.reading.cycle_holes;
}

void Reader::goto_record(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.size() != 3 && args.size() != 6) {
    fail(line, major + " expects 3 or 6 numbers (x,y,z[,i,j,k]), got " +
                   std::to_string(args.size()) + " fields");
  }
  const auto v = numbers(args, 0, args.size(), major, line);
  if (v.size() == 6 && multax_off_line_ > 0) {
    fail(line, major + " gives a tool axis after MULTAX/OFF (line " +
                   std::to_string(multax_off_line_) +
                   "): a 3-axis file with a 5-axis point is not interpreted");
  }
  if (v.size() == 6) axis_ = to_mcs_vector(parse_axis(v, 3, major, line));
  const Vec3d tip = to_mcs_point(Vec3d(v[0], v[1], v[2]));
  ++tp_.reading.motion_records;
  last_arc_circle_.reset();
  if (pending_circle_) {
    const CircleRecord c = *pending_circle_;
    last_arc_circle_ = c;
    pending_circle_.reset();
    PendingArc a;
    last_point("CIRCLE", c.line);  // the arc starts at the point before its end GOTO
    a.op = op_;
    a.start = current_op().points.size() - 1;
    a.centre = c.centre;
    a.axis = c.axis;
    a.radius_mm = c.radius_mm;
    a.turns = c.turns;
    a.record = c.record;
    a.line = c.line;
    a.movarc = c.movarc;
    a.declared_sweep_rad = c.declared_sweep_rad;
    arcs_.push_back(a);
  }
  if (major == "FROM") {
    home_ = std::make_pair(tip, axis_);
  }
  if (cycle_ && major == "GOTO") {
    rapid_next_ = false;
    drill_hole(tip, index, line);
    return;
  }
  const Motion m = (major == "FROM" || rapid_next_) ? Motion::Rapid : Motion::Feed;
  rapid_next_ = false;
  add_point(tip, m, index, line);
}

void Reader::godlta(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.size() != 1 && args.size() != 3) {
    fail(line, "GODLTA expects dx,dy,dz or a distance along the tool axis");
  }
  const auto v = numbers(args, 0, args.size(), major, line);
  const Vec3d from = last_point(major, line).tip_mm;
  const Vec3d delta = v.size() == 3 ? to_mcs_vector(Vec3d(v[0], v[1], v[2])) * scale_
                                    : Vec3d(axis_ * (v[0] * scale_));
  ++tp_.reading.motion_records;
  const Motion m = rapid_next_ ? Motion::Rapid : Motion::Feed;
  rapid_next_ = false;
  add_point(from + delta, m, index, line);
}

void Reader::gohome(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // APT's GOHOME returns to the FROM point; NX's CLSF writes its Gohome point in the record
  // (GOHOME/x,y,z[,i,j,k]): that point, as NX's posts move to it (read as the FROM point,
  // the program lost its end point and ran an 811.6 mm diagonal rising from 7 mm above
  // the holes).
  ++tp_.reading.motion_records;
  rapid_next_ = false;
  if (args.empty()) {
    if (!home_) fail(line, "GOHOME: no FROM point to return to");
    axis_ = home_->second;
    add_point(home_->first, Motion::Rapid, index, line);
  } else {
    if (args.size() != 3 && args.size() != 6) {
      fail(line, "GOHOME expects no numbers (the FROM point) or x,y,z[,i,j,k], got " +
                     std::to_string(args.size()) + " fields");
    }
    const auto v = numbers(args, 0, args.size(), major, line);
    if (v.size() == 6) axis_ = to_mcs_vector(parse_axis(v, 3, major, line));
    add_point(to_mcs_point(Vec3d(v[0], v[1], v[2])), Motion::Rapid, index, line);
  }
}

void Reader::circle(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  std::size_t nnum = 0;
  while (nnum < args.size() && is_number_like(args[nnum])) ++nnum;
  if (nnum < 6) fail(line, "CIRCLE expects at least 6 numbers (xc,yc,zc,i,j,k[,r,...])");
  const auto v = numbers(args, 0, nnum, major, line);
  CircleRecord c;
  c.centre = to_mcs_point(Vec3d(v[0], v[1], v[2]));
  c.axis = to_mcs_vector(parse_axis(v, 3, major, line));
  c.radius_mm = nnum >= 7 ? v[6] * scale_ : 0.0;
  // A radius written is the arc's (6 numbers: SOLIDWORKS, the start point gives it).
  if (nnum >= 7 && !(c.radius_mm > 0.0)) fail(line, "CIRCLE radius must be positive");
  for (std::size_t k = nnum; k < args.size(); ++k) {
    if (upper(args[k]) == "TIMES") {
      double t = 0.0;
      if (k + 1 >= args.size() || !parse_number(args[k + 1], t) || t < 1 || t > 1000 ||
          t != std::floor(t)) {
        fail(line, "CIRCLE TIMES expects a whole number from 1 to 1000");
      }
      c.turns = static_cast<int>(t);
      ++k;
    } else {
      fail(line, "CIRCLE: '" + args[k] + "' not interpreted (only TIMES,n may follow the numbers)");
    }
  }
  pend_circle(c, index, line);
}

void Reader::movarc(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // Fusion / HSM: MOVARC/xc,yc,zc,i,j,k,r,ANGLE,a -- the arc to the next GOTO sweeps a deg
  // counter-clockwise about (i,j,k).
  if (args.size() != 9 || upper(args[7]) != "ANGLE") {
    fail(line, "MOVARC expects xc,yc,zc,i,j,k,r,ANGLE,degrees (Fusion's form), got " +
                   std::to_string(args.size()) + " fields");
  }
  auto v = numbers(args, 0, 7, major, line);
  const double angle_deg = numbers(args, 8, 9, major, line)[0];
  if (!(v[6] > 0.0)) fail(line, "MOVARC radius must be positive");
  if (!(angle_deg > 0.0 && angle_deg <= 360.0 * 1000)) {
    fail(line, "MOVARC ANGLE must be within (0, 360000] deg");
  }
  CircleRecord c;
  c.centre = to_mcs_point(Vec3d(v[0], v[1], v[2]));
  c.axis = to_mcs_vector(parse_axis(v, 3, major, line));
  c.radius_mm = v[6] * scale_;
  c.movarc = true;
  c.declared_sweep_rad = deg_to_rad(angle_deg);
  c.turns = 1 + static_cast<int>(std::floor((angle_deg - 1e-6) / 360.0));
  pend_circle(c, index, line);
}

void Reader::tlaxis(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.size() != 3) {
    fail(line, "TLAXIS expects i,j,k (the tool axis); other forms are not interpreted");
  }
  axis_ = to_mcs_vector(parse_axis(numbers(args, 0, 3, major, line), 0, major, line));
}

void Reader::nurbs(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (!args.empty()) {
    fail(line, "NURBS/" + args_text +
                   ": only NX's bare NURBS/ followed by KNOT/ and CNTRL/ is interpreted");
  }
  PendingSpline sp;
  sp.record = index;
  sp.line = line;
  sp.motion = rapid_next_ ? Motion::Rapid : Motion::Feed;
  rapid_next_ = false;
  spline_ = sp;
  ++tp_.reading.motion_records;
}

void Reader::rapid(const ClRecordArgs&) { rapid_next_ = true; }

void Reader::msys(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.size() != 9) fail(line, "MSYS expects 9 numbers (origin, x axis, y axis)");
  const auto v = numbers(args, 0, 9, major, line);
  const Vec3d x = parse_axis(v, 3, major, line), y = parse_axis(v, 6, major, line);
  if (std::abs(x.dot(y)) > 1e-3) fail(line, "MSYS: its x and y axes are not perpendicular");
  ClFrame f;
  f.rotation.col(0) = x;
  f.rotation.col(1) = (y - y.dot(x) * x).normalized();
  f.rotation.col(2) = x.cross(f.rotation.col(1));
  f.origin_mm = Vec3d(v[0], v[1], v[2]) * scale_;
  f.line = line;
  const bool identity = (f.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9 &&
                        f.origin_mm.norm() < 1e-9;
  frame_ = -1;
  if (identity) return;
  std::ostringstream os;
  os << "MSYS: MCS at (" << v[0] << ", " << v[1] << ", " << v[2] << "), its z axis ("
     << f.rotation(0, 2) << ", " << f.rotation(1, 2) << ", " << f.rotation(2, 2) << ")";
  if (!options_.apply_msys) {
    tp_.declared_frames.push_back(f);
    notice(line,
           os.str() + ": the coordinates are posted as written (NX writes them in this MCS; " +
               options_.name_of("apply_msys") + " takes them as absolute and moves them into it)");
    return;
  }
  tp_.frames.push_back(f);
  frame_ = static_cast<int>(tp_.frames.size()) - 1;
  ++tp_.reading.msys_applied;
  notice(line, os.str() + ": " + options_.name_of("apply_msys") +
                   ", the coordinates that follow are moved into it and posted there");
}

void Reader::multax(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (!args.empty() && upper(args[0]) == "OFF") {
    axis_ = Vec3d::UnitZ();  // 3-axis: +Z
    multax_off_line_ = line;
  } else if (args.empty() || upper(args[0]) == "ON") {
    multax_off_line_ = 0;
  } else {
    fail(line, "MULTAX/" + args_text + ": MULTAX, MULTAX/ON or MULTAX/OFF");
  }
}

void Reader::cycle(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.empty()) fail(line, "CYCLE expects a cycle type, INIT or OFF");
  const std::string kind = upper(args[0]);
  if (kind == "OFF") {
    cycle_.reset();
  } else if (kind != "INIT" && kind != "ON") {
    start_cycle(args, line);
  }
}

void Reader::pend_circle(CircleRecord c, int index, int line) {
  c.record = index;
  c.line = line;
  tp_.records[static_cast<std::size_t>(index)].frame = frame_;
  pending_circle_ = c;
}

}  // namespace taxopt::cl
