// The CL reader knows its words (tests/data/real/SOURCES.md): one table, documented; unknown words,
// words it refuses and misspelt motion words stop it by name; stops, dwells, spindle and coolant
// reach the program where they stand; MSYS as NX's own post reads it; Fusion's MOVARC; TLAXIS;
// units.
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <sstream>

#include "cl/cl_words.hpp"
#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

std::string error_of_text(const std::string& text, const ClReadOptions& o = {}) {
  return input_error_of([&] { parse_cl(text, "w.cls", o); });
}

}  // namespace

TEST_CASE("cl words: docs/cl-files.md shows the reader's word table as it is", "[io][cl][words]") {
  const std::string doc = read_file(std::string(TAXOPT_SOURCE_DIR) + "/docs/cl-files.md");
  const std::string begin = "<!-- cl-words:begin -->\n", end = "<!-- cl-words:end -->";
  const std::size_t b = doc.find(begin), e = doc.find(end);
  REQUIRE(b != std::string::npos);
  REQUIRE(e != std::string::npos);
  const std::string shown = doc.substr(b + begin.size(), e - b - begin.size());
  INFO("the table as the code has it:\n" << cl_words_markdown());
  CHECK(shown == cl_words_markdown());
  // One entry per word; motion, state and frame words cannot be skipped.
  std::set<std::string> seen;
  for (const ClWord& w : cl_words()) {
    CHECK(seen.insert(w.word).second);
    if (w.meaning == ClWordMeaning::Motion || w.meaning == ClWordMeaning::Frame) {
      CHECK_FALSE(w.skippable);
    }
    CHECK(std::string(w.evidence).size() > 0);
  }
}

TEST_CASE(
    "cl words: every word of the real files is in the table or refused by name, and no file "
    "posts with a record skipped that the table does not call information",
    "[io][cl][words][real]") {
  for (const char* f :
       {"mech491-variable-axis-ballmill.cls", "mech491-project2-multiop.cls",
        "peening-catia-multax.aptsource", "amorim-tilt-support1.apt", "amorim-interface-glue.apt",
        "amorim-wall-holes.apt", "creopost-profilfraesen.ncl"}) {
    INFO(f);
    const std::string as_is = input_error_of([&] { read_cl_file(real_data(f)); });
    if (real_skips(f).empty()) {
      CHECK(as_is.empty());
    } else {
      // Refused by name: file, line and the word.
      CHECK_THAT(as_is, Catch::StartsWith(real_data(f) + ":"));
      bool named = false;
      for (const auto& w : real_skips(f)) named = named || as_is.find(w) != std::string::npos;
      CHECK(named);
    }
    const Toolpath tp = read_real(f);
    for (const auto& [word, count] : tp.skipped_records) {
      INFO(word);
      const ClWord* w = find_cl_word(word);
      const bool by_option = tp.skipped_by_option.count(word) > 0;
      // Skipped without the user's word only where the table says it changes nothing (an
      // INSERT here is a bracketed operator's note, dropped with a note).
      CHECK((by_option ||
             (w && (w->meaning == ClWordMeaning::Information || std::string(w->word) == "CUTCOM" ||
                    std::string(w->word) == "INSERT"))));
      CHECK(count > 0);
    }
  }
  // The peening file's SPINDLE/CLW20 is no spindle speed taxopt knows: refused by name even
  // with the machine's words skipped.
  ClReadOptions o;
  for (const auto& w : real_skips("peening-catia-multax.aptsource")) o.skip_records.insert(w);
  CHECK_THAT(input_error_of([&] { read_cl_file(real_data("peening-catia-multax.aptsource"), o); }),
             Catch::Contains("SPINDL: 'CLW20' not interpreted"));
}

