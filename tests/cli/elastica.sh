#!/usr/bin/env bash
# cambium elastica: the contract of docs/elastica.md through the tool: the three equilibria of a
# vertical heavy column at alpha = 15 with their stability, the folds and jump targets, the
# hysteresis, the S-curve CSV and plots, the Fig. 5.4 plant (9 equilibria, 4 stable), and bad
# input (named errors, exit 1 or 2, no file left behind).
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
cat >"$tmp/a15.spec" <<'SPEC'
alpha = 15
angle = 90
SPEC
"$bin" elastica "$tmp/a15.spec" --json -o "$tmp/s.csv" -o "$tmp/s.svg" -o "$tmp/s.png" >"$tmp/out.json"
head -1 "$tmp/s.csv" |
    grep -qx 'theta_tip_deg,theta_base_deg,kappa_base,strain_base,energy,tip_x,tip_y,dbase_dtip,index,stable' ||
    fail "csv header"
test "$(wc -l <"$tmp/s.csv")" -gt 500 || fail "csv rows"
grep -q '<svg' "$tmp/s.svg" || fail "svg"
head -c 4 "$tmp/s.png" | grep -q PNG || fail "png"
j=$(cat "$tmp/out.json")
# three equilibria, the middle one (the column) unstable
eq=${j#*\"equilibria\": [}
eq=${eq%%], \"folds\"*}
test "$(grep -o '"theta_tip_deg"' <<<"$eq" | wc -l)" -eq 3 || fail "equilibria: $eq"
test "$(grep -o '"stable": true' <<<"$eq" | wc -l)" -eq 2 || fail "stable count"
for k in theta_tip_deg kappa_base tip_x tip_y energy stable; do
    grep -q "\"$k\": " <<<"$eq" || fail "missing $k"
done
grep -q '"theta_tip_deg": -35.88' <<<"$eq" || fail "bent state: $eq"
grep -q '"theta_tip_deg": 90, "theta_base_deg": 90, .*"stable": false' <<<"$eq" || fail "column"
# folds at 116.41 and 63.59 degrees, each with its jump
grep -q '"folds": \[{"theta_base_deg": 116.41' <<<"$j" || fail "fold 1"
grep -q '"theta_base_deg": 63.58' <<<"$j" || fail "fold 2"
grep -q '"jump": {"theta_tip_deg": 230.43' <<<"$j" || fail "jump target"
grep -q '"hysteresis": {"sweep_min_deg": -90, "sweep_max_deg": 270, "up": \[{"from"' <<<"$j" ||
    fail "hysteresis"
# the plant of Fig. 5.4
"$bin" elastica "$CBM_SOURCE/examples/elastica/fig5_4.spec" --json >"$tmp/p.json"
test "$(grep -o '"stable": true' "$tmp/p.json" | wc -l)" -eq 4 || fail "Fig. 5.4 stable states"
test "$(grep -o '"stable": false' "$tmp/p.json" | wc -l)" -eq 5 || fail "Fig. 5.4 unstable states"
# bad input: located errors, nothing written
printf 'alpha = 15\nradius = 0.01\nbranch = parent 7\n' >"$tmp/bad.spec"
set +e
"$bin" elastica "$tmp/bad.spec" -o "$tmp/bad.csv" 2>"$tmp/err"
rc=$?
set -e
test $rc -eq 1 || fail "bad spec exit $rc"
grep -q 'bad.spec:2:1: error: .radius. has no meaning with .alpha.' "$tmp/err" || fail "$(cat "$tmp/err")"
grep -q 'bad.spec:3:' "$tmp/err" || fail "branch error: $(cat "$tmp/err")"
test ! -e "$tmp/bad.csv" || fail "file written on failure"
set +e
"$bin" elastica "$tmp/a15.spec" -o "$tmp/x.txt" 2>/dev/null
rc=$?
"$bin" elastica 2>/dev/null
rc2=$?
set -e
test $rc -eq 2 && test $rc2 -eq 2 || fail "usage exits $rc $rc2"
echo ok
