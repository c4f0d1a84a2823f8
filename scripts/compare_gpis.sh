#!/usr/bin/env bash
# The statistical macrofacet medium vs the realization-based GPIS ground truth (Renewal+) on ONE
# scene, switched by -D method=macrofacet|gpis (comparison 5 of the validation report):
#   bench/gpis_compare.xml  stationary: a gold sphere, isotropic gpss sigma 0.02, alpha 0.4 (default)
#   bench/gpis_varying.xml  issue 12, a Fig. 19/20-like panel: sigma grows along x, the correlation
#                           length along y (grids), 4 x 4 patches of one (sigma, l) each
# It renders
#   (a) a converged reference of each method (REF_SPP) as two independent halves (REF_SPP/2 spp,
#       seeds 1 and 4) whose mean is the reference and whose difference measures its own noise,
#   (b) equal-spp renders (SPP, seed 2) of both,
#   (c) an equal-time macrofacet render (its spp scaled to the gpis render's time, seed 3),
# and computes, over the whole image and per patch of a 4 x 4 partition (mfcompare patches):
#   the MSE of every render against the GPIS reference (the ground truth) and against its own
#   method's reference; each reference's own noise (the MSE against its expectation, from its
#   halves); the model difference between the references with the noise removed (bias2, an
#   unbiased estimate of the squared difference of the expectations, with its standard error) and
#   their mean difference (rel_diff, z-score); the equal-spp time ratio and the equal-MSE time
#   ratio (gpis time x gpis variance / macrofacet time x macrofacet variance, the variances being
#   the MSE against the own reference minus that reference's noise, so the model difference does
#   not enter; times are whole-image times).
# Times are CPU seconds (user + system) of each mfrender process, all threads: the machines this
# runs on are shared, and CPU time measures the render rather than the other jobs' load.
# Writes, per scene (STEM = the scene's file name without .xml):
#   validation/renders/STEM/*.exr|png      the renders
#   validation/renders/STEM.json           every number above (scene, methods, references, patches)
#   validation/renders/STEM.tsv            its rows of renders.tsv
#   validation/renders/STEM.patches.tsv    its rows of render_patches.tsv
# and rebuilds from every scene's files there (so running one scene keeps the others' results):
#   validation/renders.json       {"scenes": [per-scene objects]}
#   validation/renders.tsv        scene medium spp time_s mse image notes gpis_ref_noise
#   validation/render_patches.tsv one row per patch (header in the file)
# which crates/macrofacet-validation/examples/validate (section 5, renders.rs) reads.
#
# Usage: scripts/compare_gpis.sh [SCENE] [REF_SPP [SPP]]
#   defaults bench/gpis_compare.xml, 512, 64 (an old-style first argument that is a number is
#   REF_SPP). Measured on 2 shared cores: gpis_compare (defaults) 1.2 CPU minutes, 37 s wall;
#   `scripts/compare_gpis.sh bench/gpis_varying.xml 256 32` (64x64, the command of the report)
#   4.8 CPU minutes, 6 min wall at load 3, ~2.5 min on idle cores (the gpis reference is 70 %).
# Env: BUILD_DIR (default build/compare), THREADS (default: nproc), RES (default: the scene's own
#   `res` default: 96 for gpis_compare, 64 for gpis_varying), MFRENDER/MFCOMPARE (prebuilt tools),
#   NICE (default 19: the renders run under nice -n $NICE).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

