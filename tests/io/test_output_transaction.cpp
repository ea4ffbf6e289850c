// The outputs of a run are one transaction (issue 63.10): a rename that fails puts the ones
// before it back, and two paths to one folder are one file.
#include <catch2/catch.hpp>
#include <filesystem>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/atomic_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// Files in `dir` whose names start with '.' (a temporary or a kept old file left behind).
std::size_t hidden_files(const std::string& dir) {
  std::size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    n += e.path().filename().string().rfind(".", 0) == 0;
  }
  return n;
}

}  // namespace

TEST_CASE("output transaction: a rename that fails leaves every output as it was", "[io][atomic]") {
  TempDir t;
  write_file(t.path("a.nc"), "old program\n");
  std::filesystem::create_directory(t.path("sub"));
  {
    OutputTransaction tx;
    tx.stage(t.path("a.nc"), "new program\n");
    tx.stage(t.path("b.csv"), "new csv\n");
    tx.stage(t.path("sub/c.json"), "new report\n");
    tx.stage(t.path("d.html"), "new page\n");
    // The third target's folder goes after staging, its temporary with it: its rename fails.
    std::filesystem::remove_all(t.path("sub"));
    CHECK_THAT(input_error_of([&] { tx.commit(); }),
               Catch::Contains("c.json") && Catch::Contains("left as it was"));
  }
  CHECK(read_file(t.path("a.nc")) == "old program\n");  // the first renamed, put back
  CHECK_FALSE(file_exists(t.path("b.csv")));            // new: removed again
  CHECK_FALSE(file_exists(t.path("d.html")));           // never renamed, its temporary gone
  CHECK(hidden_files(t.dir()) == 0);
  // Committed whole: all new, no old link kept.
  OutputTransaction tx;
  tx.stage(t.path("a.nc"), "new program\n");
  tx.stage(t.path("b.csv"), "new csv\n");
  tx.commit();
  CHECK(read_file(t.path("a.nc")) == "new program\n");
  CHECK(read_file(t.path("b.csv")) == "new csv\n");
  CHECK(hidden_files(t.dir()) == 0);
}

TEST_CASE("output transaction: one folder under two paths is one file, before it exists",
          "[io][atomic]") {
  TempDir t;
  std::filesystem::create_directory(t.path("a"));
  std::filesystem::create_directory_symlink(t.path("a"), t.path("b"));
  CHECK(same_file(t.path("a/x.nc"), t.path("b/x.nc")));
  CHECK_FALSE(same_file(t.path("a/x.nc"), t.path("b/y.nc")));
  CHECK_FALSE(same_file(t.path("a/x.nc"), t.path("x.nc")));
  // The CLI refuses it before any work.
  write_file(t.path("p.cls"), "GOTO/0,0,0\nGOTO/1,0,0\n");
  const auto r = run_taxopt("--in " + t.path("p.cls") + " --method none --gcode " +
                            t.path("a/x.nc") + " --report " + t.path("b/x.nc"));
  CHECK(r.code == 2);
  CHECK_FALSE(file_exists(t.path("a/x.nc")));
}