TEST_CASE("cl words: unknown and misspelt words stop the reader -- --skip-record skips by name",
          "[io][cl][words]") {
  for (const char* word : {"GOTO1/1,0,0", "GOTOX/1,0,0", "GOT0/1,0,0", "GO TO/1,0,0",
                           "FROBNICATE/3", "RETRCT", "POSTN/1", "CLAMP/ON"}) {
    INFO(word);
    const std::string e = error_of_text(std::string("GOTO/0,0,0\n") + word + "\nGOTO/2,0,0\n");
    CHECK_THAT(e, Catch::StartsWith("w.cls:2: "));
  }
  // The library names its option by its field; a caller's own name for it where it maps one
  // (the CLI's flag).
  CHECK_THAT(error_of_text("GOTO/0,0,0\nFROBNICATE/3\n"),
             Catch::Contains("ClReadOptions::skip_records FROBNICATE skips it"));
  {
    ClReadOptions named;
    named.option_names = {{"ClReadOptions::skip_records", "--skip-record"}};
    CHECK_THAT(error_of_text("GOTO/0,0,0\nFROBNICATE/3\n", named),
               Catch::Contains("--skip-record FROBNICATE skips it"));
  }
  ClReadOptions o;
  o.skip_records = {"FROBNICATE"};
  const Toolpath tp = parse_cl("GOTO/0,0,0\nFROBNICATE/3\nFROBNICATE/4\nGOTO/2,0,0\n", "w", o);
  CHECK(tp.skipped_by_option.at("FROBNICATE") == 2);
  CHECK(tp.operations.at(0).points.size() == 2);
  // Motion, state and frame words cannot be skipped.
  for (const char* w : {"GOTO", "FEDRAT", "MSYS", "CIRCLE", "UNITS"}) {
    INFO(w);
    ClReadOptions bad;
    bad.skip_records = {w};
    CHECK_THAT(error_of_text("GOTO/0,0,0\n", bad),
               Catch::StartsWith(std::string("ClReadOptions::skip_records ") + w + ": a "));
  }
  // Refused by name: what the post would do with them is not what taxopt would write.
  for (const char* word : {"LOOP/START,15", "INVERSE/ON", "OP/THREAD,1", "CUTCOM/LEFT",
                           "MACHIN/PPLATHE,TURN", "MODE/TURN", "TURRET/1", "INSERT/G54 M00",
                           "COOLNT/THRU", "SPINDL/1000,MAXRPM,3000", "DELAY/REV,2"}) {
    INFO(word);
    const std::string e = error_of_text(std::string("GOTO/0,0,0\n") + word + "\nGOTO/2,0,0\n");
    CHECK_THAT(e, Catch::StartsWith("w.cls:2: "));
  }
  // Motion after FINI / END.
  CHECK_THAT(error_of_text("GOTO/0,0,0\nFINI\nGOTO/2,0,0\n"),
             Catch::Contains("w.cls:3: GOTO after the end of the program (line 2)"));
  CHECK(error_of_text("GOTO/0,0,0\nEND\nPPRINT/X\n").empty());
}

TEST_CASE("cl words: CR, LF and CRLF all end a line, mixed too", "[io][cl][words]") {
  const std::string body[] = {"UNITS/MM",        "LOADTL/3",   "SPINDL/2000,RPM,CLW",
                              "FEDRAT/500,MMPM", "GOTO/0,0,0", "GOTO/10,0,0"};
  for (const char* e : {"\r", "\n", "\r\n", "mixed"}) {
    const std::string ends = e;
    std::string text;
    for (std::size_t i = 0; i < 6; ++i) {
      text += body[i] + (ends != "mixed" ? ends : (i % 3 == 0 ? "\r" : i % 3 == 1 ? "\n" : "\r\n"));
    }
    INFO(ends.size());
    const Toolpath tp = parse_cl(text, "e.cls");
    REQUIRE(tp.operations.size() == 1);
    CHECK(tp.operations[0].tool.number == 3);
    CHECK(tp.operations[0].spindle_rpm == 2000.0);
    CHECK(tp.operations[0].points.size() == 2);
    CHECK(tp.operations[0].points[1].line == 6);
  }
}

