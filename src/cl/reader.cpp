// The CL reader: the file, its units, the record table (reader.hpp).
#include "cl/reader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "taxopt/core/error.hpp"
#include "util/input_file.hpp"

namespace taxopt::cl {

Toolpath Reader::run(const std::string& input) {
  tp_.source = source_;
  for (const std::string& w : options_.skip_records) {
    const ClWord* word = find_cl_word(w);
    if (w.empty() || w != upper(w)) {
      throw InputError(options_.name_of("skip_records") + " '" + w +
                       "': a record word in upper case");
    }
    if (word && !word->skippable) {
      throw InputError(options_.name_of("skip_records") + " " + w + ": a " +
                       to_string(word->meaning) + " word (" + word->what +
                       "); skipping it would change the motion");
    }
  }
  std::string text = input;
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) {
    text.erase(0, 3);
    tp_.byte_order_mark = true;
  } else if (text.rfind("\xFF\xFE", 0) == 0 || text.rfind("\xFE\xFF", 0) == 0) {
    fail(1, "UTF-16 text: save the CL file as UTF-8 or ASCII");
  }
  auto lines = split_logical(text, source_, tp_.line_end, tp_.final_line_end);
  {
    DialectEvidence ev = detect_dialect(lines);
    tp_.reading.dialect = ev.dialect;
    tp_.reading.dialect_evidence = ev.evidence;
    dialects_seen_ = std::move(ev.seen);
  }
  // A turning file is named as one wherever its first turning record stands: an unknown
  // record before it (CATIA's PPFUN) or a tool it describes (TOOLNO/1,TURN,...) is no reason.
  if (const auto [line, record] = turning_record(lines); line > 0) {
    fail(line, record + ": a turning file; taxopt posts milling only");
  }
  determine_units(lines);
  scale_ = mm_per_unit(tp_.units);
  for (const auto& ll : lines) handle(ll);
  if (spline_) finish_spline();
  if (pending_circle_) {
    throw InputError(source_, pending_circle_->line, "CIRCLE is not followed by its end GOTO");
  }
  if (point_count(tp_) == 0) {
    throw InputError(source_, 0, "no GOTO records: not a cutter-location file");
  }
  expand_arcs();
  // Drop operations that received no point (a TOOL PATH block with no motion).
  std::vector<Operationd> kept;
  for (auto& op : tp_.operations) {
    for (const ProgramEvent& e : op.events) {
      if (op.points.empty() &&
          (e.kind == ProgramEvent::Kind::Stop || e.kind == ProgramEvent::Kind::OptionalStop ||
           e.kind == ProgramEvent::Kind::Dwell)) {
        fail(e.line, "a stop or dwell in an operation without motion: not posted");
      }
    }
    if (!op.points.empty()) kept.push_back(std::move(op));
  }
  tp_.operations = std::move(kept);
  index_records();
  for (std::size_t k = 0; k < tp_.operations.size(); ++k) {
    if (tp_.operations[k].name.empty()) tp_.operations[k].name = std::to_string(k + 1);
  }
  if (!options_.units) {
    for (const Operationd& op : tp_.operations) check_feed_per_revolution(op);
  }
  return std::move(tp_);
}

void Reader::check_feed_per_revolution(const Operationd& op) const {
  // A milling feed per revolution lies within [0.002, 2.5] mm (finishing to face milling).
  // Outside it, where 25.4 times more or less lies inside, the file's numbers are in the other
  // unit than it says: a Creo file saying UNITS / INCHES over millimetre numbers posted 1193.66
  // IPM at 7958 rpm (3.8 mm a revolution, moves of 8.9 m); a Fusion inch file's FEDRAT/35,MMPM
  // at 30000 rpm is 0.0012 mm (35 in/min: 0.030 mm).
  if (!(op.spindle_rpm > 0.0)) return;
  std::vector<std::pair<double, int>> feeds;
  for (const CLPointd& p : op.points) {
    if (p.motion == Motion::Feed && p.feed_mm_per_min > 0.0) {
      feeds.push_back({p.feed_mm_per_min, p.line});
    }
  }
  if (feeds.empty()) return;
  std::nth_element(feeds.begin(), feeds.begin() + static_cast<std::ptrdiff_t>(feeds.size() / 2),
                   feeds.end());
  const auto [feed, line] = feeds[feeds.size() / 2];
  const auto plausible = [](double mm_per_rev) { return mm_per_rev >= 0.002 && mm_per_rev <= 2.5; };
  const double per_rev = feed / op.spindle_rpm;
  if (plausible(per_rev)) return;
  for (const double k : {1.0 / kMmPerInch, kMmPerInch}) {
    if (!plausible(per_rev * k)) continue;
    std::ostringstream os;
    os << "operation " << op.name << ": its feed, " << std::lround(feed) << " mm/min at "
       << std::lround(op.spindle_rpm) << " rpm, is ";
    os.precision(4);
    os << per_rev << " mm a revolution, no milling feed; read as "
       << (k < 1.0 ? "millimetres" : "inches") << " it would be " << per_rev * k
       << " mm: the file's numbers look like " << (k < 1.0 ? "millimetres" : "inches")
       << " though it reads as " << to_string(tp_.units) << "; " << options_.name_of("units") << " "
       << (k < 1.0 ? "mm" : "in") << " reads the whole file so, feed words too";
    fail(line, os.str());
  }
}

