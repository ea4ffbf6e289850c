// Hostile input, round 5 (issue 63.12): numbers as the option parser would take them, a zero
// that silently meant "the default", a spindle switched off read as no SPINDL at all.
#include <catch2/catch.hpp>
#include <filesystem>
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

TEST_CASE("hostile outputs: a full disk leaves no --plots folder behind, a link in it is refused",
          "[cli][bad-input][atomic]") {
  TempDir t;
  // Three points: a program of 0.7 KB, each plot about 3 KB.
  write_file(t.path("s.apt"),
             "UNITS/MM\nCUTTER/10,5\nLOADTL/2\nSPINDL/RPM,5000\nFEDRAT/600,MMPM\nGOTO/0,0,5\n"
             "GOTO/10,0,5\nGOTO/20,0,5\n");
  const std::string in =
      "--in " + t.path("s.apt") + " --method none -q --gcode " + t.path("o.nc") + " ";
  // A file size limit of 1 KB (SIGXFSZ ignored: writes fail with EFBIG) stands in for a disk
  // that fills while the plots are written.
  const RunResult full = run("sh -c 'trap \"\" XFSZ; ulimit -f 2; " + std::string(TAXOPT_EXE) +
                             " " + in + "--plots " + t.path("new/plots") + "'");
  INFO(full.err);
  CHECK(full.code == 2);
  CHECK_THAT(full.err, Catch::Contains("cannot write"));
  CHECK_FALSE(file_exists(t.path("new")));  // the folders the run made, gone
  CHECK_FALSE(file_exists(t.path("o.nc")));
  // A link where a plot goes: renaming over it would replace the link, not write its target.
  std::filesystem::create_directories(t.path("p"));
  write_file(t.path("target.svg"), "mine\n");
  const RunResult first = run_taxopt(in + "--plots " + t.path("p"));
  REQUIRE(first.code == 0);
  const std::string plot = std::filesystem::directory_iterator(t.path("p"))->path().string();
  std::filesystem::remove(plot);
  std::filesystem::create_symlink(t.path("target.svg"), plot);
  const RunResult linked = run_taxopt(in + "--plots " + t.path("p"));
  CHECK(linked.code == 2);
  CHECK_THAT(linked.err, Catch::Contains("is a symbolic link"));
  CHECK(std::filesystem::is_symlink(plot));
  CHECK(read_file(t.path("target.svg")) == "mine\n");
}

TEST_CASE(
    "hostile options: generate refuses a mesh too coarse for its surface (its own post "
    "refused the pair) naming --mesh-step, and writes a fine one's pair that posts",
    "[cli][bad-input]") {
  TempDir t;
  const std::string out = " --out-cls " + t.path("g.cls") + " --out-mesh " + t.path("g.stl");
  for (const char* step : {"50", "5"}) {
    const RunResult coarse = run_taxopt("generate --mesh-step " + std::string(step) + out);
    INFO(step);
    CHECK(coarse.code == 2);
    CHECK_THAT(coarse.err,
               Catch::Contains("off the surface") && Catch::Contains("a finer --mesh-step"));
    CHECK_FALSE(file_exists(t.path("g.cls")));
  }
  // The finest refused step's neighbour below posts: the check is the post's own.
  REQUIRE(run_taxopt("generate --mesh-step 2" + out).code == 0);
  const RunResult posted = run_taxopt("--in " + t.path("g.cls") + " --part " + t.path("g.stl") +
                                      " -q --gcode " + t.path("g.nc"));
  INFO(posted.err);
  CHECK(posted.code == 0);
}