TEST_CASE("cl words: units that contradict are refused or said", "[io][cl][words][units]") {
  // A change of units after motion, or two UNITS that disagree.
  CHECK_THAT(error_of_text("UNITS/MM\nGOTO/0,0,0\nUNITS/INCHES\nGOTO/1,0,0\n"),
             Catch::Contains("w.cls:3: UNITS/INCHES contradicts the mm of line 1 after motion"));
  CHECK(error_of_text("UNITS/MM\nGOTO/0,0,0\nUNITS/MM\nGOTO/1,0,0\n").empty());
  // One feed with both an inch and a millimetre word.
  CHECK_THAT(error_of_text("FEDRAT/MMPM,250,IPM\nGOTO/0,0,0\n"),
             Catch::Contains("w.cls:1: FEDRAT/MMPM,250,IPM: both an inch and a millimetre"));
  // A millimetre feed in an inch file: taken as its word says, and said.
  const Toolpath tp = parse_cl("UNITS/INCHES\nFEDRAT/35,MMPM\nGOTO/0,0,0\nGOTO/1,0,0\n", "u.cls");
  CHECK(tp.operations[0].points[1].feed_mm_per_min == Approx(35.0));
  REQUIRE(tp.notices.size() == 1);
  CHECK_THAT(tp.notices[0], Catch::Contains("u.cls:2: a feed in millimetres"));
  // --units against the file's word: read as asked, and said.
  ClReadOptions o;
  o.units = LengthUnit::Millimetre;
  const Toolpath forced = parse_cl("UNITS/INCHES\nGOTO/1,0,0\n", "u.cls", o);
  CHECK(forced.operations[0].points[0].tip_mm.x() == 1.0);
  REQUIRE(forced.notices.size() == 1);
  CHECK_THAT(forced.notices[0], Catch::Contains("though it says in"));
}

TEST_CASE("cl words: TLAXIS sets the axis of the 3-number GOTOs after it", "[io][cl][words]") {
  const Toolpath tp =
      parse_cl("GOTO/0,0,0\nTLAXIS/0,0.6,0.8\nGOTO/1,0,0\nGOTO/2,0,0,0,0,1\nGOTO/3,0,0\n", "t");
  const auto& p = tp.operations.at(0).points;
  CHECK((p[0].axis - Vec3d::UnitZ()).norm() < 1e-12);
  CHECK((p[1].axis - Vec3d(0, 0.6, 0.8)).norm() < 1e-12);
  CHECK((p[3].axis - Vec3d::UnitZ()).norm() < 1e-12);
  CHECK_THAT(error_of_text("TLAXIS/NORMPS\nGOTO/0,0,0\n"), Catch::Contains("TLAXIS expects"));
}

