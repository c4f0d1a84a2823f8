#!/usr/bin/env bash
# The render command: sets up a fresh Debian 12 machine (scripts/setup.sh), builds mfrender with
# the top-level CMake project (Release), and renders the default scene to out/default.exr and
# out/default.png. Extra arguments go to mfrender (e.g. --spp 64, -D width=1280 -D height=720).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

scripts/setup.sh

build_dir=build/render
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build_dir" -j "$(nproc)" --target mfrender

# The torus mesh is generated (deterministically) by a committed awk script.
if [ ! -s scenes/torus.obj ]; then
    awk -v R=0.5 -v r=0.2 -v U=64 -v V=24 -f scenes/make_torus.awk > scenes/torus.obj
fi

mkdir -p out
# mfrender prints a progress bar (on a terminal) and its timing line
# "mfrender: WxH, N spp in T s (...) -> out/default.exr, out/default.png" on stderr.
start=$(date +%s.%N)
"$build_dir/cpp_host/mfrender" scenes/default.xml -o out/default.exr "$@"
end=$(date +%s.%N)
echo "render: out/default.exr out/default.png ($(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s wall, including scene setup)"
