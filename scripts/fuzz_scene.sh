#!/usr/bin/env bash
# Coverage-guided fuzzing of mfrender's scene reader with libFuzzer (clang, ASan + UBSan):
#   scripts/fuzz_scene.sh [SECONDS]     (default 60; scripts/test.sh runs a 20 s smoke)
# Builds cpp_host/fuzz/fuzz_scene in build/fuzz with clang++-14 (Debian: clang-14,
# libclang-rt-14-dev; scripts/setup.sh installs them when missing), starts from the committed
# seed corpus cpp_host/fuzz/corpus (read only) plus a working corpus in build/fuzz/corpus, and
# writes any crashing input to build/fuzz/artifacts/. Exit status non-zero on a finding. Prints the
# number of executions.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-60}
[[ $seconds =~ ^[0-9]+$ ]] || { echo "usage: $0 [SECONDS]" >&2; exit 2; }
export PATH="$HOME/.cargo/bin:$PATH"
# The project's packages and clang-14 with libclang-rt-14-dev, where missing (one install path).
MF_SETUP_FUZZ=1 "$root/scripts/setup.sh"
build=$root/build/fuzz
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
    -DCMAKE_CXX_COMPILER=clang++-14 -DMFHOST_FUZZ=ON -DMF_PGO=OFF >/dev/null  # (the reader needs no profile-guided library)
cmake --build "$build" -j "$(nproc)" --target fuzz_scene >/dev/null
mkdir -p "$build/corpus" "$build/artifacts"
log=$build/fuzz_scene.log
set +e
# -rss_limit_mb / -timeout: the reader must stay bounded on any input
nice -n 19 "$build/cpp_host/fuzz_scene" "$build/corpus" "$root/cpp_host/fuzz/corpus" \
    -dict="$root/cpp_host/fuzz/scene.dict" -max_total_time="$seconds" -max_len=16384 -timeout=10 \
    -rss_limit_mb=2048 -artifact_prefix="$build/artifacts/" -print_final_stats=1 >"$log" 2>&1
status=$?
set -e
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
echo "fuzz_scene: ${execs:-?} executions in ${seconds} s, exit status $status (log: $log)"
if [ $status -ne 0 ]; then
    grep -E "ERROR|SUMMARY|Test unit written" "$log" | head -20
    exit 1
fi
