#include <catch2/catch.hpp>
#include <set>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/io/cl_file.hpp"

using namespace taxopt;
using taxopt::test::read_file;
using taxopt::test::real_data;

namespace {

struct Counts {
  int gotos = 0, with_axis = 0;
  std::set<std::tuple<long, long, long>> axes;
};

/// Each record of `first_lines` put before `body` stops the reader with an InputError naming
/// line 1.
void check_refused_at_line_1(const std::vector<std::string>& first_lines, const std::string& body) {
  for (const std::string& bad : first_lines) {
    INFO(bad);
    try {
      parse_cl(bad + body, "bad.cls");
      FAIL("accepted");
    } catch (const InputError& e) {
      CHECK(e.line() == 1);
    }
  }
}

Counts count_records(const Toolpath& tp) {
  Counts c;
  for (const auto& r : tp.records) {
    if (r.major != "GOTO") continue;
    ++c.gotos;
    // Count the numbers of the joined record text, without inline `$$` comments
    // (NX writes the contact point there: `GOTO/x,y,z $$ cx,cy,cz`).
    std::string joined;
    std::size_t start = 0;
    while (start <= r.text.size()) {
      std::size_t end = r.text.find('\n', start);
      if (end == std::string::npos) end = r.text.size();
      std::string line = r.text.substr(start, end - start);
      line = line.substr(0, line.find("$$"));
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      if (!line.empty() && line.back() == '$') line.pop_back();
      joined += line;
      start = end + 1;
    }
    const int commas = static_cast<int>(std::count(joined.begin(), joined.end(), ','));
    if (commas == 5) ++c.with_axis;
  }
  for (const auto& op : tp.operations) {
    for (const auto& p : op.points) {
      if (p.record >= 0 && tp.records[static_cast<std::size_t>(p.record)].major == "GOTO") {
        c.axes.insert({std::lround(p.axis.x() * 1e4), std::lround(p.axis.y() * 1e4),
                       std::lround(p.axis.z() * 1e4)});
      }
    }
  }
  return c;
}

}  // namespace

TEST_CASE("cl reader: every real file reads with the counts of SOURCES.md", "[io][cl]") {
  struct Expect {
    const char* file;
    int gotos, with_axis;
    LengthUnit units;
    std::size_t operations;
  };
  const Expect expects[] = {
      {"mech491-variable-axis-ballmill.cls", 348, 329, LengthUnit::Inch, 1},
      {"mech491-project2-multiop.cls", 10585, 5514, LengthUnit::Inch, 15},
      {"peening-catia-multax.aptsource", 31, 31, LengthUnit::Millimetre, 2},
      {"amorim-tilt-support1.apt", 184, 184, LengthUnit::Millimetre, 3},
      {"amorim-interface-glue.apt", 6311, 0, LengthUnit::Millimetre, 4},
      {"amorim-wall-holes.apt", 1864, 692, LengthUnit::Millimetre, 10},
      {"creopost-profilfraesen.ncl", 52, 0, LengthUnit::Millimetre, 1},
  };
  for (const auto& e : expects) {
    INFO(e.file);
    const Toolpath tp = taxopt::test::read_real(e.file);
    const Counts c = count_records(tp);
    CHECK(c.gotos == e.gotos);
    CHECK(c.with_axis == e.with_axis);
    CHECK(tp.units == e.units);
    CHECK(tp.operations.size() == e.operations);
    for (const auto& op : tp.operations) {
      for (const auto& p : op.points) {
        REQUIRE(p.axis.norm() == Approx(1.0).margin(1e-12));
        REQUIRE(p.tip_mm.allFinite());
      }
    }
  }
}

TEST_CASE("cl reader: distinct axes of the 5-axis files match SOURCES.md", "[io][cl]") {
  CHECK(count_records(taxopt::test::read_real("mech491-variable-axis-ballmill.cls")).axes.size() ==
        329);
  // 23 distinct axes on GOTOs (SOURCES.md counts them after rounding to 1e-4).
  CHECK(count_records(taxopt::test::read_real("peening-catia-multax.aptsource")).axes.size() == 23);
}

TEST_CASE("cl reader: a real file written back unchanged is byte-identical", "[io][cl]") {
  for (const char* f :
       {"mech491-variable-axis-ballmill.cls", "mech491-project2-multiop.cls",
        "peening-catia-multax.aptsource", "amorim-tilt-support1.apt", "amorim-interface-glue.apt",
        "amorim-wall-holes.apt", "creopost-profilfraesen.ncl"}) {
    INFO(f);
    const std::string text = taxopt::test::real_text(f);
    ClReadOptions o;
    for (const auto& w : taxopt::test::real_skips(f)) o.skip_records.insert(w);
    const Toolpath tp = parse_cl(text, f, o);
    CHECK(format_cl(tp, tp.operations) == text);
  }
}