TEST_CASE(
    "cl words: Fusion's MOVARC sweeps ANGLE deg counter-clockwise about its axis -- rs274 moves "
    "its path within 0.5 % of what it means",
    "[io][cl][words][movarc][rs274]") {
  // A Fusion-style pass: lead-in, three arcs of different sweeps and senses (the axis flipped
  // for clockwise), a helix, straight moves between.
  const double r = 8.0;
  std::ostringstream os;
  os.precision(10);
  os << "UNITS/MM\nLOADTL/1\nSPINDL/8000,RPM,CLW\nFEDRAT/1200,MMPM\nRAPID\nGOTO/-20,0,5\n"
        "GOTO/-20,0,0\n"
     // a quarter counter-clockwise about +Z from (0,0), heading +X, to (r, r)
     << "GOTO/0,0,0\n"
     << "MOVARC/0," << r << ",0,0,0,1," << r << ",ANGLE,90\nGOTO/" << r << "," << r << ",0\n"
     << "GOTO/" << r << "," << 3 * r
     << ",0\n"
     // 270 deg clockwise (written about -Z) about (2r, 3r), heading +Y, to (2r, 2r)
     << "MOVARC/" << 2 * r << "," << 3 * r << ",0,0,0,-1," << r << ",ANGLE,270\nGOTO/" << 2 * r
     << "," << 2 * r << ",0\n"
     << "GOTO/-20," << 2 * r
     << ",0\n"
     // a full helical turn down 2 mm about (-20, r), heading -X
     << "MOVARC/-20," << r << ",0,0,0,1," << r << ",ANGLE,360\nGOTO/-20," << 2 * r << ",-2\n"
     << "GOTO/-40," << 2 * r << ",-2\nRAPID\nGOTO/-40," << 2 * r << ",20\nFINI\n";
  const double expect = 5.0 + 20.0 + (0.5 * M_PI * r) + 2 * r + (1.5 * M_PI * r) + (2 * r + 20.0) +
                        std::hypot(2 * M_PI * r, 2.0) + 20.0;
  const Toolpath tp = parse_cl(os.str(), "fusion.apt");
  CHECK(tp.reading.arcs == 3);
  double feed_mm = 0.0;
  const auto& pts = tp.operations.at(0).points;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if (pts[i].motion == Motion::Feed) feed_mm += (pts[i].tip_mm - pts[i - 1].tip_mm).norm();
  }
  CHECK(feed_mm == Approx(expect).epsilon(1e-4));
  // Through the CLI and rs274: the feed path as the interpreter moves it.
  REQUIRE(have_rs274());
  TempDir dir;
  write_file(dir.path("f.apt"), os.str());
  const RunResult run = run_taxopt("--in " + dir.path("f.apt") + " --method none --gcode " +
                                   dir.path("o.ngc") + " -q");
  INFO(run.err);
  REQUIRE(run.code == 0);
  std::vector<CanonMove> moves;
  REQUIRE(run_rs274(dir.path("o.ngc"), moves).code == 0);
  double rs_feed = 0.0;
  for (std::size_t i = 1; i < moves.size(); ++i) {
    if (!moves[i].feed) continue;
    rs_feed += moves[i].arc ? moves[i].arc_length
                            : std::sqrt(std::pow(moves[i].x - moves[i - 1].x, 2) +
                                        std::pow(moves[i].y - moves[i - 1].y, 2) +
                                        std::pow(moves[i].z - moves[i - 1].z, 2));
  }
  CHECK(rs_feed == Approx(expect).epsilon(0.005));
  // An ANGLE its end GOTO does not match, and an arc whose neighbours run the other way.
  CHECK_THAT(error_of_text("GOTO/-10,0,0\nGOTO/0,0,0\nMOVARC/0,5,0,0,0,1,5,ANGLE,80\nGOTO/5,5,0\n"
                           "GOTO/5,20,0\n"),
             Catch::Contains("w.cls:3: MOVARC: ANGLE 80 deg"));
  CHECK_THAT(error_of_text("GOTO/10,0,0\nGOTO/0,0,0\nMOVARC/0,5,0,0,0,1,5,ANGLE,180\nGOTO/0,10,0\n"
                           "GOTO/10,10,0\n"),
             Catch::Contains("w.cls:3: MOVARC: the moves before and after it run clockwise"));
  // Where ANGLE's two readings end apart, the end GOTO decides, whatever the moves beside it
  // do: a Fusion arc after a 0.112 mm reversed move (a cusp), and one between two moves that
  // both run against it (refused before), read as written (a quarter of r 5: 7.854 mm).
  for (const auto& [before, after] :
       {std::pair<const char*, const char*>{"GOTO/0.112,0,0\nGOTO/0,0,0\n", "GOTO/5,20,0\n"},
        {"GOTO/10,0,0\nGOTO/0,0,0\n", "GOTO/5,-10,0\n"}}) {
    INFO(before << after);
    const Toolpath cusp = parse_cl(
        std::string(before) + "MOVARC/0,5,0,0,0,1,5,ANGLE,90\nGOTO/5,5,0\n" + after, "cusp.apt");
    const auto& q = cusp.operations.at(0).points;
    double arc = 0.0;
    for (std::size_t i = 2; i + 1 < q.size(); ++i) arc += (q[i].tip_mm - q[i - 1].tip_mm).norm();
    CHECK(arc == Approx(0.5 * M_PI * 5.0).epsilon(1e-4));
  }
}

