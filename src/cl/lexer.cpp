// The CL file's lexer (lexer.hpp).
#include "cl/lexer.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <set>

#include "cl/cl_words.hpp"
#include "taxopt/core/error.hpp"

namespace taxopt::cl {
namespace {

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

}  // namespace

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

bool is_point_line(const std::string& code) {
  const std::vector<std::string> fields = split_args(code);
  if (fields.size() != 3 && fields.size() != 6) return false;
  for (const std::string& f : fields) {
    const std::string t = trim(f);
    if (t.empty()) return false;
    char* end = nullptr;
    std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size()) return false;
  }
  return true;
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

namespace {

/// The file's physical lines: any of CR, LF and CRLF ends one (a file may mix them);
/// `line_end` the one it uses throughout (LF where mixed), `final_line_end` whether its last
/// line has one. A NUL byte is refused (no CL text file).
std::vector<std::string> physical_lines(const std::string& text, const std::string& source,
                                        std::string& line_end, bool& final_line_end) {
  std::vector<std::string> physical;
  line_end = "\n";
  bool saw_crlf = false;
  std::size_t start = 0;
  bool saw_lf = false, saw_cr = false;
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

  return physical;
}

/// A `$$` comment from line i: one ending in `$` continues on the next line (Creo's `$$->
/// CSYS / 1.0, 0.0,  $` and its numbers below) unless that line is a record or a comment of
/// its own: a banner of `$$$$$$$$` or a sentence ending in `US$` before a GOTO joined the GOTO
/// to the comment, and it vanished. Returns its last line's index.
std::size_t read_comment(const std::vector<std::string>& physical, std::size_t i, LogicalLine& ll) {
  const std::string first = trim(physical[i]);
  ll.kind = RecordKind::Comment;
  std::string cur = first;
  while (cur.size() > 2 && cur.back() == '$' && i + 1 < physical.size() &&
         !starts_record(physical[i + 1])) {
    ++i;
    ll.raw += "\n" + physical[i];
    cur = trim(physical[i]);
  }
  return i;
}

/// Text records (PPRINT, PARTNO, INSERT): `$$` in their text is text.
bool is_text_record(const std::string& first) {
  std::string word;
  for (char ch : first) {
    if (!std::isalpha(static_cast<unsigned char>(ch))) break;
    word += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  }
  const std::size_t after = first.find_first_not_of(" \t", word.size());
  return (word == "PPRINT" || word == "PARTNO" || word == "INSERT") &&
         (after == std::string::npos || first[after] == '/' || word == "PARTNO");
}

/// A record from line i, its `$` continuations joined (the next line follows with no
/// separator: it may split a number); a text record's `$` at the end continues it (CATIA's
/// `PPRINT/(=====$` then `=====)`) unless the next line is a record of its own (`PPRINT/TOOL
/// COST 12 US$` then `GOTO/50,0,5`: the GOTO vanished). Returns its last line's index.
std::size_t read_record(const std::vector<std::string>& physical, std::size_t i,
                        const std::string& source, LogicalLine& ll) {
  const bool text_record = is_text_record(trim(physical[i]));
  std::string code;
  std::string piece = physical[i];
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
  return i;
}

}  // namespace

std::vector<LogicalLine> split_logical(const std::string& text, const std::string& source,
                                       std::string& line_end, bool& final_line_end) {
  const std::vector<std::string> physical = physical_lines(text, source, line_end, final_line_end);
  std::vector<LogicalLine> out;
  for (std::size_t i = 0; i < physical.size(); ++i) {
    LogicalLine ll;
    ll.line = static_cast<int>(i) + 1;
    ll.raw = physical[i];
    const std::string first = trim(physical[i]);
    if (first.empty() || (first == "\x1a" && i + 1 == physical.size())) {
      // A DOS end-of-file mark (Ctrl-Z) alone on the last line: nothing to read, kept for
      // the round trip.
      ll.kind = RecordKind::Blank;
    } else if (first.rfind("$$", 0) == 0) {
      i = read_comment(physical, i, ll);
    } else if (first.size() >= 6 && upper(first.substr(0, 6)) == "REMARK" &&
               (first.size() == 6 || std::isspace(static_cast<unsigned char>(first[6])))) {
      // APT's comment statement (ANSI X3.37: REMARK and its text are not processed); Creo's
      // GPOST writes it on line 2.
      ll.kind = RecordKind::Comment;
    } else {
      i = read_record(physical, i, source, ll);
    }
    out.push_back(ll);
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

std::pair<int, std::string> turning_record(const std::vector<LogicalLine>& lines) {
  for (const auto& ll : lines) {
    if (ll.kind != RecordKind::Record) continue;
    std::string args;
    const std::string major = major_word(ll.code, args);
    const std::vector<std::string> fields = split_args(args);
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const std::string u = upper(fields[k]);
      if (major == "TURRET" ||
          ((major == "MACHIN" || major == "MODE") &&
           (u == "TURN" || u == "LATHE" || u == "MILLTURN")) ||
          (major == "TOOLNO" && u == "TURN")) {
        // The record up to the word that says so ("TOOLNO/1,TURN,...").
        std::string shown = major + "/";
        for (std::size_t j = 0; j <= k; ++j) shown += (j ? "," : "") + fields[j];
        return {ll.line, shown + (k + 1 < fields.size() ? ",..." : "")};
      }
    }
  }
  return {0, ""};
}

DialectEvidence detect_dialect(const std::vector<LogicalLine>& lines) {
  // Only what a CAM system writes in its own structure counts: a PPRINT's or a comment's free
  // text is no evidence (an audit's "PPRINT/POST FOR MAKINO D500" made a generic file Makino
  // and reversed its arcs), nor is a record other systems write too (TLDATA).
  DialectEvidence out;
  const auto found = [&](ClDialect d, int line, const std::string& what) {
    for (const DialectEvidence::Seen& s : out.seen) {
      if (s.dialect == d) return;
    }
    out.seen.push_back({d, line, what});
  };
  for (const auto& ll : lines) {
    const std::string up = upper(ll.raw);
    if (ll.kind == RecordKind::Comment) {
      // Creo's header "$$* Pro/CLfile Version ..." and CATIA's "$$ CATIA APT VERSION ...".
      if (up.rfind("$$*", 0) == 0 && up.find("PRO/CLFILE") != std::string::npos) {
        found(ClDialect::Creo, ll.line, "Creo's header ($$* Pro/CLfile)");
      }
      if (up.find("CATIA APT VERSION") != std::string::npos) {
        found(ClDialect::Catia, ll.line, "CATIA's header ($$ CATIA APT VERSION)");
      }
      continue;
    }
    if (ll.kind != RecordKind::Record) continue;
    std::string args;
    const std::string major = major_word(ll.code, args);
    if (major == "TOOL PATH" || major == "END-OF-PATH" || major == "MSYS") {
      found(ClDialect::SiemensNx, ll.line, "NX CLSF's " + major + " record");
    }
    if (major == "TRNTYP" || major.rfind("CSI_", 0) == 0) {
      found(ClDialect::SolidworksCam, ll.line, "SOLIDWORKS CAM's " + major + " record");
    }
    // Makino FF APT-CL declares itself: PPRINT/APTCL-SPEC,MAKINO-FF,<version> on line 1
    // (steptools/STEPNode examples/data/Plane_2.cldata).
    std::string text = upper(args);
    text.erase(std::remove(text.begin(), text.end(), ' '), text.end());
    if (major == "PPRINT" && text.rfind("APTCL-SPEC,MAKINO-FF", 0) == 0) {
      found(ClDialect::MakinoFfcam, ll.line, "Makino FF's PPRINT/APTCL-SPEC,MAKINO-FF");
    }
  }
  if (!out.seen.empty()) {
    out.dialect = out.seen.front().dialect;
    out.evidence = "line " + std::to_string(out.seen.front().line) + ": " + out.seen.front().what;
  }
  return out;
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

}  // namespace taxopt::cl
