#pragma once
/// @file Private helper of the compiled library (not installed): a deterministic parallel
/// filter over an index range.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "util/parallel.hpp"

namespace taxopt::detail {

/// The indices in [begin, end) for which `pred` holds, ascending, evaluated in parallel:
/// the result does not depend on the thread count.
template <class Pred>
std::vector<std::size_t> parallel_select(std::size_t begin, std::size_t end, const Pred& pred) {
  using List = std::vector<std::size_t>;
  List hits = parallel_reduce(
      begin, end, List{},
      [&](std::size_t lo, std::size_t hi, List acc) {
        for (std::size_t i = lo; i != hi; ++i) {
          if (pred(i)) acc.push_back(i);
        }
        return acc;
      },
      [](List a, const List& b) {
        a.insert(a.end(), b.begin(), b.end());
        return a;
      });
  std::sort(hits.begin(), hits.end());
  return hits;
}

}  // namespace taxopt::detail
