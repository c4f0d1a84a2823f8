#!/usr/bin/env bash
# Comparison 5 of the validation issue: the statistical macrofacet medium vs the realization-based
# GPIS ground truth (Renewal+) on ONE scene (bench/gpis_compare.xml), switched by -D method=...
#   (a) a converged reference of each method (REF_SPP, seed 1),
#   (b) equal-spp renders (SPP, seed 2) of both,
#   (c) an equal-time macrofacet render (its spp scaled to the gpis render's wall time, seed 3),
# and writes validation/renders.json (+ renders.tsv, the form crates/macrofacet-validation/examples/validate.rs reads) (schema read by crates/macrofacet-validation/examples/validate.rs) with wall times, spp,
# the MSE of each render against its own reference and against the GPIS reference (the ground
# truth: for the macrofacet renders that is the model difference plus noise), and PNG paths.
# Usage: scripts/compare_gpis.sh [REF_SPP [SPP]]   (defaults 512, 64; ~2 min on 2 idle cores,
# 1024 spp took 6 min on 2 shared cores)
# Env: BUILD_DIR (default build/compare), THREADS (default: nproc), RES (default 96).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

ref_spp=${1:-512}
spp=${2:-64}
res=${RES:-96}
threads=${THREADS:-$(nproc)}
build_dir=${BUILD_DIR:-build/compare}
scene=bench/gpis_compare.xml
outdir=validation/renders

if [ -z "${MFRENDER:-}" ] || [ -z "${MFCOMPARE:-}" ]; then
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DMF_BUILD_TESTS=OFF >/dev/null
    cmake --build "$build_dir" -j2 --target mfrender mfcompare >/dev/null
    MFRENDER="$(find "$build_dir" -name mfrender -type f -perm -u+x | head -n 1)"
    MFCOMPARE="$(find "$build_dir" -name mfcompare -type f -perm -u+x | head -n 1)"
fi
mkdir -p "$outdir"

# render NAME METHOD SPP SEED -> prints wall seconds
render() {
    local name=$1 method=$2 n=$3 seed=$4
    local start end
    start=$(date +%s%N)
    "$MFRENDER" "$scene" -D method="$method" -D spp="$n" -D res="$res" --seed "$seed" --threads "$threads" \
        -o "$outdir/$name.exr" --quiet
    end=$(date +%s%N)
    awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", (b - a) / 1e9 }'
}
mse() { "$MFCOMPARE" mse "$1" "$2"; }

echo "== references: ${ref_spp} spp, ${res}x${res}, ${threads} threads"
t_ref_mf=$(render ref_macrofacet macrofacet "$ref_spp" 1); echo "macrofacet reference: ${t_ref_mf} s"
t_ref_gp=$(render ref_gpis gpis "$ref_spp" 1);             echo "gpis reference:       ${t_ref_gp} s"

echo "== equal spp: ${spp} spp"
t_mf=$(render macrofacet macrofacet "$spp" 2); echo "macrofacet: ${t_mf} s"
t_gp=$(render gpis gpis "$spp" 2);             echo "gpis:       ${t_gp} s"

# equal time: the macrofacet spp that fits the gpis render's wall time (at least 1)
spp_et=$(awk -v s="$spp" -v a="$t_gp" -v b="$t_mf" 'BEGIN { n = int(s * a / b); if (n < 1) n = 1; print n }')
echo "== equal time: macrofacet at ${spp_et} spp (budget ${t_gp} s)"
t_et=$(render macrofacet_equal_time macrofacet "$spp_et" 3); echo "macrofacet: ${t_et} s"

R_mf=$outdir/ref_macrofacet.exr
R_gp=$outdir/ref_gpis.exr
entry() {  # NAME SPP SECONDS OWN_REF
    local name=$1 n=$2 sec=$3 own=$4
    printf '{"spp": %d, "seconds": %s, "mse_vs_own_reference": %s, "mse_vs_gpis_reference": %s, "png": "%s"}' \
        "$n" "$sec" "$(mse "$outdir/$name.exr" "$own")" "$(mse "$outdir/$name.exr" "$R_gp")" "$outdir/$name.png"
}
speedup=$(awk -v a="$t_gp" -v b="$t_mf" 'BEGIN { printf "%.3f", a / b }')
mse_refs=$(mse "$R_mf" "$R_gp")

json=validation/renders.json
{
    printf '{\n  "scene": "%s",\n  "reference_spp": %d,\n  "methods": {\n' "$scene" "$ref_spp"
    printf '    "macrofacet": %s,\n' "$(entry macrofacet "$spp" "$t_mf" "$R_mf")"
    printf '    "gpis": %s,\n' "$(entry gpis "$spp" "$t_gp" "$R_gp")"
    printf '    "macrofacet_equal_time": %s\n' "$(entry macrofacet_equal_time "$spp_et" "$t_et" "$R_mf")"
    printf '  },\n  "speedup_equal_spp": %s,\n' "$speedup"
    # extra fields (allowed by the schema): the references themselves
    printf '  "references": {"macrofacet": {"seconds": %s, "png": "%s/ref_macrofacet.png"}, "gpis": {"seconds": %s, "png": "%s/ref_gpis.png"}, "mse_macrofacet_vs_gpis": %s},\n' \
        "$t_ref_mf" "$outdir" "$t_ref_gp" "$outdir" "$mse_refs"
    printf '  "resolution": [%d, %d],\n  "threads": %d\n}\n' "$res" "$res" "$threads"
} > "$json.tmp"
mv "$json.tmp" "$json"

# The same numbers in the tab-separated form crates/macrofacet-validation/examples/validate.rs (section 5) reads from the
# validation directory: mse against the GPIS reference (the ground truth), image relative to it.
tsv=validation/renders.tsv
{
    printf '# written by scripts/compare_gpis.sh; mse = MSE against the GPIS (Renewal+) reference at %d spp\n' "$ref_spp"
    printf 'scene\tmedium\tspp\ttime_s\tmse\timage\tnotes\n'
    printf '%s\tmacrofacet\t%d\t%s\t%s\trenders/macrofacet.png\tequal spp; MSE vs own reference %s\n' \
        "$scene" "$spp" "$t_mf" "$(mse "$outdir/macrofacet.exr" "$R_gp")" "$(mse "$outdir/macrofacet.exr" "$R_mf")"
    printf '%s\tgpis\t%d\t%s\t%s\trenders/gpis.png\tequal spp (Renewal+)\n' \
        "$scene" "$spp" "$t_gp" "$(mse "$outdir/gpis.exr" "$R_gp")"
    printf '%s\tmacrofacet\t%d\t%s\t%s\trenders/macrofacet_equal_time.png\tequal time; MSE vs own reference %s\n' \
        "$scene" "$spp_et" "$t_et" "$(mse "$outdir/macrofacet_equal_time.exr" "$R_gp")" "$(mse "$outdir/macrofacet_equal_time.exr" "$R_mf")"
    printf '%s\tmacrofacet\t%d\t%s\t%s\trenders/ref_macrofacet.png\treference vs GPIS reference (includes the GPIS reference noise)\n' \
        "$scene" "$ref_spp" "$t_ref_mf" "$mse_refs"
} > "$tsv.tmp"
mv "$tsv.tmp" "$tsv"
echo "== wrote $json and $tsv"
cat "$json"