TEST_CASE("cl reader: NX traps: modal axis, IPM feed, inch ball mill, listing lines", "[io][cl]") {
  const Toolpath tp = taxopt::test::read_real("mech491-variable-axis-ballmill.cls");
  const auto& op = tp.operations.at(0);
  CHECK(op.name == "NORM_PART");
  CHECK(op.tool.is_ball());
  CHECK(op.tool.ball_radius_mm() == Approx(0.5 * 25.4));
  // Line 16: GOTO/-3.5411,-3.0016,1.2387 keeps the axis of line 13's GOTO.
  const CLPointd* p = nullptr;
  for (const auto& q : op.points) {
    if (q.line == 16) p = &q;
  }
  REQUIRE(p);
  // MSYS/3,3,0,... says the MCS lies at (3, 3, 0); NX writes the GOTOs in it already (its
  // Haas post writes them unchanged: tests/data/real-post), so they are posted as written.
  CHECK(p->tip_mm.x() == Approx(-3.5411 * 25.4));
  CHECK(p->tip_mm.y() == Approx(-3.0016 * 25.4));
  CHECK(tp.reading.msys_applied == 0);
  REQUIRE(tp.declared_frames.size() == 1);
  CHECK(tp.declared_frames[0].origin_mm.x() == Approx(3.0 * 25.4));
  CHECK(tp.notices.size() == 1);
  // --msys apply takes them as absolute and moves them into the MCS.
  const Toolpath applied = [] {
    ClReadOptions o;
    o.apply_msys = true;
    return taxopt::test::read_real("mech491-variable-axis-ballmill.cls", o);
  }();
  CHECK(applied.operations.at(0).points.at(2).tip_mm.x() == Approx((-3.5411 - 3.0) * 25.4));
  CHECK(applied.reading.msys_applied == 1);
  CHECK(p->axis.x() == Approx(-0.3778015).margin(1e-6));
  CHECK(p->feed_mm_per_min == Approx(10.0 * 25.4));
  CHECK(p->motion == Motion::Feed);
  // The first two GOTOs follow RAPID.
  CHECK(op.points[0].motion == Motion::Rapid);
  CHECK(op.points[1].motion == Motion::Rapid);
  // The trailer with no final newline is no record: one warning.
  REQUIRE(tp.warnings.size() == 1);
  CHECK(tp.warnings[0].find("Tool Path Listing") != std::string::npos);
  CHECK_FALSE(tp.final_line_end);
}

TEST_CASE("cl reader: CATIA traps: CRLF, a number split by '$', FROM with an axis", "[io][cl]") {
  const Toolpath tp = taxopt::test::read_real("peening-catia-multax.aptsource");
  CHECK(tp.line_end == "\r\n");
  // CUTTER/ 1.700000, 0.000000, 0.850000, 0, 0,$ + 0.000000, 1.968504: APT d, r, e, f, a, b,
  // h -- a 1.7 mm end mill (r = 0) of height 1.968504, the 7th number on the next line.
  const auto& op = tp.operations.back();
  CHECK(op.tool.diameter_mm == Approx(1.7));
  CHECK_FALSE(op.tool.is_ball());
  CHECK(op.tool.flute_length_mm == Approx(1.968504));
  const auto& from = tp.operations.front().points.front();
  CHECK(from.motion == Motion::Rapid);
  // Line 81 ends '..., 0$' and line 82 is '.752602': the k component is 0.752602.
  const CLPointd* p81 = nullptr;
  for (const auto& q : op.points) {
    if (q.line == 81) p81 = &q;
  }
  REQUIRE(p81);
  CHECK(p81->tip_mm.x() == Approx(-5.673572));
  const double norm81 = std::sqrt(0.655944 * 0.655944 + 0.057682 * 0.057682 + 0.752602 * 0.752602);
  CHECK(p81->axis.z() == Approx(0.752602 / norm81).margin(1e-9));
  CHECK(p81->feed_mm_per_min == Approx(2000.0));
  for (const auto& o : tp.operations) {
    for (const auto& q : o.points) CHECK(q.axis.norm() == Approx(1.0));
  }
  CHECK(tp.warnings.empty());
}

