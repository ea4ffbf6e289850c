#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each for a bounded time on its seed corpus
# (tests/fuzz/corpus/). Usage: scripts/fuzz.sh [seconds per target, default 30]
# A crash leaves its input in build/fuzz/ and fails the script; add it to the corpus and to
# the bad-input tests when fixing it.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
CXX=clang++ cmake -S fuzz -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build/fuzz
for t in cl_reader:cl machine_file:machine gcode_reader:gcode mesh_reader:mesh linuxcnc_ini:ini; do
  name=${t%%:*}
  corpus=${t##*:}
  work="build/fuzz/corpus-$corpus"
  mkdir -p "$work"
  echo "== fuzz_$name for ${seconds}s"
  (cd build/fuzz && ./fuzz_"$name" -max_total_time="$seconds" -max_len=4096 -timeout=10 \
     -rss_limit_mb=2048 -print_final_stats=1 "../../$work" "../../tests/fuzz/corpus/$corpus" 2>&1 | tail -5)
done
