// Scale: a CL file of N points (default 1,000,000) through read -> run_job (--method none)
// -> report/CSV, with wall time per stage and peak resident memory.
// Run: build/release/bench/bench_scale [points]
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "taxopt/io/cl_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;

namespace {

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  const long n = argc > 1 ? std::atol(argv[1]) : 1000000;
  // Raster passes of 1000 points over z = 10 cos(2 pi y / 40), axis 5 deg off the normal.
  auto t0 = std::chrono::steady_clock::now();
  std::string text =
      "TOOL PATH/SCALE,TOOL,BALL\nTLDATA/MILL,6.0,3.0,15.0,0,0\nLOADTL/1\nSPINDL/RPM,8000,CLW\n"
      "FEDRAT/MMPM,2000\n";
  text.reserve(static_cast<std::size_t>(n) * 80);
  char buf[200];
  const double w = 2.0 * Constants<double>::pi() / 40.0;
  for (long i = 0; i < n; ++i) {
    const long pass = i / 1000, k = i % 1000;
    const double x = 0.5 * static_cast<double>(pass), y = 0.1 * static_cast<double>(k);
    const Vec3d nrm = Vec3d(0, 10.0 * w * std::sin(w * y), 1.0).normalized();
    const Vec3d t = Vec3d(0, 1.0, -10.0 * w * std::sin(w * y)).normalized();
    const Vec3d v = Eigen::AngleAxisd(deg_to_rad(5.0), nrm.cross(t)) * nrm;
    const Vec3d tip = Vec3d(x, y, 10.0 * std::cos(w * y)) + 3.0 * nrm - 3.0 * v;
    if (k == 0) text += "RAPID\n";
    std::snprintf(buf, sizeof buf, "GOTO/%.4f,%.4f,%.4f,%.7f,%.7f,%.7f\n", tip.x(), tip.y(),
                  tip.z(), v.x(), v.y(), v.z());
    text += buf;
  }
  text += "END-OF-PATH\n";
  const double t_make = seconds(t0);
  const double rss_text = peak_rss_mb();

  t0 = std::chrono::steady_clock::now();
  const Toolpath tp = parse_cl(text, "scale.cls");
  const double t_read = seconds(t0);
  const double rss_read = peak_rss_mb();

  JobOptions options;
  options.method = Method::None;
  t0 = std::chrono::steady_clock::now();
  const JobResult result = run_job(tp, default_machine(), options);
  const double t_job = seconds(t0);
  const double rss_job = peak_rss_mb();

  t0 = std::chrono::steady_clock::now();
  const std::string report = report_json(result, tp, default_machine(), options);
  const std::string csv = points_csv(result);
  const double t_out = seconds(t0);

  std::printf("# taxopt scale benchmark\n# command: bench_scale %ld\n", n);
  std::printf("# CL text %.1f MB, G-code %.1f MB, CSV %.1f MB; result ok: %s\n",
              static_cast<double>(text.size()) / 1e6,
              static_cast<double>(result.gcode.text.size()) / 1e6,
              static_cast<double>(csv.size()) / 1e6, result.ok() ? "yes" : "no");
  std::printf("| stage | time s | peak RSS MB after |\n|---|---|---|\n");
  std::printf("| make CL text | %.2f | %.0f |\n", t_make, rss_text);
  std::printf("| read CL | %.2f | %.0f |\n", t_read, rss_read);
  std::printf("| run_job (poses, G-code, read-back, metrics) | %.2f | %.0f |\n", t_job, rss_job);
  std::printf("| report + CSV | %.2f | %.0f |\n", t_out, peak_rss_mb());
  return result.ok() ? 0 : 1;
}