TEST_CASE("cl reader: '$' joins without a separator, also inside numbers", "[io][cl]") {
  const Toolpath tp = parse_cl("GOTO/1.5,2.$\n25,0$\n.5,0,0,1\n", "t.cls");
  const auto& p = tp.operations.at(0).points.at(0);
  CHECK(p.tip_mm.y() == Approx(2.25));
  CHECK(p.tip_mm.z() == Approx(0.5));
  CHECK(p.line == 1);
}

TEST_CASE("cl reader: Creo comments continue over '$' and are no records", "[io][cl]") {
  const Toolpath tp = taxopt::test::read_real("creopost-profilfraesen.ncl");
  CHECK(tp.warnings.empty());
  // The `$$->` records are comments: only the file's own non-motion words are skipped.
  std::set<std::string> skipped;
  for (const auto& [word, count] : tp.skipped_records) skipped.insert(word);
  CHECK(skipped == std::set<std::string>{"MACHIN", "PARTNO"});
  CHECK(tp.reading.dialect == ClDialect::Creo);
  CHECK(tp.units == LengthUnit::Millimetre);
}

TEST_CASE("cl reader: SOLIDWORKS numbers, units, tools and operations", "[io][cl]") {
  const Toolpath tp = taxopt::test::read_real("amorim-tilt-support1.apt");
  const auto& p = tp.operations.at(0).points.at(0);
  CHECK(p.axis.x() == Approx(-0.173648).margin(1e-6));
  CHECK(tp.operations[0].tool.diameter_mm == Approx(16.0));
  CHECK_FALSE(tp.operations[0].tool.is_ball());
  CHECK(tp.operations[0].tool.number == 4);
  const Toolpath glue = taxopt::test::read_real("amorim-interface-glue.apt");
  bool ball14 = false;
  for (const auto& op : glue.operations)
    ball14 = ball14 || (op.tool.is_ball() && op.tool.diameter_mm == Approx(14.0));
  CHECK(ball14);
}

TEST_CASE("cl reader: numbers in every accepted spelling", "[io][cl]") {
  const Toolpath tp = parse_cl("GOTO/+1.5e2,.5,16.\nGOTO/-0.25E-1 , 2 ,3\n", "t.cls");
  const auto& pts = tp.operations.at(0).points;
  CHECK(pts[0].tip_mm == Vec3d(150.0, 0.5, 16.0));
  CHECK(pts[1].tip_mm.x() == Approx(-0.025));
}

TEST_CASE("cl reader: units from UNITS, from IPM feeds, and from the option", "[io][cl]") {
  CHECK(parse_cl("UNITS/INCHES\nGOTO/1,0,0\n", "a").operations[0].points[0].tip_mm.x() ==
        Approx(25.4));
  CHECK(parse_cl("FEDRAT/IPM,10\nGOTO/1,0,0\n", "a").units == LengthUnit::Inch);
  CHECK(parse_cl("FEDRAT/10,MMPM\nGOTO/1,0,0\n", "a").units == LengthUnit::Millimetre);
  ClReadOptions o;
  o.units = LengthUnit::Inch;
  CHECK(parse_cl("GOTO/1,0,0\n", "a", o).operations[0].points[0].tip_mm.x() == Approx(25.4));
  // An IPM feed in a millimetre file is still inches per minute.
  CHECK(parse_cl("UNITS/MM\nFEDRAT/IPM,10\nGOTO/1,0,0\n", "a")
            .operations[0]
            .points[0]
            .feed_mm_per_min == Approx(254.0));
  // No UNITS, feeds in both: one FEDRAT/IPM among MMPM feeds is no evidence of inches (it read
  // X30 as 762 mm); refused naming both lines and the option, which reads it.
  const std::string mixed = "FEDRAT/MMPM,500\nGOTO/30,0,0\nFEDRAT/IPM,20\nGOTO/40,0,0\n";
  CHECK_THAT(test::input_error_of([&] { parse_cl(mixed, "m.cls"); }),
             Catch::StartsWith("m.cls:3: ") && Catch::Contains("line 3") &&
                 Catch::Contains("line 1") && Catch::Contains("ClReadOptions::units"));
  ClReadOptions mm;
  mm.units = LengthUnit::Millimetre;
  CHECK(parse_cl(mixed, "m.cls", mm).operations[0].points[0].tip_mm.x() == Approx(30.0));
  CHECK(parse_cl("UNITS/MM\n" + mixed, "m.cls").operations[0].points[0].tip_mm.x() == Approx(30.0));
}

