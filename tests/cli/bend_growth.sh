#!/usr/bin/env bash
# cambium bend with growth: primary growth adds segments up to `length`, secondary growth adds
# rings up to `radius_final`; a growing branch with tropism ends higher than without.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
base='length = 1
segments = 50
radius = 0.004
E = 2e9
density = 700
angle = 20
steps = 10
length_initial = 0.2
radius_final = 0.01'
printf '%s\n' "$base" >"$tmp/g.spec"
printf '%s\ntropism = 0.05\n' "$base" >"$tmp/t.spec"
"$bin" bend "$tmp/g.spec" -o "$tmp/g.csv" --json >"$tmp/g.json"
test "$(wc -l <"$tmp/g.csv")" -eq 52
grep -q '"steps": 10' "$tmp/g.json"
yg=$(grep -o '"tip_y": [^,]*' "$tmp/g.json" | cut -d' ' -f2)
yt=$("$bin" bend "$tmp/t.spec" --json | grep -o '"tip_y": [^,]*' | cut -d' ' -f2)
awk -v a="$yg" -v b="$yt" 'BEGIN { if (!(b > a)) { print "tropism tip", b, "not above", a; exit 1 } }'
# the final length is `length`
awk -F, 'END { if ($1 < 0.999999 || $1 > 1.000001) { print "length", $1; exit 1 } }' "$tmp/g.csv"
echo ok
