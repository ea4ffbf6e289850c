// The outputs of a run are one transaction (issue 63.10): a rename that fails puts the ones
// before it back, and two paths to one folder are one file.
#include <catch2/catch.hpp>
#include <csignal>
#include <cstdlib>
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

// The child of the next test: commits generation after generation of 16 files until a signal
// ends it (hidden: run only when the parent names it).
TEST_CASE("output transaction: commit loop, the signal test's child", "[.commit-loop]") {
  const char* dir = std::getenv("TAXOPT_COMMIT_LOOP_DIR");
  if (!dir) return;
  // Catch's own handlers out of the way: the transaction's are installed where the default is.
  for (int sig : {SIGINT, SIGTERM}) std::signal(sig, SIG_DFL);
  OutputTransaction::remove_pending_on_signals();
  for (int gen = 1;; ++gen) {
    OutputTransaction tx;
    for (int k = 0; k < 16; ++k) {
      tx.stage(std::string(dir) + "/f" + std::to_string(k) + ".nc", std::to_string(gen) + "\n");
    }
    tx.commit();
  }
}

TEST_CASE(
    "output transaction: a SIGTERM at any moment leaves every output of one generation, no "
    "temporary or kept old file behind",
    "[io][atomic]") {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  std::size_t ended_by_signal = 0;
  for (int trial = 0; trial < 40; ++trial) {
    TempDir t;
    for (int k = 0; k < 16; ++k) write_file(t.path("f" + std::to_string(k) + ".nc"), "0\n");
    // Killed after 30 to 225 ms: before, during or between commits.
    const std::string wait_s = std::to_string(0.03 + 0.005 * (trial * 7 % 40));
    const RunResult r = run("TAXOPT_COMMIT_LOOP_DIR=" + t.dir() + " " + self +
                            " '[.commit-loop]' >/dev/null 2>&1 & p=$!; sleep " + wait_s +
                            "; kill -TERM $p; wait $p; echo $?");
    ended_by_signal += r.out.find("143") != std::string::npos;
    const std::string first = read_file(t.path("f0.nc"));
    INFO("trial " << trial << ", generation " << first);
    for (int k = 1; k < 16; ++k) CHECK(read_file(t.path("f" + std::to_string(k) + ".nc")) == first);
    CHECK(hidden_files(t.dir()) == 0);
  }
  CHECK(ended_by_signal == 40);
}