TEST_CASE("cl reader: passes are split at rapids", "[io][cl]") {
  const Toolpath tp = parse_cl(
      "RAPID\nGOTO/0,0,10\nGOTO/0,0,0\nGOTO/1,0,0\nRAPID\nGOTO/1,0,10\nRAPID\nGOTO/5,0,10\n"
      "GOTO/5,0,0\nGOTO/6,0,0\nGOTO/7,0,0\n",
      "t");
  const auto passes = feed_passes(tp.operations[0]);
  REQUIRE(passes.size() == 2);
  CHECK(passes[0].begin == 0);
  CHECK(passes[0].end == 3);
  CHECK(passes[1].begin == 4);
  CHECK(passes[1].end == 8);
}

TEST_CASE("cl reader: CIRCLE becomes chords within tolerance, counter-clockwise about its axis",
          "[io][cl]") {
  // Quarter circle of radius 10 about +Z from (10,0) to (0,10): counter-clockwise.
  ClReadOptions o;
  o.arc_tolerance_mm = 0.001;
  const Toolpath tp = parse_cl("GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,0.01\nGOTO/0,10,0\n", "t", o);
  const auto& pts = tp.operations[0].points;
  REQUIRE(pts.size() > 10);
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    CHECK(pts[i].tip_mm.head<2>().norm() == Approx(10.0).margin(1e-9));
    CHECK(pts[i].tip_mm.x() > 0.0);
    CHECK(pts[i].tip_mm.y() > 0.0);
    // Sagitta of each chord within the tolerance.
    const double chord = (pts[i].tip_mm - pts[i - 1].tip_mm).norm();
    CHECK(10.0 - std::sqrt(100.0 - chord * chord / 4) <= 0.001 + 1e-12);
  }
  // About -Z the same ends go the long way round (clockwise seen from +Z).
  const Toolpath cw = parse_cl("GOTO/10,0,0\nCIRCLE/0,0,0,0,0,-1,10\nGOTO/0,10,0\n", "t", o);
  bool went_negative = false;
  for (const auto& p : cw.operations[0].points)
    went_negative = went_negative || p.tip_mm.y() < -9.0;
  CHECK(went_negative);
  // The unchanged file still round-trips to the same text.
  CHECK(format_cl(tp, tp.operations) == "GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,0.01\nGOTO/0,10,0\n");
}

TEST_CASE("cl reader: a CIRCLE with TIMES,n is a helix of n revolutions in all", "[io][cl]") {
  // NX's helical ramps (mech491-project2-multiop.cls, lines 4641 and 4689): read as n turns in
  // all, the ramp climbs at 3.00 deg, NX's ramp angle; with n extra turns it would be 2.62.
  const Toolpath tp =
      parse_cl("GOTO/10,0,5\nCIRCLE/0,0,0,0,0,1,10,0.01,TIMES,2\nGOTO/0,10,0\n", "t");
  const auto& pts = tp.operations[0].points;
  double turned = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const double a0 = std::atan2(pts[i - 1].tip_mm.y(), pts[i - 1].tip_mm.x());
    const double a1 = std::atan2(pts[i].tip_mm.y(), pts[i].tip_mm.x());
    turned += wrap_pi(a1 - a0);
    CHECK(pts[i].tip_mm.z() <= pts[i - 1].tip_mm.z() + 1e-12);
  }
  CHECK(rad_to_deg(turned) == Approx(360.0 + 90.0).margin(1e-6));
}

TEST_CASE("cl writer: changed points become GOTOs in the file's units", "[io][cl]") {
  const Toolpath tp = parse_cl("UNITS/INCHES\nGOTO/1,2,3,0,0,1\nPAINT/COLOR,3\nGOTO/2,2,3\n", "t");
  auto ops = tp.operations;
  ops[0].points[1].axis = Vec3d(0, -std::sqrt(0.5), std::sqrt(0.5));
  const std::string out = format_cl(tp, ops);
  CHECK(out.find("UNITS/INCHES\nGOTO/1,2,3,0,0,1\nPAINT/COLOR,3\nGOTO/2.000000,2.000000,3.000000,"
                 "0.000000000,-0.707106781,0.707106781\n") == 0);
  const Toolpath back = parse_cl(out, "back");
  CHECK((back.operations[0].points[1].axis - ops[0].points[1].axis).norm() < 1e-9);
}

