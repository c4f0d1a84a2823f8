#!/usr/bin/env bash
# Fails (exit 1, printing the diff) when include/macrofacet.h differs from what the pinned cbindgen
# generates from the current crates/macrofacet-ffi/. Fix: scripts/generate_header.sh, then commit the header.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
header="${MF_CHECK_HEADER:-$root/include/macrofacet.h}"   # override: for testing this script
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

"$root/scripts/generate_header.sh" "$tmp/macrofacet.h"
if ! diff -u --label "include/macrofacet.h (committed)" --label "include/macrofacet.h (generated)" \
        "$header" "$tmp/macrofacet.h"; then
    echo "check_header: include/macrofacet.h is stale; run scripts/generate_header.sh" >&2
    exit 1
fi
# Everything the header declares must live in the library's namespace (mf_ / MF_): cbindgen also
# sees the core's public items, which must be listed under [export] exclude in cbindgen.toml.
# (Declarations start in column 0; comment lines start with '/' or ' *'.)
foreign="$(grep -vE '^[[:space:]]*(\*|/)' "$tmp/macrofacet.h" \
    | grep -oE '^#define [A-Za-z_][A-Za-z0-9_]*|^(typedef )?(struct|enum) [A-Za-z_][A-Za-z0-9_]*|[A-Za-z_][A-Za-z0-9_]*\(' \
    | sed -E 's/^#define //; s/^(typedef )?(struct|enum) //; s/\($//' \
    | grep -vE '^(mf_|MF_|MACROFACET_H$)' | sort -u || true)"
if [ -n "$foreign" ]; then
    echo "check_header: names outside the mf_/MF_ namespace reach the header (exclude them in cbindgen.toml):" >&2
    echo "$foreign" >&2
    exit 1
fi
echo "check_header: include/macrofacet.h is up to date"
