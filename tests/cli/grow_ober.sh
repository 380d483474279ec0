#!/usr/bin/env bash
# cambium grow with Oberlaender's parametric tree: the built-in presets equal the shipped
# models/ober-*.tree files; a stand with every output kind; formula and option errors name
# the file, line and column or the option; the solver's threads; exit codes.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for m in massart attims rauh troll cryptomeria carbon; do
    diff <("$bin" grow "$CBM_SOURCE/models/ober-$m.tree" --params) <("$bin" grow ober-$m --params)
done
"$bin" grow ober-troll -y 4 --stand 2x2 --spacing 2 --stagger 1 -o "$tmp/s.json" \
    -o "$tmp/s.obj" -o "$tmp/s.svg" -o "plot:$tmp/p.svg" -o "$tmp/s.mtg" --size 200 >"$tmp/out.txt"
grep -q '^year  4: 4 trees,' "$tmp/out.txt"
for f in s.json s.obj s.svg p.svg s.mtg; do test -s "$tmp/$f"; done
# the MTG: a plant per tree (all four germinate by year 4 with --stagger 1)
test "$(grep -c '/P[1-4]/A1/S1' "$tmp/s.mtg")" -eq 4
for k in age height_m leaves shoots_per_order wood_volume_m3 carbon_tax carbon_mean; do
    grep -q "\"$k\":" "$tmp/s.json" || { echo "missing $k"; exit 1; }
done
test "$(grep -o '"tree":' "$tmp/s.json" | wc -l)" -eq 4
# --mechanics: the statics of the final trees in the report and a picture of the bent trees
"$bin" grow ober-troll -y 4 --stand 2x1 --mechanics --quiet -o "$tmp/m.json" -o "mech:$tmp/m.svg"
test -s "$tmp/m.svg"
test "$(grep -o '"max_tip_difference_m":' "$tmp/m.json" | wc -l)" -eq 2
test "$(grep -o '"mech_max_tip_difference_m":' "$tmp/m.json" | wc -l)" -eq 8
grep -q '"converged":true' "$tmp/m.json"
set +e
"$bin" grow ober-troll -y 2 -o "mech:$tmp/n.svg" 2>"$tmp/err.txt"
rc=$?
set -e
test $rc -eq 2
grep -q 'needs --mechanics' "$tmp/err.txt"
test ! -e "$tmp/n.svg"
# light with stems and the mechanics in the growth: the rays' line
"$bin" grow ober-carbon -y 3 -D lightStems=1 -D mechanicsFeedback=1 -o "$tmp/c.json" >"$tmp/c.txt"
grep -q '^light: [1-9][0-9]* rays in .* M rays/s' "$tmp/c.txt"
# same seed, same report; -D sets formulas
"$bin" grow ober-troll -y 4 --stand 2x2 --spacing 2 --stagger 1 -o "$tmp/t.json" --quiet
cmp <(grep -v seconds "$tmp/s.json") <(grep -v seconds "$tmp/t.json")
"$bin" grow ober-rauh -y 3 -D 'specificLengthLambda[1]=len * position' --quiet -o "$tmp/r.json"
# errors: a formula's unknown variable at its line and column, exit 1
printf 'family = oberlaender\n\nbendingLambda = order * bogus\n' >"$tmp/bad.tree"
set +e
"$bin" grow "$tmp/bad.tree" -y 2 2>"$tmp/err.txt"
rc=$?
set -e
test $rc -eq 1
grep -q 'bad.tree:3:25: error: bendingLambda: unknown variable .bogus.' "$tmp/err.txt"
# the solver's threads (-D solve_threads=N, as the fruit tree's): the same report with 1 and 2,
# a bad count refused naming it, exit 2
"$bin" grow ober-troll -y 4 -D mechanicsFeedback=1 -D solve_threads=1 --mechanics --quiet \
    -o "$tmp/t1.json"
"$bin" grow ober-troll -y 4 -D mechanicsFeedback=1 -D solve_threads=2 --mechanics --quiet \
    -o "$tmp/t2.json"
cmp <(grep -v seconds "$tmp/t1.json") <(grep -v seconds "$tmp/t2.json")
for v in -1 1.5 1025; do
    set +e
    "$bin" grow ober-troll -y 1 -D solve_threads=$v 2>"$tmp/err.txt"
    rc=$?
    set -e
    test $rc -eq 2
    grep -q 'solve_threads' "$tmp/err.txt"
done
set +e
"$bin" grow ober-rauh --stand 0x3 2>"$tmp/err.txt"
rc=$?
set -e
test $rc -eq 2
grep -q 'stand' "$tmp/err.txt"
echo ok