TEST_CASE(
    "cl reader: a `$` at the end of a comment or a text record is text, not a continuation -- "
    "the record after it is read (a banner, a price in a PPRINT), while a commented-out list "
    "goes on as Creo writes it",
    "[io][cl][hostile]") {
  const std::string head = "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\n";
  const std::string tail = "GOTO/0,0,5\nGOTO/50,0,5\nGOTO/50,50,5\n";
  for (const std::string& trap :
       {std::string("PPRINT/TOOL COST 12 US$\n"), std::string("PARTNO BRACKET $\n"),
        std::string("$$$$$$$$$$$$$$$$$$$$\n"), std::string("$$ price in US$\n")}) {
    INFO(trap);
    const Toolpath tp = parse_cl(head + trap + tail, "t.cls");
    std::size_t points = 0;
    for (const Operationd& op : tp.operations) points += op.points.size();
    CHECK(points == 3);
  }
  // Creo: `$$-> CSYS / 1, 0, 0, 0,  $` continues its list on the next line, in the comment.
  const Toolpath creo =
      parse_cl(head + "$$-> CSYS / 1.0, 0.0, 0.0, 0.0,  $\n            0.0, 1.0, 0.0, 0.0\n" + tail,
               "c.cls");
  std::size_t points = 0;
  for (const Operationd& op : creo.operations) points += op.points.size();
  CHECK(points == 3);
}

TEST_CASE("cl reader: GOHOME with NX's Gohome point goes there, without it to the FROM point",
          "[io][cl][hostile]") {
  const std::string head =
      "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nFROM/0,0,100\nGOTO/10,10,5\n"
      "GOTO/20,10,5\n";
  const auto last_tip = [](const Toolpath& tp) {
    return tp.operations.back().points.back().tip_mm;
  };
  const Toolpath nx = parse_cl(head + "GOHOME/20.0,10.0,50.0,0.0,0.0,1.0\n", "nx.cls");
  CHECK(last_tip(nx).isApprox(Vec3d(20, 10, 50)));
  CHECK(nx.operations.back().points.back().motion == Motion::Rapid);
  const Toolpath apt = parse_cl(head + "GOHOME\n", "apt.cls");
  CHECK(last_tip(apt).isApprox(Vec3d(0, 0, 100)));
  CHECK_THROWS_AS(parse_cl(head + "GOHOME/1,2\n", "bad.cls"), InputError);
}

TEST_CASE(
    "cl reader: a CIRCLE whose end GOTO is off its circle is refused naming its line, "
    "not posted as a spiral",
    "[io][cl][hostile][arcs]") {
  const std::string head = "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nGOTO/10,0,0\n";
  // On the circle: read, with its chords.
  const Toolpath ok =
      parse_cl(head + "CIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\nGOTO/0,20,0\n", "ok.cls");
  CHECK(ok.operations.front().points.size() > 4);
  // 5 mm off (radius 10 to 15), and 0.01 mm off: refused, the CIRCLE's line named.
  for (const char* end : {"GOTO/0,15,0\n", "GOTO/0,10.01,0\n"}) {
    INFO(end);
    try {
      parse_cl(head + "CIRCLE/0,0,0,0,0,1,10\n" + end + "GOTO/0,20,0\n", "bad.cls");
      FAIL("accepted");
    } catch (const InputError& e) {
      CHECK(e.line() == 4);
      CHECK_THAT(e.what(), Catch::Contains("not on the circle"));
    }
  }
}

TEST_CASE(
    "cl reader: the words production posts read every day -- MODE/MILL, SET/MODE,ABSOL and "
    "APT's REMARK -- are read, and the modes that change what the moves mean are refused by name",
    "[io][cl][words]") {
  const std::string body =
      "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/50,0,5\n";
  const auto points = [](const Toolpath& tp) {
    std::size_t n = 0;
    for (const Operationd& op : tp.operations) n += op.points.size();
    return n;
  };
  // Fusion 360's APT line 1, Makino FFCAM's DEFINE section, Creo GPOST's line 2.
  CHECK(points(parse_cl("MODE/MILL\n" + body, "fusion.apt")) == 2);
  CHECK(points(parse_cl("UNITS/MM\nSET/MODE,ABSOL\n" + body, "makino.cldata")) == 2);
  CHECK(points(parse_cl("PARTNO PART1\nREMARK created by GPOST\nREMARK\n" + body, "creo.ncl")) ==
        2);
  check_refused_at_line_1({"MODE/TURN\n", "MODE/MILL,TURN\n", "SET/MODE,INCR\n", "SET/TOOL,3\n"},
                          body);
  // A word that starts like REMARK is no comment.
  CHECK_THROWS_AS(parse_cl("REMARKABLE/1\n" + body, "x.cls"), InputError);
}

