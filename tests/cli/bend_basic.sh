#!/usr/bin/env bash
# cambium bend: small-deflection cantilever against w L^4 / (8 EI) (1 + 1/N^2, the exact factor
# of the staggered discretisation), CSV and JSON outputs, both solvers.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/rod.spec" <<'SPEC'
# a stiff horizontal rod: deflection 1e-6 of its length
length = 2          # m
segments = 40
radius = 0.02
E = 1e15
density = 700
angle = 0
tolerance = 1e-12
SPEC
"$bin" bend "$tmp/rod.spec" -o "$tmp/nodes.csv" -o "$tmp/sum.json" --json >"$tmp/stdout.json"
head -1 "$tmp/nodes.csv" | grep -qx 's,x,y,z,angle_deg,curvature,moment,stress'
test "$(wc -l <"$tmp/nodes.csv")" -eq 42
cmp "$tmp/stdout.json" "$tmp/sum.json"
grep -q "\"stage\": \"newton\", \"unstable_modes\": 0, \"stable\": true" "$tmp/stdout.json"
for k in tip_x tip_y tip_z tip_angle_deg base_moment passes residual seconds stage unstable_modes stable lowest_eigenvalue; do
    grep -q "\"$k\": " "$tmp/stdout.json" || { echo "missing $k"; exit 1; }
done
tipy=$(grep -o '"tip_y": [^,]*' "$tmp/stdout.json" | cut -d' ' -f2)
awk -v y="$tipy" 'BEGIN {
    pi = 3.14159265358979323846; r = 0.02; L = 2; E = 1e15; N = 40
    w = 700 * pi * r * r * 9.81; I = pi * r^4 / 4
    d = w * L^4 / (8 * E * I) * (1 + 1 / (N * N))
    rel = (-y - d) / d; if (rel < 0) rel = -rel
    if (rel > 1e-8) { printf "tip_y %.12g expected %.12g (rel %.3g)\n", -y, d, rel; exit 1 }
}'
# the base moment of the CSV: w L^2 / 2, clockwise (negative)
awk -F, 'NR == 2 { pi = 3.14159265358979323846; m = -700 * pi * 0.0004 * 9.81 * 2; 
    if (($7 - m) / m > 1e-9 || ($7 - m) / m < -1e-9) { print "base moment " $7 " expected " m; exit 1 } }' "$tmp/nodes.csv"
# relax reaches the same tip
sed 's/^tolerance.*/tolerance = 1e-12\nsolver = relax\nalpha = 0.9/' "$tmp/rod.spec" >"$tmp/relax.spec"
tipr=$("$bin" bend "$tmp/relax.spec" --json | grep -o '"tip_y": [^,]*' | cut -d' ' -f2)
awk -v a="$tipy" -v b="$tipr" 'BEGIN { d = (a - b) / a; if (d < 0) d = -d; if (d > 1e-9) { print a, b; exit 1 } }'
echo ok
