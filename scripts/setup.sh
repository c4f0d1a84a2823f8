#!/usr/bin/env bash
# Installs what building and testing macrofacet needs on Debian 12, only what is missing:
# the Debian packages of the C/C++ side and the pinned cbindgen. Safe to run repeatedly.
set -euo pipefail

APT_PACKAGES=(cmake g++ make pkg-config libembree-dev libopenexr-dev libpng-dev libpugixml-dev)
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
