#!/usr/bin/env bash
# Installs what building and testing macrofacet needs on Debian 12, only what is missing:
# the Debian packages of the C/C++ side, the pinned cbindgen, and the toolchain's llvm-tools
# (llvm-profdata, for the profile-guided release build: CMake's MF_PGO). Safe to run repeatedly.
# Optional extras, only when asked:
#   MF_SETUP_FUZZ=1     clang-14 + libclang-rt-14-dev (libFuzzer: scripts/fuzz_scene.sh; scripts/test.sh
#                       asks for them unless MF_SETUP_FUZZ=0)
#   MF_SETUP_MITSUBA=1  Mitsuba 3.9.1 and nanobind 2.14.0 (headers) from PyPI: the Mitsuba plugin
#                       (mitsuba_plugin/) and the Mitsuba comparison tests (scripts/test.sh asks
#                       for them unless MF_SETUP_MITSUBA=0)
#   MF_SETUP_SLURM=1    slurm-wlm + munge (scripts/slurm_local_test.sh)
set -euo pipefail

APT_PACKAGES=(cmake g++ make pkg-config libembree-dev libopenexr-dev libpng-dev libpugixml-dev libjpeg-dev zlib1g-dev libopenvdb-dev libboost-dev)
if [ "${MF_SETUP_FUZZ:-0}" = 1 ]; then APT_PACKAGES+=(clang-14 libclang-rt-14-dev); fi
if [ "${MF_SETUP_SLURM:-0}" = 1 ]; then APT_PACKAGES+=(slurm-wlm munge); fi
CBINDGEN_VERSION=0.29.4

if ! command -v cargo >/dev/null 2>&1; then
    echo "setup: cargo (a Rust toolchain, 1.80 or newer) is required and was not found" >&2
    exit 1
fi

missing=()
for package in "${APT_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$package")
    fi
done
if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}" >&2
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo=sudo; fi
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! cbindgen --version 2>/dev/null | grep -qx "cbindgen $CBINDGEN_VERSION"; then
    echo "setup: installing cbindgen $CBINDGEN_VERSION" >&2
    cargo install --locked --quiet cbindgen --version "$CBINDGEN_VERSION"
fi

# llvm-profdata of rustc's own LLVM (rustup's llvm-tools component, the active toolchain's
# version): without it CMake builds the library without profile guidance, and says so.
sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
if [ ! -x "$sysroot/lib/rustlib/$host/bin/llvm-profdata" ]; then
    if command -v rustup >/dev/null 2>&1; then
        echo "setup: installing the Rust toolchain's llvm-tools (rustup component)" >&2
        rustup component add llvm-tools >/dev/null 2>&1 || echo "setup: rustup could not add llvm-tools: the library builds without profile guidance" >&2
    else
        echo "setup: no rustup to add llvm-tools: the library builds without profile guidance" >&2
    fi
fi

if [ "${MF_SETUP_MITSUBA:-0}" = 1 ]; then
    # nanobind provides the nanobind and robin_map headers that Mitsuba's headers include (the
    # wheel lacks them); 2.14.0 matches Mitsuba 3.9.1's pinned copies
    for pin in mitsuba==3.9.1 nanobind==2.14.0; do
        name=${pin%%==*} version=${pin##*==}
        if ! python3 -c "import $name, sys; sys.exit($name.__version__ != '$version')" 2>/dev/null; then
            echo "setup: installing $pin (pip)" >&2
            python3 -m pip install --quiet --root-user-action=ignore "$pin"
        fi
    done
fi
