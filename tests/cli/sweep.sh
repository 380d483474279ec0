#!/usr/bin/env bash
# cambium sweep: one-at-a-time sweeps of a built-in tree (docs/cli.md): the table's rows and
# columns, one plot per sweep, fixed seeds give the same rows twice, usage errors exit 2 and
# write nothing.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
"$bin" sweep fruit-tree --param density=500,900 --param solver=fast,approx -n 2 --seeds 1,2 \
    -o "$tmp/s.csv" -o "$tmp/s.svg" -o "$tmp/s.json"
head -1 "$tmp/s.csv" | grep -qx 'param,value,seed,extent_x,extent_y,extent_z,segments,seconds' || fail header
test "$(wc -l <"$tmp/s.csv")" -eq 9 || fail "rows: $(wc -l <"$tmp/s.csv")"
grep -q '^solver,approx,2,' "$tmp/s.csv" || fail "approx row"
grep -q '<svg' "$tmp/s-density.svg" && grep -q '<svg' "$tmp/s-solver.svg" || fail "plots"
grep -q '"param": "density", "value": "900", "seed": "1"' "$tmp/s.json" || fail json
# extents are positive, the segment count the same for one seed across densities (3 years' growth
# is not gated by the wood's weight here) and the runs reproducible
awk -F, 'NR > 1 && !($4 > 0 && $5 > 0 && $6 > 0 && $7 > 0) { exit 1 }' "$tmp/s.csv" || fail extents
"$bin" sweep fruit-tree --param density=500,900 --param solver=fast,approx -n 2 --seeds 1,2 -o "$tmp/t.csv"
cut -d, -f1-7 "$tmp/s.csv" >"$tmp/a"
cut -d, -f1-7 "$tmp/t.csv" >"$tmp/b"
cmp -s "$tmp/a" "$tmp/b" || fail "not reproducible"
# one sweep: the plot is the file named
"$bin" sweep fruit-tree --param density=600 -n 1 -o "$tmp/one.svg"
test -s "$tmp/one.svg" || fail "single plot"
for bad in "--param nosuch=1" "--param density=abc" "--param density" "--seeds x --param density=1" "--param density=1 -o $tmp/x.txt"; do
    set +e
    # shellcheck disable=SC2086
    "$bin" sweep fruit-tree $bad -n 1 -o "$tmp/never.csv" 2>"$tmp/err"; rc=$?
    set -e
    test $rc -eq 2 || fail "'$bad' exits $rc"
    test ! -e "$tmp/never.csv" || fail "'$bad' wrote a file"
done
# an L-system model: NAME is a #define, -n its steps; with mechanics the plant's segments, else
# the turtle's primitives; a name the model does not define is a usage error
src=${CBM_SOURCE:-$(cd "$(dirname "$0")/../.." && pwd)}
"$bin" sweep "$src/models/jirasek-hanging.l" --param DENSITY=300,900 -n 6 -o "$tmp/l.csv" -o "$tmp/l.svg"
test "$(wc -l <"$tmp/l.csv")" -eq 3 || fail "l rows"
grep -q '<svg' "$tmp/l.svg" || fail "l plot"
# the heavier wood hangs lower: a smaller vertical extent, the same segment count
awk -F, 'NR == 2 { y = $5; n = $7 } NR == 3 { if (!($5 < y) || $7 != n || n == 0) exit 1 }' "$tmp/l.csv" || fail "DENSITY"
"$bin" run "$src/models/jirasek-hanging.l" -n 6 -D DENSITY=900 -o "segments:$tmp/r.csv" >/dev/null
test "$(awk -F, 'NR == 3 { print $7 }' "$tmp/l.csv")" -eq $(($(wc -l <"$tmp/r.csv") - 1)) || fail "l segments"
"$bin" sweep "$src/models/cpfg-herb-sublsystems.l" --param ANGLE=120,137.5 -n 6 >"$tmp/c.txt"
awk -F, 'NR > 1 && !($7 > 0 && $4 > 0) { exit 1 }' "$tmp/c.txt" || fail "cpfg sweep"
set +e
"$bin" sweep "$src/models/jirasek-hanging.l" --param NOSUCH=1 -n 1 -o "$tmp/never.csv" 2>"$tmp/err"; rc=$?
set -e
test $rc -eq 2 && grep -q "not a #define" "$tmp/err" || fail "unknown define: $rc"
test ! -e "$tmp/never.csv" || fail "unknown define wrote a file"
echo ok
