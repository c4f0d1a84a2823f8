#!/usr/bin/env bash
# Issue 12 probe: is a patch's macrofacet-vs-gpis gap in bench/gpis_varying.xml there without the
# spatial variation? Renders bench/gpis_stationary_patch.xml (the same plate, camera, light with a
# constant sigma and lengthscale) with both media as two seeded independent halves each (REF_SPP/2
# spp, seeds 1 and 4, as scripts/compare_gpis.sh renders its references), then prints
# `mfcompare patches` over the whole image (1 x 1) and the 4 x 4 partition of compare_gpis.sh
# (a = macrofacet, b = gpis: rel_diff = (mf - gpis) / gpis and its z from the halves).
#
# Usage: scripts/probe_stationary_patch.sh SIGMA LENGTHSCALE [REF_SPP]   (REF_SPP default 256)
#   SIGMA / LENGTHSCALE "-": not passed (a SCENE with its own fields, e.g. bench/gpis_varying.xml).
# Env: MFRENDER, MFCOMPARE (default build/p/...), THREADS (default nproc), NICE (default 19),
#      SCENE (default bench/gpis_stationary_patch.xml), OUT (default out/probe12),
#      SEEDS (default "1 4": an even count of seeds, REF_SPP/2 spp each; with 2k seeds the halves
#      are the averages of the odd-numbered and of the even-numbered seeds' renders, so each
#      method gets k * REF_SPP spp; renders already in OUT are reused).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { echo "usage: $0 SIGMA LENGTHSCALE [REF_SPP]" >&2; exit 2; }
sigma=$1 lengthscale=$2 ref_spp=${3:-256}
scene=${SCENE:-bench/gpis_stationary_patch.xml}
mfrender=${MFRENDER:-$(find build/p -name mfrender -type f -perm -u+x | head -n 1)}
mfcompare=${MFCOMPARE:-$(find build/p -name mfcompare -type f -perm -u+x | head -n 1)}
threads=${THREADS:-$(nproc)}
outdir=${OUT:-out/probe12}/$(basename "$scene" .xml)_s${sigma}_l${lengthscale}_${ref_spp}
mkdir -p "$outdir"
half=$((ref_spp / 2))
defines=()
[ "$sigma" = - ] || defines+=(-D sigma="$sigma")
[ "$lengthscale" = - ] || defines+=(-D lengthscale="$lengthscale")
read -r -a seeds <<< "${SEEDS:-1 4}"
[ $((${#seeds[@]} % 2)) = 0 ] || { echo "$0: SEEDS needs an even count" >&2; exit 2; }
for method in macrofacet gpis; do
    for seed in "${seeds[@]}"; do
        [ -f "$outdir/${method}_$seed.exr" ] && continue
        TIMEFORMAT="$method seed $seed: %3U s user %3S s sys %3R s wall"
        time nice -n "${NICE:-19}" "$mfrender" "$scene" -D method="$method" -D spp="$half" \
            "${defines[@]}" --seed "$seed" --threads "$threads" \
            -o "$outdir/${method}_$seed.exr" --quiet
    done
done
halves=()
for method in macrofacet gpis; do
    for parity in 0 1; do
        parts=()
        for ((i = parity; i < ${#seeds[@]}; i += 2)); do parts+=("$outdir/${method}_${seeds[i]}.exr"); done
        if [ ${#parts[@]} = 1 ]; then
            halves+=("${parts[0]}")
        else
            "$mfcompare" average "$outdir/${method}_half$parity.exr" "${parts[@]}"
            halves+=("$outdir/${method}_half$parity.exr")
        fi
    done
done
echo "== $scene sigma $sigma lengthscale $lengthscale, $((ref_spp * ${#seeds[@]} / 2)) spp per method, seeds ${seeds[*]} (a = macrofacet, b = gpis)"
"$mfcompare" patches 1 1 "${halves[@]}" | tee "$outdir/image_${#seeds[@]}seeds.tsv"
"$mfcompare" patches 4 4 "${halves[@]}" | tee "$outdir/patches_${#seeds[@]}seeds.tsv"
