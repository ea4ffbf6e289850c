// APT / NX CLSF reader. The traps it survives are listed in docs/cl-files.md; each has a test.
#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <sstream>

#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/cl_words.hpp"
#include "util/text.hpp"

namespace taxopt {
namespace {

using detail::trim;

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

/// Strict decimal number: [+-]? (d+ [. d*] | . d+) ([eE] [+-]? d+)?, finite.
bool parse_number(const std::string& token, double& out) {
  const std::string t = trim(token);
  std::size_t i = 0;
  const std::size_t n = t.size();
  if (i < n && (t[i] == '+' || t[i] == '-')) ++i;
  std::size_t digits = 0;
  while (i < n && std::isdigit(static_cast<unsigned char>(t[i]))) ++i, ++digits;
  if (i < n && t[i] == '.') {
    ++i;
    while (i < n && std::isdigit(static_cast<unsigned char>(t[i]))) ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < n && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < n && (t[i] == '+' || t[i] == '-')) ++i;
    std::size_t exp_digits = 0;
    while (i < n && std::isdigit(static_cast<unsigned char>(t[i]))) ++i, ++exp_digits;
    if (exp_digits == 0) return false;
  }
  if (i != n) return false;
  // The grammar is checked above; from_chars does not take a leading '+' (it does take "16.").
  const char* first = t.data() + (t[0] == '+' ? 1 : 0);
  double value = 0.0;
  auto [ptr, ec] = std::from_chars(first, t.data() + n, value);
  if (ec != std::errc() || ptr != t.data() + n || !std::isfinite(value)) return false;
  out = value;
  return true;
}

bool is_number_like(const std::string& token) {
  double v;
  return parse_number(token, v);
}

std::vector<std::string> split_args(const std::string& args) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : args) {
    if (c == ',') {
      out.push_back(trim(cur));
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(trim(cur));
  if (out.size() == 1 && out[0].empty()) out.clear();
  return out;
}

/// Whether a physical line starts a record of its own: a `$$` comment, or a word followed by
/// a slash (GOTO/..., PPRINT/...).
bool starts_record(const std::string& physical) {
  std::size_t k = 0;
  while (k < physical.size() && std::isspace(static_cast<unsigned char>(physical[k]))) ++k;
  if (physical.compare(k, 2, "$$") == 0) return true;
  const std::size_t word = k;
  while (k < physical.size() && std::isalnum(static_cast<unsigned char>(physical[k]))) ++k;
  if (k == word || !std::isalpha(static_cast<unsigned char>(physical[word]))) return false;
  while (k < physical.size() && (physical[k] == ' ' || physical[k] == '\t')) ++k;
  return k < physical.size() && physical[k] == '/';
}

/// A logical line: physical lines joined over `$` continuations.
struct LogicalLine {
  std::string raw;   // physical lines joined by '\n'
  std::string code;  // the record text with continuations joined and `$$` comments removed
  int line = 0;
  RecordKind kind = RecordKind::Record;
};

/// Major word of a record line, or "" when the line is no record.
std::string major_word(const std::string& code, std::string& args) {
  const std::size_t slash = code.find('/');
  std::string head;
  if (slash != std::string::npos) {
    head = code.substr(0, slash);
    args = code.substr(slash + 1);
  } else {
    std::size_t e = 0;
    while (e < code.size() && !std::isspace(static_cast<unsigned char>(code[e]))) ++e;
    head = code.substr(0, e);
    args = trim(code.substr(e));
  }
  // Fold blanks inside the head ("TOOL PATH", "GOTO  " -> "GOTO").
  std::string folded;
  bool space = false;
  for (char c : trim(head)) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      space = true;
      continue;
    }
    if (space && !folded.empty()) folded += ' ';
    space = false;
    folded += c;
  }
  if (folded.empty() || !std::isalpha(static_cast<unsigned char>(folded[0]))) return "";
  for (char c : folded) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == ' ')) {
      return "";
    }
  }
  const std::string up = upper(folded);
  // APT words are upper case; a mixed-case head is only accepted for words we know
  // (listing headers such as "Tool Path Listing has 388 lines." are no records).
  if (folded != up && !find_cl_word(up)) return "";
  if (slash == std::string::npos && up.find(' ') != std::string::npos) return "";
  return up;
}

