#!/usr/bin/env bash
# Speed figures (never asserted by tests): the core's per-call costs and mfrender on the design
# notes' Mitsuba 3 anchor scenes (bench/anchor.xml), printed beside Mitsuba 3.9.1's times on the
# same 2-core machine kind. Usage: scripts/bench.sh [--quick | --instructions]
#   --quick         128x128, 16 spp
#   --instructions  only the tracking targets' pairs, as instruction counts of mfrender's rendering
#                   loop under callgrind (valgrind): steady where shared machines make seconds vary
#                   by +-15 %; small images, ~2 min (docs/performance.md)
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
# As scripts/test.sh: Mitsuba 3.9.1 and nanobind (pinned, PyPI) for the plugin's figures, unless
# MF_SETUP_MITSUBA=0.
export MF_SETUP_MITSUBA=${MF_SETUP_MITSUBA:-1}
scripts/setup.sh
plugin=()
if [ "$MF_SETUP_MITSUBA" = 1 ]; then plugin=(-DMF_BUILD_MITSUBA_PLUGIN=ON); fi
mode="${1:-}"
case "$mode" in ""|--quick|--instructions) ;; *) echo "usage: scripts/bench.sh [--quick | --instructions]" >&2; exit 2 ;; esac

build_dir=build/bench
build_mfrender() {
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DMF_BUILD_TESTS=OFF "${plugin[@]}" >/dev/null
    cmake --build "$build_dir" -j "$(nproc)" --target mfrender >/dev/null
    mfrender="$(find "$build_dir" -name mfrender -type f -perm -u+x | head -n 1)"
}
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

if [ "$mode" = "--instructions" ]; then
    command -v valgrind >/dev/null || { echo "scripts/bench.sh --instructions needs valgrind (sudo apt-get install valgrind)" >&2; exit 1; }
    build_mfrender
    instructions() {  # ARGS...: instructions of PathIntegrator::Li and everything it calls, 1 thread
        rm -f "$out/cg.out"
        # Li itself only: a function whose name contains Li's (a lambda of Li, or a template
        # instantiated with one) would toggle the collection off again on entry.
        if ! valgrind --tool=callgrind --callgrind-out-file="$out/cg.out" --toggle-collect='mf::PathIntegrator::Li(mf::Ray, mf::Medium const?, mf::Sampler&) const' \
            "$mfrender" "$@" --threads 1 --quiet -o "$out/cg.exr" >"$out/cg.log" 2>&1; then
            echo "scripts/bench.sh: mfrender $* failed under callgrind:" >&2
            grep -v "^==" "$out/cg.log" | tail -n 5 >&2
            return 1
        fi
        awk '/^summary:/ { print $2 }' "$out/cg.out"
    }
    instruction_ratio() {  # LABEL "ARGS A" "ARGS B"
        local a b
        a=$(instructions $2) || exit 1
        b=$(instructions $3) || exit 1
        printf '%-58s %6.2fx   (A %.1f M, B %.1f M instructions)\n' "$1" "$(awk -v x="$a" -v y="$b" 'BEGIN { print x / y }')" \
            "$(awk -v x="$a" 'BEGIN { print x / 1e6 }')" "$(awk -v y="$b" 'BEGIN { print y / 1e6 }')"
    }
    r="bench/anchor.xml -D res=64 -D spp=8"
    echo "== tracking targets as instruction ratios (callgrind, 1 thread; anchor 64x64/8 spp, gpis_compare 32x32/8 spp)"
    instruction_ratio "sphere thin shell / roughconductor (target <= 1.5)" "$r -D object=macrofacet" "$r -D object=roughconductor"
    instruction_ratio "torus thin shell / roughconductor (target <= 2)" "$r -D object=torus_macrofacet" "$r -D object=torus_roughconductor"
    instruction_ratio "torus thin shell, sigma varying +-20 % / stationary" "$r -D object=torus_varying" "$r -D object=torus_macrofacet"
    g="bench/gpis_compare.xml -D res=32 -D spp=8"
    instruction_ratio "gpis / macrofacet at equal spp (target >= 10)" "$g -D method=gpis" "$g -D method=macrofacet"
    exit 0
fi

echo "== core queries (cargo run --release -p macrofacet --example bench_core)"
cargo run --release --quiet -p macrofacet --example bench_core
echo "== varying parameters: gpis vs macrofacet (cargo run --release -p macrofacet --example bench_core fields)"
cargo run --release --quiet -p macrofacet --example bench_core fields

build_mfrender

res=512 spp=64
if [ "$mode" = "--quick" ]; then res=128 spp=16; fi
declare -A mitsuba=([homogeneous]="scalar_rgb 10.5 s, llvm_ad_rgb 7.0 s" [roughconductor]="scalar_rgb 5.5 s, llvm_ad_rgb 1.45 s" [macrofacet]="(no Mitsuba counterpart)")
echo "== mfrender on bench/anchor.xml, ${res}x${res} at ${spp} spp, $(nproc) threads"
for object in homogeneous roughconductor macrofacet; do
    start=$(date +%s%N)
    "$mfrender" bench/anchor.xml -D object="$object" -D res="$res" -D spp="$spp" -o "$out/$object.exr" --quiet
    end=$(date +%s%N)
    seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", (b - a) / 1e9 }')
    printf '%-15s %7s s    Mitsuba 3.9.1 at 512x512/64 spp: %s\n' "$object" "$seconds" "${mitsuba[$object]}"
