#!/usr/bin/env bash
# cambium run on models/taylor-hell-buckling.l: the apple column of Taylor-Hell's Table 6.1 buckles
# at 181 segments (18.1 m) through the language, as `cambium buckle` finds; -D sets the wood.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" run "$CBM_SOURCE/models/taylor-hell-buckling.l" -D E_WOOD=8.77e9 -D DENSITY=745 \
    -o "$tmp/apple.str"
grep -q '^Apex(181,18.1,1.00883' "$tmp/apple.str"
test "$(grep -c '^S({' "$tmp/apple.str")" -eq 181
"$bin" buckle --E 8.77e9 --density 745 --radius 0.05 --segment 0.1 --json >"$tmp/native.json"
grep -q '"segments": 181' "$tmp/native.json"
