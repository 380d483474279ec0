#!/usr/bin/env bash
# cambium elastica with steps > 0 (docs/elastica.md "Growth"): the inverse problem keeps the rod
# static (hold_error), the frames, the cell CSV and plots, and bad growth keys (named errors,
# exit 1, no file left behind).
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
cat >"$tmp/hold.spec" <<'SPEC'
length_initial = 1
length = 1.1
steps = 10
segments = 110
radius = 1
E = 4
density = 1
gravity = 1
angle = 30
taper = step
stiffness_ratio = 13
stiffness_tau = 4
control = static
SPEC
"$bin" elastica "$tmp/hold.spec" --json -o "$tmp/g.csv" -o "$tmp/g.svg" -o "$tmp/g.png" >"$tmp/out.json"
head -1 "$tmp/g.csv" |
    grep -qx 'step,time,s,x,y,theta_deg,x_g,y_g,kappa,kappa_g,kappa_c,kappa_o_g,k_ss,k_as,k_i,stiffness,weight,radius,born' ||
    fail "csv header"
# 11 frames of 100..110 cells
test "$(wc -l <"$tmp/g.csv")" -eq $((1 + 100 + 101 + 102 + 103 + 104 + 105 + 106 + 107 + 108 + 109 + 110)) ||
    fail "csv rows $(wc -l <"$tmp/g.csv")"
grep -q '<svg' "$tmp/g.svg" || fail "svg"
head -c 4 "$tmp/g.png" | grep -q PNG || fail "png"
j=$(cat "$tmp/out.json")
test "$(grep -o '"step": ' <<<"$j" | wc -l)" -eq 11 || fail "frames"
grep -q '"control": "static"' <<<"$j" || fail "control"
# every hold error below 1e-10 rad
for e in $(grep -o '"hold_error": [-0-9.e+]*' <<<"$j" | cut -d' ' -f2); do
    awk -v e="$e" 'BEGIN { exit !(e < 1e-10) }' || fail "hold error $e"
done
grep -q '"jumped": true' <<<"$j" && fail "jumped"
# bad input
printf 'length_initial = 1\nlength = 1.1\nsteps = 2\nsegments = 110\ntaper = conical\n' >"$tmp/bad.spec"
if "$bin" elastica "$tmp/bad.spec" -o "$tmp/bad.csv" 2>"$tmp/err"; then fail "bad taper accepted"; fi
grep -q 'bad.spec:5:9: error: .*taper.*linear, uniform or step' "$tmp/err" || fail "taper message: $(cat "$tmp/err")"
test ! -e "$tmp/bad.csv" || fail "file left behind"
printf 'alpha = 15\ncontrol = 0.1\n' >"$tmp/bad2.spec"
if "$bin" elastica "$tmp/bad2.spec" 2>"$tmp/err"; then fail "growth key without steps accepted"; fi
grep -q "'control' is a growth key" "$tmp/err" || fail "growth key message: $(cat "$tmp/err")"
printf 'length_initial = 1.005\nlength = 1.1\nsteps = 2\nsegments = 110\n' >"$tmp/bad3.spec"
if "$bin" elastica "$tmp/bad3.spec" 2>"$tmp/err"; then fail "fractional cells accepted"; fi
grep -q 'whole number of segments' "$tmp/err" || fail "cells message: $(cat "$tmp/err")"
echo ok
