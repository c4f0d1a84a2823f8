#!/usr/bin/env bash
# Render a scene as a Slurm job array of N shards plus a merge job that runs when all shards
# succeeded. Prints the two job ids. The output directory must be on storage every node sees.
#   scripts/slurm_render.sh SCENE.xml N OUTDIR [mfrender args, e.g. --spp 4096 -D res=2160]
# Environment: MFRENDER (default: build/render/cpp_host/mfrender), SBATCH_ARGS (extra sbatch
# options for both jobs, e.g. "--partition=render --time=02:00:00").
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
[ $# -ge 3 ] || { echo "usage: $0 SCENE.xml N OUTDIR [mfrender args...]" >&2; exit 2; }
scene=$(realpath "$1") n=$2 outdir=$3
shift 3
[[ $n =~ ^[1-9][0-9]*$ ]] || { echo "slurm_render: N must be a positive integer" >&2; exit 2; }
mfrender=$(realpath "${MFRENDER:-$here/../build/render/cpp_host/mfrender}")
[ -x "$mfrender" ] || { echo "slurm_render: $mfrender is not executable (set MFRENDER)" >&2; exit 2; }
mkdir -p "$outdir"
outdir=$(realpath "$outdir")
# fail early on scene errors instead of in N array tasks
"$mfrender" "$scene" --check "$@" >/dev/null
read -r -a extra <<<"${SBATCH_ARGS:-}"
array=$(sbatch --parsable "${extra[@]}" --chdir="$outdir" --array="0-$((n - 1))" \
    "$here/slurm/mfrender_shard.sbatch" "$mfrender" "$scene" "$outdir" "$n" "$@")
merge=$(sbatch --parsable "${extra[@]}" --chdir="$outdir" --dependency="afterok:${array%%;*}" \
    "$here/slurm/mfrender_merge.sbatch" "$mfrender" "$outdir" "$n" "$outdir/$(basename "${scene%.xml}").exr")
echo "array job ${array%%;*} ($n shards), merge job ${merge%%;*} -> $outdir/$(basename "${scene%.xml}").exr"
