#!/usr/bin/env bash
# cambium run on the shipped Jirasek models (mechanics inside the L+C dialect): each runs to its
# derivation length and writes a picture and its string; a model error exits 1 with the message.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for m in jirasek-s-branch jirasek-hanging jirasek-cherries jirasek-ground jirasek-cycad; do
    "$bin" run "$CBM_SOURCE/models/$m.l" -o "$tmp/$m.str" -o "$tmp/$m.svg"
    test -s "$tmp/$m.svg"
    grep -q '^I({' "$tmp/$m.str"
done
# the S-branch: 30 internodes, the first with a positive carried mass
test "$(grep -c '^I({' "$tmp/jirasek-s-branch.str")" -eq 30
# a bad segment stops the run with exit 1 and names the operation and the segment
set +e
"$bin" run "$CBM_SOURCE/models/jirasek-s-branch.l" -D SEG=0 -o "$tmp/bad.str" 2>"$tmp/err"
rc=$?
set -e
test "$rc" -eq 1
grep -q 'AddRings(): mechanical segment 1: length must be > 0' "$tmp/err"
test ! -e "$tmp/bad.str"
