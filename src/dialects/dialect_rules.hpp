#pragma once
/// @file What a controller's dialect is, in one place: how taxopt writes its words, which words
/// it reads back from a program (read_gcode_moves), and which a machine file's program template
/// may hold (docs/gcode-dialects.md). One class per controller, each in its own file of this
/// folder with the manual it follows; `rules_of` finds it (dialects.cpp holds the list).
/// Internal to the library: the writer's Dialect (gcode/dialect.hpp) formats with these words.

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "taxopt/kinematics/machine.hpp"
#include "util/text.hpp"

namespace taxopt::gcode {

/// `text` (a number as "%.*f" writes it) without the sign of a negative zero: no "-0.0000",
/// a negative number that rounds to zero is written as zero.
inline std::string fmt_signless_zero(const char* text) {
  std::string s = text;
  bool all_zero = true;
  for (char c : s) {
    if (c != '-' && c != '0' && c != '.') all_zero = false;
  }
  if (all_zero && !s.empty() && s[0] == '-') s.erase(0, 1);
  return s;
}

/// `v` with `decimals` decimals, as every dialect writes a number: printf's "%.*f"
/// (detail::fixed_text, a program of 143,840 points formats over a million numbers) without a
/// negative zero's sign.
inline std::string fmt(double v, int decimals) {
  return fmt_signless_zero(detail::fixed_text(v, decimals).text);
}

/// The value a reader gets back from fmt(v, decimals) (from_chars: strtod's value, correctly
/// rounded, in the C locale). Read from the text before fmt drops a zero's sign: a text of
/// zeros reads as 0 whatever its sign, every other text as fmt writes it.
inline double round_to(double v, int decimals) {
  const detail::FixedText f = detail::fixed_text(v, decimals);
  double out = 0.0;
  if (std::from_chars(f.text, f.text + f.size, out).ec != std::errc()) {
    out = std::strtod(f.text, nullptr);
  }
  return out == 0.0 ? 0.0 : out;
}

/// Comment text for a controller: no parentheses (they close a LinuxCNC or Fanuc comment),
/// no line breaks.
inline std::string comment_text(const std::string& text) {
  std::string s;
  for (char c : text) {
    if (c == '(') {
      s += '[';
    } else if (c == ')') {
      s += ']';
    } else if (c == '\n' || c == '\r') {
      s += ' ';
    } else {
      s += c;
    }
  }
  return s;
}

/// Comment text for a controller that reads its program as a tape, from one `%` to the next
/// (Fanuc, Haas): comment_text with each `%` written "pct" -- a `%` inside a comment (an
/// operation named FINISH_100%_STOCK) ends the program there.
inline std::string tape_comment_text(const std::string& text) {
  std::string s;
  for (char c : comment_text(text)) {
    if (c == '%') {
      s += "pct";
    } else {
      s += c;
    }
  }
  return s;
}

/// `n` with leading zeros to `width` digits (a Fanuc or Haas program number, O0001).
inline std::string zero_padded(int n, int width) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%0*d", width, n);
  return buf;
}

/// The program's name and number as a dialect writes them at its start and end.
struct ProgramName {
  std::string name;
  int number = 1;
  bool inch = false;
};

/// What the reader takes out of a line before its words (DialectRules::own_words).
struct LineMarks {
  /// Nothing more to read in the line (a TNC's program begin or end block).
  bool nothing_more = false;
  /// The program's unit set by the line (mm per program unit).
  std::optional<double> mm_per_unit;
  /// Tool centre point control switched on or off.
  std::optional<bool> tcp;
  /// The block's positions are in machine coordinates (Sinumerik's SUPA).
  bool machine_coordinates = false;
};

