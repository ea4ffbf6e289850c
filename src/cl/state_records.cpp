// The CL records that change what the moves mean: feed, tool, spindle, coolant, tolerances and
// modes (reader.hpp).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "cl/reader.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt::cl {

Operationd& Reader::current_op() {
  if (op_ < 0) {
    Operationd op;
    op.name = pending_name_;
    op.tool = tool_;
    op.spindle_rpm = spindle_rpm_;
    op.spindle_clockwise = spindle_cw_;
    op.coolant = coolant_;
    tp_.operations.push_back(op);
    op_ = static_cast<int>(tp_.operations.size()) - 1;
    pending_name_.clear();
  }
  return tp_.operations[static_cast<std::size_t>(op_)];
}

void Reader::tool_changed() {
  if (op_ >= 0) {
    auto& op = tp_.operations[static_cast<std::size_t>(op_)];
    // A FROM before the first tool is the program's start point, not an operation of its own
    // (a Makino FF file: FROM, then SELECT/TOOL and LOAD/TOOL; it made a tool-less operation,
    // refused for its missing tool, or written as an approach, a retract and the approach
    // again): the tool's operation starts there.
    const bool only_start =
        !op.tool.number && !(op.tool.diameter_mm > 0.0) &&
        std::all_of(op.points.begin(), op.points.end(), [&](const CLPointd& p) {
          return p.record >= 0 && tp_.records[static_cast<std::size_t>(p.record)].major == "FROM";
        });
    if (!op.points.empty() && !only_start) {
      const std::string name = in_block_ ? op.name : std::string();
      op_ = -1;
      pending_name_ = name;
    } else {
      op.tool = tool_;
    }
  }
}

double Reader::bounded_feed(double mm_per_min, const std::string& major, int line) {
  // A feed the G-code can write (0.01 mm/min is F0.0004 in inches) and a machine can run
  // (1e6 mm/min is 1 km/min).
  if (!(mm_per_min >= 0.01 && mm_per_min <= 1e6)) {
    std::ostringstream os;
    os << major << ": a feed of " << mm_per_min
       << " mm/min is outside [0.01, 1e6] mm/min (no program writes or runs it)";
    fail(line, os.str());
  }
  return mm_per_min;
}

double Reader::feed_of(const std::vector<std::string>& args, std::size_t from,
                       const std::string& major, int line, double* per_rev_mm) {
  double value = -1.0;
  int count = 0;
  double to_mm = scale_;
  bool per_rev = false;
  for (std::size_t k = from; k < args.size(); ++k) {
    const std::string u = upper(args[k]);
    double v;
    if (parse_number(args[k], v)) {
      value = v;
      ++count;
    } else if (u == "MMPM") {
      to_mm = options_.units ? scale_ : 1.0;  // --units reads the feed words in its unit too
    } else if (u == "IPM") {
      to_mm = options_.units ? scale_ : kMmPerInch;
    } else if (u == "PERMIN") {
      to_mm = scale_;
    } else if (u == "MMPR") {
      to_mm = options_.units ? scale_ : 1.0, per_rev = true;
    } else if (u == "IPR") {
      to_mm = options_.units ? scale_ : kMmPerInch, per_rev = true;
    } else if (u == "PERREV") {
      to_mm = scale_, per_rev = true;
    } else {
      fail(line, major + ": expected a feed and MMPM, IPM, PERMIN, MMPR, IPR or PERREV, got '" +
                     args[k] + "'");
    }
  }
  if (count != 1) fail(line, major + " expects exactly one number (the feed)");
  if (!(value > 0.0)) fail(line, major + ": feed must be positive");
  if (per_rev_mm) *per_rev_mm = per_rev ? value * to_mm : 0.0;
  if (!per_rev) return bounded_feed(value * to_mm, major, line);
  if (per_rev_mm && value * to_mm > 1e3) {
    fail(line, major + ": a feed of " + std::to_string(value * to_mm) +
                   " mm per revolution is no cutting feed");
  }
  if (!(spindle_rpm_ > 0.0)) {
    if (!per_rev_mm) {
      tp_.warnings.push_back(format_location(
          source_, line, "feed per revolution without a spindle speed: feed unknown"));
    }
    return 0.0;
  }
  return bounded_feed(value * to_mm * spindle_rpm_, major, line);
}

