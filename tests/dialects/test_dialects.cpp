// Every dialect of src/dialects/: its words, written by its rules, are read back by the reader
// with the same rules (tool, length offset, TCP, the retract in machine coordinates, the
// units), its template codes are taken and the others' refused, and its name is the machine
// file's. A new dialect in all_dialects() is checked here without a line more.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "dialects/dialect_rules.hpp"
#include "machine/template_block.hpp"
#include "support.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"

using namespace taxopt;
using taxopt::gcode::DialectRules;

namespace {

/// A small tcp-mode program in `r`'s words alone (no writer): start, a comment, set-up, tool,
/// length and TCP on, a rapid and two feed blocks, TCP off, the retract, the park and the end.
struct SmallProgram {
  std::string text;
  int last_feed_line = 0;  // the line of the second feed block
  int retract_line = 0;
};

SmallProgram small_program(const DialectRules& r, bool inch) {
  SmallProgram p;
  std::vector<std::string> lines;
  int n = 0;
  const auto add = [&](const std::string& s) { lines.push_back(s); };
  const auto block = [&](const std::string& words) { add(r.block(words, n)); };
  // Hostile words in the name and a comment: a unit code and a '%' (a TNC's begin block).
  const gcode::ProgramName name{"G70-G71-TEST", 7, inch};
  for (const auto& s : r.start(name)) add(s);
  add(r.comment("a comment (with parentheses) at 50% of G70", n));
  block(r.setup(inch, false));
  if (const std::string w = r.default_work_offset(); !w.empty()) block(w);
  for (const auto& s : r.tool_change(3)) block(s);
  block("S8000 M3");
  for (const auto& s : r.length_on(true, 3)) block(s);
  for (const auto& s : r.tcp_on(3)) block(s);
  const auto num = [&](double v) { return r.number(v, 4); };
  block(r.first_move_prefix(true, 3) + r.rapid() + " X" + num(10) + " Y" + num(20) + " Z" + num(5) +
        " A" + num(15) + " C" + num(30));
  block(r.linear() + " X" + num(12) + " Y" + num(20) + " Z" + num(4) + " F" + num(600));
  p.last_feed_line = static_cast<int>(lines.size()) + 1;
  block(r.linear() + " X" + num(14) + " Y" + num(21) + " Z" + num(4) + " A" + num(16));
  for (const auto& s : r.tcp_off(true)) block(s);
  p.retract_line = static_cast<int>(lines.size()) + 1;
  for (const auto& s : r.retract(num(100))) block(s);
  for (const auto& s : r.park(num(-50), num(60))) block(s);
  block(r.end());
  for (const auto& s : r.finish(name)) add(s);
  for (const auto& s : lines) p.text += s + "\n";
  return p;
}

}  // namespace

TEST_CASE("dialects: one rules object per GcodeDialect, named as the machine file names it",
          "[dialects]") {
  const auto& all = gcode::all_dialects();
  REQUIRE(all.size() == gcode_dialects().size());
  std::set<std::string> names;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const DialectRules& r = *all[k];
    INFO(r.name());
    CHECK(static_cast<std::size_t>(r.id()) == k);  // the order of the enum
    CHECK(&gcode::rules_of(r.id()) == &r);
    CHECK(std::string(to_string(r.id())) == r.name());
    names.insert(r.name());
    // The machine file takes the name and gives the dialect back.
    std::string toml = taxopt::test::read_file(std::string(TAXOPT_SOURCE_DIR) +
                                               "/data/machines/generic-ac-trt.toml");
    const std::string line = "dialect = \"linuxcnc\"";
    REQUIRE(toml.find(line) != std::string::npos);
    toml.replace(toml.find(line), line.size(), "dialect = \"" + std::string(r.name()) + "\"");
    const Machine m = parse_machine_toml(toml, "dialect.toml");
    CHECK(m.gcode.dialect == r.id());
    CHECK(max_decimals(r.id()) == r.max_decimals());
    CHECK(max_feed_decimals(r.id()) == r.max_feed_decimals());
    CHECK(has_inverse_time(r.id()) == r.inverse_time());
  }
  CHECK(names.size() == all.size());
}

TEST_CASE("dialects: each dialect's words read back by its own reader", "[dialects]") {
  for (const DialectRules* rp : gcode::all_dialects()) {
    const DialectRules& r = *rp;
    for (const bool inch : {false, true}) {
      INFO(r.name() << (inch ? " inch" : " mm"));
      const SmallProgram p = small_program(r, inch);
      INFO(p.text);
      const std::vector<GcodeMove> moves =
          read_gcode_moves(p.text, "dialect.nc", r.id(), {}, 'A', {});
      // The rapid, the two feed blocks, the retract and the park.
      REQUIRE(moves.size() == 5);
      const double unit_mm = inch ? kMmPerInch : 1.0;
      CHECK(moves[0].rapid);
      CHECK(moves[0].xyz_mm.isApprox(Vec3d(10, 20, 5) * unit_mm));
      CHECK(moves[0].tilt_deg == Approx(15));
      CHECK(moves[0].c_deg == Approx(30));
      for (int k = 0; k < 3; ++k) {
        CHECK(moves[k].tool == 3);
        CHECK(moves[k].spindle_on);
        CHECK(moves[k].length_offset);  // on before (or with) the first move
        CHECK(moves[k].tcp);
        CHECK_FALSE(moves[k].retract);
      }
      CHECK_FALSE(moves[1].rapid);
      CHECK(moves[1].feed == Approx(600));
      CHECK(moves[2].line == p.last_feed_line);
      CHECK(moves[2].xyz_mm.isApprox(Vec3d(14, 21, 4) * unit_mm));
      CHECK(moves[2].tilt_deg == Approx(16));
      // The retract: in machine coordinates, to its Z or the reference point; after TCP off.
      CHECK(moves[3].retract);
      CHECK(moves[3].positioning);
      CHECK(moves[3].tcp == r.read_words().tcp_from_start);  // LinuxCNC's: its kinematics
      CHECK(moves[3].machine_mm.z() == Approx(r.retract_to_reference() ? 0.0 : 100 * unit_mm));
      CHECK(moves[3].given == 0x4u);
      // The park: X and Y in machine coordinates.
      CHECK(moves[4].retract);
      CHECK(moves[4].given == 0x3u);
      CHECK(moves[4].machine_mm.x() == Approx(-50 * unit_mm));
      CHECK(moves[4].machine_mm.y() == Approx(60 * unit_mm));
    }
  }
}