/// The words read_gcode_moves reads in a program of the dialect (besides those every dialect
/// shares: G0 G1 G17-G19 G40 G54 G80 G90 G93 G94, X Y Z A/B C F M N S T).
struct ReadWords {
  bool g2_g3_arcs = true;          ///< G2/G3 with I J K
  bool g20_g21_units = true;       ///< G20/G21 (ISO); else the dialect's own (own_words, G700/G710)
  bool g700_g710_units = false;    ///< Sinumerik's G700/G710
  bool g4_dwell = false;           ///< G4 P, the CL file's DELAY
  bool path_control = false;       ///< LinuxCNC's G64 P Q and G61
  bool g43_length = true;          ///< G43 (H): tool length compensation on
  bool g49_cancels = true;         ///< G49: length compensation off
  bool g49_cancels_tcp = false;    ///< G49 also ends tool centre point control (Fanuc, Haas)
  double tcp_g_code = 0.0;         ///< the G code of length and TCP on (43.4, 234); 0: none
  bool g53_machine = true;         ///< G53: the block in machine coordinates
  bool g91_g28 = false;            ///< G91 G28: the reference return (Fanuc's retract)
  bool h_word = true;              ///< H, the length offset number
  bool o_word = false;             ///< O, the program number
  bool d_word = false;             ///< D, the tool's offset (Sinumerik: D0 off, D1 on)
  bool m128_m91 = false;           ///< a TNC's M128/M129 (TCP) and M91 (machine coordinates)
  bool t_calls_tool = false;       ///< T is the tool call, length included (TNC: T n G17)
  bool length_from_start = false;  ///< the tool's length is applied from the start (TNC)
  bool tcp_from_start = false;     ///< TCP is the controller's kinematics (LinuxCNC)

  /// A control whose units, tool length and machine coordinates have words of its own
  /// (Sinumerik's G700 D SUPA, a TNC's program block, tool call and M91): none of G20/G21,
  /// G43, G49, G53, H.
  static ReadWords without_iso_words() {
    ReadWords r;
    r.g20_g21_units = r.g43_length = r.g49_cancels = r.g53_machine = r.h_word = false;
    return r;
  }
};

/// The words a machine file's program template may hold in the dialect (template_block.cpp).
struct TemplateWords {
  bool paren_comments = true;               ///< "( )" comments (not Sinumerik's or a TNC's)
  std::vector<double> g_codes;              ///< G codes any template block may hold
  std::vector<double> tool_change_g_codes;  ///< ... and gcode.tool_change besides
  std::vector<std::string> long_words;      ///< words of several letters (Sinumerik's FFWON)
  bool settable_frames = false;             ///< work offsets G505 ... G599 (Sinumerik)
  /// Fanuc, Haas: the program is read as a tape from one `%` to the next, so no `%` in a
  /// comment, and `;` is no comment there (it is LinuxCNC's, Sinumerik's and a TNC's).
  bool tape = false;
};

/// One controller's dialect. Defaults are the ISO words LinuxCNC, Fanuc and Haas share; each
/// dialect overrides what its controller does differently.
class DialectRules {
 public:
  virtual ~DialectRules() = default;
  virtual GcodeDialect id() const = 0;
  /// The name in a machine file's gcode.dialect and the CLI's --dialect: "linuxcnc" ...
  virtual const char* name() const = 0;

  // --- What the controller takes ---------------------------------------------------------
  /// The most decimals of a position or angle.
  virtual int max_decimals() const = 0;
  /// The most decimals of an F word.
  virtual int max_feed_decimals() const { return 15; }
  /// G93 inverse time is written.
  virtual bool inverse_time() const { return true; }

