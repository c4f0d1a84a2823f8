#!/usr/bin/env bash
# Regenerates include/macrofacet.h from crates/macrofacet-ffi/ with the pinned cbindgen (see cbindgen.toml).
# Never edit the header by hand. Usage: scripts/generate_header.sh [output-file]
# (the default output is include/macrofacet.h; scripts/check_header.sh passes a temp file).
set -euo pipefail

CBINDGEN_VERSION=0.29.4
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/include/macrofacet.h}"
# A cbindgen earlier in PATH wins (and has its version checked); cargo's bin dir is the fallback.
export PATH="$PATH:${CARGO_HOME:-$HOME/.cargo}/bin"

if ! command -v cbindgen >/dev/null 2>&1; then
    echo "generate_header: cbindgen not found; install the pinned version with" >&2
    echo "    cargo install --locked cbindgen --version $CBINDGEN_VERSION   (or run scripts/setup.sh)" >&2
    exit 1
fi
found="$(cbindgen --version 2>/dev/null || true)"
if [ "$found" != "cbindgen $CBINDGEN_VERSION" ]; then
    echo "generate_header: need cbindgen $CBINDGEN_VERSION, found '${found:-nothing}' at $(command -v cbindgen)" >&2
    echo "    cargo install --locked --force cbindgen --version $CBINDGEN_VERSION   (or run scripts/setup.sh)" >&2
    exit 1
fi

# cbindgen parses the ffi crate's sources (cargo metadata for the layout); it builds nothing.
# Its warnings about private constants are expected and hidden unless it fails.
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
if ! (cd "$root" && cbindgen --quiet --config cbindgen.toml --crate macrofacet-ffi --output "$out" crates/macrofacet-ffi) >"$log" 2>&1; then
    cat "$log" >&2
    echo "generate_header: cbindgen failed" >&2
    exit 1
fi
