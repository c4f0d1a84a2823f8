#!/usr/bin/env bash
# Coverage-guided fuzzing of the C ABI (libFuzzer through cargo-fuzz; README, "Fuzzing").
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]   every target (or those named) for SECONDS each
#                                           (default 60), one after another, under nice -n 19;
#                                           prints the executions per target
#   scripts/fuzz.sh --runs N [TARGET...]    the same for N inputs each instead
#   scripts/fuzz.sh --smoke                 a bounded smoke: each target replays its committed
#                                           seeds and runs a fixed number of inputs (fewer for
#                                           tracking and fields; used by
#                                           scripts/test.sh); exits 2 when the nightly
#                                           toolchain is missing
#
# The corpus grows in fuzz/corpus/TARGET (only the committed seeds, seed-*, are tracked); a crash
# is saved in fuzz/artifacts/TARGET and ends the script with status 1. Reproduce one with
#   cargo +nightly fuzz run TARGET fuzz/artifacts/TARGET/crash-...
# (set MF_FUZZ_DEBUG=1 to print the parameters and queries it decodes to).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

CARGO_FUZZ_VERSION=0.13.2
TARGETS=(params errors medium_queries phase gpis tracking fields ndf)
SMOKE_RUNS=20000
# The tracking targets' inputs walk whole rays through a medium around a surface (with ASan,
# ~300 inputs/s for tracking, ~80/s for fields, some of them seconds): their smoke runs fewer.
declare -A SMOKE_RUNS_OF=([tracking]=3000 [fields]=1000)
# Build options per target (default: AddressSanitizer and compare tracing). The gpis marches are
# long numeric loops (Cholesky updates) where compare tracing and ASan make an input 5x slower
# (500 instead of 2500 inputs/s) without reaching more of the ABI's branches; that target is
# built without them, in its own target directory.
declare -A BUILD_OPTIONS=([gpis]="--no-trace-compares --sanitizer none --target-dir fuzz/target/fast")

smoke=0
seconds=60
runs=""
if [ "${1:-}" = "--smoke" ]; then
    smoke=1
    shift
elif [ "${1:-}" = "--runs" ]; then
    runs="$2"
    shift 2
elif [ -n "${1:-}" ]; then
    seconds="$1"
    shift
fi
if [ "$#" -gt 0 ]; then
    TARGETS=("$@")
fi

if ! rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    echo "fuzz: no nightly Rust toolchain (rustup toolchain install nightly); skipped" >&2
    exit 2
fi
if [ "$(cargo fuzz --version 2>/dev/null || true)" != "cargo-fuzz $CARGO_FUZZ_VERSION" ]; then
    echo "fuzz: installing cargo-fuzz $CARGO_FUZZ_VERSION from crates.io" >&2
    nice -n 19 cargo install --locked cargo-fuzz --version "$CARGO_FUZZ_VERSION"
fi

nice -n 19 cargo +nightly fuzz build >&2
nice -n 19 cargo +nightly fuzz build ${BUILD_OPTIONS[gpis]} gpis >&2

declare -A executions
for target in "${TARGETS[@]}"; do
    corpus="fuzz/corpus/$target"
    if [ "$smoke" = 1 ]; then
        # Only the committed seeds, in a scratch corpus: the smoke does not depend on (or grow)
        # a local corpus from earlier long runs.
        scratch="$(mktemp -d)"
        cp "$corpus"/seed-* "$scratch"/ 2>/dev/null || true
        args=("$scratch" -- "-runs=${SMOKE_RUNS_OF[$target]:-$SMOKE_RUNS}")
    else
        mkdir -p "$corpus"
        if [ -n "$runs" ]; then
            args=("$corpus" -- "-runs=$runs")
        else
            args=("$corpus" -- "-max_total_time=$seconds")
        fi
    fi
    log="$(mktemp)"
    echo "== fuzz $target" >&2
    # shellcheck disable=SC2086 # the options are words
    if ! nice -n 19 cargo +nightly fuzz run ${BUILD_OPTIONS[$target]:-} "$target" "${args[@]}" -print_final_stats=1 >"$log" 2>&1; then
        grep -E "panicked|ERROR|SUMMARY|Test unit written" -A3 "$log" >&2 || tail -40 "$log" >&2
        echo "fuzz: target $target found a failure (full log: $log)" >&2
        exit 1
    fi
    executions[$target]="$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo '?')"
    rm -f "$log"
    [ "$smoke" = 1 ] && rm -rf "$scratch"
done

printf '%-16s %15s\n' target executions
for target in "${TARGETS[@]}"; do
    printf '%-16s %15s\n' "$target" "${executions[$target]}"
done
