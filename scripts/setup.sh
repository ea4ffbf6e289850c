#!/usr/bin/env bash
# Installs every Debian package taxopt needs to build, test and verify its G-code.
# Idempotent: packages already present are left alone; safe to run any number of times.
set -euo pipefail

# `setup.sh --demo` installs what building taxopt and running its demo need (scripts/demo.sh);
# without it, everything the tests need too (scripts/test.sh).
PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev          # maths (templated on Scalar)
  libfcl-dev libccd-dev  # tool-vs-part collision
  libcgal-dev            # mesh I/O, AABB tree, jet fitting
  libcli11-dev           # command line
  libtbb-dev             # parallel over contact points
  libtomlplusplus-dev    # machine file (TOML, with source positions for errors)
  nlohmann-json3-dev     # JSON report
  libjs-three libjs-dygraphs  # the HTML page (--html): 3D view and plots, embedded at write time
)
if [ "${1:-}" != "--demo" ]; then
  PACKAGES+=(
    catch2                 # tests (v2)
    linuxcnc-uspace        # rs274 and the motion controller the integration tests run
    python3-numpy          # the controller test: the commanded path against the points
    clang clang-format libclang-rt-14-dev  # fuzzing, sanitizers, formatting
    librsvg2-bin           # render SVG plots to PNG for inspection
    chromium fonts-liberation   # the page's tests: headless Chromium loads it, offline
  )
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "setup: installing ${missing[*]}" >&2
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
else
  echo "setup: all packages present" >&2
fi
