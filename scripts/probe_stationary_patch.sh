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
#      SCENE (default bench/gpis_stationary_patch.xml), OUT (default out/probe12).
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
for method in macrofacet gpis; do
    for seed in 1 4; do
        TIMEFORMAT="$method seed $seed: %3U s user %3S s sys %3R s wall"
        time nice -n "${NICE:-19}" "$mfrender" "$scene" -D method="$method" -D spp="$half" \
            "${defines[@]}" --seed "$seed" --threads "$threads" \
            -o "$outdir/${method}_$seed.exr" --quiet
    done
done
halves=("$outdir/macrofacet_1.exr" "$outdir/macrofacet_4.exr" "$outdir/gpis_1.exr" "$outdir/gpis_4.exr")
echo "== $scene sigma $sigma lengthscale $lengthscale, $ref_spp spp per method (a = macrofacet, b = gpis)"
"$mfcompare" patches 1 1 "${halves[@]}" | tee "$outdir/image.tsv"
"$mfcompare" patches 4 4 "${halves[@]}" | tee "$outdir/patches.tsv"
