#!/usr/bin/env bash
# The test command of the README (and of CI): installs what is missing, builds with warnings
# as errors, runs the whole test suite, builds the example consumer against the installed
# package, then runs the suite again under AddressSanitizer + UndefinedBehaviorSanitizer and
# under ThreadSanitizer, and fuzzes the readers for a bounded time.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each stage says when it starts, in seconds since the script did (CI's time is bounded).
started=$SECONDS
stage() { echo "== [$((SECONDS - started)) s] $*"; }
bash scripts/setup.sh

jobs=$(nproc)
stage "release build and tests"
cmake --preset release
cmake --build --preset release -j "$jobs"
# LinuxCNC's motion controller (label controller: serial, about 5 minutes on one core) runs
# beside the fuzzers at the end, which take one core; the rest of the suite here.
ctest --preset release -j "$jobs" -LE controller

stage "install and build the example consumer against it"
prefix="$PWD/build/install"
rm -rf "$prefix" build/consumer
cmake --install build/release --prefix "$prefix"
python3 scripts/check_doc_snippets.py docs/library.md "$prefix"
cmake -S examples/consumer -B build/consumer -G Ninja -DCMAKE_PREFIX_PATH="$prefix"
cmake --build build/consumer
./build/consumer/taxopt_consumer tests/data/real/mech491-variable-axis-ballmill.cls build/consumer/out.ngc
rs274 -g build/consumer/out.ngc > build/consumer/rs274.log
./build/consumer/taxopt_consumer data/demo/sine.cls data/demo/sine.stl build/consumer/demo.ngc
rs274 -g build/consumer/demo.ngc > build/consumer/rs274-demo.log
# A post with nothing read from files: points, part and two machines (A/C table-table, B/C
# head-head) in code, one plan, a verified program for each.
rm -rf build/in-memory-post
cmake -S examples/in_memory_post -B build/in-memory-post -G Ninja -DCMAKE_PREFIX_PATH="$prefix"
cmake --build build/in-memory-post
./build/in-memory-post/taxopt_in_memory_post build/in-memory-post/ac.ngc build/in-memory-post/head.ngc
for p in ac head; do rs274 -g build/in-memory-post/$p.ngc > build/in-memory-post/rs274-$p.log; done

stage "the library shared, and both installs through pkg-config"
# A shared build carries its private dependencies: the consumer finds Eigen only, links
# libtaxopt alone, and runs the same job. pkg-config builds the consumer against each install
# (the static one with --static: its private libraries). The shared library exports what the
# public headers declare TAXOPT_API and nothing else; the CLI, linked to it, is a user of that
# API only and writes the same files as the static build's.
shared="$PWD/build/install-shared"
rm -rf "$shared" build/consumer-shared build/consumer-pc build/cli-shared
cmake --preset shared
cmake --build --preset shared -j "$jobs"
python3 scripts/check_exports.py build/shared/libtaxopt.so include/taxopt
# The soname is major.minor, as the package's compatibility (SameMinorVersion) is.
readelf -d build/shared/libtaxopt.so | grep SONAME
readelf -d build/shared/libtaxopt.so | grep "\[libtaxopt.so.$(sed -n 's/^project(taxopt VERSION \([0-9]*\.[0-9]*\).*/\1/p' CMakeLists.txt)\]" >/dev/null
for v in release shared; do
  mkdir -p build/cli-shared/$v
  ./build/$v/taxopt --in data/demo/sine.cls --part data/demo/sine.stl --quiet \
    --gcode build/cli-shared/$v/demo.nc --points-csv build/cli-shared/$v/points.csv \
    --out-cls build/cli-shared/$v/out.cls --html build/cli-shared/$v/demo.html
done
for f in demo.nc points.csv out.cls; do cmp build/cli-shared/release/$f build/cli-shared/shared/$f; done
cmake --install build/shared --prefix "$shared"
# Every installed header stands alone (a consumer includes any one first).
for h in $(cd "$shared/include" && find taxopt -name '*.hpp' | sort); do
  echo "#include <$h>" | g++ -std=c++17 -fsyntax-only -x c++ - -I"$shared/include" \
    $(pkg-config --cflags eigen3)
done
cmake -S examples/consumer -B build/consumer-shared -G Ninja -DCMAKE_PREFIX_PATH="$shared"
cmake --build build/consumer-shared
needed=$(readelf -d build/consumer-shared/taxopt_consumer | grep NEEDED)
echo "$needed"
echo "$needed" | grep -q "libtaxopt.so"
if echo "$needed" | grep -Eq "tbb|fcl|gmp|mpfr|ccd"; then
  echo "the consumer of the shared library links a private dependency of taxopt" >&2
  exit 1
fi
./build/consumer-shared/taxopt_consumer data/demo/sine.cls data/demo/sine.stl build/consumer-shared/demo.ngc
cmp build/consumer/demo.ngc build/consumer-shared/demo.ngc
mkdir -p build/consumer-pc
# shellcheck disable=SC2046
g++ -O1 examples/consumer/main.cpp -o build/consumer-pc/shared \
  $(PKG_CONFIG_PATH="$shared/lib/pkgconfig" pkg-config --cflags --libs taxopt) -std=c++17 \
  -Wl,-rpath,"$shared/lib"
# shellcheck disable=SC2046
g++ -O1 examples/consumer/main.cpp -o build/consumer-pc/static \
  $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --static --cflags --libs taxopt) -std=c++17
# The static library's private dependencies, every one a consumer links (toml++ reads a machine
# file).
for dep in tbb fcl gmp mpfr tomlplusplus; do
  PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --print-requires-private taxopt | grep -x "$dep" >/dev/null
done
for v in shared static; do
  ./build/consumer-pc/$v data/demo/sine.cls data/demo/sine.stl build/consumer-pc/demo-$v.ngc
  cmp build/consumer/demo.ngc build/consumer-pc/demo-$v.ngc
done

stage "AddressSanitizer + UndefinedBehaviorSanitizer"
cmake --preset asan
cmake --build --preset asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --preset asan -j "$jobs"

stage "ThreadSanitizer (the parallel loops run on std::threads here: src/util/parallel.hpp)"
# What it adds is on the parallel stages: the tests that run every one of them (contacts, the
# C-space raster, the optimisers, the verification) in-process, and the CLI's 1-against-2-thread
# byte comparisons. The rest of the suite runs under ASan + UBSan above.
cmake --preset tsan
cmake --build --preset tsan -j "$jobs"
TSAN_OPTIONS=halt_on_error=1 ctest --preset tsan -j "$jobs" -R "threads|pipeline:|cspace"

stage "fuzzing (libFuzzer, bounded), and LinuxCNC's motion controller beside it"
ctest --preset release -L controller > build/controller.log 2>&1 &
controller=$!
bash scripts/fuzz.sh 30
controller_rc=0
wait "$controller" || controller_rc=$?
cat build/controller.log
if [ "$controller_rc" != 0 ]; then
  echo "the controller tests failed (exit $controller_rc)" >&2
  exit 1
fi
stage "done"