done

# The tracking targets (the library owns the volume event): a thin macrofacet shell against the
# same object as a Mitsuba-style roughconductor surface, one thread, runs alternated (A B A B A B)
# so that drift of a shared machine cancels in the median CPU-time ratio.
cpu_seconds() {  # COMMAND... -> user + system CPU seconds of the command
    local TIMEFORMAT='%3U %3S'
    { time "$@" >/dev/null 2>&1; } 2>&1 | awk '{ print $1 + $2 }'
}
median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
paired_ratio() {  # LABEL "COMMAND A" "COMMAND B"
    local label=$1 a=$2 b=$3 ratios=() ta tb
    for _ in 1 2 3; do
        ta=$(cpu_seconds $a); tb=$(cpu_seconds $b)
        ratios+=("$(awk -v x="$ta" -v y="$tb" 'BEGIN { printf "%.3f", x / y }')")
    done
    printf '%-58s %6.2fx   (A %s s, B %s s, last pair)\n' "$label" "$(printf '%s\n' "${ratios[@]}" | median)" "$ta" "$tb"
}
r="bench/anchor.xml -D res=256 -D spp=16 --threads 1 --quiet -o $out/pair.exr"
echo "== tracking targets: CPU-time ratios, median of 3 alternated pairs, 1 thread"
paired_ratio "sphere thin shell / roughconductor (target <= 1.5)" "$mfrender $r -D object=macrofacet" "$mfrender $r -D object=roughconductor"
paired_ratio "torus thin shell / roughconductor (target <= 2)" "$mfrender $r -D object=torus_macrofacet" "$mfrender $r -D object=torus_roughconductor"
paired_ratio "torus thin shell, sigma varying +-20 % / stationary (target <= 1.5)" "$mfrender $r -D object=torus_varying" "$mfrender $r -D object=torus_macrofacet"
g="bench/gpis_compare.xml -D spp=32 -D res=96 --threads 1 --quiet -o $out/pair.exr"
paired_ratio "gpis / macrofacet at equal spp (equal MSE: compare_gpis.sh)" "$mfrender $g -D method=gpis" "$mfrender $g -D method=macrofacet"
start=$(date +%s%N)
"$mfrender" scenes/default.xml -o "$out/default.exr" --quiet
end=$(date +%s%N)
echo "default scene (480x270, 20 spp, $(nproc) threads): $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", (b - a) / 1e9 }') s wall (target <= 8 s)"

# Building a large mesh surface (mf_surface_new_mesh), on one thread and on every core: a torus
# of 65,536 triangles from scenes/make_torus.awk as a thin shell's mean surface (mfrender --check
# builds the scene, its surfaces and boundaries, and renders nothing).
awk -v R=1 -v r=0.4 -v U=256 -v V=128 -f scenes/make_torus.awk > "$out/large_torus.obj"
cat > "$out/large_torus.xml" <<XML
<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, -5, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film>
    </sensor>
    <shape type="obj">
        <string name="filename" value="large_torus.obj"/>
        <bsdf type="null"/>
        <medium type="macrofacet" name="interior">
            <float name="sigma" value="0.001"/>
            <string name="distribution" value="beckmann"/>
            <float name="alpha" value="0.3"/>
        </medium>
    </shape>
</scene>
XML
for threads in 1 "$(nproc)"; do
    start=$(date +%s%N)
    "$mfrender" "$out/large_torus.xml" --check --threads "$threads" >/dev/null
    end=$(date +%s%N)
    echo "mesh surface of 65,536 triangles, built on $threads thread(s): $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", (b - a) / 1e9 }') s wall (scene setup)"
done

# The Mitsuba 3 plugin: the thin gold shell as a macrofacet medium vs the same sphere as
# Mitsuba's roughconductor, both scalar_rgb, equal spp, one process (where the plugin is built:
# python3 finds mitsuba 3.9.1 and nanobind, which this script installs unless MF_SETUP_MITSUBA=0).
if grep -q "^MF_BUILD_MITSUBA_PLUGIN:BOOL=ON" "$build_dir/CMakeCache.txt"; then
    cmake --build "$build_dir" -j "$(nproc)" --target macrofacet_mitsuba >/dev/null
    echo "== Mitsuba 3.9.1 with the macrofacet plugin, bench/anchor.xml, ${res}x${res} at ${spp} spp, $(nproc) threads"
    PYTHONPATH="$build_dir/mitsuba" python3 scripts/bench_mitsuba.py "$res" "$spp"
else
    echo "== Mitsuba plugin benchmark skipped: the plugin is not built (MF_SETUP_MITSUBA=0)"
fi
