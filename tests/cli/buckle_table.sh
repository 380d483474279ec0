#!/usr/bin/env bash
# cambium buckle: Taylor-Hell's Table 6.1 (apple and yellow poplar: r = 0.05 m, 0.1 m segments)
# buckles within one segment of the thesis' lengths; --json gives buckling_length_m and
# greenhill_length_m; the text form names both.
set -uo pipefail
bin=$1
fail() { echo "FAIL: $*"; exit 1; }
out=$("$bin" buckle --E 8.77e9 --density 745 --radius 0.05 --segment 0.1 --json) || fail "apple exit $?"
bl=$(printf '%s' "$out" | grep -o '"buckling_length_m": [^,}]*' | cut -d' ' -f2)
gl=$(printf '%s' "$out" | grep -o '"greenhill_length_m": [^,}]*' | cut -d' ' -f2)
awk -v b="$bl" 'BEGIN { exit !(b >= 18.0 - 1e-9 && b <= 18.2 + 1e-9) }' || fail "apple buckles at $bl (thesis 18.1)"
awk -v g="$gl" 'BEGIN { exit !(g > 18.04 && g < 18.06) }' || fail "apple Greenhill $gl (18.05)"
out=$("$bin" buckle --E 10.38e9 --density 427 --radius 0.05 --segment 0.1) || fail "poplar exit $?"
printf '%s\n' "$out" | grep -q '^buckling length  23.0000 m' || fail "poplar: $out"
printf '%s\n' "$out" | grep -q '^Greenhill length 22.98' || fail "poplar Greenhill: $out"
"$bin" buckle --help | grep -q 'usage: cambium buckle' || fail "help"
echo ok