TEST_CASE("dialects: a dwell, where the dialect writes one, is a block its reader takes",
          "[dialects]") {
  for (const DialectRules* r : gcode::all_dialects()) {
    INFO(r->name());
    const std::string dwell = r->dwell(1.5);
    CHECK(dwell.empty() == !r->read_words().g4_dwell);
    if (dwell.empty()) continue;
    int n = 0;
    const std::string text = r->block(r->setup(false, false), n) + "\n" + r->block(dwell, n) +
                             "\n" + r->block(r->rapid() + " X1. Y2. Z3. A0. C0.", n) + "\n";
    CHECK(read_gcode_moves(text, "dwell.nc", r->id(), {}, 'A', {}).size() == 1);
  }
}

TEST_CASE("dialects: a template takes the dialect's own G codes and refuses the others'",
          "[dialects]") {
  std::set<double> every;
  for (const DialectRules* r : gcode::all_dialects()) {
    for (double g : r->template_words().g_codes) every.insert(g);
  }
  REQUIRE(every.size() > 5);
  for (const DialectRules* r : gcode::all_dialects()) {
    const gcode::TemplateWords words = r->template_words();
    const std::set<double> own(words.g_codes.begin(), words.g_codes.end());
    for (double g : every) {
      const std::string block =
          "G" + gcode::fmt(g, g == static_cast<int>(g) ? 0 : 1) + (g == 4 ? " P1" : "");
      INFO(r->name() << ": " << block);
      const std::string problem = template_block_problem(block, "gcode.header", r->id(), false);
      CHECK(problem.empty() == (own.count(g) == 1));
    }
    for (const std::string& w : words.long_words) {
      INFO(r->name() << ": " << w);
      CHECK(template_block_problem(w == "CYCLE832" ? "CYCLE832(0.01, 0, 1)" : w, "gcode.header",
                                   r->id(), false)
                .empty());
    }
  }
}

TEST_CASE(
    "dialects: Fanuc and Haas read a program as a tape from one % to the next -- no % in a "
    "written comment or a template's, and a semicolon is no comment there (it is elsewhere)",
    "[dialects][hostile]") {
  for (const DialectRules* r : gcode::all_dialects()) {
    INFO(r->name());
    const bool tape = r->template_words().tape;
    CHECK(tape == (r->id() == GcodeDialect::Fanuc || r->id() == GcodeDialect::Haas));
    int n = 0;
    const std::string c = r->comment("operation FINISH_100%_STOCK", n);
    CHECK((c.find('%') == std::string::npos) == tape);
    if (tape) {
      CHECK(c == "(operation FINISH_100pct_STOCK)");
      const gcode::ProgramName name{"AT_50%", 7, false};
      const std::vector<std::string> start = r->start(name);
      // The program's own marks, and no other.
      std::size_t marks = 0;
      for (const std::string& s : start)
        marks += static_cast<std::size_t>(std::count(s.begin(), s.end(), '%'));
      CHECK(marks == 1);
    }
    const std::string percent =
        template_block_problem("G40 (100% STOCK)", "gcode.header", r->id(), false);
    const std::string semicolon =
        template_block_problem("G40;G0 X-300 Z-50", "gcode.header", r->id(), false);
    if (tape) {
      CHECK_THAT(percent, Catch::Contains("'%' in a comment"));
      CHECK_THAT(semicolon, Catch::Contains("';'"));
    } else if (r->template_words().paren_comments) {
      CHECK(percent.empty());
      CHECK(semicolon.empty());
    }
  }
}

TEST_CASE("dialects: a number is written as printf's %.*f writes it, and read back as strtod",
          "[dialects][gcode]") {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-12, 6), decimals(0, 6);
  std::vector<double> values = {0.0,    -0.0,     0.5,       1.5,        2.5,
                                -0.5,   0.125,    -0.00004,  0.00005,    1e300,
                                -1e300, 4.9e-324, 359.99995, -179.99995, 1e-7};
  for (int k = 0; k < 20000; ++k) values.push_back(unit(rng) * std::pow(10.0, exponent(rng)));
  for (double v : values) {
    const int d = decimals(rng);
    char buf[400];
    std::snprintf(buf, sizeof buf, "%.*f", d, v);
    std::string want = buf;
    if (want.find_first_not_of("-0.") == std::string::npos && want[0] == '-') want.erase(0, 1);
    INFO(v << " with " << d << " decimals");
    REQUIRE(gcode::fmt(v, d) == want);
    REQUIRE(gcode::round_to(v, d) == std::strtod(want.c_str(), nullptr));
  }
}