void Reader::fail(int line, const std::string& what) const {
  // A message quotes the record: never a 10 MB token back (tests/test_bad_input.cpp).
  throw InputError(source_, line, what.size() > 400 ? what.substr(0, 400) + "... (cut)" : what);
}

void Reader::notice(int line, const std::string& what) {
  tp_.notices.push_back(format_location(source_, line, what));
}

/// What a CL file says of its units: the first UNITS record, the first motion, the first feed
/// word in inches and in millimetres (Reader::determine_units).
struct Reader::UnitEvidence {
  std::optional<LengthUnit> declared;
  std::string declared_record;
  int declared_line = 0, motion_line = 0, inch_feed_line = 0, mm_feed_line = 0;
};

void Reader::units_record(const LogicalLine& ll, const std::string& major, const std::string& args,
                          UnitEvidence& e) const {
  const auto fields = split_args(args);
  const std::string a = upper(fields.empty() ? std::string() : fields[0]);
  LengthUnit u = LengthUnit::Millimetre;
  if (fields.size() == 1 && (a == "INCHES" || a == "INCH" || a == "IN")) {
    u = LengthUnit::Inch;
  } else if (fields.size() != 1 ||
             !(a == "MM" || a == "MILLIMETERS" || a == "MILLIMETRES" || a == "METRIC")) {
    fail(ll.line, major + " expects INCHES or MM, got '" + trim(args) + "'");
  }
  if (e.declared && *e.declared != u) {
    fail(ll.line, major + "/" + a + " contradicts the " + to_string(*e.declared) + " of line " +
                      std::to_string(e.declared_line) +
                      (e.motion_line && e.motion_line < ll.line
                           ? " after motion (line " + std::to_string(e.motion_line) + ")"
                           : std::string()) +
                      ": a change of units inside a file is not interpreted");
  }
  if (!e.declared) {
    e.declared = u;
    e.declared_line = ll.line;
    e.declared_record = major + "/" + trim(args);
  }
}

Reader::UnitEvidence Reader::unit_evidence(const std::vector<LogicalLine>& lines) const {
  UnitEvidence e;
  for (const auto& ll : lines) {
    if (ll.kind != RecordKind::Record) continue;
    std::string args;
    const std::string major = major_word(ll.code, args);
    const ClWord* w = find_cl_word(major);
    if (w && w->meaning == ClWordMeaning::Motion && e.motion_line == 0) e.motion_line = ll.line;
    if (major == "UNITS" || major == "UNIT") units_record(ll, major, args, e);
    if (major == "FEDRAT") {
      int inch = 0, mm = 0;
      for (const auto& a : split_args(args)) {
        const std::string u = upper(a);
        inch += u == "IPM" || u == "IPR";
        mm += u == "MMPM" || u == "MMPR";
      }
      if (inch && mm) {
        fail(ll.line, "FEDRAT/" + trim(args) + ": both an inch and a millimetre feed word");
      }
      if (inch && !e.inch_feed_line) e.inch_feed_line = ll.line;
      if (mm && !e.mm_feed_line) e.mm_feed_line = ll.line;
    }
  }
  return e;
}

void Reader::determine_units(const std::vector<LogicalLine>& lines) {
  const UnitEvidence e = unit_evidence(lines);
  // A file states its units before it moves: declared after the first motion, the units of
  // the moves before it are not known (they were read in the declared ones without a word).
  if (e.declared && e.motion_line && e.motion_line < e.declared_line && !options_.units) {
    const char* unit = *e.declared == LengthUnit::Inch ? "inches" : "millimetres";
    fail(e.declared_line, e.declared_record + " comes after the first motion (line " +
                              std::to_string(e.motion_line) +
                              "): whether the moves before it are in " + unit +
                              " too is not known; give " + options_.name_of("units") + " in|mm");
  }
  // Without UNITS the feed words are the only evidence; where they say both, one FEDRAT/IPM
  // among millimetre feeds read the whole file in inches (X30 as 762 mm): not known.
  if (!e.declared && !options_.units && e.inch_feed_line && e.mm_feed_line) {
    fail(std::max(e.inch_feed_line, e.mm_feed_line),
         "the file states no UNITS and its feeds say inches (IPM/IPR, line " +
             std::to_string(e.inch_feed_line) + ") and millimetres (MMPM/MMPR, line " +
             std::to_string(e.mm_feed_line) + "): the unit of its coordinates is not known; give " +
             options_.name_of("units") + " in|mm");
  }
  const LengthUnit from_file =
      e.declared ? *e.declared : (e.inch_feed_line ? LengthUnit::Inch : LengthUnit::Millimetre);
  tp_.units = options_.units ? *options_.units : from_file;
  notice_units(e);
}