std::vector<LogicalLine> split_logical(const std::string& text, const std::string& source,
                                       std::string& line_end, bool& final_line_end) {
  std::vector<std::string> physical;
  line_end = "\n";
  bool saw_crlf = false;
  std::size_t start = 0;
  bool saw_lf = false, saw_cr = false;
  // Any of CR, LF and CRLF ends a line (a file may mix them).
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\0') {
      const int line = static_cast<int>(physical.size()) + 1;
      throw InputError(source, line, "binary data (NUL byte): not a CL text file");
    }
    if (text[i] == '\n' || text[i] == '\r') {
      physical.push_back(text.substr(start, i - start));
      if (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') {
        ++i;
        saw_crlf = true;
      } else if (text[i] == '\r') {
        saw_cr = true;
      } else {
        saw_lf = true;
      }
      start = i + 1;
    }
  }
  final_line_end = start == text.size();
  if (start < text.size()) physical.push_back(text.substr(start));
  if (saw_crlf && !saw_lf) line_end = "\r\n";
  if (saw_cr && !saw_lf && !saw_crlf) line_end = "\r";

  std::vector<LogicalLine> out;
  std::size_t i = 0;
  while (i < physical.size()) {
    LogicalLine ll;
    ll.line = static_cast<int>(i) + 1;
    ll.raw = physical[i];
    const std::string first = trim(physical[i]);
    // A DOS end-of-file mark (Ctrl-Z) alone on the last line: nothing to read, kept for the
    // round trip.
    if (first.empty() || (first == "\x1a" && i + 1 == physical.size())) {
      ll.kind = RecordKind::Blank;
      out.push_back(ll);
      ++i;
      continue;
    }
    if (first.rfind("$$", 0) == 0) {
      // A comment; one ending in `$` continues on the next line (Creo's `$$-> CSYS / 1.0,
      // 0.0,  $` and its numbers below) unless that line is a record or a comment of its own:
      // a banner of `$$$$$$$$` or a sentence ending in `US$` before a GOTO joined the GOTO to
      // the comment, and it vanished.
      ll.kind = RecordKind::Comment;
      std::string cur = first;
      while (cur.size() > 2 && cur.back() == '$' && i + 1 < physical.size() &&
             !starts_record(physical[i + 1])) {
        ++i;
        ll.raw += "\n" + physical[i];
        cur = trim(physical[i]);
      }
      out.push_back(ll);
      ++i;
      continue;
    }
    if (first.size() >= 6 && upper(first.substr(0, 6)) == "REMARK" &&
        (first.size() == 6 || std::isspace(static_cast<unsigned char>(first[6])))) {
      // APT's comment statement (ANSI X3.37: REMARK and its text are not processed); Creo's
      // GPOST writes it on line 2.
      ll.kind = RecordKind::Comment;
      out.push_back(ll);
      ++i;
      continue;
    }
    std::string code;
    std::string piece = physical[i];
    // Text records (PPRINT, PARTNO, INSERT): `$$` in their text is text; a `$` at the end
    // continues them (CATIA's `PPRINT/(=====$` then `=====)`) unless the next line is a record
    // of its own (`PPRINT/TOOL COST 12 US$` then `GOTO/50,0,5`: the GOTO vanished).
    const bool text_record = [&] {
      std::string word;
      for (char ch : first) {
        if (!std::isalpha(static_cast<unsigned char>(ch))) break;
        word += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      }
      const std::size_t after = first.find_first_not_of(" \t", word.size());
      return (word == "PPRINT" || word == "PARTNO" || word == "INSERT") &&
             (after == std::string::npos || first[after] == '/' || word == "PARTNO");
    }();
    for (;;) {
      const std::size_t comment = text_record ? std::string::npos : piece.find("$$");
      if (comment != std::string::npos) piece = piece.substr(0, comment);
      std::string t = piece;
      while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
      if (!t.empty() && t.back() == '$' &&
          !(text_record && i + 1 < physical.size() && starts_record(physical[i + 1]))) {
        // `$` continuation: the next line follows with no separator (it may split a number).
        t.pop_back();
        code += t;
        if (i + 1 >= physical.size()) {
          throw InputError(source, static_cast<int>(i) + 1,
                           "record ends in a '$' continuation but the file ends");
        }
        ++i;
        ll.raw += "\n" + physical[i];
        piece = physical[i];
        continue;
      }
      code += piece;
      break;
    }
    ll.code = trim(code);
    out.push_back(ll);
    ++i;
  }
  return out;
}

/// The lines NX's listing window puts around a CLSF: "Information listing created by<TAB>...",
/// "Date<TAB>...", "Current work part<TAB>...", "Node name<TAB>..." and the trailer "Tool Path
/// Listing has N lines.".
bool is_listing_line(const std::string& code) {
  const std::size_t tab = code.find('\t');
  if (tab != std::string::npos && tab > 0) {
    bool words = true;
    for (std::size_t i = 0; i < tab; ++i) {
      const unsigned char c = static_cast<unsigned char>(code[i]);
      words = words && (std::isalpha(c) || c == ' ');
    }
    if (words) return true;
  }
  const std::string t = trim(code);
  const std::string head = "Tool Path Listing has ";
  if (t.rfind(head, 0) != 0) return false;
  std::size_t i = head.size();
  const std::size_t digits = i;
  while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i;
  return i > digits && (t.substr(i) == " lines." || t.substr(i) == " lines");
}

/// Recognises the CAM system from its records and comments (docs/cl-files.md).
ClDialect detect_dialect(const std::vector<LogicalLine>& lines) {
  bool nx = false, creo = false, catia = false, solidworks = false, ffcam = false, makino = false;
  for (const auto& ll : lines) {
    const std::string up = upper(ll.raw);
    ffcam = ffcam || up.find("FFCAM") != std::string::npos;
    makino = makino || up.find("MAKINO") != std::string::npos;
    if (ll.kind == RecordKind::Comment) {
      creo = creo || up.find("PRO/CLFILE") != std::string::npos ||
             up.find("CREO") != std::string::npos;
      catia = catia || up.find("CATIA") != std::string::npos;
      continue;
    }
    if (ll.kind != RecordKind::Record) continue;
    std::string args;
    const std::string major = major_word(ll.code, args);
    nx = nx || major == "TOOL PATH" || major == "TLDATA" || major == "END-OF-PATH" ||
         major == "MSYS";
    solidworks = solidworks || major.rfind("CSI_", 0) == 0 || major == "TRNTYP";
  }
  // FFCAM names itself; a machine called Makino in another system's file does not make it one.
  if (ffcam) return ClDialect::MakinoFfcam;
  if (nx) return ClDialect::SiemensNx;
  if (creo) return ClDialect::Creo;
  if (catia) return ClDialect::Catia;
  if (solidworks) return ClDialect::SolidworksCam;
  if (makino) return ClDialect::MakinoFfcam;
  return ClDialect::Generic;
}

/// The sense in which a dialect's CIRCLE records run, with the evidence (docs/cl-files.md);
/// Auto where nothing is documented or measured.
ArcDirection documented_arc_direction(ClDialect dialect) {
  switch (dialect) {
    case ClDialect::SiemensNx:  // NX CLSF manual: "axis vector ... assuming a clockwise direction"
    case ClDialect::MakinoFfcam:  // tangent continuity: every decidable arc of real files
      return ArcDirection::Clockwise;
    case ClDialect::SolidworksCam:  // APT's right-hand rule; tangents of real files agree
    case ClDialect::Creo:
    case ClDialect::Catia: return ArcDirection::CounterClockwise;
    case ClDialect::Generic: break;
  }
  return ArcDirection::Auto;
}

/// How far an arc's end may lie off its circle, in the CL file's unit (mm or inch): the
/// rounding of its numbers (MOVARC's and CIRCLE's ends alike).
constexpr double kArcEndTolerance = 0.002;

