#pragma once
/// @file Private helper of the compiled library (not installed): the parallel loops of taxopt.
///
/// They run on oneTBB. Under ThreadSanitizer (TAXOPT_TSAN) they run on std::threads instead:
/// Debian's libtbb is not instrumented, so TSan cannot see the synchronisation of its task
/// queue and reports races inside TBB's own partitioner; with std::thread (create and join)
/// TSan sees every happens-before, and what it reports is in taxopt's loop bodies.

#include <algorithm>
#include <cstddef>
#include <exception>
#include <vector>

#ifdef TAXOPT_TSAN
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <thread>
#else
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#endif

namespace taxopt::detail {

#ifdef TAXOPT_TSAN
/// Threads to use: the job's arena (JobOptions::threads) or TBB's global limit, at least 2 so
/// that TSan has two to watch.
inline std::size_t tsan_threads() {
  const std::size_t limit = std::min<std::size_t>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
      static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency())));
  return std::max<std::size_t>(2, std::min<std::size_t>(limit, 8));
}

/// Runs work(t) for t in [0, threads) on as many std::threads; the first exception (by t) is
/// rethrown after every thread has ended, as TBB's loops do.
template <class Work>
void run_threads(std::size_t threads, const Work& work) {
  std::vector<std::exception_ptr> errors(threads);
  std::vector<std::thread> pool;
  for (std::size_t t = 0; t < threads; ++t) {
    pool.emplace_back([&, t] {
      try {
        work(t);
      } catch (...) {
        errors[t] = std::current_exception();
      }
    });
  }
  for (std::thread& th : pool) th.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}
#endif

/// Calls body(i) for every i in [begin, end), in parallel.
template <class Body>
void parallel_for(std::size_t begin, std::size_t end, const Body& body) {
#ifdef TAXOPT_TSAN
  if (end <= begin) return;
  const std::size_t n = end - begin, threads = std::min(tsan_threads(), n);
  run_threads(threads, [&](std::size_t t) {
    for (std::size_t i = begin + t * n / threads; i < begin + (t + 1) * n / threads; ++i) body(i);
  });
#else
  tbb::parallel_for(begin, end, body);
#endif
}

/// Reduces [begin, end) in parallel: `chunk(lo, hi, acc)` folds the indices [lo, hi) into a
/// value started at `identity`, `join(left, right)` combines neighbouring chunks in order.
template <class T, class Chunk, class Join>
T parallel_reduce(std::size_t begin, std::size_t end, const T& identity, const Chunk& chunk,
                  const Join& join) {
#ifdef TAXOPT_TSAN
  if (end <= begin) return identity;
  const std::size_t n = end - begin, threads = std::min(tsan_threads(), n);
  std::vector<T> parts(threads, identity);
  run_threads(threads, [&](std::size_t t) {
    parts[t] = chunk(begin + t * n / threads, begin + (t + 1) * n / threads, identity);
  });
  T acc = identity;
  for (const T& p : parts) acc = join(acc, p);
  return acc;
#else
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(begin, std::max(begin, end)), identity,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        return chunk(r.begin(), r.end(), std::move(acc));
      },
      join);
#endif
}

/// Runs f and g side by side and returns when both have; an exception of either is rethrown
/// (f's first) after both have ended.
template <class F, class G>
void parallel_invoke(const F& f, const G& g) {
#ifdef TAXOPT_TSAN
  std::exception_ptr g_error;
  std::thread other([&] {
    try {
      g();
    } catch (...) {
      g_error = std::current_exception();
    }
  });
  std::exception_ptr f_error;
  try {
    f();
  } catch (...) {
    f_error = std::current_exception();
  }
  other.join();
  if (f_error) std::rethrow_exception(f_error);
  if (g_error) std::rethrow_exception(g_error);
#else
  std::exception_ptr f_error, g_error;
  tbb::parallel_invoke(
      [&] {
        try {
          f();
        } catch (...) {
          f_error = std::current_exception();
        }
      },
      [&] {
        try {
          g();
        } catch (...) {
          g_error = std::current_exception();
        }
      });
  if (f_error) std::rethrow_exception(f_error);
  if (g_error) std::rethrow_exception(g_error);
#endif
}

}  // namespace taxopt::detail
