#!/usr/bin/env bash
# Shards as local processes: N concurrent `mfrender --shard I/N` runs, merged, must equal the
# single run (to float rounding); merge must refuse a missing shard, a duplicate and a part of
# another render. usage: shard_local.sh MFRENDER MFCOMPARE SCENE WORKDIR
set -euo pipefail
mfrender=$1 mfcompare=$2 scene=$3 work=$4
mkdir -p "$work"
rm -f "$work"/shard_* "$work"/single.*
args=(-D spp=12 -D res=40 --quiet --threads 1)
"$mfrender" "$scene" "${args[@]}" -o "$work/single.exr"
n=4
pids=()
for ((i = 0; i < n; i++)); do
    "$mfrender" "$scene" "${args[@]}" --shard "$i/$n" -o "$work/shard_$i.mfpart" &
    pids+=($!)
done
for p in "${pids[@]}"; do wait "$p"; done
"$mfrender" merge -o "$work/shard_merged.exr" "$work"/shard_3.mfpart "$work"/shard_1.mfpart "$work"/shard_0.mfpart "$work"/shard_2.mfpart
diff=$("$mfcompare" maxreldiff "$work/single.exr" "$work/shard_merged.exr")
echo "max relative difference single vs merged: $diff"
awk -v d="$diff" 'BEGIN { exit !(d <= 1e-6) }' || { echo "FAIL: merged image differs from the single run"; exit 1; }
# refusals: missing shard, duplicate shard, a shard of another seed
expect_fail() {
    local what=$1 pattern=$2; shift 2
    if out=$("$@" 2>&1); then echo "FAIL: merge accepted $what"; exit 1; fi
    grep -q "$pattern" <<<"$out" || { echo "FAIL: $what: unexpected message: $out"; exit 1; }
    echo "refused $what: $out"
}
expect_fail "a missing shard" "are missing" "$mfrender" merge -o "$work/shard_bad.exr" "$work"/shard_0.mfpart "$work"/shard_1.mfpart "$work"/shard_2.mfpart
expect_fail "a duplicate shard" "are both shard" "$mfrender" merge -o "$work/shard_bad.exr" "$work"/shard_0.mfpart "$work"/shard_0.mfpart "$work"/shard_1.mfpart "$work"/shard_2.mfpart
"$mfrender" "$scene" "${args[@]}" --seed 7 --shard 3/4 -o "$work/shard_other.mfpart"
expect_fail "a shard of another seed" "settings differ" "$mfrender" merge -o "$work/shard_bad.exr" "$work"/shard_0.mfpart "$work"/shard_1.mfpart "$work"/shard_2.mfpart "$work"/shard_other.mfpart
head -c 100 "$work/shard_0.mfpart" > "$work/shard_trunc.mfpart"
expect_fail "a truncated part" "not a valid mfrender partial" "$mfrender" merge -o "$work/shard_bad.exr" "$work"/shard_trunc.mfpart
[ ! -e "$work/shard_bad.exr" ] || { echo "FAIL: a refused merge left an output"; exit 1; }
echo "1 passed, 0 failed"
