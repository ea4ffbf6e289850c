// The catalogue of malformed CL input: each kind is an InputError naming the file and the
// line of the record, with what was expected.
#include <catch2/catch.hpp>

#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"

using namespace taxopt;

namespace {

struct BadCase {
  const char* name;
  std::string text;
  int line;
  const char* says;
};

}  // namespace

TEST_CASE("cl reader: every malformed kind is an error with file, line and expectation",
          "[io][cl][bad-input]") {
  const BadCase cases[] = {
      {"double point", "GOTO/0,0,0\nGOTO/1,2..0,3\n", 2, "expected a number, got '2..0'"},
      {"nan", "GOTO/1,nan,3\n", 1, "got 'nan'"},
      {"inf", "GOTO/inf,1,3\n", 1, "got 'inf'"},
      {"overflow", "GOTO/1e999,0,0\n", 1, "got '1e999'"},
      {"hex", "GOTO/0x10,0,0\n", 1, "got '0x10'"},
      {"empty field", "GOTO/1,,3\n", 1, "got ''"},
      {"blank separated", "GOTO/1 2 3\n", 1, "expects 3 or 6 numbers"},
      {"two numbers", "GOTO/1,2\n", 1, "expects 3 or 6 numbers"},
      {"seven numbers", "GOTO/1,2,3,0,0,1,5\n", 1, "expects 3 or 6 numbers"},
      {"zero axis", "GOTO/1,2,3,0,0,0\n", 1, "tool axis (i,j,k) is zero"},
      {"long axis", "GOTO/1,2,3,0,0,1.1\n", 1, "expected a unit vector"},
      {"short axis", "\n\nFROM/1,2,3,0.5,0,0.5\nGOTO/1,2,3\n", 3, "expected a unit vector"},
      {"negative feed", "FEDRAT/-5\nGOTO/1,2,3\n", 1, "feed must be positive"},
      {"zero feed", "FEDRAT/MMPM,0\nGOTO/1,2,3\n", 1, "feed must be positive"},
      {"feed without number", "FEDRAT/MMPM\nGOTO/1,2,3\n", 1, "exactly one number"},
      {"feed unit unknown", "FEDRAT/10,FURLONGS\nGOTO/1,2,3\n", 1, "MMPM, IPM"},
      {"units unknown", "UNITS/FURLONGS\nGOTO/1,2,3\n", 1, "expects INCHES or MM"},
      {"continuation at end", "GOTO/1,2,3\nGOTO/1,2,$\n", 2, "file ends"},
      {"circle without end", "GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\n", 2,
       "not followed by its end GOTO"},
      {"circle then rapid", "GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nRAPID\nGOTO/0,10,0\n", 3,
       "must be followed by its end GOTO"},
      {"circle short", "GOTO/10,0,0\nCIRCLE/0,0,0,0,0\nGOTO/0,10,0\n", 2, "at least 6 numbers"},
      {"circle zero axis", "GOTO/10,0,0\nCIRCLE/0,0,0,0,0,0,10\nGOTO/0,10,0\n", 2, "is zero"},
      {"circle times", "GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,TIMES,0\nGOTO/0,10,0\n", 2, "TIMES"},
      {"circle no start", "CIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\n", 1, "no start point"},
      {"binary", std::string("GOTO/1,2,3\nGO\0TO/1,2,3\n", 22), 2, "binary data"},
      {"empty", "", 0, "no GOTO records"},
      {"comments only", "$$ nothing here\nPAINT/COLOR,3\n", 0, "no GOTO records"},
      {"listing only", "Tool Path Listing has 3 lines.\n", 0, "no GOTO records"},
      {"negative diameter", "TLDATA/MILL,-6,3\nGOTO/1,2,3\n", 1, "diameter must be positive"},
      {"corner over radius", "CUTTER/6,4\nGOTO/1,2,3\n", 1, "corner radius"},
      {"cutter text", "CUTTER/abc\nGOTO/1,2,3\n", 1, "expected a number, got 'abc'"},
      {"loadtl text", "LOADTL/x\nGOTO/1,2,3\n", 1, "expected a number"},
      // Found by fuzz_cl_reader: a huge tool number overflowed the int it is stored in.
      {"loadtl huge", "LOADTL / 4444444444444444444444444444444\nGOTO/1,2,3\n", 1, "tool number"},
      {"load tool fraction", "LOAD/TOOL,2.5\nGOTO/1,2,3\n", 1, "tool number"},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    try {
      parse_cl(c.text, "bad.cls");
      FAIL("no error for " << c.name);
    } catch (const InputError& e) {
      CHECK(e.file() == "bad.cls");
      CHECK(e.line() == c.line);
      CHECK_THAT(e.message(), Catch::Contains(c.says));
      if (c.line > 0) {
        CHECK_THAT(std::string(e.what()),
                   Catch::StartsWith("bad.cls:" + std::to_string(c.line) + ": "));
      }
    }
  }
}

TEST_CASE("cl reader: a reader error names the first line of a continued record",
          "[io][cl][bad-input]") {
  try {
    parse_cl("GOTO/0,0,0\nGOTO/1,2,$\nabc\n", "c.cls");
    FAIL("accepted");
  } catch (const InputError& e) {
    CHECK(e.line() == 2);
  }
}

TEST_CASE("cl reader: a missing file is an input error", "[io][cl][bad-input]") {
  CHECK_THROWS_AS(read_cl_file("/nonexistent/taxopt/x.cls"), InputError);
}

TEST_CASE(
    "cl reader: a few curve records cannot ask for more than 1e6 points -- four MOVARC of 400 "
    "turns at r 1000 (3.9 GB before) are refused naming the record",
    "[io][cl][bad-input][hostile]") {
  std::string text = "FEDRAT/MMPM,500\nRAPID\nGOTO/1000,0,0\n";
  for (int k = 0; k < 4; ++k) text += "MOVARC/0,0,0,0,0,1,1000,ANGLE,144000\nGOTO/1000,0,0\n";
  try {
    parse_cl(text, "arc.cls");
    FAIL("accepted");
  } catch (const InputError& e) {
    CHECK(e.line() == 6);
    CHECK_THAT(e.message(),
               Catch::Contains("MOVARC: the file's arcs, splines and drilling cycles up to here "
                               "expand to") &&
                   Catch::Contains("more than the 1e6"));
  }
  // Forty holes of 1e4 pecks each (3e4 points a hole) from 45 lines.
  std::string holes =
      "UNIT/MM\nFEDRAT/500,MMPM\nRAPID\nGOTO/0,0,50\nCYCLE/INIT\n"
      "CYCLE/DEEP2,FEDTO,9.99,1STPECK,0.001,SUBPECK,0.001,MMPM,100.,RAPTO,3.\n";
  for (int k = 0; k < 40; ++k) holes += "GOTO/" + std::to_string(10 * k) + ",0,0\n";
  holes += "CYCLE/OFF\n";
  try {
    parse_cl(holes, "holes.cls");
    FAIL("accepted");
  } catch (const InputError& e) {
    CHECK_THAT(e.message(), Catch::Contains("CYCLE: the file's arcs, splines and drilling cycles"));
  }
  // One such arc of 40 turns at r 10 mm is a helix a program may hold (1,800 chords a turn).
  CHECK_NOTHROW(
      parse_cl("FEDRAT/MMPM,500\nRAPID\nGOTO/10,0,0\n"
               "MOVARC/0,0,0,0,0,1,10,ANGLE,14400\nGOTO/10,0,0\n",
               "helix.cls"));
}
