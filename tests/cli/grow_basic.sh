#!/usr/bin/env bash
# cambium grow: the built-in fruit tree for a few years with every output kind; determinism of
# the segments table; parameter files, -D overrides and their errors; exit codes.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" grow -y 3 --seed 5 -o "$tmp/t.csv" -o "$tmp/t.json" -o "$tmp/t.mtg" -o "$tmp/t.obj" \
    -o "$tmp/t.svg" --size 200 --quiet
for f in t.csv t.json t.mtg t.obj t.svg; do test -s "$tmp/$f"; done
head -1 "$tmp/t.csv" | grep -q '^id,parent,order'
for k in year segments height_m crown_width_m leaves fruit breaks reaction_wood_segments \
    equilibrium_passes seconds; do
    grep -q "\"$k\":" "$tmp/t.json" || { echo "missing $k"; exit 1; }
done
test "$(grep -o '"year":' "$tmp/t.json" | wc -l)" -eq 3
# a growth animation: one frame every 10 growth steps
"$bin" grow -y 1 --every 10 -o "$tmp/anim.glb" --quiet
test -s "$tmp/anim.glb"
# same seed, same table
"$bin" grow -y 3 -D seed=5 -o "$tmp/u.csv" --quiet
cmp "$tmp/t.csv" "$tmp/u.csv"
# a parameter file with an override; the shipped models parse
"$bin" grow "$CBM_SOURCE/models/poplar-crooked.tree" -y 2 -D fairness=0.5 -o "$tmp/p.csv" >"$tmp/out.txt"
grep -q '^year  2:' "$tmp/out.txt"
"$bin" grow "$CBM_SOURCE/models/fruit-tree.tree" --params | grep -qx 'fairness = 1'
"$bin" grow poplar-wild --params | grep -qx 'form = wild'
# --seeds: the distribution over seeds (3 seeds, 2 years)
"$bin" grow -y 2 --seeds 1-3 -o "$tmp/stats.json" >"$tmp/seeds.txt"
grep -q '^year  2, median of 3 seeds:' "$tmp/seeds.txt"
grep -q '^3 seeds in .* 0 collapsed$' "$tmp/seeds.txt"
for k in '"seeds":' '"collapsed_seeds":' '"median":' '"q1":' '"q3":' '"min":' '"max":' \
    '"base_diameter_m":' '"final":' '"breaks_total":'; do
    grep -q "$k" "$tmp/stats.json" || { echo "stats: missing $k"; exit 1; }
done
test "$(grep -o '"seed":' "$tmp/stats.json" | wc -l)" -eq 3
set +e
"$bin" grow --seeds 3-1 -o "$tmp/x.json" 2>/dev/null; rs1=$?
"$bin" grow --seeds 1-2 -o "$tmp/x.png" 2>/dev/null; rs2=$?
"$bin" grow --seeds 1-2 --seed 4 2>/dev/null; rs3=$?
set -e
test $rs1 -eq 2 && test $rs2 -eq 2 && test $rs3 -eq 2
test ! -e "$tmp/x.json"
# errors: file:line:col, exit 1; bad usage, exit 2
printf 'fairness = 0.5\nwobble = 1\n' >"$tmp/bad.tree"
set +e
"$bin" grow "$tmp/bad.tree" -o "$tmp/x.csv" 2>"$tmp/err.txt"
rc=$?
set -e
test $rc -eq 1
grep -q "bad.tree:2:1: error: unknown parameter 'wobble'" "$tmp/err.txt"
test ! -e "$tmp/x.csv"
set +e
"$bin" grow -D fairness=7 -o "$tmp/x.csv" 2>/dev/null; rc1=$?
"$bin" grow no-such-model 2>/dev/null; rc2=$?
"$bin" grow -y 2 -o "$tmp/x.weird" 2>/dev/null; rc3=$?
set -e
test $rc1 -eq 2 && test $rc2 -eq 2 && test $rc3 -eq 2
echo ok