TEST_CASE(
    "cl words: stops, dwells, spindle and coolant changes reach the program where they stand -- "
    "a surface speed becomes rpm through the cutter's diameter",
    "[io][cl][words][program][rs274]") {
  const std::string text =
      "UNITS/MM\nCUTTER/10,5\nLOADTL/2\nSPINDL/150,SMM,CLW\nCOOLNT/MIST\nFEDRAT/600,MMPM\n"
      "GOTO/0,0,10\nGOTO/0,0,0\nGOTO/10,0,0\nSTOP\nGOTO/20,0,0\nOPSTOP\nGOTO/30,0,0\n"
      "DELAY/1.5\nGOTO/40,0,0\nSPINDL/OFF\nRAPID\nGOTO/50,0,0\nSPINDL/3000,RPM,CCLW\nCOOLNT/FLOOD\n"
      "GOTO/60,0,0\nCOOLNT/OFF\nGOTO/70,0,0\nFINI\n";
  const Toolpath tp = parse_cl(text, "p.apt");
  const auto& op = tp.operations.at(0);
  // 150 m/min at 10 mm: 4775 rpm.
  CHECK(op.spindle_rpm == Approx(150000.0 / (M_PI * 10.0)));
  REQUIRE(op.coolant);
  CHECK(*op.coolant == ClCoolant::Mist);
  CHECK(op.events.size() == 7);
  // COOLNT/ON resumes the coolant last chosen, as APT's does (issue 63.12): mist after MIST and
  // OFF, flood before any choice.
  const auto coolant_on = [](const std::string& cl) {
    const Toolpath t = parse_cl(cl + "COOLNT/ON\nGOTO/0,0,0\nGOTO/1,0,0\n", "c.apt");
    const auto& events = t.operations.at(0).events;
    for (auto e = events.rbegin(); e != events.rend(); ++e) {
      if (e->kind == ProgramEvent::Kind::Coolant) return e->coolant;
    }
    return t.operations.at(0).coolant.value_or(ClCoolant::Off);
  };
  const std::string start = "UNITS/MM\nCUTTER/10,5\nLOADTL/2\nFEDRAT/600,MMPM\nGOTO/0,0,5\n";
  CHECK(coolant_on(start + "COOLNT/MIST\nGOTO/0,0,4\nCOOLNT/OFF\nGOTO/0,0,3\n") == ClCoolant::Mist);
  CHECK(coolant_on(start) == ClCoolant::Flood);
  REQUIRE(have_rs274());
  TempDir dir;
  write_file(dir.path("p.apt"), text);
  const RunResult run = run_taxopt("--in " + dir.path("p.apt") + " --method none --gcode " +
                                   dir.path("o.ngc") + " -q");
  INFO(run.err);
  REQUIRE(run.code == 0);
  const std::string g = read_file(dir.path("o.ngc"));
  std::vector<CanonMove> moves;
  REQUIRE(run_rs274(dir.path("o.ngc"), moves).code == 0);
  // A feed move with the spindle off (the rapid made a feed) is refused by the program check.
  std::string feeding = text;
  feeding.replace(feeding.find("RAPID\nGOTO/50"), 6, "");
  write_file(dir.path("f.apt"), feeding);
  const RunResult off = run_taxopt("--in " + dir.path("f.apt") + " --method none --gcode " +
                                   dir.path("f.ngc") + " -q");
  CHECK(off.code == 1);
  CHECK_THAT(off.err, Catch::Contains("moves at feed with the spindle stopped"));
  const auto lines = lines_of(g);
  // Each event stands between the blocks of the points before and after it.
  const std::size_t x10 = line_of(lines, "X10."), x20 = line_of(lines, "X20."),
                    x30 = line_of(lines, "X30."), x40 = line_of(lines, "X40."),
                    x50 = line_of(lines, "X50."), x60 = line_of(lines, "X60."),
                    x70 = line_of(lines, "X70.");
  REQUIRE(x70 != std::string::npos);
  const std::size_t spindle = line_of(lines, "S4775 M3");
  const std::size_t mist = line_of(lines, "M7");
  CHECK(spindle < line_of(lines, "X0. Y0. Z0."));
  CHECK(mist < line_of(lines, "X0. Y0. Z0."));
  CHECK(line_of(lines, "M0", x10) < x20);
  CHECK(line_of(lines, "M1", x20) < x30);
  CHECK(line_of(lines, "G4 P1.5", x30) < x40);
  CHECK(line_of(lines, "M5", x40) < x50);
  CHECK(line_of(lines, "S3000 M4", x50) < x60);
  CHECK(line_of(lines, "M8", x50) < x60);
  CHECK(line_of(lines, "M9", x60) < x70);
  // After the program: the spindle is stopped once more only if it turns.
  CHECK(line_of(lines, "M5", x70) != std::string::npos);
  // A surface speed without a cutter is refused; DELAY for a dialect without a known dwell.
  CHECK_THAT(error_of_text("SPINDL/0.0001,RPM\nGOTO/0,0,0\n"),
             Catch::Contains("w.cls:1: SPINDL: 0.000100 rpm is no spindle speed"));
  CHECK_THAT(error_of_text("SPINDL/500,SFM\nGOTO/0,0,0\n"),
             Catch::Contains("w.cls:1: SPINDL/SFM: a surface speed needs the cutter's diameter"));
}

