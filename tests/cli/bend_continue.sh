#!/usr/bin/env bash
# cambium bend --continue: the heavy rod of alpha = 15 swept in base angle from 0 to 150 degrees
# (docs/bend.md "Continuation"): CSV header and rows, JSON branch and folds, the fold within
# 0.05 degrees of the elastica's (116.4134), the jump; by arclength (the default: both folds,
# round the unstable arc) and by natural steps (--natural: one fold, then the jump); the plot;
# the column past Greenhill's load with --switch-branch; usage errors and nothing written on
# them.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'length = 8.604725161155775\nsegments = 40\nradius = 0.01\ntolerance = 1e-10\n' >"$tmp/r.spec"
"$bin" bend "$tmp/r.spec" --continue angle=0:150:30 -o "$tmp/b.csv" -o "$tmp/b.json"
head -1 "$tmp/b.csv" | grep -qx 'param,tip_angle_deg,tip_x,tip_y,tip_z,unstable_modes,lowest_eigenvalue,energy,jumped'
test "$(wc -l <"$tmp/b.csv")" -gt 31
grep -q '"branch": \[{"param": 0,' "$tmp/b.json"
grep -q '"method": "arclength", "switch_branch": false, "end": "to"' "$tmp/b.json"
folds=$(grep -o '"kind": "fold", "bracket": [^,]*, "switched": false, "at": {"param": [^,]*' "$tmp/b.json" |
    sed 's/.*"param": //' | tr '\n' ' ')
# both folds of the S-curve (the elastica's 116.413407 and 63.586593), in this order
echo "$folds" | awk '{ d1 = $1 - 116.413407; d2 = $2 - 63.586593; if (d1 < 0) d1 = -d1; if (d2 < 0) d2 = -d2
    if (NF != 2 || d1 > 0.05 || d2 > 0.05) { print "folds", $0; exit 1 } }'
grep -q '"jump": {"param"' "$tmp/b.json"
# the unstable arc between the folds: rows going back in the angle with unstable modes
awk -F, 'NR > 2 && $1 < p && $6 > 0 { n++ } { p = $1 } END { if (n < 5) { print "unstable rows", n; exit 1 } }' "$tmp/b.csv"
# the last row: round the two folds the rod hangs to the left (tip_x < 0), stable
tail -1 "$tmp/b.csv" | awk -F, '{ if (!($1 == 150 && $3 < 0 && $6 == 0)) { print; exit 1 } }'
"$bin" bend "$tmp/r.spec" --continue angle=0:150:30 | grep -q '^fold at 116\.4'
# natural steps: one fold, then the jump to the left
"$bin" bend "$tmp/r.spec" --continue angle=0:150:30 --natural -o "$tmp/n.csv" -o "$tmp/n.json" -o "$tmp/n.svg"
test "$(grep -o '"kind": "fold"' "$tmp/n.json" | wc -l)" -eq 1
if grep -q '"method"' "$tmp/n.json"; then exit 1; fi
awk -F, 'NR > 2 && $1 < p { exit 1 } { p = $1 }' "$tmp/n.csv"
grep -q '<svg' "$tmp/n.svg"
# the column past Greenhill's load (g_c = 5.1256 m/s^2 at 90 degrees): switched onto the
# buckled branch, which ends bent and stable
printf 'length = 8.604725161155775\nsegments = 40\nradius = 0.01\nangle = 90\n' >"$tmp/c.spec"
"$bin" bend "$tmp/c.spec" --continue gravity=4:15:20 --switch-branch |
    grep -q '^bifurcation (branch switched) at 5\.12'
"$bin" bend "$tmp/c.spec" --continue gravity=4:15:20 --switch-branch -o "$tmp/c.csv" -o "$tmp/c.png"
test -s "$tmp/c.png"
tail -1 "$tmp/c.csv" | awk -F, '{ if (!($1 == 15 && $3 > 1 && $6 == 0)) { print; exit 1 } }'
# the second bifurcation of the straight column (the second buckling load, 36.61 m/s^2 for the
# elastica): --switch-at 2 leaves there; the JSON numbers the bifurcations met
"$bin" bend "$tmp/c.spec" --continue gravity=4:60:40 --switch-branch --switch-at 2 |
    grep -q '^bifurcation (branch switched) at 36\.5'
"$bin" bend "$tmp/c.spec" --continue gravity=4:60:40 --switch-branch --switch-at 2 --json |
    grep -q '"switch_at": 2, .*"switched": true, .*"bifurcation": 2}'
# usage errors (exit 2) and refused specs (exit 1), nothing written
set +e
"$bin" bend "$tmp/c.spec" --continue gravity=4:6 --switch-at 2 2>/dev/null; rc9=$?
"$bin" bend "$tmp/c.spec" --continue gravity=4:6 --switch-branch --switch-at -1 2>/dev/null; rc10=$?
"$bin" bend "$tmp/r.spec" --continue width=0:1 -o "$tmp/x.csv" 2>/dev/null; rc1=$?
"$bin" bend "$tmp/r.spec" --continue angle=0:10 --natural --switch-branch 2>/dev/null; rc5=$?
"$bin" bend "$tmp/r.spec" --natural -o "$tmp/x.csv" 2>/dev/null; rc6=$?
"$bin" bend "$tmp/r.spec" -o "$tmp/x.svg" 2>/dev/null; rc7=$?
"$bin" bend "$tmp/r.spec" --continue length=0:1 -o "$tmp/x.csv" 2>/dev/null; rc8=$?
"$bin" bend "$tmp/r.spec" --continue angle=5:5 -o "$tmp/x.csv" 2>/dev/null; rc2=$?
"$bin" bend "$tmp/r.spec" --continue angle=0:10:0 2>/dev/null; rc3=$?
printf 'solver = relax\n' >>"$tmp/r.spec"
"$bin" bend "$tmp/r.spec" --continue angle=0:10 -o "$tmp/x.csv" 2>"$tmp/err"; rc4=$?
set -e
test $rc1 -eq 2 && test $rc2 -eq 2 && test $rc3 -eq 2 && test $rc4 -eq 1
test $rc5 -eq 2 && test $rc6 -eq 2 && test $rc7 -eq 2 && test $rc8 -eq 1
test $rc9 -eq 2 && test $rc10 -eq 2
grep -q 'fast' "$tmp/err"
test ! -e "$tmp/x.csv" && test ! -e "$tmp/x.svg"
