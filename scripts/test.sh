#!/usr/bin/env bash
# The one command that sets up a fresh Debian machine and runs every test:
# the Rust tests (cargo), the header freshness check, and the CMake/ctest suite (C and C++ ABI
# tests, sanitizers, the install/consumer test, the mfrender host tests).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

scripts/setup.sh

echo "== cargo test (release; statistical tests are seeded and bounded)" >&2
cargo test --release --locked

echo "== header freshness" >&2
scripts/check_header.sh

echo "== cmake + ctest" >&2
build_dir=build/test
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)"
