#!/usr/bin/env bash
# The parameter table of README.md ("## Medium parameters") is the one documentation of the names
# the library accepts (mf_params_* / ParamSet / scene files). This check fails when the table and
# the names the library reads differ in either direction:
#   - a name the library reads is missing from the table, or
#   - the table lists a name the library does not read.
#
# The library's names are the ones its parameter reader (`struct Reader` in params.rs) is asked
# for: string literals passed to `r.float/rgb/unit_rgb/string/has(...)`, and the string literals of
# the name arrays those calls index (`const NAMES` / `let *_names = [...]`). A reader call with any
# other argument fails the check, so a refactor cannot hide names from it.
#
# Usage: scripts/check_params_doc.sh [README [PARAMS_RS...]]   (defaults: README.md, the params.rs
# of the tree that defines `struct Reader` and every params.rs that builds one with `Reader::new`,
# e.g. the gpis crate's). Exit 0: the table and the library agree.
set -euo pipefail
cd "$(dirname "$0")/.."

readme=${1:-README.md}
params_files=("${@:2}")
if ((${#params_files[@]} == 0)); then
    # Found by content, not by path, so the check survives moving the crate (src/ -> crates/*/src/).
    definition=$(grep -rlE --include=params.rs '^(pub(\([a-z]+\))? )?struct Reader\b' src crates 2>/dev/null | head -n 1 || true)
    if [[ -n "$definition" ]]; then
        mapfile -t params_files < <({ echo "$definition"; grep -rlE --include=params.rs 'Reader::new\(' src crates 2>/dev/null; } | sort -u)
    fi
fi
if ((${#params_files[@]} == 0)); then
    echo "check_params_doc: no params.rs defining 'struct Reader' found (give its path as the second argument)" >&2
    exit 1
fi
for f in "${params_files[@]}"; do
    [[ -f "$f" ]] || { echo "check_params_doc: $f not found" >&2; exit 1; }
done
params="${params_files[*]}"
[[ -f "$readme" ]] || { echo "check_params_doc: $readme not found" >&2; exit 1; }

fail=0

# ---- names the library reads
reader_calls=$(grep -ohE '\br\.(float|rgb|unit_rgb|string|has)\([^)]*\)' "${params_files[@]}" || true)
literal_names=$(grep -oE '\(\"[A-Za-z0-9_]+\"' <<<"$reader_calls" | tr -d '("' || true)
# Calls whose argument is not a literal must index one of the name arrays (or be the closure
# variable iterating one of them); anything else is an unknown source of names.
while IFS= read -r call; do
    [[ -z "$call" ]] && continue
    arg=$(sed -E 's/^r\.[a-z_]+\(([^,]*).*\)$/\1/' <<<"$call")   # the first argument: the name
    case "$arg" in
        \"*\") ;;
        NAMES\[*\] | names\[*\] | n | name) ;;
        *)
            echo "check_params_doc: $params reads a parameter name this check cannot see: '$call'" >&2
            echo "  (pass a string literal, or an element of a 'const NAMES' / 'let *_names' array of literals)" >&2
            fail=1
            ;;
    esac
done <<<"$reader_calls"
array_names=$(grep -hE '(const[[:space:]]+NAMES|let[[:space:]]+[a-z_]*names)\b[^=]*=[[:space:]]*\[' "${params_files[@]}" |
    grep -oE '"[A-Za-z0-9_]+"' | tr -d '"' || true)
library=$(printf '%s\n%s\n' "$literal_names" "$array_names" | sed '/^$/d' | sort -u)
if [[ $(wc -l <<<"$library") -lt 10 ]]; then
    echo "check_params_doc: found only $(wc -l <<<"$library") names in $params; the extraction is broken" >&2
    exit 1
fi

# ---- names the README table lists: first column of the rows of "## Medium parameters", every
# `name` in backticks; a name written `_y` after `lengthscale_x` means `lengthscale_y`.
documented=$(awk '
    /^## / { in_section = ($0 == "## Medium parameters"); next }
    /^#/ { if (in_section) in_section = 0; next }
    in_section && /^\| *`/ {
        split($0, cells, "|")
        cell = cells[2]
        stem = ""
        while (match(cell, /`[^`]+`/)) {
            name = substr(cell, RSTART + 1, RLENGTH - 2)
            cell = substr(cell, RSTART + RLENGTH)
            if (substr(name, 1, 1) == "_") {
                name = stem name
            } else {
                stem = name
                sub(/_[^_]*$/, "", stem)
            }
            print name
        }
    }' "$readme" | sort -u)
if [[ -z "$documented" ]]; then
    echo "check_params_doc: no table rows found under '## Medium parameters' in $readme" >&2
    exit 1
fi

missing=$(comm -23 <(echo "$library") <(echo "$documented"))
extra=$(comm -13 <(echo "$library") <(echo "$documented"))
if [[ -n "$missing" ]]; then
    echo "check_params_doc: $params accepts names that the table of $readme (\"Medium parameters\") does not list:" >&2
    sed 's/^/  /' <<<"$missing" >&2
    fail=1
fi
if [[ -n "$extra" ]]; then
    echo "check_params_doc: the table of $readme (\"Medium parameters\") lists names that $params does not accept:" >&2
    sed 's/^/  /' <<<"$extra" >&2
    fail=1
fi
if [[ $fail -ne 0 ]]; then
    exit 1
fi
echo "check_params_doc: the $(wc -l <<<"$library") parameter names of $params and the table of $readme agree"
