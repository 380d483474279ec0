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
echo ok