TEST_CASE(
    "cl reader: hostile input, round 4 -- a DOS Ctrl-Z at the end is read past, CYCLE/TAP and a "
    "length register other than the tool's (LOAD/TOOL,5,ADJUST,7) are refused naming the line",
    "[io][cl][hostile]") {
  const std::string body =
      "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/50,0,5\n";
  const Toolpath z = parse_cl(body + "FINI\n\x1a", "dos.cls");
  CHECK(z.operations.front().points.size() == 2);
  CHECK(format_cl(z, z.operations) == body + "FINI\n\x1a");
  const Toolpath nx = parse_cl("LOAD/TOOL,5,ADJUST,5\n" + body, "nx.cls");
  CHECK(nx.operations.front().tool.number == 5);
  check_refused_at_line_1({"LOAD/TOOL,5,ADJUST,7\n", "LOAD/TOOL,5,SPINDLE,7\n",
                           "CYCLE/TAP,FEDTO,10,RAPTO,2,MMPM,100\n"},
                          body);
}

TEST_CASE(
    "cl reader: LOADTL as CAM systems write it -- Creo's OSETNO, Fusion's pocket, length and "
    "offset by position, IN and LENGTH -- the register the tool's own, the length the tool "
    "model's gauge length -- another register or a word not known is refused naming the line",
    "[io][cl][words]") {
  const std::string body = "CUTTER/6.0,3.0\nFEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/50,0,5\n";
  // usnistgov/engineering-design-models, Creo's thread_mill.ncl line 7 (its comment included).
  const Toolpath creo = parse_cl("LOADTL / 4,  OSETNO,  4 $$-> THREAD TOOL\n" + body, "c.ncl");
  CHECK(creo.operations.front().tool.number == 4);
  CHECK(creo.operations.front().tool.gauge_length_mm == 0.0);
  // Fusion's APT post: LOADTL/tool, pocket, body length, length offset.
  const Toolpath fusion = parse_cl("LOADTL/1, 0, 60., 1\n" + body, "f.apt");
  CHECK(fusion.operations.front().tool.number == 1);
  CHECK(fusion.operations.front().tool.gauge_length_mm == Approx(60.0));
  // The length in the file's unit; the tool model's shank ends there (less the ball radius).
  const Toolpath inch = parse_cl(
      "UNITS/INCHES\nLOADTL/3, IN, 12, LENGTH, 2.5, OSETNO, 3\nCUTTER/0.25,0.125\nFEDRAT/IPM,20\n"
      "GOTO/0,0,1\nGOTO/2,0,1\n",
      "i.apt");
  const Tool& tool = inch.operations.front().tool;
  CHECK(tool.gauge_length_mm == Approx(63.5));
  const ToolModel model = ToolModel::ball_end(tool);
  CHECK(model.bodies.back().end_mm == Approx(63.5 - 3.175));
  // An option's gauge length wins.
  ToolOverrides o;
  o.gauge_length_mm = 80.0;
  CHECK(ToolModel::ball_end(tool, o).bodies.back().end_mm == Approx(80.0 - 3.175));
  // A length shorter than the flutes names the options that give one.
  Tool short_tool = tool;
  short_tool.gauge_length_mm = 5.0;
  CHECK_THAT(test::input_error_of([&] { ToolModel::ball_end(short_tool); }),
             Catch::Contains("LOADTL LENGTH") && Catch::Contains("--gauge-length"));
  check_refused_at_line_1({"LOADTL/5,OSETNO,7\n", "LOADTL/1, 0, 60., 2\n", "LOADTL/5,LENGTH,-3\n",
                           "LOADTL/5,POCKET,3\n", "LOADTL/5,LENGTH\n", "LOADTL/5,0,60\n"},
                          body);
}

TEST_CASE("cl reader: tool records beyond the tool options' bounds are refused naming the line",
          "[io][cl][hostile]") {
  const std::string body = "FEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/50,0,5\n";
  check_refused_at_line_1(
      {"CUTTER/5000\n", "TLDATA/MILL,6.0,3.0,1000000000.0,0.0,0.0\n", "LOADTL/100000\n"}, body);
  CHECK_NOTHROW(parse_cl("LOADTL/99999\nCUTTER/6\n" + body, "ok.cls"));
}

