#include <catch2/catch.hpp>
#include <random>

#include "taxopt/plan/segmenter.hpp"

using namespace taxopt;

namespace {

/// Index of the sample nearest to x.
std::size_t nearest(const std::vector<double>& xs, double x) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < xs.size(); ++i) {
    if (std::abs(xs[i] - x) < std::abs(xs[best] - x)) best = i;
  }
  return best;
}

}  // namespace

TEST_CASE("segmenter: the inflection points of a sampled sine are found at their indices",
          "[plan][segmenter]") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> amp(2.0, 15.0), wave(20.0, 60.0), phase(0.0, 6.28),
      jitter(0.3, 1.0);
  for (int t = 0; t < 20; ++t) {
    const double a = amp(rng), lambda = wave(rng), ph = phase(rng);
    const bool uneven = t % 2 == 1;  // unequal steps: the printed eq. 27 fails there
    std::vector<double> xs;
    for (double x = 0.0; x <= 100.0; x += uneven ? jitter(rng) : 0.5) xs.push_back(x);
    std::vector<Vec3d> pts;
    const double k = 2.0 * Constants<double>::pi() / lambda;
    for (double x : xs) pts.emplace_back(x, 3.0, a * std::sin(k * x + ph));
    const CurveShape<double> shape = segment_curve(pts, Vec3d::UnitZ());
    // Inflections where k x + ph = m pi. One within an eighth of a wavelength of an end has
    // too little curvature on its outer side to be told from noise: those are not compared.
    const double margin = lambda / 8.0;
    const auto inside = [&](double x) { return x > margin && x < xs.back() - margin; };
    std::vector<std::size_t> expected;
    for (int m = -1; m < 20; ++m) {
      const double x = (m * Constants<double>::pi() - ph) / k;
      if (inside(x)) expected.push_back(nearest(xs, x));
    }
    std::vector<std::size_t> found;
    for (std::size_t i : shape.inflections) {
      if (inside(xs[i])) found.push_back(i);
    }
    INFO("trial " << t << " amplitude " << a << " wavelength " << lambda);
    REQUIRE(found.size() == expected.size());
    REQUIRE(shape.inflections.size() <= expected.size() + 2);
    for (std::size_t i = 0; i < expected.size(); ++i) {
      // The middle of the stretch between the counted curvatures of both signs: the nearest
      // sample, or its neighbour when the crossing falls between two samples.
      CHECK(std::abs(static_cast<long>(found[i]) - static_cast<long>(expected[i])) <= 1);
    }
    // Extremes at k x + ph = pi/2 + m pi.
    std::vector<double> true_extremes;
    for (int m = -1; m < 20; ++m) {
      true_extremes.push_back((Constants<double>::pi() / 2 + m * Constants<double>::pi() - ph) / k);
    }
    const auto near_any = [](double x, const std::vector<double>& list, double tol) {
      for (double y : list) {
        if (std::abs(x - y) <= tol) return true;
      }
      return false;
    };
    std::vector<double> found_x;
    for (std::size_t i : shape.extremes) found_x.push_back(xs[i]);
    for (double x : true_extremes) {
      if (inside(x)) CHECK(near_any(x, found_x, 1.6));
    }
    for (double x : found_x) CHECK(near_any(x, true_extremes, 1.6));
    // Keys: the ends and the inflections (the sine's intervals are symmetric).
    CHECK(shape.keys.front() == 0);
    CHECK(shape.keys.back() == pts.size() - 1);
  }
}

TEST_CASE("segmenter: a straight slope with uneven steps and a noisy flat give no inflection",
          "[plan][segmenter]") {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> step(0.1, 1.5), noise(-1e-4, 1e-4);
  std::vector<Vec3d> slope, flat;
  double x = 0.0;
  for (int i = 0; i < 200; ++i, x += step(rng)) {
    slope.emplace_back(x, 0.0, 0.7 * x);
    flat.emplace_back(x, 0.0, 5.0 + noise(rng));  // CL files carry 4 to 6 decimals
  }
  for (const auto* pts : {&slope, &flat}) {
    const CurveShape<double> shape = segment_curve(*pts, Vec3d::UnitZ());
    CHECK(shape.inflections.empty());
    CHECK(shape.keys == std::vector<std::size_t>{0, pts->size() - 1});
  }
}

TEST_CASE("segmenter: a strongly asymmetric interval gets a key at its extreme point",
          "[plan][segmenter]") {
  // One crest between two troughs, z = 10 cos(pi/2 (x - top) / w) with w = w_left before the
  // top and w_right after it: inflections at top - w_left and top + w_right.
  const auto skewed = [](double w_left, double w_right) {
    std::vector<Vec3d> pts;
    for (double x = -2.0 * w_left; x <= 2.0 * w_right + 1e-9; x += 0.5) {
      const double w = x < 0.0 ? w_left : w_right;
      pts.emplace_back(x, 0.0, 10.0 * std::cos(0.5 * Constants<double>::pi() * x / w));
    }
    return pts;
  };
  const std::vector<Vec3d> lopsided = skewed(20.0, 45.0), even = skewed(30.0, 30.0);
  const CurveShape<double> a = segment_curve(lopsided, Vec3d::UnitZ());
  const CurveShape<double> b = segment_curve(even, Vec3d::UnitZ());
  REQUIRE(a.inflections.size() == 2);
  REQUIRE(b.inflections.size() == 2);
  const auto top = [](const std::vector<Vec3d>& pts) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (pts[i].z() > pts[best].z()) best = i;
    }
    return best;
  };
  // The lopsided hump gets its top as a key, the even one does not.
  CHECK(std::find(a.keys.begin(), a.keys.end(), top(lopsided)) != a.keys.end());
  CHECK(std::find(b.keys.begin(), b.keys.end(), top(even)) == b.keys.end());
  CHECK(b.keys.size() == 4);
  CHECK(a.keys.size() == 5);
}

TEST_CASE("segmenter: repeated points and a climb up a vertical wall are handled",
          "[plan][segmenter]") {
  std::vector<Vec3d> pts;
  for (int i = 0; i <= 20; ++i) pts.emplace_back(i * 0.5, 0.0, 0.0);
  pts.push_back(pts.back());                                           // a repeated point
  for (int i = 1; i <= 20; ++i) pts.emplace_back(10.0, 0.0, i * 0.5);  // straight up
  const CurveShape<double> shape = segment_curve(pts, Vec3d::UnitZ());
  for (double f2 : shape.f2_per_mm) CHECK(std::isfinite(f2));
  // One concave corner: no sign change of f'', so no inflection.
  CHECK(shape.inflections.empty());
}
