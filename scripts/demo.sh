#!/usr/bin/env bash
# The main job of the README: installs what is missing, builds, and runs taxopt on the
# bundled demo case in data/ (the paper's sine-surface part), writing taxopt-demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake --preset release
cmake --build --preset release -j "$(nproc)"
./build/release/taxopt demo --out taxopt-demo
