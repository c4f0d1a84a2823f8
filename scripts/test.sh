#!/usr/bin/env bash
# The one command that sets up a fresh Debian machine and runs every test:
# the Rust tests (cargo), the header freshness check, the parameter-table check, and the
# CMake/ctest suite (C and C++ ABI tests, sanitizers, the install/consumer test, the mfrender host
# tests, the Mitsuba 3 plugin's tests and the comparisons with Mitsuba 3), and the fuzz smokes (the
# scene reader under libFuzzer, the library's cargo-fuzz targets).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

# Every test includes the Mitsuba 3 plugin's and the scene reader's fuzz smoke: setup installs the
# pinned Mitsuba 3.9.1 and nanobind from PyPI, and clang-14 with libclang-rt-14-dev from Debian,
# when they are missing, and the plugin is built (MF_SETUP_MITSUBA=0 skips the plugin, whose tests
# then report themselves skipped with the reason; MF_SETUP_FUZZ=0 skips the fuzz smoke).
export MF_SETUP_MITSUBA=${MF_SETUP_MITSUBA:-1} MF_SETUP_FUZZ=${MF_SETUP_FUZZ:-1}
scripts/setup.sh
plugin=()
if [ "$MF_SETUP_MITSUBA" = 1 ]; then plugin=(-DMF_BUILD_MITSUBA_PLUGIN=ON); fi

echo "== cargo test (release; every workspace crate; statistical tests are seeded and bounded)" >&2
cargo test --release --locked

echo "== header freshness" >&2
scripts/check_header.sh

echo "== parameter table (README \"Medium parameters\" == the names the library reads)" >&2
scripts/check_params_doc.sh

echo "== cmake + ctest" >&2
build_dir=build/test
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "${plugin[@]}" >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)"

# A bounded smoke of the scene-reader fuzzer (libFuzzer, ASan + UBSan; the long run is
# scripts/fuzz_scene.sh SECONDS).
if [ "$MF_SETUP_FUZZ" = 1 ]; then
    echo "== fuzz smoke (scene reader, 20 s)" >&2
    scripts/fuzz_scene.sh 20
else
    echo "== fuzz smoke of the scene reader skipped (MF_SETUP_FUZZ=0)" >&2
fi

# ---- fuzz smoke (issue 9): each cargo-fuzz target replays its committed seeds and runs a fixed
# number of inputs, wherever the nightly toolchain is present (every machine of ours has it;
# scripts/fuzz.sh installs the pinned cargo-fuzz from crates.io when it is missing; the long runs:
# scripts/fuzz.sh SECONDS).
echo "== fuzz smoke (scripts/fuzz.sh --smoke)" >&2
if ! rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    echo "fuzz smoke skipped: no nightly Rust toolchain (rustup toolchain install nightly)" >&2
else
    scripts/fuzz.sh --smoke
fi
# ---- end of fuzz smoke
