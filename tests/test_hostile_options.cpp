// Hostile input, round 5 (issue 63.12): numbers as the option parser would take them, a zero
// that silently meant "the default", a spindle switched off read as no SPINDL at all.
#include <catch2/catch.hpp>
#include <string>

#include "support.hpp"

using namespace taxopt::test;

TEST_CASE(
    "hostile options: a number is a decimal -- 0x100, 0b11 and 1e2x are refused naming the "
    "option, and --contact-tolerance 0 is refused rather than read as the default",
    "[cli][bad-input]") {
  TempDir t;
  const std::string in = "--in " + std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls" +
                         " --method none -q --gcode " + t.path("o.ngc");
  for (const char* bad :
       {"--feed 0x100", "--feed 0b11", "--grid 1e2x", "--threads 0x2", "--work-offset 0,0x5,1"}) {
    INFO(bad);
    const RunResult r = run_taxopt(in + " " + std::string(bad));
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("a decimal number, got"));
    CHECK_FALSE(file_exists(t.path("o.ngc")));
  }
  // Decimals in every form stay numbers.
  const RunResult ok = run_taxopt(in + " --feed 1.5e2");
  INFO(ok.err);
  CHECK(ok.code == 0);
  const RunResult zero = run_taxopt(in + " --contact-tolerance 0");
  CHECK(zero.code == 2);
  CHECK_THAT(zero.err, Catch::Contains("--contact-tolerance must be within (0, 1] mm, got 0"));
  const RunResult generated = run_taxopt("generate --width 0x10 --out-cls " + t.path("g.cls"));
  CHECK(generated.code == 2);
  CHECK_THAT(generated.err, Catch::Contains("--width: a decimal number, got 0x10"));
}

TEST_CASE("hostile options: a spindle set to 0 rpm is said as the spindle off, not as no SPINDL",
          "[cli][bad-input]") {
  TempDir t;
  write_file(t.path("s.apt"),
             "UNITS/MM\nCUTTER/10,5\nLOADTL/2\nSPINDL/RPM,0\nFEDRAT/600,MMPM\nGOTO/0,0,5\n"
             "GOTO/10,0,5\n");
  const RunResult r =
      run_taxopt("--in " + t.path("s.apt") + " --method none -q --gcode " + t.path("o.ngc"));
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("s.apt:6") && Catch::Contains("SPINDL/OFF or a speed of 0"));
}