void Reader::fedrat(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  feed_mm_per_min_ = feed_of(args, 0, major, line, &feed_per_rev_mm_);
  feed_line_ = line;
}

void Reader::tldata(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.empty() || upper(args[0]) != "MILL") {
    tp_.warnings.push_back(format_location(source_, line, "TLDATA other than MILL ignored"));
    skipped(major);
    return;
  }
  if (args.size() < 3) fail(line, "TLDATA/MILL expects diameter and corner radius");
  const auto v = numbers(args, 1, args.size(), major, line);
  set_tool(v[0], v[1], v.size() > 2 ? v[2] : 0.0, line);
}

void Reader::cutter(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.empty()) fail(line, "CUTTER expects a diameter");
  const auto v = numbers(args, 0, std::min<std::size_t>(args.size(), 7), major, line);
  if (v.size() == 7 && v[0] > 0.0 && v[1] > 0.5 * v[0] + 1e-9) {
    tapered_ball(v, line);
    return;
  }
  set_tool(v[0], v.size() > 1 ? v[1] : 0.0, v.size() > 6 ? v[6] : 0.0, line);
}

namespace {

std::string args_text_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

LoadtlWords Reader::loadtl_words(const std::vector<std::string>& args, std::size_t at,
                                 bool positional, int line, const std::string& shown) {
  LoadtlWords w;
  double n[3];
  if (positional && args.size() == at + 4 && parse_number(args[at + 1], n[0]) &&
      parse_number(args[at + 2], n[1]) && parse_number(args[at + 3], n[2])) {
    w.length = n[1];
    w.register_ = n[2];
    return w;
  }
  for (std::size_t k = at + 1; k < args.size(); ++k) {
    const std::string word = upper(args[k]);
    double value = 0.0;
    const bool valued = k + 1 < args.size() && parse_number(args[k + 1], value);
    if (valued && (word == "ADJUST" || word == "OSETNO")) {
      w.register_ = value;
    } else if (valued && word == "LENGTH") {
      w.length = value;
    } else if (!(valued && word == "IN")) {
      fail(line, shown + ": '" + args[k] +
                     "' not interpreted (ADJUST or OSETNO with the tool's own number, LENGTH "
                     "and IN with a number may follow, or Fusion's pocket, length and offset)");
    }
    ++k;
  }
  return w;
}

void Reader::load_tool(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (major == "LOAD" && (args.empty() || upper(args[0]) != "TOOL")) {
    fail(line, "LOAD/" + args_text + ": only LOAD/TOOL,n is interpreted");
  }
  const std::size_t at = major == "LOADTL" ? 0 : 1;
  if (args.size() <= at) fail(line, major + " expects a tool number");
  const auto v = numbers(args, at, at + 1, major, line);
  // As --tool-number: five digits, what the dialects' T words take.
  if (!(v[0] >= 0.0 && v[0] <= 99999.0 && v[0] == std::floor(v[0]))) {
    fail(line, major + ": tool number must be a whole number from 0 to 99999");
  }
  const LoadtlWords words =
      loadtl_words(args, at, major == "LOADTL", line, major + "/" + args_text);
  if (words.length && !(*words.length > 0.0 && *words.length * scale_ <= 1000.0)) {
    fail(line, major + "/" + args_text + ": the tool length must be in (0, 1000] mm");
  }
  if (words.register_ && v[0] == 0.0) {
    fail(line, major + "/" + args_text + ": tool 0 is no tool number (T0 loads none), so the " +
                   "length offset register " + args_text_number(*words.register_) +
                   " belongs to no tool: number the tool in the CAM system (1 to 99999; " +
                   "taxopt writes its own register, T1 H1)");
  }
  if (words.register_ && *words.register_ != v[0]) {
    fail(line, major + "/" + args_text + ": the length offset register " +
                   args_text_number(*words.register_) +
                   " is not the tool's number; taxopt writes the tool's own (H" + args[at] +
                   "): give the tool its own register in the CAM system");
  }
  if (announced_tool_ && announced_tool_->number != static_cast<int>(v[0])) {
    fail(line, major + "/" + args_text + " loads tool " + args[at] + " where TOOLNO at line " +
                   std::to_string(announced_tool_->line) + " announced tool " +
                   std::to_string(announced_tool_->number) +
                   ": which tool the machine holds is not known (" +
                   options_.name_of("skip_records") + " TOOLNO trusts the LOADTL)");
  }
  announced_tool_.reset();
  tool_.number = static_cast<int>(v[0]);
  tool_.gauge_length_mm = words.length ? *words.length * scale_ : 0.0;
  if (words.length) {
    notice(line, major + ": the tool's length below the holder, " +
                     args_text_number(tool_.gauge_length_mm) +
                     " mm, is the collision check's gauge length unless an option or the "
                     "machine file's holder gives one");
  }
  tool_changed();
}

void Reader::toolno(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // CATIA V5 writes TOOLNO/number, diameter before TPRINT and the LOADTL that loads the tool
  // (its NC Manufacturing documentation, "Import APT Source File": TOOLNO/1, 10.000000 /
  // TPRINT/T1 End Mill D 10 / LOADTL; tests/data/real/peening-catia-multax.aptsource the same
  // after its CUTTER). The number is checked against the LOADTL, the diameter against the
  // CUTTER; the change is the LOADTL's.
  if (args.empty() || args.size() > 2) {
    fail(line, "TOOLNO expects a tool number and a diameter (CATIA's TOOLNO/n,d), got " +
                   std::to_string(args.size()) + " fields");
  }
  const auto v = numbers(args, 0, args.size(), major, line);
  if (!(v[0] >= 0.0 && v[0] <= 99999.0 && v[0] == std::floor(v[0]))) {
    fail(line, "TOOLNO: tool number must be a whole number from 0 to 99999");
  }
  AnnouncedTool t;
  t.number = static_cast<int>(v[0]);
  t.line = line;
  if (v.size() == 2) {
    if (!(v[1] > 0.0 && v[1] * scale_ <= 1000.0)) {
      fail(line, "TOOLNO: the diameter must be within (0, 1000] mm");
    }
    t.diameter_mm = v[1] * scale_;
    if (tool_.diameter_mm > 0.0 &&
        std::abs(t.diameter_mm - tool_.diameter_mm) > 1e-6 * std::max(1.0, tool_.diameter_mm)) {
      std::ostringstream os;
      os << "TOOLNO/" << args_text << ": a tool of diameter " << t.diameter_mm
         << " mm, where the CUTTER before it gives " << tool_.diameter_mm
         << " mm: which tool cuts is not known";
      fail(line, os.str());
    }
  }
  announced_tool_ = t;
}

void Reader::spindl(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  spindle(args, line);
}

void Reader::coolnt(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.size() != 1) fail(line, "COOLNT expects one of ON, FLOOD, MIST, OFF");
  const std::string a = upper(args[0]);
  ClCoolant c = ClCoolant::Off;
  if (a == "ON") {
    // APT's ON resumes the coolant last chosen (FLOOD before any): after MIST and OFF it is
    // mist again (issue 63.12: it was written M8).
    c = chosen_coolant_;
  } else if (a == "FLOOD" || a == "MIST") {
    c = chosen_coolant_ = a == "MIST" ? ClCoolant::Mist : ClCoolant::Flood;
  } else if (a != "OFF") {
    fail(line, "COOLNT/" + args[0] +
                   ": a coolant taxopt does not write (ON, FLOOD, MIST and OFF are: M8, M7, "
                   "M9); " +
                   options_.name_of("skip_records") + " COOLNT drops every COOLNT record");
  }
  coolant_ = c;
  ProgramEvent e;
  e.kind = ProgramEvent::Kind::Coolant;
  e.coolant = c;
  state_change(e, line);
}