  // --- Writing -----------------------------------------------------------------------------
  /// A block as written (a TNC numbers its blocks: N10 ... *); `number` counts the blocks.
  virtual std::string block(const std::string& words, int& number) const {
    (void)number;
    return words;
  }
  /// A comment, as a block of its own.
  virtual std::string comment(const std::string& text, int& number) const;
  /// Lines before the comments: the program start.
  virtual std::vector<std::string> start(const ProgramName&) const { return {}; }
  /// A comment naming the program after the start ("program NAME").
  virtual bool names_program() const { return false; }
  /// The largest program number its O word takes (gcode.program_number; Fanuc's O1 to O9999).
  virtual int max_program_number() const { return 9999; }
  /// The modal set-up block: units, absolute, plane, no compensation, feed mode.
  virtual std::string setup(bool inch, bool inverse_time) const;
  /// The path control block after the set-up (LinuxCNC's G64 P<blend> Q0), in program units.
  virtual std::string path_control(double blend_tolerance, int decimals) const {
    (void)blend_tolerance;
    (void)decimals;
    return {};
  }
  /// The work offset written where the template names none.
  virtual std::string default_work_offset() const { return "G54"; }
  /// The retract to machine Z (`z` written); its target is the machine's Z there, or the
  /// reference point (retract_to_reference).
  virtual std::vector<std::string> retract(const std::string& z) const = 0;
  virtual bool retract_to_reference() const { return false; }
  /// The end's park of X and Y in machine coordinates.
  virtual std::vector<std::string> park(const std::string& x, const std::string& y) const = 0;
  /// The tool change where the template has none.
  virtual std::vector<std::string> tool_change(int tool) const {
    return {"T" + std::to_string(tool) + " M6"};
  }
  /// The tool length offset on for an operation, as blocks of its own.
  virtual std::vector<std::string> length_on(bool tcp, int offset) const {
    (void)tcp;
    (void)offset;
    return {};
  }
  /// Tool centre point control on, before an operation's first move (tcp mode only).
  virtual std::vector<std::string> tcp_on(int offset) const {
    (void)offset;
    return {};
  }
  /// The length compensation (and TCP) come on with the operation's first motion block,
  /// first_move_prefix, instead of blocks of their own.
  virtual bool length_on_first_move() const { return false; }
  /// Words in front of an operation's first motion block (Fanuc starts G43.4 there).
  virtual std::string first_move_prefix(bool tcp, int offset) const {
    (void)tcp;
    (void)offset;
    return {};
  }
  /// Length compensation and TCP off after an operation.
  virtual std::vector<std::string> tcp_off(bool tcp) const {
    (void)tcp;
    return {"G49"};
  }
  /// A dwell of `seconds`; empty: the dialect has none taxopt writes.
  virtual std::string dwell(double seconds) const {
    (void)seconds;
    return {};
  }
  virtual std::string rapid() const { return "G0"; }
  virtual std::string linear() const { return "G1"; }
  /// G2/G3 are written where a run of points is an arc.
  virtual bool writes_arcs() const { return true; }
  /// An arc may follow a turn of A or C under tool centre point control (Fanuc's G43.4 and
  /// Haas's G234 refuse circular interpolation there).
  virtual bool arc_after_tcp_turn() const { return true; }
  /// Under TCP the controller plans every block, rapids too, in the program's axes and its
  /// kinematics turn them into joints (LinuxCNC's trajectory planner): the writer bounds a rapid
  /// to the joints' rate, and the read-back times the blocks by that planner's model
  /// (controller/linuxcnc_planner.hpp). The others move the joints of a rapid at their rates.
  virtual bool tcp_planned_in_program_axes() const { return false; }
  /// The program end code.
  virtual std::string end() const { return "M30"; }
  /// Lines after the end.
  virtual std::vector<std::string> finish(const ProgramName&) const { return {}; }
  /// Every number carries its decimal point (Fanuc reads "10" as 0.010 mm).
  virtual bool point_in_every_number() const { return false; }
  /// A coordinate as written: `decimals` decimals, with its point where the controller needs
  /// one.
  std::string number(double v, int decimals) const {
    std::string s = fmt(v, decimals);
    if (point_in_every_number() && s.find('.') == std::string::npos) s += '.';
    return s;
  }

  // --- Reading back ------------------------------------------------------------------------
  virtual ReadWords read_words() const { return {}; }
  /// The dialect's own words taken out of `line` before its address words are read.
  virtual LineMarks own_words(std::string& line) const {
    (void)line;
    return {};
  }

  // --- A machine file's program template ---------------------------------------------------
  virtual TemplateWords template_words() const = 0;
  /// Why the word `letter``number` may not stand in a template of the dialect; empty: the
  /// common rules decide.
  virtual std::string template_refusal(char letter, double number) const {
    (void)letter;
    (void)number;
    return {};
  }
};

/// The rules of `dialect`.
const DialectRules& rules_of(GcodeDialect dialect);
/// Every dialect taxopt writes, in the order of GcodeDialect.
const std::vector<const DialectRules*>& all_dialects();

// One function per dialect, defined in its file.
const DialectRules& linuxcnc_rules();
const DialectRules& fanuc_rules();
const DialectRules& siemens_rules();
const DialectRules& heidenhain_rules();
const DialectRules& haas_rules();

}  // namespace taxopt::gcode