TEST_CASE(
    "cl words: a tapered ball CUTTER is read as its ball and taper -- its flanks are checked as "
    "cylinders that enclose the cone",
    "[io][cl][words][tool]") {
  const double r = 3.0, b = 5.0, h = 30.0;
  const double b_rad = deg_to_rad(b);
  const double d = 2.0 * r * (1.0 - std::sin(b_rad)) / std::cos(b_rad);
  std::ostringstream os;
  os.precision(12);
  os << "UNITS/MM\nCUTTER/" << d << "," << r << ",0," << r << ",0," << b << "," << h
     << "\nGOTO/0,0,0\nGOTO/1,0,0\n";
  const Toolpath tp = parse_cl(os.str(), "t.apt");
  const Tool& tool = tp.operations.at(0).tool;
  CHECK(tool.is_ball());
  CHECK(tool.ball_radius_mm() == Approx(r));
  CHECK(tool.taper_rad == Approx(b_rad));
  CHECK(tool.flute_length_mm == Approx(h));
  REQUIRE(tp.notices.size() == 1);
  CHECK_THAT(tp.notices[0], Catch::Contains("tapered ball-end mill"));
  // The cone, R / cos b + s tan b at s above the ball centre, lies inside the flute bodies,
  // which exceed it by at most 0.02 mm, or by its rise over a 64th of the flutes.
  const ToolModel m = ToolModel::ball_end(tool);
  REQUIRE(m.flute_bodies > 1);
  for (int k = 0; k <= 1000; ++k) {
    const double s = (h - r) * k / 1000.0;
    const double cone = r / std::cos(b_rad) + s * std::tan(b_rad);
    bool inside = false;
    for (int i = 0; i < m.flute_bodies; ++i) {
      const ToolBody& body = m.bodies[static_cast<std::size_t>(i)];
      if (s >= body.start_mm - 1e-12 && s <= body.end_mm + 1e-12) {
        inside = inside || body.radius_mm >= cone - 1e-12;
        CHECK(body.radius_mm - cone <= std::max(0.02, (h - r) * std::tan(b_rad) / 64.0) + 1e-9);
      }
    }
    REQUIRE(inside);
  }
  // The shank past the flutes is the cone's top by default, never thinner.
  CHECK(m.bodies[static_cast<std::size_t>(m.flute_bodies)].radius_mm >=
        r / std::cos(b_rad) + (h - r) * std::tan(b_rad) - 1e-9);
  // r > d/2 that is no tapered ball: refused, naming the formula.
  CHECK_THAT(error_of_text("CUTTER/6,3.5,0,3.5,0,0,30\nGOTO/0,0,0\n"),
             Catch::Contains("d = 2 r (1 - sin b) / cos b"));
}