void Reader::cutcom(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.empty() || upper(args[0]) != "OFF") {
    fail(line, "CUTCOM/" + args_text +
                   ": cutter compensation in the control is not posted (taxopt writes the "
                   "tool centre path the file gives, without G41/G42); " +
                   options_.name_of("skip_records") +
                   " CUTCOM posts that path as it is, without the control's wear compensation");
  }
  skipped(major);
}

void Reader::set_mode(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  if (args.size() != 2 || upper(args[0]) != "MODE" || upper(args[1]) != "ABSOL") {
    fail(line, "SET/" + args_text +
                   ": only SET/MODE,ABSOL is read (absolute coordinates); incremental or "
                   "other settings change what the moves mean");
  }
  skipped(major);
}

void Reader::tolerance(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // APT: INTOL/OUTTOL/TOLER ds[,ps[,cs1[,cs2]]], a missing value the one before it: the
  // part surface's is the second, else the first.
  if (args.empty() || args.size() > 4) {
    fail(line, major + " expects 1 to 4 tolerances (drive, part, check surfaces)");
  }
  const auto v = numbers(args, 0, args.size(), major, line);
  const double t = v.size() > 1 ? v[1] : v[0];
  for (double x : v) {
    if (!(x >= 0.0 && x * scale_ <= kMaxCamToleranceMm)) {
      std::ostringstream os;
      os << major << "/" << args_text << ": a tolerance within [0, " << kMaxCamToleranceMm / scale_
         << "] " << to_string(tp_.units) << " expected (a finishing tolerance; "
         << options_.name_of("skip_records") << " " << major << " ignores it)";
      fail(line, os.str());
    }
  }
  // TOLER is OUTTOL in some APT processors and the whole band in others: either way the
  // band the path may lie off the surface, which is all taxopt takes from them.
  (major == "INTOL" ? inside_tolerance_ : outside_tolerance_) = t;
  tolerance_given_ = true;
}