TEST_CASE(
    "cl reader: SOLIDWORKS CAM's bracketed INSERT note is dropped with a note, its prose is "
    "a comment where it stands and address words are refused as code",
    "[io][cl][words]") {
  const std::string body =
      "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/50,0,5\n";
  const Toolpath tp =
      parse_cl("INSERT/[HOLDER=C40-16ERP412] 16MM CRB 2FL 32 LOC\n" + body, "s.apt");
  CHECK(tp.operations.front().points.size() == 2);
  bool noted = false;
  for (const std::string& w : tp.warnings)
    noted = noted || w.find("operator's note") != std::string::npos;
  CHECK(noted);
  // Prose after the tool (as SOLIDWORKS CAM writes it: tests/data/real/amorim-*.apt line 11):
  // an event before the operation's first point, its text kept.
  const std::string tool = "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\n";
  const Toolpath prose =
      parse_cl(tool +
                   "INSERT/Stock Size X135. Y135. Z30.\nFEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/50,0,5\n"
                   "INSERT/(Check the clamps)\nGOTO/50,10,5\n",
               "s.apt");
  REQUIRE(prose.operations.size() == 1);
  const auto& ev = prose.operations.front().events;
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].kind == ProgramEvent::Kind::Comment);
  CHECK(ev[0].text == "Stock Size X135. Y135. Z30.");
  CHECK(ev[0].before_point == 0);
  CHECK(ev[0].line == 2);
  // Address words only are code the file means the controller to run: refused with the line;
  // so are control characters and text beyond a comment block's length.
  // A program stop among other text too: written as prose or dropped, it would run on past the
  // operator.
  for (const std::string& bad : std::vector<std::string>{
           "INSERT/G54 G90", "INSERT/X135. Y135.", "INSERT/", "INSERT/Stock\x01Size",
           "INSERT/" + std::string(201, 'a'), "INSERT/M00 REMOVE CLAMP", "INSERT/G90 M01",
           "INSERT/(END) M30", "INSERT/[CHANGE PALLET] M60", "INSERT/REMOVE THE M1 CLAMP"}) {
    INFO(bad);
    CHECK_THAT(taxopt::test::input_error_of([&] { parse_cl(tool + bad + "\n" + body, "s.apt"); }),
               Catch::StartsWith("s.apt:2: "));
  }
}

TEST_CASE(
    "cl reader: a program stop in an INSERT, alone or beside an operator's note, is the stop "
    "STOP or OPSTOP writes, the note a comment before it -- never a comment or dropped",
    "[io][cl][words]") {
  const std::string tool = "TLDATA/MILL,6.0,3.0,50.0,0.0,0.0\nFEDRAT/MMPM,500\nGOTO/0,0,5\n";
  struct Case {
    std::string insert;
    ProgramEvent::Kind kind;
    std::string note;
  };
  for (const Case& c : std::vector<Case>{
           {"INSERT/M00 (REMOVE CLAMP)", ProgramEvent::Kind::Stop, "REMOVE CLAMP"},
           {"INSERT/(REMOVE CLAMP) M00", ProgramEvent::Kind::Stop, "REMOVE CLAMP"},
           {"INSERT/[CHECK PART] M01", ProgramEvent::Kind::OptionalStop, "CHECK PART"},
           {"INSERT/m1", ProgramEvent::Kind::OptionalStop, ""},
           {"INSERT/M00", ProgramEvent::Kind::Stop, ""},
           {"INSERT/M0 (A) [B]", ProgramEvent::Kind::Stop, "A; B"}}) {
    INFO(c.insert);
    const Toolpath tp = parse_cl(tool + c.insert + "\nGOTO/50,0,5\n", "s.apt");
    REQUIRE(tp.operations.size() == 1);
    const auto& ev = tp.operations.front().events;
    REQUIRE(ev.size() == (c.note.empty() ? 1u : 2u));
    if (!c.note.empty()) {
      CHECK(ev[0].kind == ProgramEvent::Kind::Comment);
      CHECK(ev[0].text == c.note);
    }
    CHECK(ev.back().kind == c.kind);
    CHECK(ev.back().before_point == 1);
  }
}

