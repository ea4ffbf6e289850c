#!/usr/bin/env bash
# The main job of the README: installs what is missing, builds, and runs taxopt on the
# bundled demo case in data/ (the paper's sine-surface part), writing taxopt-demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
# Only what the demo needs: its packages, and the library and CLI (no tests, no benchmarks).
bash scripts/setup.sh --demo
cmake --preset demo
cmake --build --preset demo -j "$(nproc)"
./build/demo/taxopt demo --out taxopt-demo