void Reader::notice_units(const UnitEvidence& e) {
  const char* name = to_string(tp_.units);
  // --units reads the whole file in its unit, the feed words' too (a Creo file saying UNITS /
  // INCHES over millimetre numbers, read with --units mm, kept its 1193.66 IPM as 30319 mm/min).
  const int other_feed_line = tp_.units == LengthUnit::Inch ? e.mm_feed_line : e.inch_feed_line;
  if (options_.units && e.declared && *e.declared != *options_.units) {
    notice(e.declared_line, options_.name_of("units") + " " + name + " read the file in " + name +
                                " though it says " + to_string(*e.declared) + " here" +
                                (other_feed_line ? ", its feed words too" : ""));
  } else if (options_.units && other_feed_line) {
    notice(other_feed_line,
           options_.name_of("units") + " " + name + " read the file in " + name +
               ", its feed words too, though they say " +
               (tp_.units == LengthUnit::Inch ? "millimetres (MMPM/MMPR)" : "inches (IPM/IPR)") +
               " from here");
  } else if (tp_.units == LengthUnit::Millimetre && e.inch_feed_line) {
    notice(e.inch_feed_line,
           "a feed in inches (IPM/IPR) in a file read in millimetres: the "
           "feed is taken as its word says, the coordinates in mm (" +
               options_.name_of("units") + " mm reads the feeds in mm too)");
  } else if (tp_.units == LengthUnit::Inch && e.mm_feed_line) {
    notice(e.mm_feed_line,
           "a feed in millimetres (MMPM/MMPR) in a file read in inches: the feed "
           "is taken as its word says, the coordinates in inches (" +
               options_.name_of("units") + " in reads the feeds in inches too)");
  }
}

std::vector<double> Reader::numbers(const std::vector<std::string>& args, std::size_t from,
                                    std::size_t to, const std::string& major, int line) const {
  std::vector<double> out;
  for (std::size_t k = from; k < to && k < args.size(); ++k) {
    double v = 0.0;
    if (!parse_number(args[k], v)) {
      fail(line, major + " field " + std::to_string(k + 1) + ": expected a number, got '" +
                     args[k] + "'");
    }
    out.push_back(v);
  }
  return out;
}

Vec3d Reader::parse_axis(const std::vector<double>& v, std::size_t at, const std::string& major,
                         int line) const {
  Vec3d axis(v[at], v[at + 1], v[at + 2]);
  const double len = axis.norm();
  if (len < 1e-12) fail(line, major + ": tool axis (i,j,k) is zero");
  if (std::abs(len - 1.0) > options_.axis_length_tolerance) {
    std::ostringstream os;
    os << major << ": tool axis (" << v[at] << "," << v[at + 1] << "," << v[at + 2]
       << ") has length " << len << ", expected a unit vector";
    fail(line, os.str());
  }
  return axis / len;
}