/// A CIRCLE whose end GOTO has been read: its chords go between points `start` and
/// `start + 1` of operation `op` once the file's arc sense is decided.
struct PendingArc {
  int op = -1;
  std::size_t start = 0;
  Vec3d centre = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
  double radius_mm = 0.0;  // 0: from the start point
  int turns = 1;           // TIMES,n: n revolutions in all
  int record = -1;
  int line = 0;
  /// What the straight moves before and after say: +1 counter-clockwise about `axis`,
  /// -1 clockwise, 0 undecided; and whether every deciding side is unambiguous.
  int evidence = 0;
  bool strong = false;
  bool clockwise = false;
  /// MOVARC (Fusion / HSM): counter-clockwise about `axis` through `declared_sweep_rad`, as
  /// written; it takes no part in deciding the CIRCLE sense.
  bool movarc = false;
  double declared_sweep_rad = 0.0;
};

struct CircleRecord {
  Vec3d centre, axis;
  double radius_mm = 0.0;
  int turns = 1;
  int record = -1;
  int line = 0;
  bool movarc = false;
  double declared_sweep_rad = 0.0;
};

/// NX NURBS/ + KNOT/ + CNTRL/ records being collected.
struct PendingSpline {
  int record = -1;
  int line = 0;
  Motion motion = Motion::Feed;
  std::vector<double> knots;
  std::vector<Eigen::Vector4d> control;  // x, y, z (mm), weight
};

/// A drilling cycle in force (CYCLE/kind,... up to CYCLE/OFF).
struct DrillCycle {
  std::string kind;
  int line = 0;
  double depth_mm = 0.0, rapid_to_mm = 0.0, retract_to_mm = 0.0;
  double first_peck_mm = 0.0, next_peck_mm = 0.0;
  double feed_mm_per_min = 0.0;
  bool feed_out = false;  // bore, ream, tap: the tool leaves the hole at the feed
};

/// The vote of one straight move on an arc's sense: +1 when it runs along the
/// counter-clockwise tangent (about n, at radius vector r), -1 against it, 0 undecided.
/// `strong` is cleared when the vote is less than clear-cut.
int tangent_vote(const Vec3d& move, const Vec3d& radius, const Vec3d& n, bool& strong) {
  const Vec3d in_plane = move - move.dot(n) * n;
  const Vec3d tangent = n.cross(radius - radius.dot(n) * n);
  const double m = move.norm(), p = in_plane.norm(), t = tangent.norm();
  if (m < 1e-9 || t < 1e-9 || p < 0.5 * m) return 0;  // a plunge or no move: says nothing
  const double c = in_plane.dot(tangent) / (p * t);
  if (std::abs(c) < 0.9) return 0;  // a corner: says nothing
  if (std::abs(c) < 0.99) strong = false;
  return c > 0.0 ? 1 : -1;
}

class Reader {
 public:
  Reader(const std::string& source, const ClReadOptions& options)
      : source_(source), options_(options) {}

