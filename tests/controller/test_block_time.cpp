// The block time model (controller/block_time.hpp): the rules the schedule, the guard, the
// global objective, the post and the report share.
#include <catch2/catch.hpp>

#include "controller/block_time.hpp"
#include "taxopt/io/gcode.hpp"

using namespace taxopt;

TEST_CASE(
    "block time: a kept block time holds, but never shorter than its own over the feed "
    "ratio",
    "[controller][model]") {
  using controller::kept_time_s;
  CHECK(kept_time_s(2.0, 1.0, 2.0) == 2.0);  // slower than its own: as the input ran it
  CHECK(kept_time_s(0.3, 1.0, 2.0) == 0.5);  // would need F at 3.3x: held at 2x
  CHECK(kept_time_s(0.0, 1.0, 2.0) == 1.0);  // nothing kept: its own
  std::size_t capped = 0;
  const std::vector<double> t =
      controller::kept_block_times_s({0.0, 0.3, 2.0, 0.6}, {0.0, 1.0, 1.0, 1.0}, 2.0, &capped);
  CHECK(t == std::vector<double>{0.0, 0.5, 2.0, 0.6});
  CHECK(capped == 1);
}

TEST_CASE(
    "block time: the tip rule is the tip's distance over the feed, the turn's in deg/min "
    "where the tip stands still",
    "[controller][model]") {
  controller::BlockTiming tip;
  tip.feed_mm_per_min = {0.0, 600.0, 600.0};
  const Posed p0{0.0, 0.0}, p1{deg_to_rad(3.0), deg_to_rad(4.0)};
  // 10 mm at 600 mm/min: 1 s.
  CHECK(tip.move_time_s(1, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == Approx(1.0));
  // A and C alone, 5 deg at 600 deg/min: 0.5 s.
  CHECK(tip.move_time_s(2, Vec3d(1, 1, 1), p0, Vec3d(1, 1, 1), p1) == Approx(0.5));
  CHECK(tip.move_time_s(0, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == 0.0);  // no feed
  // "cutter-path": the input's 4 s block kept; its 0.1 s block held at the ratio (1 s / 2).
  controller::BlockTiming kept = tip;
  kept.kept_s = {0.0, 4.0, 0.1};
  kept.max_feed_ratio = 2.0;
  CHECK(kept.move_time_s(1, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == Approx(4.0));
  CHECK(kept.move_time_s(2, Vec3d(0, 0, 0), p0, Vec3d(6, 8, 0), p0) == Approx(0.5));
}
