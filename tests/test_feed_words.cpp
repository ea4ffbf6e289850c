// The F words a program writes against the feeds the CL file programmed: with feed_reference
// "cutter-path" each block keeps its input block's time, within gcode.max_feed_ratio of the
// programmed feed; the report says how far the written F words went, judged on the program
// read back.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>

#include "support.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

struct Run {
  JobResult result;
  /// Written F over programmed F of every feed block, read back from the G-code text.
  double max_ratio = 0.0, min_ratio = 1e300;
};

Run run_demo(double max_feed_ratio) {
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  const Toolpath tp = read_cl_file(d + "sine.cls");
  const Part part(read_mesh_file(d + "sine.stl"));
  Machine machine = default_machine();
  machine.gcode.max_feed_ratio = max_feed_ratio;
  JobOptions options;
  options.part = &part;
  options.method = Method::Paper;
  Run out;
  out.result = run_job(tp, machine, options);
  double programmed = 0.0;
  for (const CLPointd& p : tp.operations.front().points) {
    if (p.motion == Motion::Feed) programmed = p.feed_mm_per_min;  // one FEDRAT in the demo
  }
  REQUIRE(programmed > 0.0);
  // Each feed point's block as read back (GcodeProgram::emitted: its line; minus an arc's).
  std::map<int, const GcodeMove*> at_line;
  const std::vector<GcodeMove> moves = read_gcode_moves(out.result.gcode.text, "demo.ngc");
  for (const GcodeMove& m : moves) at_line[m.line] = &m;
  const auto& points = tp.operations.front().points;
  for (std::size_t i = 1; i < points.size(); ++i) {
    const int line = std::abs(out.result.gcode.emitted[0][i]);
    if (points[i].motion != Motion::Feed || line == 0) continue;
    REQUIRE(at_line.count(line));
    const double r = at_line[line]->feed / programmed;
    out.max_ratio = std::max(out.max_ratio, r);
    out.min_ratio = std::min(out.min_ratio, r);
  }
  return out;
}

}  // namespace

TEST_CASE(
    "feed words: each block keeps its input block's time within gcode.max_feed_ratio of the "
    "programmed feed, and the report says how far the F words went, as read back",
    "[program][feed]") {
  const Run free = run_demo(100.0), two = run_demo(2.0), tight = run_demo(1.2);
  for (const Run* r : {&free, &two, &tight}) {
    REQUIRE(r->result.ok());
    REQUIRE(r->result.operations.front().feed_words);
  }
  const auto& words = [](const Run& r) { return *r.result.operations.front().feed_words; };
  // Unbounded, the paper's axes keep the input's times with F up to 1.67 x the programmed:
  // the ratio of 2 never binds, 1.2 does.
  CHECK(words(free).max_ratio > 1.5);
  CHECK(words(free).lengthened_blocks == 0);
  CHECK(words(two).lengthened_blocks == 0);
  CHECK(two.result.gcode.text == free.result.gcode.text);
  CHECK(words(tight).lengthened_blocks > 0);
  CHECK(words(tight).max_feed_ratio == 1.2);
  // The F words as read back stay within the ratio (F rounded to 3 decimals of 1000 mm/min).
  CHECK(tight.max_ratio <= 1.2 + 1e-6);
  CHECK(words(tight).max_ratio == Approx(tight.max_ratio).margin(1e-9));
  CHECK(words(free).max_ratio == Approx(free.max_ratio).margin(1e-9));
  CHECK(words(free).min_ratio == Approx(free.min_ratio).margin(1e-9));
  // Below the programmed feed there is no bound: the slow blocks are the same.
  CHECK(tight.min_ratio == Approx(free.min_ratio).margin(1e-9));
  // The lengthened blocks take longer on the machine, and the rates are those of the program
  // as timed: the cycle grows, the peak rotary speed does not.
  CHECK(tight.result.gcode.time_s > free.result.gcode.time_s);
  CHECK(tight.result.operations.front().after.max_omega_deg_s <=
        free.result.operations.front().after.max_omega_deg_s * (1.0 + 1e-9));
}