  Toolpath run(const std::string& input) {
    tp_.source = source_;
    for (const std::string& w : options_.skip_records) {
      const ClWord* word = find_cl_word(w);
      if (w.empty() || w != upper(w)) {
        throw InputError("--skip-record '" + w + "': a record word in upper case");
      }
      if (word && !word->skippable) {
        throw InputError("--skip-record " + w + ": a " + to_string(word->meaning) + " word (" +
                         word->what + "); skipping it would change the motion");
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
    tp_.reading.dialect = detect_dialect(lines);
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
    return std::move(tp_);
  }

 private:
  [[noreturn]] void fail(int line, const std::string& what) const {
    // A message quotes the record: never a 10 MB token back (issue 35).
    throw InputError(source_, line, what.size() > 400 ? what.substr(0, 400) + "... (cut)" : what);
  }

  void notice(int line, const std::string& what) {
    tp_.notices.push_back(format_location(source_, line, what));
  }

  /// The file's length unit (docs/cl-files.md, "Units"): --units, else the first UNITS/UNIT
  /// record, else inches when a feed is IPM/IPR, else mm. A change of unit is refused; feed
  /// words and --units that contradict the file's unit are said (not behind -v).
  void determine_units(const std::vector<LogicalLine>& lines) {
    std::optional<LengthUnit> declared;
    int declared_line = 0, motion_line = 0, inch_feed_line = 0, mm_feed_line = 0;
    for (const auto& ll : lines) {
      if (ll.kind != RecordKind::Record) continue;
      std::string args;
      const std::string major = major_word(ll.code, args);
      const ClWord* w = find_cl_word(major);
      if (w && w->meaning == ClWordMeaning::Motion && motion_line == 0) motion_line = ll.line;
      if (major == "UNITS" || major == "UNIT") {
        const auto fields = split_args(args);
        const std::string a = upper(fields.empty() ? std::string() : fields[0]);
        LengthUnit u = LengthUnit::Millimetre;
        if (fields.size() == 1 && (a == "INCHES" || a == "INCH" || a == "IN")) {
          u = LengthUnit::Inch;
        } else if (fields.size() != 1 ||
                   !(a == "MM" || a == "MILLIMETERS" || a == "MILLIMETRES" || a == "METRIC")) {
          fail(ll.line, major + " expects INCHES or MM, got '" + trim(args) + "'");
        }
        if (declared && *declared != u) {
          fail(ll.line, major + "/" + a + " contradicts the " + to_string(*declared) + " of line " +
                            std::to_string(declared_line) +
                            (motion_line && motion_line < ll.line
                                 ? " after motion (line " + std::to_string(motion_line) + ")"
                                 : std::string()) +
                            ": a change of units inside a file is not interpreted");
        }
        if (!declared) {
          declared = u;
          declared_line = ll.line;
        }
      }
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
        if (inch && !inch_feed_line) inch_feed_line = ll.line;
        if (mm && !mm_feed_line) mm_feed_line = ll.line;
      }
    }
    const LengthUnit from_file =
        declared ? *declared : (inch_feed_line ? LengthUnit::Inch : LengthUnit::Millimetre);
    tp_.units = options_.units ? *options_.units : from_file;
    const char* name = to_string(tp_.units);
    if (options_.units && declared && *declared != *options_.units) {
      notice(declared_line, std::string("--units ") + name + " read the file in " + name +
                                " though it says " + to_string(*declared) + " here");
    } else if (options_.units && !declared && inch_feed_line &&
               *options_.units != LengthUnit::Inch) {
      notice(inch_feed_line, std::string("--units ") + name + " read the file in " + name +
                                 " though its feeds are in inches (IPM/IPR) from here");
    }
    if (tp_.units == LengthUnit::Millimetre && inch_feed_line) {
      notice(inch_feed_line,
             "a feed in inches (IPM/IPR) in a file read in millimetres: the "
             "feed is taken as its word says, the coordinates in mm");
    }
    if (tp_.units == LengthUnit::Inch && mm_feed_line) {
      notice(mm_feed_line,
             "a feed in millimetres (MMPM/MMPR) in a file read in inches: the feed "
             "is taken as its word says, the coordinates in inches");
    }
  }

  std::vector<double> numbers(const std::vector<std::string>& args, std::size_t from,
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

  Operationd& current_op() {
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

  /// A tool change outside a TOOL PATH block starts a new operation once the current one
  /// has moved.
  void tool_changed() {
    if (op_ >= 0) {
      auto& op = tp_.operations[static_cast<std::size_t>(op_)];
      if (!op.points.empty()) {
        const std::string name = in_block_ ? op.name : std::string();
        op_ = -1;
        pending_name_ = name;
      } else {
        op.tool = tool_;
      }
    }
  }

  Vec3d parse_axis(const std::vector<double>& v, std::size_t at, const std::string& major,
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

  /// A point of the file (in its units and frame) in taxopt's millimetres and MCS.
  Vec3d to_mcs_point(const Vec3d& p) const {
    const Vec3d mm = p * scale_;
    if (frame_ < 0) return mm;
    const ClFrame& f = tp_.frames[static_cast<std::size_t>(frame_)];
    return f.rotation.transpose() * (mm - f.origin_mm);
  }
  /// A direction of the file in the MCS.
  Vec3d to_mcs_vector(const Vec3d& v) const {
    if (frame_ < 0) return v;
    return tp_.frames[static_cast<std::size_t>(frame_)].rotation.transpose() * v;
  }

  void add_point(const Vec3d& tip_mm, Motion motion, int record, int line) {
    if (++points_ > 20000000) fail(line, "more than 2e7 CL points: the file cannot be posted");
    check_reach(tip_mm, tp_.records[static_cast<std::size_t>(record)].major, line);
    auto& op = current_op();
    CLPointd p;
    p.tip_mm = tip_mm;
    p.axis = axis_;
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

  /// Coordinates beyond any machine (1e6 mm = 1 km) are a broken file, not a program.
  void check_reach(const Vec3d& p_mm, const std::string& major, int line) const {
    if (p_mm.cwiseAbs().maxCoeff() > kMaxCoordinateMm) {
      std::ostringstream os;
      os << major << ": point (" << p_mm.x() << ", " << p_mm.y() << ", " << p_mm.z()
         << ") mm lies beyond +-1e6 mm: not a machinable coordinate";
      fail(line, os.str());
    }
  }
  /// The largest CAM tolerance taken (INTOL, OUTTOL, TOLER), mm: a finishing path's band.
  static constexpr double kMaxCamToleranceMm = 1.0;

  const CLPointd& last_point(const std::string& major, int line) {
    auto& op = current_op();
    if (op.points.empty()) fail(line, major + " has no start point (no GOTO or FROM before it)");
    return op.points.back();
  }

  /// The angle an arc turns from `start` to `end`, counter-clockwise about `c.axis` (already
  /// turned for the sense), with TIMES' extra revolutions.
  static double arc_sweep_rad(const PendingArc& c, const Vec3d& start, const Vec3d& end_mm) {
    const Vec3d s = start - c.centre, e = end_mm - c.centre;
    const Vec3d sp = s - s.dot(c.axis) * c.axis, ep = e - e.dot(c.axis) * c.axis;
    double phi = std::atan2(sp.cross(ep).dot(c.axis), sp.dot(ep));
    if (phi <= 1e-12) phi += Constants<double>::two_pi();
    return phi + Constants<double>::two_pi() * (c.turns - 1);
  }

  /// Chords of an arc from `start` to `end` (exclusive of both), counter-clockwise about
  /// `c.axis` (already turned for the sense), within the chordal tolerance.
  std::vector<Vec3d> arc_chords(const PendingArc& c, const Vec3d& start, const Vec3d& end_mm) {
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
    if (segments > 1e6)
      fail(c.line, "CIRCLE needs more than 1e6 chords: radius or TIMES too large");
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

  /// Decides the sense of every arc (the file's convention, checked against the tangents of
  /// the straight moves beside each arc) and inserts their chords.
  void expand_arcs() {
    auto& rd = tp_.reading;
    // Which points end or start an arc: the moves into / out of them are not straight.
    std::vector<std::set<std::size_t>> ends(tp_.operations.size()), starts(ends.size());
    for (const auto& a : arcs_) {
      starts[static_cast<std::size_t>(a.op)].insert(a.start);
      ends[static_cast<std::size_t>(a.op)].insert(a.start + 1);
    }
    int ccw_votes = 0, cw_votes = 0, circles = 0;
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
      if (a.movarc) continue;  // its sense is written: it does not vote on the CIRCLEs'
      ++circles;
      if (a.evidence > 0) ++ccw_votes;
      if (a.evidence < 0) ++cw_votes;
    }
    if (circles == 0) {
      // No CIRCLE to decide: the report still names the sense the file's arcs would have had.
      if (options_.arc_direction != ArcDirection::Auto) {
        rd.arc_convention = options_.arc_direction;
        rd.arc_convention_source = "option";
      } else if (documented_arc_direction(rd.dialect) != ArcDirection::Auto) {
        rd.arc_convention = documented_arc_direction(rd.dialect);
      }
      check_movarcs();
      insert_chords();
      return;
    }
    rd.arcs = circles;
    rd.arcs_decidable = ccw_votes + cw_votes;
    const auto lines_of = [this](int sign) {
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
    };
    const char* dialect = to_string(rd.dialect);
    ArcDirection convention = options_.arc_direction;
    if (convention != ArcDirection::Auto) {
      rd.arc_convention_source = "option";
    } else {
      convention = documented_arc_direction(rd.dialect);
      if (convention == ArcDirection::Auto) {
        // Nothing documented for this CAM system: the file's own arcs must say it clearly.
        const int decided = ccw_votes + cw_votes;
        if (decided == 0) {
          convention = ArcDirection::CounterClockwise;
          notice(arcs_.front().line,
                 "CIRCLE: the CAM system is not recognised and no arc's neighbouring moves "
                 "decide its sense; APT's counter-clockwise about (i,j,k) is assumed "
                 "(--arc-direction cw|ccw sets it)");
        } else if (std::max(ccw_votes, cw_votes) >= 0.8 * decided) {
          convention =
              ccw_votes > cw_votes ? ArcDirection::CounterClockwise : ArcDirection::Clockwise;
          rd.arc_convention_source = "tangents";
          notice(arcs_.front().line,
                 std::string("CIRCLE: the CAM system is not recognised; ") +
                     std::to_string(std::max(ccw_votes, cw_votes)) + " of " +
                     std::to_string(decided) + " decidable arcs run " +
                     (convention == ArcDirection::Clockwise ? "clockwise" : "counter-clockwise") +
                     " about their axis by the tangents of the moves beside them, so every arc "
                     "is read so (--arc-direction cw|ccw sets it)");
        } else {
          fail(arcs_.front().line,
               "CIRCLE: the CAM system is not recognised and its arcs disagree: " +
                   std::to_string(ccw_votes) + " run counter-clockwise (lines " + lines_of(1) +
                   ") and " + std::to_string(cw_votes) + " clockwise (lines " + lines_of(-1) +
                   ") by the moves beside them; give --arc-direction cw|ccw");
        }
      }
    }
    rd.arc_convention = convention;
    const int convention_sign = convention == ArcDirection::Clockwise ? -1 : 1;
    const int agree = convention_sign > 0 ? ccw_votes : cw_votes;
    const int contra = convention_sign > 0 ? cw_votes : ccw_votes;
    rd.arcs_contradicting = contra;
    const std::string sense =
        convention == ArcDirection::Clockwise ? "clockwise" : "counter-clockwise";
    if (contra > agree && rd.arc_convention_source == "documented") {
      fail(arcs_.front().line,
           "CIRCLE: " + std::to_string(contra) + " of " + std::to_string(contra + agree) +
               " decidable arcs (lines " + lines_of(-convention_sign) + ") run against the " +
               sense + " sense " + dialect +
               " files use about (i,j,k), by the moves before and after them; if the file is "
               "right, give --arc-direction cw|ccw");
    }
    if (contra > agree && rd.arc_convention_source == "option") {
      notice(arcs_.front().line, "CIRCLE: --arc-direction " + std::string(to_string(convention)) +
                                     " is against the tangents of " + std::to_string(contra) +
                                     " of " + std::to_string(contra + agree) +
                                     " decidable arcs (lines " + lines_of(-convention_sign) +
                                     "); applied as asked");
    }
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
    if (rd.arcs_reversed > 0) {
      std::string lines;
      for (int l : rd.reversed_arc_lines) lines += (lines.empty() ? "" : ", ") + std::to_string(l);
      notice(rd.reversed_arc_lines.front(),
             std::to_string(rd.arcs_reversed) + " CIRCLE record(s) (lines " + lines +
                 ") are run against the " + sense + " sense " + dialect +
                 " files use: the moves before and after each of them run the other way "
                 "(--arc-direction cw|ccw applies one sense to every arc)");
    }
    check_movarcs();
    insert_chords();
  }

  /// MOVARC's sense and sweep are written: the GOTO must end the arc ANGLE deg on, and the
  /// moves beside it must not clearly run the other way.
  void check_movarcs() {
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
      if (a.evidence < 0 && a.strong) {
        fail(a.line,
             "MOVARC: the moves before and after it run clockwise about its axis, "
             "against the counter-clockwise sweep it writes");
      }
      ++tp_.reading.arcs;
    }
  }

  /// Inserts the chords of every arc, operation by operation; events keep their place (an
  /// event before an arc's end GOTO stands before the arc).
  void insert_chords() {
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
          if (points_ > 20000000)
            fail(a.line, "more than 2e7 CL points: the file cannot be posted");
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

  /// Records' operation and point ranges from the points (after arcs were inserted and empty
  /// operations dropped).
  void index_records() {
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

  /// Rational B-spline point at t (de Boor on homogeneous coordinates).
  static Vec3d spline_point(const std::vector<double>& U, const std::vector<Eigen::Vector4d>& P,
                            int p, double t) {
    const int n = static_cast<int>(P.size()) - 1;
    int k = p;
    while (k < n && t >= U[static_cast<std::size_t>(k + 1)]) ++k;
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

  /// Evaluates the NURBS collected since its NURBS record into points within the chordal
  /// tolerance. NX's layout (docs/cl-files.md): the current point is the first control
  /// point, the CNTRL records the others; KNOT lists the knots after the p + 1 zeros and the
  /// last of the p + 1 ones, so the degree is p = (CNTRL count + 1) - (KNOT count).
  void finish_spline() {
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
    std::vector<Eigen::Vector4d> P;
    P.emplace_back(start.x(), start.y(), start.z(), 1.0);
    P.insert(P.end(), sp.control.begin(), sp.control.end());
    const double tol = options_.arc_tolerance_mm;
    std::vector<Vec3d> out;
    // Each knot span in 4 pieces, then halved while the curve strays from the chord.
    std::function<void(double, const Vec3d&, double, const Vec3d&, int)> sample =
        [&](double t0, const Vec3d& a, double t1, const Vec3d& b, int depth) {
          const Vec3d chord = b - a;
          const double len = chord.norm();
          double dev = 0.0;
          for (double f : {0.25, 0.5, 0.75}) {
            const Vec3d q = spline_point(U, P, p, t0 + f * (t1 - t0)) - a;
            const double along = len > 0.0 ? q.dot(chord) / len : 0.0;
            dev = std::max(dev, len > 0.0 ? (q - along * chord / len).norm() : q.norm());
          }
          if (dev > tol && depth < 40) {
            const double tm = 0.5 * (t0 + t1);
            const Vec3d mpt = spline_point(U, P, p, tm);
            sample(t0, a, tm, mpt, depth + 1);
            sample(tm, mpt, t1, b, depth + 1);
            return;
          }
          if (out.size() >= 1000000) fail(sp.line, what + " needs more than 1e6 points");
          out.push_back(b);
        };
    Vec3d a = start;
    double t0 = 0.0;
    for (std::size_t i = static_cast<std::size_t>(p); i + 1 < U.size(); ++i) {
      if (!(U[i + 1] > U[i])) continue;
      for (int piece = 1; piece <= 4; ++piece) {
        const double t1 = U[i] + (U[i + 1] - U[i]) * piece / 4.0;
        const Vec3d b = spline_point(U, P, p, t1);
        sample(t0, a, t1, b, 0);
        a = b;
        t0 = t1;
      }
    }
    for (const Vec3d& q : out) add_point(q, sp.motion, sp.record, sp.line);
    ++tp_.reading.splines;
    tp_.reading.spline_points += static_cast<int>(out.size());
  }

  void handle(const LogicalLine& ll) {
    ClRecord rec;
    rec.kind = ll.kind;
    rec.text = ll.raw;
    rec.line = ll.line;
    std::string args;
    if (ll.kind == RecordKind::Record) {
      rec.major = major_word(ll.code, args);
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
  }

  /// A feed word's value: FEDRAT/f, /{MMPM|IPM|PERMIN|MMPR|IPR|PERREV},f or /f,unit.
  double feed_of(const std::vector<std::string>& args, std::size_t from, const std::string& major,
                 int line) {
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
        to_mm = 1.0;
      } else if (u == "IPM") {
        to_mm = kMmPerInch;
      } else if (u == "PERMIN") {
        to_mm = scale_;
      } else if (u == "MMPR") {
        to_mm = 1.0, per_rev = true;
      } else if (u == "IPR") {
        to_mm = kMmPerInch, per_rev = true;
      } else if (u == "PERREV") {
        to_mm = scale_, per_rev = true;
      } else {
        fail(line, major + ": expected a feed and MMPM, IPM, PERMIN, MMPR, IPR or PERREV, got '" +
                       args[k] + "'");
      }
    }
    if (count != 1) fail(line, major + " expects exactly one number (the feed)");
    if (!(value > 0.0)) fail(line, major + ": feed must be positive");
    // A feed the G-code can write (0.01 mm/min is F0.0004 in inches) and a machine can run
    // (1e6 mm/min is 1 km/min).
    const auto bounded = [&](double mm_per_min) {
      if (!(mm_per_min >= 0.01 && mm_per_min <= 1e6)) {
        std::ostringstream os;
        os << major << ": a feed of " << mm_per_min
           << " mm/min is outside [0.01, 1e6] mm/min (no program writes or runs it)";
        fail(line, os.str());
      }
      return mm_per_min;
    };
    if (!per_rev) return bounded(value * to_mm);
    if (!(spindle_rpm_ > 0.0)) {
      tp_.warnings.push_back(format_location(
          source_, line, "feed per revolution without a spindle speed: feed unknown"));
      return 0.0;
    }
    return bounded(value * to_mm * spindle_rpm_);
  }

  void start_cycle(const std::vector<std::string>& args, int line) {
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

  /// The moves of a drilling cycle at a hole whose top is `top`: in at the retract height, down
  /// to the rapid plane, feed to depth in pecks (back to the rapid plane between them), out.
  void drill_hole(const Vec3d& top, int record, int line) {
    const DrillCycle& c = *cycle_;
    const Vec3d u = axis_;
    const double clear = std::max(c.retract_to_mm, c.rapid_to_mm);
    const double saved_feed = feed_mm_per_min_;
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
    ++tp_.reading.cycle_holes;
  }

  void skipped(const std::string& major) { ++tp_.skipped_records[major]; }

  void interpret(const std::string& major, const std::string& args_text, int index, int line) {
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
          fail(line,
               "CNTRL expects x,y,z[,weight], got " + std::to_string(args.size()) + " fields");
        }
        const auto v = numbers(args, 0, args.size(), major, line);
        const double w = v.size() == 4 ? v[3] : 1.0;
        if (!(w > 0.0)) fail(line, "CNTRL: weight must be positive");
        const Vec3d q = to_mcs_point(Vec3d(v[0], v[1], v[2]));
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
                     "neither moves the tool nor changes what the moves mean, --skip-record " +
                     major + " skips it");
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
    if (major == "GOTO" || major == "FROM") {
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
      if (pending_circle_) {
        const CircleRecord c = *pending_circle_;
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
    } else if (major == "GODLTA") {
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
    } else if (major == "GOHOME") {
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
    } else if (major == "CIRCLE") {
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
          fail(line,
               "CIRCLE: '" + args[k] + "' not interpreted (only TIMES,n may follow the numbers)");
        }
      }
      c.record = index;
      c.line = line;
      tp_.records[static_cast<std::size_t>(index)].frame = frame_;
      pending_circle_ = c;
    } else if (major == "MOVARC") {
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
      c.record = index;
      c.line = line;
      tp_.records[static_cast<std::size_t>(index)].frame = frame_;
      pending_circle_ = c;
    } else if (major == "TLAXIS") {
      if (args.size() != 3) {
        fail(line, "TLAXIS expects i,j,k (the tool axis); other forms are not interpreted");
      }
      axis_ = to_mcs_vector(parse_axis(numbers(args, 0, 3, major, line), 0, major, line));
    } else if (major == "NURBS") {
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
    } else if (major == "RAPID") {
      rapid_next_ = true;
    } else if (major == "FEDRAT") {
      feed_mm_per_min_ = feed_of(args, 0, major, line);
    } else if (major == "MSYS") {
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
      const bool identity =
          (f.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9 &&
          f.origin_mm.norm() < 1e-9;
      frame_ = -1;
      if (identity) return;
      std::ostringstream os;
      os << "MSYS: MCS at (" << v[0] << ", " << v[1] << ", " << v[2] << "), its z axis ("
         << f.rotation(0, 2) << ", " << f.rotation(1, 2) << ", " << f.rotation(2, 2) << ")";
      if (!options_.apply_msys) {
        tp_.declared_frames.push_back(f);
        notice(line, os.str() +
                         ": the coordinates are posted as written (NX writes them in this MCS; "
                         "--msys apply takes them as absolute and moves them into it)");
        return;
      }
      tp_.frames.push_back(f);
      frame_ = static_cast<int>(tp_.frames.size()) - 1;
      ++tp_.reading.msys_applied;
      notice(line, os.str() +
                       ": --msys apply, the coordinates that follow are moved into it and "
                       "posted there");
    } else if (major == "MULTAX") {
      if (!args.empty() && upper(args[0]) == "OFF") {
        axis_ = Vec3d::UnitZ();  // 3-axis: +Z
        multax_off_line_ = line;
      } else if (args.empty() || upper(args[0]) == "ON") {
        multax_off_line_ = 0;
      } else {
        fail(line, "MULTAX/" + args_text + ": MULTAX, MULTAX/ON or MULTAX/OFF");
      }
    } else if (major == "CYCLE") {
      if (args.empty()) fail(line, "CYCLE expects a cycle type, INIT or OFF");
      const std::string kind = upper(args[0]);
      if (kind == "OFF") {
        cycle_.reset();
      } else if (kind != "INIT" && kind != "ON") {
        start_cycle(args, line);
      }
    } else if (major == "TLDATA") {
      if (args.empty() || upper(args[0]) != "MILL") {
        tp_.warnings.push_back(format_location(source_, line, "TLDATA other than MILL ignored"));
        skipped(major);
        return;
      }
      if (args.size() < 3) fail(line, "TLDATA/MILL expects diameter and corner radius");
      const auto v = numbers(args, 1, args.size(), major, line);
      set_tool(v[0], v[1], v.size() > 2 ? v[2] : 0.0, line);
    } else if (major == "CUTTER") {
      if (args.empty()) fail(line, "CUTTER expects a diameter");
      const auto v = numbers(args, 0, std::min<std::size_t>(args.size(), 7), major, line);
      if (v.size() == 7 && v[0] > 0.0 && v[1] > 0.5 * v[0] + 1e-9) {
        tapered_ball(v, line);
        return;
      }
      set_tool(v[0], v.size() > 1 ? v[1] : 0.0, v.size() > 6 ? v[6] : 0.0, line);
    } else if (major == "LOADTL" ||
               (major == "LOAD" && !args.empty() && upper(args[0]) == "TOOL")) {
      const std::size_t at = major == "LOADTL" ? 0 : 1;
      if (args.size() <= at) fail(line, major + " expects a tool number");
      const auto v = numbers(args, at, at + 1, major, line);
      // As --tool-number: five digits, what the dialects' T words take.
      if (!(v[0] >= 0.0 && v[0] <= 99999.0 && v[0] == std::floor(v[0]))) {
        fail(line, major + ": tool number must be a whole number from 0 to 99999");
      }
      // NX: LOAD/TOOL,n,ADJUST,h (its real files: h = n). taxopt writes the length offset of
      // the tool's own register (H n): another register is refused, not dropped (the machine
      // would run with another tool's length).
      for (std::size_t k = at + 1; k < args.size(); ++k) {
        const std::string w = upper(args[k]);
        double h = 0.0;
        if (w == "ADJUST" && k + 1 < args.size() && parse_number(args[k + 1], h)) {
          if (h != v[0]) {
            fail(line, major + "/" + args_text + ": the length offset register " + args[k + 1] +
                           " is not the tool's number; taxopt writes the tool's own (H" + args[at] +
                           "): give the tool its own register in the CAM system");
          }
          ++k;
          continue;
        }
        fail(line, major + "/" + args_text + ": '" + args[k] +
                       "' not interpreted (only ADJUST,n with the tool's own number may follow)");
      }
      tool_.number = static_cast<int>(v[0]);
      tool_changed();
    } else if (major == "SPINDL" || major == "SPINDLE") {
      spindle(args, line);
    } else if (major == "COOLNT") {
      if (args.size() != 1) fail(line, "COOLNT expects one of ON, FLOOD, MIST, OFF");
      const std::string a = upper(args[0]);
      ClCoolant c = ClCoolant::Off;
      if (a == "ON" || a == "FLOOD") {
        c = ClCoolant::Flood;
      } else if (a == "MIST") {
        c = ClCoolant::Mist;
      } else if (a != "OFF") {
        fail(line, "COOLNT/" + args[0] +
                       ": a coolant taxopt does not write (ON, FLOOD, MIST and OFF are: M8, M7, "
                       "M9); --skip-record COOLNT drops every COOLNT record");
      }
      coolant_ = c;
      ProgramEvent e;
      e.kind = ProgramEvent::Kind::Coolant;
      e.coolant = c;
      state_change(e, line);
    } else if (major == "CUTCOM") {
      if (args.empty() || upper(args[0]) != "OFF") {
        fail(line, "CUTCOM/" + args_text +
                       ": cutter compensation in the control is not posted (taxopt writes the "
                       "tool centre path the file gives, without G41/G42); --skip-record CUTCOM "
                       "posts that path as it is, without the control's wear compensation");
      }
      skipped(major);
    } else if (major == "SET") {
      if (args.size() != 2 || upper(args[0]) != "MODE" || upper(args[1]) != "ABSOL") {
        fail(line, "SET/" + args_text +
                       ": only SET/MODE,ABSOL is read (absolute coordinates); incremental or "
                       "other settings change what the moves mean");
      }
      skipped(major);
    } else if (major == "INTOL" || major == "OUTTOL" || major == "TOLER") {
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
          os << major << "/" << args_text << ": a tolerance within [0, "
             << kMaxCamToleranceMm / scale_ << "] " << to_string(tp_.units)
             << " expected (a finishing tolerance; --skip-record " << major << " ignores it)";
          fail(line, os.str());
        }
      }
      // TOLER is OUTTOL in some APT processors and the whole band in others: either way the
      // band the path may lie off the surface, which is all taxopt takes from them.
      (major == "INTOL" ? inside_tolerance_ : outside_tolerance_) = t;
      tolerance_given_ = true;
    } else if (major == "MODE") {
      // MODE/MILL says what taxopt posts anyway; any other mode changes what the moves mean.
      if (args.size() != 1 || upper(args[0]) != "MILL") {
        fail(line, "MODE/" + args_text +
                       ": a machine mode taxopt does not post (only MODE/MILL is read); a "
                       "turning or other mode changes what the moves mean");
      }
      skipped(major);
    } else if (major == "MACHIN") {
      for (const auto& a : args) {
        const std::string u = upper(a);
        if (u == "TURN" || u == "LATHE" || u == "MILLTURN") {
          fail(line, "MACHIN/" + args_text + ": a turning file; taxopt posts milling only");
        }
      }
      skipped(major);
    } else if (major == "STOP" || major == "OPSTOP") {
      ProgramEvent e;
      e.kind = major == "STOP" ? ProgramEvent::Kind::Stop : ProgramEvent::Kind::OptionalStop;
      add_event(e, line);
    } else if (major == "DELAY") {
      double sec = 0.0;
      if (args.size() != 1 || !parse_number(args[0], sec) || !(sec > 0.0 && sec <= 3600.0)) {
        fail(line,
             "DELAY expects a dwell in seconds within (0, 3600] (DELAY/REV,n is not "
             "interpreted)");
      }
      ProgramEvent e;
      e.kind = ProgramEvent::Kind::Dwell;
      e.dwell_s = sec;
      add_event(e, line);
    } else if (major == "INSERT") {
      // SOLIDWORKS CAM's INSERT/[HOLDER=C40-16ERP412] 16MM CRB 2FL 32 LOC: a bracketed note to
      // the operator, no block: dropped with a note. Any other text is what the post would write
      // into the program as it stands (INSERT/Stock Size X135. Y135. Z30. reads as a move):
      // refused, as unchecked text.
      const std::string text = trim(args_text);
      if (!text.empty() && (text.front() == '[' || text.front() == '(')) {
        tp_.warnings.push_back(format_location(
            source_, line, "INSERT/" + text.substr(0, 60) + ": an operator's note, not written"));
        skipped(major);
      } else {
        fail(line, "INSERT/" + args_text.substr(0, 60) +
                       ": text for the controller, which taxopt does not pass unchecked into a "
                       "program; --skip-record INSERT drops it");
      }
    } else if (major == "FINI" || major == "END") {
      finished_line_ = line;
    } else if (major == "LOAD" && (args.empty() || upper(args[0]) != "TOOL")) {
      fail(line, "LOAD/" + args_text + ": only LOAD/TOOL,n is interpreted");
    } else if (major == "TOOL PATH") {
      op_ = -1;
      in_block_ = true;
      pending_name_ = args.empty() ? std::string() : args[0];
      for (std::size_t k = 1; k + 1 < args.size(); ++k) {
        if (upper(args[k]) == "TOOL") tool_.name = args[k + 1];
      }
    } else if (major == "END-OF-PATH") {
      op_ = -1;
      in_block_ = false;
    } else if (major != "UNITS" && major != "UNIT") {
      skipped(major);
    }
  }

  /// SPINDL/[speed][,RPM|SFM|SMM][,CLW|CCLW] or /OFF or /ON: the spindle from here on.
  void spindle(const std::vector<std::string>& args, int line) {
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
        os << "SPINDL: " << *value << " " << unit << " at the cutter's diameter "
           << tool_.diameter_mm << " mm is " << std::lround(rpm) << " rpm";
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
    ProgramEvent e;
    e.kind = ProgramEvent::Kind::Spindle;
    e.spindle_rpm = rpm;
    e.spindle_clockwise = cw;
    state_change(e, line);
  }

  /// A spindle or coolant change: the operation's own setting before its first point, an
  /// event where it stands after (none before any operation: current_op copies the state).
  void state_change(const ProgramEvent& e, int line) {
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

  /// An event before the operation's next point.
  void add_event(ProgramEvent e, int line) {
    auto& op = current_op();
    e.before_point = op.points.size();
    e.line = line;
    op.events.push_back(e);
  }

  /// APT's CUTTER/d,r,e,f,a,b,h with r > d/2: a tapered ball-end mill of ball radius r whose
  /// flanks, at b from the axis, are tangent to the ball (e = 0, f = r, a = 0); d is the
  /// diameter where the flank line meets the tip plane, 2 r (1 - sin b) / cos b.
  void tapered_ball(const std::vector<double>& v, int line) {
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

  void set_tool(double d, double r, double length, int line) {
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

  std::string source_;
  ClReadOptions options_;
  Toolpath tp_;
  double scale_ = 1.0;
  int op_ = -1;
  int frame_ = -1;
  bool in_block_ = false;
  std::string pending_name_;
  Tool tool_;
  double spindle_rpm_ = 0.0;
  bool spindle_cw_ = true;
  Vec3d axis_ = Vec3d::UnitZ();
  bool rapid_next_ = false;
  double feed_mm_per_min_ = 0.0;
  /// The CAM's tolerances of the part surface in force (INTOL, OUTTOL, TOLER), file units.
  double inside_tolerance_ = 0.0, outside_tolerance_ = 0.0;
  bool tolerance_given_ = false;
  std::optional<CircleRecord> pending_circle_;
  std::vector<PendingArc> arcs_;
  std::optional<PendingSpline> spline_;
  std::optional<DrillCycle> cycle_;
  std::optional<std::pair<Vec3d, Vec3d>> home_;
  std::size_t points_ = 0;
  double last_rpm_ = 0.0;
  std::optional<ClCoolant> coolant_;
  int finished_line_ = 0;    // line of FINI / END
  int multax_off_line_ = 0;  // line of the MULTAX/OFF in force
};

}  // namespace

Toolpath parse_cl(const std::string& text, const std::string& source,
                  const ClReadOptions& options) {
  return Reader(source, options).run(text);
}

Toolpath read_cl_file(const std::string& path, const ClReadOptions& options) {
  // A CL file is a regular file: a FIFO would hang and /dev/zero would be read whole (issue
  // 35). 2 GB is beyond the 2e7 points the reader posts at the most.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, 0, "not a regular file (a CL file is one)");
  }
  if (std::filesystem::file_size(path, ec) > (std::uintmax_t{2} << 30)) {
    throw InputError(path, 0, "larger than 2 GB: more than the 2e7 CL points taxopt posts");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open CL file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "cannot read CL file");
  return parse_cl(ss.str(), path, options);
}

}  // namespace taxopt
