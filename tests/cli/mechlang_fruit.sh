#!/usr/bin/env bash
# cambium run on Taylor-Hell's fruit tree in the L+C dialect: two years grow the same 127
# internodes as the native model (the same bud fates before the first fruit), the picture and the
# string are written; a bad parameter stops the run with exit 1 and the call named.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
m="$CBM_SOURCE/models/taylor-hell-fruit-tree.l"
"$bin" run "$m" -D YEARS=2 -o "$tmp/tree.str" -o "$tmp/tree.svg"
test -s "$tmp/tree.svg"
head -1 "$tmp/tree.str" | grep -q '^Year(1,4,0,0)$'
test "$(grep -c '^I({' "$tmp/tree.str")" -eq 127
test "$(grep -c '^Apex(' "$tmp/tree.str")" -eq 38
set +e
"$bin" run "$m" -D KAPPA=0 -D YEARS=1 -o "$tmp/bad.str" 2>"$tmp/err"
rc=$?
set -e
test "$rc" -eq 1
grep -q 'RingRate(kappa in (0, 1\]' "$tmp/err"
test ! -e "$tmp/bad.str"
