// Feed scheduling speed: schedule_feed on one chain of N feed moves (default 100,000), one core.
// Two paths: a smooth sine-like zig-zag finishing path as an A/C machine moves it (the joints of
// a ball-end mill following z = 10 cos(2 pi y / 40) with the axis on the normal), and a random
// walk of the five joints with reversals (conflicting joints, more sweeps). Target:
// 100,000 points in <= 0.2 s on one core.
// Run: build/release/bench/bench_feed [points] [repeats]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "taxopt/io/machine_file.hpp"
#include "taxopt/kinematics/feed_schedule.hpp"

using namespace taxopt;

namespace {

FeedChain sine_chain(std::size_t n) {
  FeedChain c;
  const MachineKinematicsd ac = default_machine_kinematics();
  const double w = 2.0 * Constants<double>::pi() / 40.0, step_mm = 0.2;
  Posed prev{};
  for (std::size_t i = 0; i < n; ++i) {
    // Zig-zag passes 100 mm long, 0.5 mm apart, the step-over at feed too.
    const std::size_t pass = i / 500, k = i % 500;
    const double y = step_mm * static_cast<double>(pass % 2 == 0 ? k : 499 - k);
    const double x = 0.5 * static_cast<double>(pass % 200);
    const Vec3d tip(x, y, 10.0 * std::cos(w * y));
    const Vec3d normal = Vec3d(0.0, 10.0 * w * std::sin(w * y), 1.0).normalized();
    // The branch nearest the previous pose, C unwound.
    Posed best{};
    double d = 1e300;
    for (Posed p : ac.inverse(normal)) {
      p.c_rad += 2.0 * Constants<double>::pi() *
                 std::round((prev.c_rad - p.c_rad) / (2.0 * Constants<double>::pi()));
      const double e = std::hypot(p.tilt_rad - prev.tilt_rad, p.c_rad - prev.c_rad);
      if (e < d) d = e, best = p;
    }
    prev = best;
    const Vec3d m = ac.to_machine_mm(tip, best);
    c.joints.push_back({m.x(), m.y(), m.z(), rad_to_deg(best.tilt_rad), rad_to_deg(best.c_rad)});
    if (i > 0) c.min_time_s.push_back(60.0 * step_mm / 2000.0);  // 2000 mm/min
  }
  return c;
}

FeedChain random_chain(std::size_t n) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  FeedChain c;
  JointPosition q{}, dir{};
  for (std::size_t i = 0; i < n; ++i) {
    c.joints.push_back(q);
    for (std::size_t j = 0; j < kJointCount; ++j) {
      dir[j] += 0.3 * u(rng);
      if (u(rng) > 0.95) dir[j] = -dir[j];
      q[j] += (j < 3 ? 0.05 : 0.1) * dir[j];
    }
    if (i + 1 < n) c.min_time_s.push_back(0.006);
  }
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? static_cast<std::size_t>(std::atol(argv[1])) : 100000;
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  const JointLimits limits = default_joint_limits();
  std::printf("bench_feed %zu %d (schedule_feed, one thread, best of %d; default_joint_limits)\n\n",
              n, repeats, repeats);
  std::printf("| path | points | sweeps | limited segments | time s | target s |\n");
  std::printf("|---|---:|---:|---:|---:|---:|\n");
  for (const auto& [name, chain] :
       {std::pair<const char*, FeedChain>{"sine zig-zag finishing path", sine_chain(n)},
        {"random walk with reversals", random_chain(n)}}) {
    double best = 1e300;
    FeedSchedule s;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      s = schedule_feed(chain, limits);
      best = std::min(best,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::size_t limited = 0;
    for (FeedBound b : s.bound) limited += b != FeedBound::Programmed ? 1 : 0;
    std::printf("| %s | %zu | %d | %zu | %.4f | 0.2 |\n", name, n, s.sweeps, limited, best);
  }
  return 0;
}
