// The least tilt from the designed normal (issue 60): held by default at the input's own
// least, asked larger with --min-tilt, given up only where no free axis keeps it, and what it
// costs the rates, on the bundled demo (the CAM's 5 deg lead; its input hits the part on the
// lead side at 330 points, so the free axes are on the other side of the normal there).
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "support.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

struct DemoRun {
  RunResult result;
  nlohmann::json op;  // the report's one operation
  std::vector<std::string> codes;
};

DemoRun run_demo(TempDir& dir, const std::string& args) {
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  DemoRun run;
  run.result = run_taxopt("--in " + d + "sine.cls --part " + d + "sine.stl -q --gcode " +
                          dir.path("o.nc") + " --report " + dir.path("r.json") + " " + args);
  if (run.result.code != 0) return run;
  const auto report = nlohmann::json::parse(read_file(dir.path("r.json")));
  run.op = report["operations"][0];
  for (const auto& f : report["findings"]) run.codes.push_back(f["code"]);
  return run;
}

bool has(const DemoRun& run, const std::string& code) {
  return std::find(run.codes.begin(), run.codes.end(), code) != run.codes.end();
}

}  // namespace

TEST_CASE(
    "least tilt: by default every method keeps the input's least angle from the normal at every "
    "written point of the demo and still beats its input, which without it comes nearer",
    "[least-tilt][integration][slow]") {
  TempDir dir;
  double held_peak[2] = {0.0, 0.0};
  int k = 0;
  for (const char* method : {"paper", "global"}) {
    INFO("--method " << method);
    const DemoRun held = run_demo(dir, std::string("--method ") + method);
    INFO(held.result.err);
    REQUIRE(held.result.code == 0);
    const auto& c = held.op["cutting"];
    // The input's least, 4.58 deg from the mesh's normals, rounded down to 0.1 deg.
    CHECK(c["least_tilt_deg"] == Approx(4.5));
    CHECK(c["least_tilt_from"] == "input");
    CHECK(c["least_tilt_held"] == true);
    CHECK(c["points_below_least_tilt"] == 0);
    CHECK(c["after"]["least_tilt_deg"].get<double>() >= 4.5 - 0.01);
    CHECK_FALSE(has(held, "least_tilt_not_kept"));
    // Still below the input's 48.1 deg/s^2 (measured: paper 43.8, global 8.2; without the
    // bound 14.2 and 7.6). The paper's keys go round the cap round the normal sideways, which
    // near the A/C pole turns C: its cost is the axis's bending, blind to C.
    const double before = held.op["before"]["max_accel_deg_s2"];
    const double after = held.op["after"]["max_accel_deg_s2"];
    CHECK(after <= (std::string(method) == "paper" ? 0.95 : 0.25) * before);
    held_peak[k++] = after;

    // --min-tilt 0 holds none: the methods then come nearer the normal than the input's 4.5
    // (measured 2.75 and 2.91 deg), which is what the bound above prevents.
    const DemoRun free = run_demo(dir, std::string("--method ") + method + " --min-tilt 0");
    REQUIRE(free.result.code == 0);
    CHECK(free.op["cutting"]["least_tilt_held"] == false);
    CHECK(free.op["cutting"]["after"]["least_tilt_deg"].get<double>() < 4.0);
  }
  CHECK(held_peak[1] <= held_peak[0] * 1.001);
}

TEST_CASE("least tilt: asked larger than the input's, each point keeps the input's own angle there",
          "[least-tilt][integration][slow]") {
  TempDir dir;
  // 8 deg: the input is at 4.6-5 deg everywhere, so each point's bound is its own angle: no
  // written axis comes nearer the normal than the input did.
  const DemoRun eight = run_demo(dir, "--method paper --min-tilt 8");
  INFO(eight.result.err);
  REQUIRE(eight.result.code == 0);
  CHECK(eight.op["cutting"]["least_tilt_from"] == "option");
  CHECK(eight.op["cutting"]["points_below_least_tilt"] == 0);
  CHECK(eight.op["cutting"]["after"]["least_tilt_deg"].get<double>() >=
        eight.op["cutting"]["before"]["least_tilt_deg"].get<double>() - 0.01);
  CHECK(eight.op["verification"]["collision_free"] == true);
}
