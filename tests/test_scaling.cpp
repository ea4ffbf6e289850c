// Every stage grows linearly with the job (issue 65): the generated sine at two sizes, four
// times the points apart, run as a user runs it; each stage's time and the whole process's may
// grow by at most twice the points' ratio (a stage quadratic in the points grows 16 times).
// A ratio, not a time: the same on a fast machine, a slow one and under the sanitizers.
// bench/stage_table.py prints the table this samples (docs/benchmarks.md).
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "support.hpp"

using namespace taxopt::test;

namespace {

struct Sample {
  double points = 0.0;
  std::map<std::string, double> seconds;  // the stages and "whole"
};

/// The least of `runs` runs of the sine `width_mm` wide (590 mm long, 0.75 mm mesh) per stage.
Sample run_sine(const TempDir& t, double width_mm, int runs) {
  const std::string cls = t.path("s.cls"), stl = t.path("s.stl");
  const RunResult g =
      run_taxopt("generate --surface sine --width " + std::to_string(width_mm) +
                 " --length 590 --mesh-step 0.75 --out-cls " + cls + " --out-mesh " + stl);
  REQUIRE(g.code == 0);
  Sample s;
  for (int k = 0; k < runs; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const RunResult r = run_taxopt("--in " + cls + " --part " + stl + " --gcode " + t.path("o.nc") +
                                   " --report " + t.path("r.json"));
    const double whole =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    INFO(r.err);
    REQUIRE(r.code <= 1);
    const auto j = nlohmann::json::parse(read_file(t.path("r.json")));
    std::map<std::string, double> at = {{"whole", whole}};
    s.points = 0.0;
    for (const auto& op : j["operations"]) {
      s.points += op["points"].get<double>();
      for (const char* stage : {"contacts", "optimise", "post", "verify"}) {
        at[stage] += op["timings_s"][stage].get<double>();
      }
    }
    for (const auto& [name, seconds] : at) {
      s.seconds[name] = k == 0 ? seconds : std::min(s.seconds[name], seconds);
    }
  }
  return s;
}

}  // namespace

TEST_CASE("scaling: every stage and the whole run grow linearly with the points",
          "[scaling][slow]") {
  const TempDir t;
  const Sample small = run_sine(t, 12.5, 2);
  const Sample large = run_sine(t, 50.0, 2);
  const double points_ratio = large.points / small.points;
  REQUIRE(points_ratio > 3.5);
  for (const auto& [stage, seconds] : large.seconds) {
    const double before = small.seconds.at(stage);
    INFO(stage << ": " << before << " s at " << small.points << " points, " << seconds << " s at "
               << large.points);
    // Below 20 ms a stage's time is mostly the clock's and the scheduler's.
    if (before < 0.02) continue;
    CHECK(seconds / before <= 2.0 * points_ratio);
  }
}
