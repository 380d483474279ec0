#!/usr/bin/env bash
# cambium bend: every spec error names FILE:line:col; bad usage exits 2, job failures exit 1;
# a failed job leaves no output file behind.
set -uo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
printf 'length = 1\nfoo = 3\nradius = -1\nE 5\nangle = 100\nsolver = quick\nsegments = 2.5\nlength = 2\ntolerance = nan\n' >"$tmp/bad.spec"
"$bin" bend "$tmp/bad.spec" -o "$tmp/out.csv" 2>"$tmp/err"
test $? -eq 1 || fail "bad spec should exit 1"
test ! -e "$tmp/out.csv" || fail "output written for a bad spec"
grep -q "bad.spec:2:1: error: unknown key 'foo'" "$tmp/err" || fail "unknown key"
grep -q "bad.spec:3:10: error: 'radius' = -1 is out of range" "$tmp/err" || fail "range"
grep -q "bad.spec:4:3: error: expected '='" "$tmp/err" || fail "syntax"
grep -q "bad.spec:5:9: error: 'angle'" "$tmp/err" || fail "angle"
grep -q "bad.spec:6:10: error: unknown solver 'quick'" "$tmp/err" || fail "solver"
grep -q "bad.spec:7:12: error: 'segments' expects a whole number" "$tmp/err" || fail "integer"
grep -q "bad.spec:8:1: error: key 'length' given twice" "$tmp/err" || fail "twice"
grep -q "bad.spec:9:13: error: 'tolerance' expects a finite number" "$tmp/err" || fail "nan"
# usage errors
"$bin" bend 2>/dev/null; test $? -eq 2 || fail "no spec should exit 2"
"$bin" bend "$tmp/bad.spec" --frobnicate 2>/dev/null; test $? -eq 2 || fail "unknown option"
"$bin" bend "$tmp/bad.spec" -o "$tmp/x.png" 2>/dev/null; test $? -eq 2 || fail "bad format"
"$bin" bend "$tmp/missing.spec" 2>/dev/null; test $? -eq 1 || fail "missing file"
# non-convergence is a failure with the residual reported, and no output
printf 'E = 1e6\ndensity = 1000\nsolver = relax\nalpha = 0.01\nmax_passes = 5\n' >"$tmp/nc.spec"
"$bin" bend "$tmp/nc.spec" -o "$tmp/nc.csv" 2>"$tmp/err"
test $? -eq 1 || fail "non-convergence should exit 1"
grep -q "residual" "$tmp/err" || fail "residual not reported"
test ! -e "$tmp/nc.csv" || fail "output written after non-convergence"
"$bin" bend --help | grep -q "usage: cambium bend" || fail "help"
echo ok