scene=bench/gpis_compare.xml
if [ $# -gt 0 ] && ! [[ $1 =~ ^[0-9]+$ ]]; then
    scene=$1
    shift
fi
ref_spp=${1:-512}
spp=${2:-64}
threads=${THREADS:-$(nproc)}
build_dir=${BUILD_DIR:-build/compare}
niceness=${NICE:-19}
[ -f "$scene" ] || { echo "compare_gpis.sh: no scene file \"$scene\"" >&2; exit 2; }
if ! [[ $ref_spp =~ ^[0-9]+$ && $spp =~ ^[0-9]+$ ]] || [ "$ref_spp" -lt 2 ] || [ $((ref_spp % 2)) -ne 0 ] || [ "$spp" -lt 1 ]; then
    echo "compare_gpis.sh: REF_SPP must be an even integer >= 2 (two halves) and SPP an integer >= 1, got \"$ref_spp\" \"$spp\"" >&2
    exit 2
fi
res_args=()
[ -n "${RES:-}" ] && res_args=(-D "res=$RES")
stem=$(basename "$scene" .xml)
outdir=validation/renders/$stem
grid=4  # patches per side

if [ -z "${MFRENDER:-}" ] || [ -z "${MFCOMPARE:-}" ]; then
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DMF_BUILD_TESTS=OFF >/dev/null
    cmake --build "$build_dir" -j2 --target mfrender mfcompare >/dev/null
    MFRENDER="$(find "$build_dir" -name mfrender -type f -perm -u+x | head -n 1)"
    MFCOMPARE="$(find "$build_dir" -name mfcompare -type f -perm -u+x | head -n 1)"
fi
mkdir -p "$outdir"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# render NAME METHOD SPP SEED -> prints the render's CPU seconds (user + system, all threads):
# on a machine shared with other jobs the wall time measures their load as much as the render,
# the CPU time what the render costs (= wall time x threads on dedicated cores, up to scaling).
render() {
    local name=$1 method=$2 n=$3 seed=$4 TIMEFORMAT='%3U %3S'
    if ! { time nice -n "$niceness" "$MFRENDER" "$scene" -D method="$method" -D spp="$n" "${res_args[@]}" \
            --seed "$seed" --threads "$threads" -o "$outdir/$name.exr" --quiet; } 2> "$tmp/render.err"; then
        head -n -1 "$tmp/render.err" >&2  # its last line is the time
        exit 1
    fi
    tail -n 1 "$tmp/render.err" | awk '{ printf "%.3f", $1 + $2 }'
}
add() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", a + b }'; }

half=$((ref_spp / 2))
echo "== $scene: references ${ref_spp} spp as two halves, ${threads} threads (times: CPU seconds)"
t1=$(render ref_macrofacet_a macrofacet "$half" 1); t2=$(render ref_macrofacet_b macrofacet "$half" 4)
t_ref_mf=$(add "$t1" "$t2"); echo "macrofacet reference: ${t_ref_mf} s"
t1=$(render ref_gpis_a gpis "$half" 1); t2=$(render ref_gpis_b gpis "$half" 4)
t_ref_gp=$(add "$t1" "$t2"); echo "gpis reference:       ${t_ref_gp} s"
for m in macrofacet gpis; do
    "$MFCOMPARE" average "$outdir/ref_$m.exr" "$outdir/ref_${m}_a.exr" "$outdir/ref_${m}_b.exr"
done

echo "== equal spp: ${spp} spp"
t_mf=$(render macrofacet macrofacet "$spp" 2); echo "macrofacet: ${t_mf} s"
t_gp=$(render gpis gpis "$spp" 2);             echo "gpis:       ${t_gp} s"

# equal time: the macrofacet spp whose time is the gpis render's (at least 1 spp), scaled from
# the equal-spp render's time per spp; once more from the first try's if that missed by > 10 %
# (fixed costs such as loading the scene do not scale with spp).
scale_spp() { awk -v s="$1" -v a="$2" -v b="$3" 'BEGIN { n = int(s * a / b + 0.5); if (n < 1) n = 1; print n }'; }
spp_et=$(scale_spp "$spp" "$t_gp" "$t_mf")
echo "== equal time: macrofacet at ${spp_et} spp (budget ${t_gp} s)"
t_et=$(render macrofacet_equal_time macrofacet "$spp_et" 3); echo "macrofacet: ${t_et} s"
if awk -v a="$t_et" -v b="$t_gp" 'BEGIN { exit !(a > 1.1 * b || a < 0.9 * b) }'; then
    spp_et=$(scale_spp "$spp_et" "$t_gp" "$t_et")
    t_et=$(render macrofacet_equal_time macrofacet "$spp_et" 3); echo "macrofacet at ${spp_et} spp: ${t_et} s"
fi

# ---------------------------------------------------------------------------------- statistics
R=$outdir/ref
# patches N FILE IMAGES... -> mfcompare's table without its header
patches() { local n=$1 out=$2; shift 2; "$MFCOMPARE" patches "$n" "$n" "$@" | tail -n +2 > "$out"; }
for n in 1 "$grid"; do
    # references against each other, with both halves: noise of each, model difference
    patches "$n" "$tmp/refs_$n" "${R}_macrofacet_a.exr" "${R}_macrofacet_b.exr" "${R}_gpis_a.exr" "${R}_gpis_b.exr"
    for name in macrofacet gpis macrofacet_equal_time; do
        own=${R}_macrofacet.exr
        [ "$name" = gpis ] && own=${R}_gpis.exr
        patches "$n" "$tmp/${name}_vs_gpis_$n" "$outdir/$name.exr" "${R}_gpis.exr"
        patches "$n" "$tmp/${name}_vs_own_$n" "$outdir/$name.exr" "$own"
    done
done
# One line per patch (whole image: n = 1): the columns below, in this order.
columns="row col row_label col_label mean_gpis_ref noise_gpis_ref noise_macrofacet_ref mse_refs bias2 bias2_se rel_diff z"
columns+=" mse_macrofacet_spp mse_gpis_spp mse_macrofacet_time mse_macrofacet_spp_own mse_gpis_spp_own speedup_equal_mse"
row_labels=$(sed -n 's/.*patch-rows: *//p' "$scene" | head -n 1)
col_labels=$(sed -n 's/.*patch-columns: *//p' "$scene" | head -n 1)
joined() {  # N -> the joined per-patch table
    local n=$1
    paste "$tmp/refs_$n" "$tmp/macrofacet_vs_gpis_$n" "$tmp/gpis_vs_gpis_$n" "$tmp/macrofacet_equal_time_vs_gpis_$n" \
        "$tmp/macrofacet_vs_own_$n" "$tmp/gpis_vs_own_$n" |
    awk -F'\t' -v OFS='\t' -v rl="$row_labels" -v cl="$col_labels" -v tg="$t_gp" -v tm="$t_mf" -v n="$n" '
        function label(spec, i,   f, k) {  # "name v0 v1 ..." -> "name=v_i"; "-" without a spec
            k = split(spec, f, " ")
            return (n > 1 && k > i + 1) ? f[1] "=" f[i + 2] : "-"
        }
        {
            # refs: row col mse mean_a mean_b noise_a noise_b bias2 bias2_se rel_diff z (a = macrofacet, b = gpis)
            # then five 5-column tables: row col mse mean_a mean_b
            var_mf = $29 - $6; var_gp = $34 - $7  # MSE vs own reference minus that reference noise
            speed = (var_mf > 0 && var_gp > 0) ? sprintf("%.3g", (tg * var_gp) / (tm * var_mf)) : "nan"
            print $1, $2, label(rl, $1), label(cl, $2), $5, $7, $6, $3, $8, $9, $10, $11, $14, $19, $24, $29 - 0, $34 - 0, speed
        }'
}
joined 1 > "$tmp/full"
joined "$grid" | awk -F'\t' -v OFS='\t' -v s="$scene" '{ print s, $0 }' > "$outdir.patches.tsv"
speedup=$(awk -v a="$t_gp" -v b="$t_mf" 'BEGIN { printf "%.3f", a / b }')
IFS=$'\t' read -r _ _ _ _ _ noise_gp noise_mf mse_refs bias2 bias2_se rel_diff z \
    mse_mf mse_gp mse_et mse_mf_own mse_gp_own speedup_mse < "$tmp/full"
mse_et_own=$(awk -F'\t' '{ print $3 }' "$tmp/macrofacet_equal_time_vs_own_1")

# Per-scene JSON: the whole-image numbers (the schema of the stationary comparison: methods with
# spp, seconds, mse_vs_own_reference, mse_vs_gpis_reference, png), the references with their
# noise and the model difference, and the patches.
json_patches=$(awk -F'\t' -v cols="$columns" '
    BEGIN { k = split(cols, name, " ") }
    {
        line = "      {"
        for (i = 1; i <= k; ++i) {
            v = $(i + 1)
            if (!(name[i] ~ /label/) && v ~ /^[-+0-9.eE]+$/) line = line sprintf("\"%s\": %s", name[i], v)
            else line = line sprintf("\"%s\": \"%s\"", name[i], v)
            if (i < k) line = line ", "
        }
        printf "%s%s}", (NR > 1 ? ",\n" : ""), line
    }' "$outdir.patches.tsv")
entry() {  # NAME SPP SECONDS MSE_OWN MSE_GPIS
    printf '{"spp": %d, "seconds": %s, "mse_vs_own_reference": %s, "mse_vs_gpis_reference": %s, "png": "%s/%s.png"}' \
        "$2" "$3" "$4" "$5" "$outdir" "$1"
}
{
    printf '{\n  "scene": "%s",\n  "reference_spp": %d,\n  "methods": {\n' "$scene" "$ref_spp"
    printf '    "macrofacet": %s,\n' "$(entry macrofacet "$spp" "$t_mf" "$mse_mf_own" "$mse_mf")"
    printf '    "gpis": %s,\n' "$(entry gpis "$spp" "$t_gp" "$mse_gp_own" "$mse_gp")"
    printf '    "macrofacet_equal_time": %s\n' "$(entry macrofacet_equal_time "$spp_et" "$t_et" "$mse_et_own" "$mse_et")"
    printf '  },\n  "speedup_equal_spp": %s,\n  "speedup_equal_mse": %s,\n' "$speedup" "$speedup_mse"
    printf '  "references": {"macrofacet": {"seconds": %s, "noise": %s, "png": "%s/ref_macrofacet.png"}, ' "$t_ref_mf" "$noise_mf" "$outdir"
    printf '"gpis": {"seconds": %s, "noise": %s, "png": "%s/ref_gpis.png"}, ' "$t_ref_gp" "$noise_gp" "$outdir"
    printf '"mse_macrofacet_vs_gpis": %s, "bias2": %s, "bias2_se": %s, "rel_diff": %s, "z": %s},\n' \
        "$mse_refs" "$bias2" "$bias2_se" "$rel_diff" "$z"
    printf '  "patches": [\n%s\n  ],\n' "$json_patches"
    printf '  "threads": %d\n}\n' "$threads"
} > "$outdir.json.tmp"
mv "$outdir.json.tmp" "$outdir.json"

# This scene's rows of renders.tsv (images relative to validation/): the MSE against the GPIS
# reference, whose own noise (gpis_ref_noise) is part of every such MSE.
rel=renders/$stem
{
    printf '%s\tmacrofacet\t%d\t%s\t%s\t%s/macrofacet.png\tequal spp; MSE vs own reference %s\t%s\n' \
        "$scene" "$spp" "$t_mf" "$mse_mf" "$rel" "$mse_mf_own" "$noise_gp"
    printf '%s\tgpis\t%d\t%s\t%s\t%s/gpis.png\tequal spp (Renewal+)\t%s\n' "$scene" "$spp" "$t_gp" "$mse_gp" "$rel" "$noise_gp"
    printf '%s\tmacrofacet\t%d\t%s\t%s\t%s/macrofacet_equal_time.png\tequal time; MSE vs own reference %s\t%s\n' \
        "$scene" "$spp_et" "$t_et" "$mse_et" "$rel" "$mse_et_own" "$noise_gp"
    printf '%s\tmacrofacet\t%d\t%s\t%s\t%s/ref_macrofacet.png\treference vs GPIS reference (their noise %s + %s; model difference bias2 %s +- %s)\t%s\n' \
        "$scene" "$ref_spp" "$t_ref_mf" "$mse_refs" "$rel" "$noise_mf" "$noise_gp" "$bias2" "$bias2_se" "$noise_gp"
} > "$outdir.tsv"

# Rebuild the combined files from every scene compared so far.
{
    printf '{\n  "scenes": [\n'
    first=1
    for f in validation/renders/*.json; do
        [ $first = 1 ] || printf ',\n'
        first=0
        sed 's/^/    /' "$f"
    done
    printf '\n  ]\n}\n'
} > validation/renders.json.tmp
mv validation/renders.json.tmp validation/renders.json
{
    printf '# written by scripts/compare_gpis.sh; mse = MSE against the GPIS (Renewal+) reference of the scene, gpis_ref_noise = that reference'"'"'s own noise (its MSE against its expectation, from two independent halves), time_s = CPU seconds (user + system, all threads) of the render\n'
    printf 'scene\tmedium\tspp\ttime_s\tmse\timage\tnotes\tgpis_ref_noise\n'
    for f in validation/renders/*.tsv; do
        case $f in *.patches.tsv) ;; *) cat "$f" ;; esac
    done
} > validation/renders.tsv.tmp
mv validation/renders.tsv.tmp validation/renders.tsv
{
    printf '# written by scripts/compare_gpis.sh: per patch (row 0 = top, col 0 = left) of a %dx%d partition; mean_gpis_ref the patch mean of the GPIS reference; noise_* each reference'"'"'s own noise; mse_refs the references'"'"' MSE; bias2 +- bias2_se that MSE with both noises removed (the model difference); rel_diff and z the references'"'"' mean difference; mse_*_spp / mse_macrofacet_time against the GPIS reference, *_own against the own reference; speedup_equal_mse = gpis time x variance / macrofacet time x variance at equal spp\n' "$grid" "$grid"
    printf 'scene\t%s\n' "${columns// /$'\t'}"
    cat validation/renders/*.patches.tsv
} > validation/render_patches.tsv.tmp
mv validation/render_patches.tsv.tmp validation/render_patches.tsv
echo "== wrote $outdir.json, validation/renders.{json,tsv} and validation/render_patches.tsv"
cat "$outdir.json"
