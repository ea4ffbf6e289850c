// APT / NX CLSF reader. The traps it survives are listed in docs/cl-files.md; each has a test.
#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"

namespace taxopt {
namespace {

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

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

/// A logical line: physical lines joined over `$` continuations.
struct LogicalLine {
  std::string raw;   // physical lines joined by '\n'
  std::string code;  // the record text with continuations joined and `$$` comments removed
  int line = 0;
  RecordKind kind = RecordKind::Record;
};

const std::set<std::string>& known_words() {
  static const std::set<std::string> words = {
      "GOTO",   "FROM",   "RAPID",   "FEDRAT",    "TLDATA",      "CUTTER", "LOADTL", "LOAD",
      "MULTAX", "SPINDL", "SPINDLE", "TOOL PATH", "END-OF-PATH", "PAINT",  "MSYS",   "FINI",
      "UNITS",  "UNIT",   "CIRCLE",  "PARTNO",    "SELECT",      "END",    "COOLNT", "CUTCOM",
      "INSERT", "PPRINT", "CSYS",    "TRNTYP",    "CYCLE",       "STOP",   "MACHIN", "TPRINT"};
  return words;
}

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
  if (folded != up && !known_words().count(up)) return "";
  if (slash == std::string::npos && up.find(' ') != std::string::npos) return "";
  return up;
}

std::vector<LogicalLine> split_logical(const std::string& text, const std::string& source,
                                       std::string& line_end, bool& final_line_end) {
  std::vector<std::string> physical;
  line_end = "\n";
  bool saw_crlf = false;
  std::size_t start = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\0') {
      const int line = static_cast<int>(physical.size()) + 1;
      throw InputError(source, line, "binary data (NUL byte): not a CL text file");
    }
    if (text[i] == '\n') {
      std::size_t e = i;
      if (e > start && text[e - 1] == '\r') {
        --e;
        saw_crlf = true;
      }
      physical.push_back(text.substr(start, e - start));
      start = i + 1;
    }
  }
  final_line_end = start == text.size();
  if (start < text.size()) {
    std::string last = text.substr(start);
    if (!last.empty() && last.back() == '\r') last.pop_back();
    physical.push_back(last);
  }
  if (saw_crlf) line_end = "\r\n";

  std::vector<LogicalLine> out;
  std::size_t i = 0;
  while (i < physical.size()) {
    LogicalLine ll;
    ll.line = static_cast<int>(i) + 1;
    ll.raw = physical[i];
    const std::string first = trim(physical[i]);
    if (first.empty()) {
      ll.kind = RecordKind::Blank;
      out.push_back(ll);
      ++i;
      continue;
    }
    if (first.rfind("$$", 0) == 0) {
      // A comment; a comment ending in `$` continues on the next line (Creo's `$$->`).
      ll.kind = RecordKind::Comment;
      std::string cur = first;
      while (cur.size() > 2 && cur.back() == '$' && i + 1 < physical.size()) {
        ++i;
        ll.raw += "\n" + physical[i];
        cur = trim(physical[i]);
      }
      out.push_back(ll);
      ++i;
      continue;
    }
    std::string code;
    std::string piece = physical[i];
    for (;;) {
      const std::size_t comment = piece.find("$$");
      if (comment != std::string::npos) piece = piece.substr(0, comment);
      std::string t = piece;
      while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
      if (!t.empty() && t.back() == '$') {
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

struct PendingCircle {
  Vec3d centre;
  Vec3d axis;
  double radius = 0.0;  // 0: from the start point
  int turns = 0;        // TIMES,n: n extra full turns
  int record = -1;
  int line = 0;
};

class Reader {
 public:
  Reader(const std::string& source, const ClReadOptions& options)
      : source_(source), options_(options) {}

  Toolpath run(const std::string& text) {
    tp_.source = source_;
    auto lines = split_logical(text, source_, tp_.line_end, tp_.final_line_end);
    determine_units(lines);
    scale_ = mm_per_unit(tp_.units);
    for (const auto& ll : lines) handle(ll);
    if (pending_circle_) {
      throw InputError(source_, pending_circle_->line, "CIRCLE is not followed by its end GOTO");
    }
    if (point_count(tp_) == 0) {
      throw InputError(source_, 0, "no GOTO records: not a cutter-location file");
    }
    // Drop operations that received no point (a TOOL PATH block with no motion).
    std::vector<int> remap(tp_.operations.size(), -1);
    std::vector<Operationd> kept;
    for (std::size_t k = 0; k < tp_.operations.size(); ++k) {
      if (!tp_.operations[k].points.empty()) {
        remap[k] = static_cast<int>(kept.size());
        kept.push_back(std::move(tp_.operations[k]));
      }
    }
    tp_.operations = std::move(kept);
    for (auto& r : tp_.records) {
      if (r.op >= 0) r.op = remap[static_cast<std::size_t>(r.op)];
    }
    for (std::size_t k = 0; k < tp_.operations.size(); ++k) {
      if (tp_.operations[k].name.empty()) tp_.operations[k].name = std::to_string(k + 1);
    }
    return std::move(tp_);
  }

 private:
  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(source_, line, what);
  }

  void determine_units(const std::vector<LogicalLine>& lines) {
    if (options_.units) {
      tp_.units = *options_.units;
      return;
    }
    bool inch_feed = false;
    for (const auto& ll : lines) {
      if (ll.kind != RecordKind::Record) continue;
      std::string args;
      const std::string major = major_word(ll.code, args);
      if (major == "UNITS" || major == "UNIT") {
        const std::string a = upper(trim(split_args(args).empty() ? "" : split_args(args)[0]));
        if (a == "INCHES" || a == "INCH" || a == "IN") {
          tp_.units = LengthUnit::Inch;
        } else if (a == "MM" || a == "MILLIMETERS" || a == "MILLIMETRES" || a == "METRIC") {
          tp_.units = LengthUnit::Millimetre;
        } else {
          fail(ll.line, major + " expects INCHES or MM, got '" + trim(args) + "'");
        }
        return;
      }
      if (major == "FEDRAT") {
        for (const auto& a : split_args(args)) {
          const std::string u = upper(a);
          if (u == "IPM" || u == "IPR") inch_feed = true;
        }
      }
    }
    tp_.units = inch_feed ? LengthUnit::Inch : LengthUnit::Millimetre;
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

  void add_point(const Vec3d& tip_mm, Motion motion, int record, int line) {
    auto& op = current_op();
    CLPointd p;
    p.tip_mm = tip_mm;
    p.axis = axis_;
    p.feed_mm_per_min = feed_mm_per_min_;
    p.motion = motion;
    p.line = line;
    p.record = record;
    auto& r = tp_.records[static_cast<std::size_t>(record)];
    if (r.first_point < 0) r.first_point = static_cast<int>(op.points.size());
    r.op = op_;
    ++r.point_count;
    op.points.push_back(p);
  }

  void expand_circle(const PendingCircle& c, const Vec3d& end_mm, int goto_line) {
    auto& op = current_op();
    if (op.points.empty()) fail(c.line, "CIRCLE has no start point (no GOTO before it)");
    const Vec3d start = op.points.back().tip_mm;
    const Vec3d s = start - c.centre, e = end_mm - c.centre;
    const double hs = s.dot(c.axis), he = e.dot(c.axis);
    const Vec3d sp = s - hs * c.axis, ep = e - he * c.axis;
    const double rs = sp.norm(), re = ep.norm();
    const double tol = options_.arc_tolerance_mm;
    if (rs < 1e-9 || re < 1e-9) fail(c.line, "CIRCLE: start or end point lies on its axis");
    const double r_given = c.radius > 0.0 ? c.radius : rs;
    const double mismatch = std::max(std::abs(rs - r_given), std::abs(re - r_given));
    if (mismatch > 0.01 * r_given + 0.01) {
      std::ostringstream os;
      os << source_ << ":" << goto_line << ": CIRCLE radius " << r_given
         << " mm but the arc's ends lie at " << rs << " and " << re
         << " mm from its axis; interpolated as a spiral";
      tp_.warnings.push_back(os.str());
    }
    // Right-hand rule: the motion is counter-clockwise about the CIRCLE axis (APT).
    double phi = std::atan2(sp.cross(ep).dot(c.axis), sp.dot(ep));
    if (phi <= 1e-12) phi += Constants<double>::two_pi();
    phi += Constants<double>::two_pi() * c.turns;
    const double r_max = std::max(rs, re);
    const double step = tol < r_max ? 2.0 * std::acos(1.0 - tol / r_max) : phi;
    const double segments = std::ceil(phi / step);
    if (segments > 1e6)
      fail(c.line, "CIRCLE needs more than 1e6 chords: radius or TIMES too large");
    const int n = std::max(1, static_cast<int>(segments));
    const Vec3d u = sp / rs, w = c.axis.cross(u);
    for (int k = 1; k < n; ++k) {
      const double t = static_cast<double>(k) / n;
      const double th = phi * t, r = rs + (re - rs) * t;
      const Vec3d p =
          c.centre + (hs + (he - hs) * t) * c.axis + r * (std::cos(th) * u + std::sin(th) * w);
      add_point(p, Motion::Feed, c.record, c.line);
    }
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

  void interpret(const std::string& major, const std::string& args_text, int index, int line) {
    const auto args = split_args(args_text);
    if (pending_circle_ && major != "GOTO" && major != "PAINT" && major != "FEDRAT") {
      fail(line, "CIRCLE at line " + std::to_string(pending_circle_->line) +
                     " must be followed by its end GOTO, got " + major);
    }
    if (major == "GOTO" || major == "FROM") {
      if (args.size() != 3 && args.size() != 6) {
        fail(line, major + " expects 3 or 6 numbers (x,y,z[,i,j,k]), got " +
                       std::to_string(args.size()) + " fields");
      }
      const auto v = numbers(args, 0, args.size(), major, line);
      if (v.size() == 6) axis_ = parse_axis(v, 3, major, line);
      const Vec3d tip = Vec3d(v[0], v[1], v[2]) * scale_;
      if (pending_circle_) {
        const PendingCircle c = *pending_circle_;
        pending_circle_.reset();
        expand_circle(c, tip, line);
      }
      const Motion m = (major == "FROM" || rapid_next_) ? Motion::Rapid : Motion::Feed;
      rapid_next_ = false;
      add_point(tip, m, index, line);
    } else if (major == "CIRCLE") {
      std::size_t nnum = 0;
      while (nnum < args.size() && is_number_like(args[nnum])) ++nnum;
      if (nnum < 6) fail(line, "CIRCLE expects at least 6 numbers (xc,yc,zc,i,j,k[,r,...])");
      const auto v = numbers(args, 0, nnum, major, line);
      PendingCircle c;
      c.centre = Vec3d(v[0], v[1], v[2]) * scale_;
      c.axis = parse_axis(v, 3, major, line);
      c.radius = nnum >= 7 ? v[6] * scale_ : 0.0;
      if (c.radius < 0.0) fail(line, "CIRCLE radius must not be negative");
      for (std::size_t k = nnum; k < args.size(); ++k) {
        if (upper(args[k]) == "TIMES") {
          double t = 0.0;
          if (k + 1 >= args.size() || !parse_number(args[k + 1], t) || t < 1 || t > 1000 ||
              t != std::floor(t)) {
            fail(line, "CIRCLE TIMES expects a whole number from 1 to 1000");
          }
          c.turns = static_cast<int>(t);
        }
      }
      c.record = index;
      c.line = line;
      pending_circle_ = c;
    } else if (major == "RAPID") {
      rapid_next_ = true;
    } else if (major == "FEDRAT") {
      double value = -1.0;
      int count = 0;
      double to_mm = scale_;
      bool per_rev = false;
      for (const auto& a : args) {
        const std::string u = upper(a);
        double v;
        if (parse_number(a, v)) {
          value = v;
          ++count;
        } else if (u == "MMPM") {
          to_mm = 1.0;
        } else if (u == "IPM") {
          to_mm = kMmPerInch;
        } else if (u == "MMPR") {
          to_mm = 1.0, per_rev = true;
        } else if (u == "IPR") {
          to_mm = kMmPerInch, per_rev = true;
        } else {
          fail(line, "FEDRAT: expected a feed and MMPM, IPM, MMPR or IPR, got '" + a + "'");
        }
      }
      if (count != 1) fail(line, "FEDRAT expects exactly one number (the feed)");
      if (!(value > 0.0)) fail(line, "FEDRAT: feed must be positive");
      if (per_rev) {
        if (!(spindle_rpm_ > 0.0)) {
          tp_.warnings.push_back(format_location(
              source_, line, "feed per revolution without a spindle speed: feed unknown"));
          feed_mm_per_min_ = 0.0;
        } else {
          feed_mm_per_min_ = value * to_mm * spindle_rpm_;
        }
      } else {
        feed_mm_per_min_ = value * to_mm;
      }
    } else if (major == "TLDATA") {
      if (args.empty() || upper(args[0]) != "MILL") {
        tp_.warnings.push_back(format_location(source_, line, "TLDATA other than MILL ignored"));
        return;
      }
      if (args.size() < 3) fail(line, "TLDATA/MILL expects diameter and corner radius");
      const auto v = numbers(args, 1, args.size(), major, line);
      set_tool(v[0], v[1], v.size() > 2 ? v[2] : 0.0, line);
    } else if (major == "CUTTER") {
      if (args.empty()) fail(line, "CUTTER expects a diameter");
      const auto v = numbers(args, 0, std::min<std::size_t>(args.size(), 7), major, line);
      set_tool(v[0], v.size() > 1 ? v[1] : 0.0, v.size() > 6 ? v[6] : 0.0, line);
    } else if (major == "LOADTL" ||
               (major == "LOAD" && !args.empty() && upper(args[0]) == "TOOL")) {
      const std::size_t at = major == "LOADTL" ? 0 : 1;
      if (args.size() <= at) fail(line, major + " expects a tool number");
      const auto v = numbers(args, at, at + 1, major, line);
      if (!(v[0] >= 0.0 && v[0] <= 1e6 && v[0] == std::floor(v[0]))) {
        fail(line, major + ": tool number must be a whole number from 0 to 1000000");
      }
      tool_.number = static_cast<int>(v[0]);
      tool_changed();
    } else if (major == "SPINDL" || major == "SPINDLE") {
      for (const auto& a : args) {
        const std::string u = upper(a);
        double v;
        if (parse_number(a, v)) {
          if (v < 0.0) fail(line, major + ": spindle speed must not be negative");
          spindle_rpm_ = v;
        } else if (u == "CLW") {
          spindle_cw_ = true;
        } else if (u == "CCLW") {
          spindle_cw_ = false;
        } else if (u == "OFF") {
          spindle_rpm_ = 0.0;
        }
      }
      if (op_ >= 0 && tp_.operations[static_cast<std::size_t>(op_)].points.empty()) {
        tp_.operations[static_cast<std::size_t>(op_)].spindle_rpm = spindle_rpm_;
        tp_.operations[static_cast<std::size_t>(op_)].spindle_clockwise = spindle_cw_;
      }
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
    } else if (!known_words().count(major)) {
      ++tp_.unknown_records[major];
    }
  }

  void set_tool(double d, double r, double length, int line) {
    if (!(d > 0.0)) fail(line, "tool diameter must be positive");
    if (r < 0.0 || r > 0.5 * d + 1e-9) fail(line, "tool corner radius must be in [0, diameter/2]");
    if (length < 0.0) fail(line, "tool length must not be negative");
    tool_.diameter_mm = d * scale_;
    tool_.corner_radius_mm = r * scale_;
    tool_.flute_length_mm = length * scale_;
    tool_.from_file = true;
    tool_changed();
  }

  std::string source_;
  ClReadOptions options_;
  Toolpath tp_;
  double scale_ = 1.0;
  int op_ = -1;
  bool in_block_ = false;
  std::string pending_name_;
  Tool tool_;
  double spindle_rpm_ = 0.0;
  bool spindle_cw_ = true;
  Vec3d axis_ = Vec3d::UnitZ();
  bool rapid_next_ = false;
  double feed_mm_per_min_ = 0.0;
  std::optional<PendingCircle> pending_circle_;
};

}  // namespace

Toolpath parse_cl(const std::string& text, const std::string& source,
                  const ClReadOptions& options) {
  return Reader(source, options).run(text);
}

Toolpath read_cl_file(const std::string& path, const ClReadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open CL file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "cannot read CL file");
  return parse_cl(ss.str(), path, options);
}

}  // namespace taxopt