void Reader::handle(const LogicalLine& ll) {
  ClRecord rec;
  rec.kind = ll.kind;
  rec.text = ll.raw;
  rec.line = ll.line;
  std::string args;
  if (ll.kind == RecordKind::Record) {
    rec.major = major_word(ll.code, args);
    if (rec.major.empty() && after_goto_ && is_point_line(ll.code)) {
      // Pro/CLfile writes a GOTO of several points a point a line, no `$` (its CIRCLE's
      // GOTO: Creo gg.ncl, a full circle as three arcs); after a CIRCLE, each is an arc on
      // it from the point before, the points after it written in the record before's.
      rec.major = "GOTO";
      args = ll.code;
      if (last_arc_circle_) {
        pending_circle_ = last_arc_circle_;
        pending_circle_->record = last_point("GOTO", ll.line).record;
      }
      if (!goto_continued_) {
        goto_continued_ = true;
        tp_.warnings.push_back(format_location(
            source_, ll.line,
            "a GOTO's further points on lines of their own, no '$' (Pro/CLfile's form): each "
            "read as a GOTO" +
                std::string(last_arc_circle_ ? ", an arc on the CIRCLE before" : "")));
      }
    }
    if (rec.major.empty()) {
      // Only the lines NX's listing window adds around a CLSF are no records; anything
      // else that cannot be read is an error, never a skipped line (it may be UNITS).
      if (!is_listing_line(ll.code)) {
        fail(ll.line, "not a CL record: '" + trim(ll.code).substr(0, 60) +
                          "' (expected a record word such as GOTO/, or a $$ comment)");
      }
      rec.kind = RecordKind::NotRecord;
      tp_.warnings.push_back(format_location(
          source_, ll.line, "not a CL record, skipped: '" + trim(ll.code).substr(0, 60) + "'"));
    }
  }
  tp_.records.push_back(rec);
  if (rec.kind != RecordKind::Record) return;
  const int index = static_cast<int>(tp_.records.size()) - 1;
  interpret(rec.major, args, index, ll.line);
  after_goto_ = rec.major == "GOTO" && !spline_ && !cycle_;
}

void Reader::interpret(const std::string& major, const std::string& args_text, int index,
                       int line) {
  const auto args = split_args(args_text);
  if (spline_) {
    if (major == "KNOT") {
      if (!spline_->control.empty()) fail(line, "KNOT after the CNTRL records of its NURBS");
      for (double k : numbers(args, 0, args.size(), major, line)) spline_->knots.push_back(k);
      tp_.records[static_cast<std::size_t>(index)].owner = spline_->record;
      return;
    }
    if (major == "CNTRL") {
      if (args.size() != 3 && args.size() != 4) {
        fail(line, "CNTRL expects x,y,z[,weight], got " + std::to_string(args.size()) + " fields");
      }
      const auto v = numbers(args, 0, args.size(), major, line);
      const double w = v.size() == 4 ? v[3] : 1.0;
      if (!(w > 0.0)) fail(line, "CNTRL: weight must be positive");
      const Vec3d q = to_mcs_point(Vec3d(v[0], v[1], v[2]));
      // The curve lies in its control points' hull: one a light year out made the spans'
      // bisection run 28 s (a fuzzed file) before the point budget stopped it.
      check_reach(q * scale_, major, line);
      spline_->control.emplace_back(q.x(), q.y(), q.z(), w);
      tp_.records[static_cast<std::size_t>(index)].owner = spline_->record;
      return;
    }
    finish_spline();
  }
  if (major == "KNOT" || major == "CNTRL") fail(line, major + " outside a NURBS record");
  if (pending_circle_ && major != "GOTO" && major != "PAINT" && major != "FEDRAT") {
    fail(line, std::string(pending_circle_->movarc ? "MOVARC" : "CIRCLE") + " at line " +
                   std::to_string(pending_circle_->line) +
                   " must be followed by its end GOTO, got " + major);
  }
  const ClWord* word = find_cl_word(major);
  if (options_.skip_records.count(major)) {
    skipped(major);
    ++tp_.skipped_by_option[major];
    return;
  }
  if (!word) {
    fail(line, major +
                   ": not a record word taxopt knows (docs/cl-files.md lists them); if it "
                   "neither moves the tool nor changes what the moves mean, " +
                   options_.name_of("skip_records") + " " + major + " skips it");
  }
  if (finished_line_ > 0 && word->meaning == ClWordMeaning::Motion) {
    fail(line, major + " after the end of the program (line " + std::to_string(finished_line_) +
                   "): motion after FINI or END is not posted");
  }
  if (word->meaning == ClWordMeaning::Refused) {
    fail(line, major + ": " + word->what +
                   "; taxopt does not interpret it and cannot skip it (post the file "
                   "without it, or expand it in the CAM system)");
  }
  const ClRecordArgs r{major, args, args_text, index, line};
  const auto& readers = record_readers();
  if (const auto it = readers.find(major); it != readers.end()) {
    (this->*(it->second))(r);
  } else if (major != "UNITS" && major != "UNIT") {
    skipped(major);
  }
}

}  // namespace taxopt::cl

namespace taxopt {

Toolpath parse_cl(const std::string& text, const std::string& source,
                  const ClReadOptions& options) {
  return cl::Reader(source, options).run(text);
}

Toolpath read_cl_file(const std::string& path, const ClReadOptions& options) {
  // 2 GB is beyond the 2e7 points the reader posts at the most.
  return parse_cl(detail::read_input_file(path, std::uintmax_t{2} << 30, "a CL file", "CL file",
                                          "larger than 2 GB: more than the 2e7 CL points taxopt "
                                          "posts"),
                  path, options);
}

}  // namespace taxopt