TEST_CASE(
    "cl reader: CATIA's TOOLNO/n,d announces the LOADTL's tool: read and checked against the "
    "LOADTL's number and the CUTTER's diameter, refused naming both where they differ",
    "[io][cl][catia]") {
  // The records as CATIA V5 writes a tool change (tests/data/real/peening-catia-multax.aptsource).
  const auto file = [](const std::string& toolno, const std::string& loadtl) {
    return "$$ TOOLCHANGEBEGINNING\nCUTTER/  1.700000,  0.000000,  0.850000,  0.000000,  "
           "0.000000,$\n         0.000000,  1.968504\n" +
           toolno + "\nTPRINT/T13 End Mill D 1.7\n" + loadtl +
           "\n$$ TOOLCHANGEEND\nMULTAX\nFEDRAT/ 500.0000,MMPM\nGOTO/ 1.0, 2.0, 3.0, 0.0, 0.0, "
           "1.0\nGOTO/ 5.0, 2.0, 3.0\n";
  };
  const Toolpath tp = parse_cl(file("TOOLNO/13,    1.700000", "LOADTL/13"), "catia.aptsource");
  REQUIRE(tp.operations.size() == 1);
  CHECK(tp.operations[0].tool.number == 13);
  CHECK(tp.operations[0].tool.diameter_mm == Approx(1.7));
  CHECK(parse_cl(file("TOOLNO/13", "LOADTL/13"), "c.apt").operations[0].tool.number == 13);
  // Another tool loaded than announced, another diameter than the CUTTER's: which tool cuts
  // is not known.
  const std::string other =
      test::input_error_of([&] { parse_cl(file("TOOLNO/13,    1.700000", "LOADTL/12"), "c.apt"); });
  CHECK_THAT(other, Catch::Contains("c.apt:6: LOADTL/12 loads tool 12 where TOOLNO at line 4 "
                                    "announced tool 13"));
  const std::string wider =
      test::input_error_of([&] { parse_cl(file("TOOLNO/13,    6.000000", "LOADTL/13"), "c.apt"); });
  CHECK_THAT(wider, Catch::Contains("c.apt:4: TOOLNO/13,    6.000000: a tool of diameter 6 mm, "
                                    "where the CUTTER before it gives 1.7 mm"));
  // Hostile values: a fraction, a negative number, three fields, text.
  for (const char* bad : {"TOOLNO/1.5, 1.7", "TOOLNO/-1, 1.7", "TOOLNO/13, 1.7, 2", "TOOLNO/T13",
                          "TOOLNO/13, -1.7", "TOOLNO/", "TOOLNO/13, nan"}) {
    INFO(bad);
    CHECK_THAT(test::input_error_of([&] { parse_cl(file(bad, "LOADTL/13"), "c.apt"); }),
               Catch::Contains("c.apt:4: TOOLNO"));
  }
  // --skip-record TOOLNO: the LOADTL alone, unchecked.
  ClReadOptions skip;
  skip.skip_records.insert("TOOLNO");
  CHECK(parse_cl(file("TOOLNO/13,    6.000000", "LOADTL/12"), "c.apt", skip)
            .operations[0]
            .tool.number == 12);
}

TEST_CASE(
    "cl reader: a FROM before the first tool is the start of that tool's operation, not a "
    "tool-less operation of its own (Makino FF's layout)",
    "[io][cl][words]") {
  // The records as Makino FF writes its start (steptools/STEPNode examples/data/Plane_2.cldata,
  // Apache-2.0): the start point, then the tool.
  const Toolpath tp = parse_cl(
      "PPRINT/APTCL-SPEC,MAKINO-FF,1\nUNITS/MM\nSET/MODE,ABSOL\n"
      "FROM/0.0,0.0,50.0,0.0,0.0,1.0\nSELECT/TOOL,45\nLOAD/TOOL,45\nRAPID\nGOTO/0.0,0.0,50.0\n"
      "SPINDL/RPM,1310,CLW\nRAPID\nGOTO/-22.1,7.95,29.0\nFEDRAT/PERMIN,141\nGOTO/-22.1,7.95,28.0\n"
      "GOTO/-30.0,7.95,28.0\n",
      "plane.cldata");
  REQUIRE(tp.operations.size() == 1);
  const Operationd& op = tp.operations[0];
  CHECK(op.tool.number == 45);
  REQUIRE(op.points.size() == 5);
  CHECK(op.points[0].line == 4);  // the FROM
  CHECK(op.points[0].motion == Motion::Rapid);
  // A FROM after a tool's moves still ends nothing: it is a move of that operation.
  const Toolpath two = parse_cl(
      "LOADTL/1\nFEDRAT/MMPM,500\nGOTO/0,0,5\nGOTO/10,0,5\nFROM/0,0,50\nLOADTL/2\nGOTO/5,5,5\n",
      "two.cls");
  REQUIRE(two.operations.size() == 2);
  CHECK(two.operations[0].points.size() == 3);
}