TEST_CASE(
    "cl words: with MSYS posted as written, a part mesh in the MCS is taken as it is and one in "
    "absolute coordinates is moved into the MCS, decided by where the ball touches it",
    "[io][cl][words][msys][part]") {
  std::mt19937 rng(32);
  const auto hfs = random_heightfields(rng);
  const GeneratedCl g = raster_cl(hfs[1], 3.0, 0.0, 3, 2.0, 10.0, 30.0, 10.0, 40.0);
  // The MCS at (100, -50, 20) turned a quarter about z: p_abs = R p + o.
  const std::size_t eol = g.text.find('\n');
  const std::string text =
      g.text.substr(0, eol + 1) + "MSYS/100,-50,20,0,1,0,-1,0,0\n" + g.text.substr(eol + 1);
  const Toolpath tp = parse_cl(text, "m.cls");
  REQUIRE(tp.declared_frames.size() == 1);
  // The points are as written.
  CHECK((tp.operations.at(0).points.at(0).tip_mm - g.tips_mm.at(0)).norm() < 1e-6);
  const TriangleMesh in_mcs = heightfield_mesh(hfs[1], 1.0);
  Eigen::Matrix3d R;
  R << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Vec3d o(100, -50, 20);
  TriangleMesh absolute = in_mcs;
  for (Vec3d& v : absolute.vertices) v = R * v + o;
  std::string note;
  const TriangleMesh a = part_mesh_for(tp, in_mcs, LengthUnit::Millimetre, &note);
  CHECK_THAT(note, Catch::Contains("taken as it is"));
  const TriangleMesh b = part_mesh_for(tp, absolute, LengthUnit::Millimetre, &note);
  CHECK_THAT(note, Catch::Contains("moved into the MCS"));
  REQUIRE(a.vertices.size() == b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) {
    REQUIRE((a.vertices[i] - in_mcs.vertices[i]).norm() < 1e-12);
    REQUIRE((b.vertices[i] - in_mcs.vertices[i]).norm() < 1e-9);
  }
  // A mesh the points touch in neither frame is refused.
  TriangleMesh elsewhere = in_mcs;
  for (Vec3d& v : elsewhere.vertices) v += Vec3d(0, 0, 40);
  CHECK_THROWS_WITH(part_mesh_for(tp, elsewhere, LengthUnit::Millimetre, &note),
                    Catch::Contains("neither frame"));
}

TEST_CASE(
    "cl words: hostile records -- end knots repeated, an axis after MULTAX/OFF, a zero "
    "CIRCLE radius -- are refused by line",
    "[io][cl][words][hostile]") {
  const std::string head = "TOOL PATH/OP,TOOL,T\nGOTO/0,0,0\n";
  CHECK_THAT(
      error_of_text(
          head +
          "NURBS/\nKNOT/0,0,1\nCNTRL/1,1,1\nCNTRL/2,1,1\nCNTRL/3,2,1\nCNTRL/4,2,1\nGOTO/5,3,3\n"),
      Catch::Contains("w.cls:3: NURBS at line 3: knot 1 repeats an end knot"));
  CHECK_THAT(
      error_of_text(
          head +
          "NURBS/\nKNOT/0.5,1,1\nCNTRL/1,1,1\nCNTRL/2,1,1\nCNTRL/3,2,1\nCNTRL/4,2,1\nGOTO/5,3,3\n"),
      Catch::Contains("knot 2 repeats an end knot"));
  CHECK_THAT(error_of_text("GOTO/0,0,0\nMULTAX/OFF\nGOTO/1,0,0,0.5,0,0.8660254\n"),
             Catch::Contains("w.cls:3: GOTO gives a tool axis after MULTAX/OFF (line 2)"));
  CHECK(error_of_text("GOTO/0,0,0\nMULTAX/OFF\nGOTO/1,0,0\nMULTAX/ON\nGOTO/1,0,0,0,0,1\n").empty());
  CHECK_THAT(error_of_text("GOTO/0,10,0\nCIRCLE/0,0,0,0,0,1,0\nGOTO/10,0,0\n"),
             Catch::Contains("w.cls:2: CIRCLE radius must be positive"));
}