void Reader::mode(const ClRecordArgs& r) {
  [[maybe_unused]] const auto& [major, args, args_text, index, line] = r;
  // MODE/MILL says what taxopt posts anyway; any other mode changes what the moves mean.
  if (args.size() != 1 || upper(args[0]) != "MILL") {
    fail(line, "MODE/" + args_text +
                   ": a machine mode taxopt does not post (only MODE/MILL is read); a "
                   "turning or other mode changes what the moves mean");
  }
  skipped(major);
}

void Reader::machin(const ClRecordArgs& r) {
  // A turning machine (MACHIN/...,TURN) was refused before the file was read (turning_record).
  skipped(r.major);
}

void Reader::spindle(const std::vector<std::string>& args, int line) {
  std::optional<double> value;
  std::string unit = "RPM";
  bool off = false, on = false, cw = spindle_cw_;
  for (const auto& a : args) {
    const std::string u = upper(a);
    double v = 0.0;
    if (parse_number(a, v)) {
      if (value) fail(line, "SPINDL: two speeds in one record");
      value = v;
    } else if (u == "RPM" || u == "SFM" || u == "SMM") {
      unit = u;
    } else if (u == "CLW" || u == "CCLW") {
      cw = u == "CLW";
    } else if (u == "OFF") {
      off = true;
    } else if (u == "ON") {
      on = true;
    } else {
      fail(line, "SPINDL: '" + a +
                     "' not interpreted (a speed, RPM, SFM, SMM, CLW, CCLW, ON and OFF are)");
    }
  }
  double rpm = spindle_rpm_;
  if (off) {
    rpm = 0.0;
  } else if (value) {
    if (!(*value >= 0.0 && *value <= 1e6)) {
      fail(line, "SPINDL: speed must be within [0, 1e6]");
    }
    rpm = *value;
    if (unit != "RPM") {
      // A surface speed: rpm through the cutter's diameter (ft/min or m/min).
      if (!(tool_.diameter_mm > 0.0)) {
        fail(line, "SPINDL/" + unit +
                       ": a surface speed needs the cutter's diameter, and no "
                       "CUTTER or TLDATA came before it");
      }
      const double mm_per_min = *value * (unit == "SFM" ? 304.8 : 1000.0);
      rpm = mm_per_min / (Constants<double>::pi() * tool_.diameter_mm);
      if (!(rpm <= 1e6)) {
        fail(line, "SPINDL/" + unit +
                       ": the surface speed at the cutter's diameter is more "
                       "than 1e6 rpm");
      }
      std::ostringstream os;
      os << "SPINDL: " << *value << " " << unit << " at the cutter's diameter " << tool_.diameter_mm
         << " mm is " << std::lround(rpm) << " rpm";
      notice(line, os.str());
    }
    if (rpm > 0.0 && rpm < 1.0) {
      // Written as S0, which turns nothing: the program check found the cut without spindle.
      fail(line, "SPINDL: " + std::to_string(rpm) +
                     " rpm is no spindle speed (0 is off, else at least 1 rpm)");
    }
    if (rpm > 0.0) last_rpm_ = rpm;
  } else if (on) {
    if (!(last_rpm_ > 0.0)) fail(line, "SPINDL/ON with no speed given before it");
    rpm = last_rpm_;
  }
  spindle_rpm_ = rpm;
  spindle_cw_ = cw;
  // A feed per revolution is the spindle's: the feed per minute of the moves after this one.
  if (feed_per_rev_mm_ > 0.0) {
    feed_mm_per_min_ = rpm > 0.0 ? bounded_feed(feed_per_rev_mm_ * rpm,
                                                "SPINDL (the feed per revolution of "
                                                "line " +
                                                    std::to_string(feed_line_) + ")",
                                                line)
                                 : 0.0;
  }
  ProgramEvent e;
  e.kind = ProgramEvent::Kind::Spindle;
  e.spindle_rpm = rpm;
  e.spindle_clockwise = cw;
  state_change(e, line);
}

