#!/usr/bin/env bash
# cambium bend with solver = fem: a small load matches the closed form w L^4 / 8 EI; growth with
# fem runs every step as one increment and sags more than the one-shot statics of the final rod
# (the memory of the load path); fem keys without solver = fem, and fem with motion, are errors.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
printf 'length = 1\nsegments = 10\nradius = 0.01\nE = 1e11\ndensity = 600\nsolver = fem\nfem_increments = 1\n' >"$tmp/a.spec"
"$bin" bend "$tmp/a.spec" -o "$tmp/a.csv" --json >"$tmp/a.json"
test "$(wc -l <"$tmp/a.csv")" -eq 12 || fail "node table"
grep -q '"solver": "fem"' "$tmp/a.json" || fail "solver name in json"
y=$(grep -o '"tip_y": [^,]*' "$tmp/a.json" | cut -d' ' -f2)
# w L^4 / 8 EI = 600 g pi r^2 / (8 E pi r^4 / 4) = 2.943e-4 m
awk -v y="$y" 'BEGIN { d = -y; if (d < 2.9429e-4 || d > 2.9431e-4) { print "tip", d; exit 1 } }'
base='length = 1
segments = 40
radius = 0.004
E = 2e9
density = 700
angle = 20
steps = 10
length_initial = 0.2
radius_final = 0.01'
printf '%s\nsolver = fem\n' "$base" >"$tmp/g.spec"
"$bin" bend "$tmp/g.spec" --json >"$tmp/g.json"
grep -q '"steps": 10' "$tmp/g.json" || fail "fem growth steps"
yg=$(grep -o '"tip_y": [^,]*' "$tmp/g.json" | cut -d' ' -f2)
printf 'length = 1\nsegments = 40\nradius = 0.01\nE = 2e9\ndensity = 700\nangle = 20\n' >"$tmp/s.spec"
ys=$("$bin" bend "$tmp/s.spec" --json | grep -o '"tip_y": [^,]*' | cut -d' ' -f2)
awk -v a="$yg" -v b="$ys" 'BEGIN { if (!(a < b)) { print "grown tip", a, "not below one-shot", b; exit 1 } }'
# errors name the file
printf 'length = 1\nfem_sigma = 0.5\n' >"$tmp/e.spec"
"$bin" bend "$tmp/e.spec" 2>"$tmp/err" && fail "fem key without solver = fem accepted"
grep -q "e.spec: error: the fem_\* keys need solver = fem" "$tmp/err" || { cat "$tmp/err"; fail "message"; }
printf 'solver = fem\nfem_axial = sideways\n' >"$tmp/f.spec"
"$bin" bend "$tmp/f.spec" 2>"$tmp/err" && fail "bad fem_axial accepted"
grep -q "f.spec:2:13: error: unknown fem_axial 'sideways'" "$tmp/err" || { cat "$tmp/err"; fail "axial message"; }
printf 'solver = fem\nduration = 1\n' >"$tmp/m.spec"
"$bin" bend "$tmp/m.spec" 2>"$tmp/err" && fail "fem with motion accepted"
grep -q "solver = fem cannot be combined with duration" "$tmp/err" || fail "motion message"
echo ok
