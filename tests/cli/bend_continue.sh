#!/usr/bin/env bash
# cambium bend --continue: the heavy rod of alpha = 15 swept in base angle from 0 to 150 degrees
# (docs/bend.md "Continuation"): CSV header and rows, JSON branch and folds, the fold within
# 0.05 degrees of the elastica's (116.4134), the jump; usage errors and nothing written on them.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'length = 8.604725161155775\nsegments = 40\nradius = 0.01\ntolerance = 1e-10\n' >"$tmp/r.spec"
"$bin" bend "$tmp/r.spec" --continue angle=0:150:30 -o "$tmp/b.csv" -o "$tmp/b.json"
head -1 "$tmp/b.csv" | grep -qx 'param,tip_angle_deg,tip_x,tip_y,tip_z,unstable_modes,lowest_eigenvalue,energy,jumped'
test "$(wc -l <"$tmp/b.csv")" -gt 31
grep -q '"branch": \[{"param": 0,' "$tmp/b.json"
fold=$(grep -o '"kind": "fold", "bracket": [^,]*, "at": {"param": [^,]*' "$tmp/b.json" | sed 's/.*"param": //')
awk -v f="$fold" 'BEGIN { d = f - 116.413407; if (d < 0) d = -d; if (d > 0.05) { print "fold", f; exit 1 } }'
grep -q '"jump": {"param"' "$tmp/b.json"
# the last row: past the fold the rod hangs to the left (tip_x < 0), stable
tail -1 "$tmp/b.csv" | awk -F, '{ if (!($1 == 150 && $3 < 0 && $6 == 0)) { print; exit 1 } }'
"$bin" bend "$tmp/r.spec" --continue angle=0:150:30 | grep -q '^fold at 116\.4'
# usage errors (exit 2) and refused specs (exit 1), nothing written
set +e
"$bin" bend "$tmp/r.spec" --continue length=0:1 -o "$tmp/x.csv" 2>/dev/null; rc1=$?
"$bin" bend "$tmp/r.spec" --continue angle=5:5 -o "$tmp/x.csv" 2>/dev/null; rc2=$?
"$bin" bend "$tmp/r.spec" --continue angle=0:10:0 2>/dev/null; rc3=$?
printf 'solver = relax\n' >>"$tmp/r.spec"
"$bin" bend "$tmp/r.spec" --continue angle=0:10 -o "$tmp/x.csv" 2>"$tmp/err"; rc4=$?
set -e
test $rc1 -eq 2 && test $rc2 -eq 2 && test $rc3 -eq 2 && test $rc4 -eq 1
grep -q 'fast' "$tmp/err"
test ! -e "$tmp/x.csv"