void Reader::state_change(const ProgramEvent& e, int line) {
  if (op_ < 0) return;
  auto& op = tp_.operations[static_cast<std::size_t>(op_)];
  if (!op.points.empty()) {
    add_event(e, line);
    return;
  }
  if (e.kind == ProgramEvent::Kind::Spindle) {
    op.spindle_rpm = e.spindle_rpm;
    op.spindle_clockwise = e.spindle_clockwise;
  } else {
    op.coolant = e.coolant;
  }
}

void Reader::add_event(ProgramEvent e, int line) {
  auto& op = current_op();
  e.before_point = op.points.size();
  e.line = line;
  op.events.push_back(e);
}

void Reader::tapered_ball(const std::vector<double>& v, int line) {
  const double d = v[0], r = v[1], e = v[2], f = v[3], a = v[4], b = v[5], h = v[6];
  const double b_rad = deg_to_rad(b);
  const double d_expected = 2.0 * r * (1.0 - std::sin(b_rad)) / std::cos(b_rad);
  if (!(b > 0.0 && b < 45.0) || std::abs(e) > 1e-6 * r + 1e-9 ||
      std::abs(f - r) > 1e-6 * r + 1e-9 || std::abs(a) > 1e-9 ||
      std::abs(d - d_expected) > 1e-3 * d_expected + 1e-6) {
    std::ostringstream os;
    os << "CUTTER: corner radius " << r << " > diameter/2 (" << 0.5 * d
       << ") is a tapered ball only with e = 0, f = r, a = 0, a taper b within (0, 45) deg and "
          "d = 2 r (1 - sin b) / cos b ("
       << d_expected << " for b = " << b << ")";
    fail(line, os.str());
  }
  set_tool(2.0 * r, r, h, line);
  tool_.taper_rad = b_rad;
  tool_changed();
  std::ostringstream os;
  os << "CUTTER: a tapered ball-end mill, ball radius " << r * scale_ << " mm, taper " << b
     << " deg; its flanks are checked as steps of cylinders that enclose the cone";
  notice(line, os.str());
}

void Reader::set_tool(double d, double r, double length, int line) {
  if (!(d > 0.0)) fail(line, "tool diameter must be positive");
  if (r < 0.0 || r > 0.5 * d + 1e-9) fail(line, "tool corner radius must be in [0, diameter/2]");
  if (length < 0.0) fail(line, "tool length must not be negative");
  // The bounds of the options that override them (--tool-radius, --flute-length: a metre).
  if (d * scale_ > 1000.0 || length * scale_ > 1000.0) {
    fail(line, "tool diameter or length beyond 1000 mm (the tool options' bound)");
  }
  tool_.diameter_mm = d * scale_;
  tool_.corner_radius_mm = r * scale_;
  tool_.flute_length_mm = length * scale_;
  tool_.taper_rad = 0.0;
  tool_.from_file = true;
  tool_changed();
}

}  // namespace taxopt::cl
