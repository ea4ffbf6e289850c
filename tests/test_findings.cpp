// Structured outcomes (issue 19): a library caller tells the kinds of finding apart by code,
// the display lists hold the same messages, and the report carries the codes.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <random>

#include "support.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// Every finding's message is in the display list of its severity, in order, and nothing else.
void check_lists(const JobResult& r) {
  std::vector<std::string> problems, safety, warnings;
  for (const Finding& f : r.findings) {
    (f.severity == Severity::Problem  ? problems
     : f.severity == Severity::Safety ? safety
                                      : warnings)
        .push_back(f.message);
  }
  CHECK(problems == r.problems);
  CHECK(safety == r.safety_warnings);
  CHECK(warnings == r.warnings);
  CHECK(r.ok() == problems.empty());
}

}  // namespace

TEST_CASE(
    "findings: a caller tells no part, an unreachable pose and a dynamic limit apart by "
    "code, with the operation and the CL line",
    "[findings][io]") {
  std::mt19937 rng(2027);
  const Heightfield hf = random_heightfields(rng).front();
  const GeneratedCl g = raster_cl(hf, 3.0, 20.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
  const Toolpath tp = parse_cl(g.text, "f.cls");

  // No part: a safety finding, and the output is still ok.
  JobOptions options;
  options.method = Method::None;
  const JobResult plain = run_job(tp, default_machine(), options);
  CHECK(plain.ok());
  CHECK(plain.has(FindingCode::NoPart));
  CHECK_FALSE(plain.has(FindingCode::UnreachablePose));
  check_lists(plain);

  // A tilt range the 20 deg axes cannot reach: a problem at the first point that fails.
  Machine narrow = default_machine();
  narrow.ac.a.min_rad = deg_to_rad(-5.0);
  narrow.ac.a.max_rad = deg_to_rad(5.0);
  const JobResult out = run_job(tp, narrow, options);
  CHECK_FALSE(out.ok());
  REQUIRE(out.has(FindingCode::UnreachablePose));
  for (const Finding& f : out.findings) {
    if (f.code != FindingCode::UnreachablePose) continue;
    CHECK(f.severity == Severity::Problem);
    REQUIRE(f.operation);
    CHECK(*f.operation == 0);
    CHECK(f.line > 0);
    CHECK(f.message.find("f.cls:" + std::to_string(f.line)) != std::string::npos);
  }
  check_lists(out);

  // A slow rotary table at the programmed feed: velocity or acceleration above the limit.
  Machine slow = default_machine();
  slow.limits[static_cast<std::size_t>(Joint::A)] = {0.5, 1.0, 0.0};
  slow.limits[static_cast<std::size_t>(Joint::C)] = {0.5, 1.0, 0.0};
  options.method = Method::Paper;
  options.max_deviation_deg = 5.0;
  const JobResult limited = run_job(tp, slow, options);
  CHECK(limited.has(FindingCode::DynamicLimitExceeded));
  check_lists(limited);

  // The report carries the codes, severities, operations and lines.
  const auto rep = nlohmann::json::parse(report_json(out, tp, narrow, options));
  REQUIRE(rep["findings"].size() == out.findings.size());
  bool seen = false;
  for (const auto& f : rep["findings"]) {
    if (f["code"] != "unreachable_pose") continue;
    seen = true;
    CHECK(f["severity"] == "problem");
    CHECK(f["operation"] == tp.operations[0].name);
    CHECK(f["line"].get<int>() > 0);
  }
  CHECK(seen);
}
