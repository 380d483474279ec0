#!/usr/bin/env bash
# Several bending methods on one problem (docs/methods.md): `cambium compare` with every output,
# its usage errors; `solver = approx` in a bend spec; `-D solver=approx` for the built-in trees;
# SolverMethod(n) in an L+C model.
set -euo pipefail
bin=$1
src=${CBM_SOURCE:-$(cd "$(dirname "$0")/../.." && pwd)}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
cat >"$tmp/rod.spec" <<'SPEC'
length = 1
segments = 40
radius = 0.01
E = 1e9
density = 800
angle = 10
SPEC
# the methods named, so that a method added later does not change the row count
"$bin" compare "$tmp/rod.spec" --solvers relax,fast,approx -o "$tmp/c.csv" -o "$tmp/c.json" -o "$tmp/c.svg" --json >"$tmp/out.json"
cmp "$tmp/out.json" "$tmp/c.json" || fail "--json and -o .json differ"
head -1 "$tmp/c.csv" | grep -qx 'solver,node,s,x,y,z,angle_deg' || fail "csv header"
test "$(wc -l <"$tmp/c.csv")" -eq $((1 + 3 * 41)) || fail "csv rows"
grep -q '<svg' "$tmp/c.svg" || fail "svg"
for k in '"solver": "relax"' '"solver": "fast"' '"solver": "approx"' '"peak_bytes": ' '"from": "approx", "to": "fast"'; do
    grep -q "$k" "$tmp/out.json" || fail "json lacks $k"
done
# relax and fast find the same equilibrium: their distance is tiny; approx is another shape
awk 'BEGIN { RS = "{"; FS = "," }
     /"from": "relax", "to": "fast"/ { split($3, a, ": "); if (a[2] + 0 > 1e-5) bad = 1; seen++ }
     /"from": "fast", "to": "approx"/ { split($3, a, ": "); if (a[2] + 0 < 1e-3) bad = 1; seen++ }
     END { exit bad || seen != 2 }' "$tmp/out.json" || fail "distances"
"$bin" compare "$tmp/rod.spec" --solvers approx,fast | grep -q '^approx ' || fail "text output"
# usage errors: exit 2, nothing written
set +e
"$bin" compare "$tmp/rod.spec" --solvers fast,nosuch -o "$tmp/x.csv" 2>"$tmp/err"; rc=$?
set -e
test $rc -eq 2 || fail "unknown solver exits $rc"
grep -q "unknown solver 'nosuch' (expected relax, fast, approx" "$tmp/err" || fail "message"
test ! -e "$tmp/x.csv" || fail "wrote on a usage error"
set +e
"$bin" compare "$tmp/rod.spec" --solvers fast,fast 2>"$tmp/err"; rc=$?
"$bin" compare "$tmp/rod.spec" -o "$tmp/x.txt" 2>/dev/null; rc2=$?
set -e
test $rc -eq 2 && test $rc2 -eq 2 || fail "duplicate solver / bad output: $rc $rc2"

# bend with solver = approx, both modes; motion is refused with it
printf 'solver = approx\napprox_mode = thesis\n' >>"$tmp/rod.spec"
"$bin" bend "$tmp/rod.spec" --json | grep -q '"solver": "approx"' || fail "bend approx"
printf 'duration = 1\n' >>"$tmp/rod.spec"
set +e
"$bin" bend "$tmp/rod.spec" 2>"$tmp/err"; rc=$?
set -e
test $rc -eq 1 && grep -q "needs solver relax or fast" "$tmp/err" || fail "approx with duration"
printf 'solver = approx\napprox_mode = sideways\n' >"$tmp/bad.spec"
set +e
"$bin" bend "$tmp/bad.spec" 2>"$tmp/err"; rc=$?
set -e
test $rc -eq 1 && grep -q "bad.spec:2:15: error: unknown approx_mode 'sideways'" "$tmp/err" || fail "approx_mode"

# the built-in trees
"$bin" grow -D solver=approx --params | grep -qx 'solver = approx' || fail "grow -D solver"
"$bin" grow --params | grep -qx 'solver = fast' || fail "default solver"
set +e
"$bin" grow -D solver=nosuch --params >/dev/null 2>"$tmp/err"; rc=$?
set -e
test $rc -ne 0 && grep -q "nosuch" "$tmp/err" || fail "grow bad solver"
"$bin" grow -D solver=approx -n 2 -o "$tmp/t.csv" >/dev/null || fail "grow with approx"
# the approx load: calibrated by default, the thesis's tip load on request (another tree)
"$bin" grow --params | grep -qx 'approx_load = calibrated' || fail "default approx_load"
"$bin" grow -D solver=approx -D approx_load=thesis -n 2 -o "$tmp/th.csv" >/dev/null ||
    fail "grow with the thesis load"
! cmp -s "$tmp/t.csv" "$tmp/th.csv" || fail "approx_load=thesis changed nothing"
"$bin" grow -D solver=approx -D approx_load=calibrated -n 2 -o "$tmp/ca.csv" >/dev/null
cmp -s "$tmp/t.csv" "$tmp/ca.csv" || fail "approx_load=calibrated is not the default"
set +e
"$bin" grow -D approx_load=tip --params >/dev/null 2>"$tmp/err"; rc=$?
set -e
test $rc -ne 0 && grep -q "'tip' is not one of thesis calibrated" "$tmp/err" || fail "bad approx_load"

# L+C: SolverMethod(2) bends with approx (another shape than the default), 9 is an error
sed 's/^Start: {/Start: {\n    SolverMethod(2);/' "$src/models/jirasek-hanging.l" >"$tmp/h.l"
grep -q 'SolverMethod(2)' "$tmp/h.l" || fail "sed"
"$bin" run "$tmp/h.l" -n 6 -o "segments:$tmp/a.csv" >/dev/null
"$bin" run "$src/models/jirasek-hanging.l" -n 6 -o "segments:$tmp/f.csv" >/dev/null
! cmp -s "$tmp/a.csv" "$tmp/f.csv" || fail "SolverMethod(2) changed nothing"
sed 's/SolverMethod(2)/SolverMethod(9)/' "$tmp/h.l" >"$tmp/h9.l"
set +e
"$bin" run "$tmp/h9.l" -n 2 2>"$tmp/err" >/dev/null; rc=$?
set -e
test $rc -eq 1 && grep -q "SolverMethod(n): n is 0 .. [0-9]*, in the order relax, fast, approx" "$tmp/err" || fail "SolverMethod(9): $(cat "$tmp/err")"
# one plant, four methods: an L+C model grown once per method; cbm_lsys_def.solver overrides the
# model's SolverMethod(), so compare's approx plant is the one the model grows with
# SolverMethod(2), and a model asking for approx is still bent by fast when compare says fast
"$bin" compare "$tmp/h.l" -n 6 --solvers relax,fast,approx,fem -o "$tmp/p.csv" -o "$tmp/p.json" -o "$tmp/p.svg"
head -1 "$tmp/p.csv" | grep -qx 'solver,segment,x0,y0,z0,x1,y1,z1' || fail "plant csv header"
nseg=$(($(wc -l <"$tmp/f.csv") - 1))
test "$(wc -l <"$tmp/p.csv")" -eq $((1 + 4 * nseg)) || fail "plant csv rows"
grep -q '<svg' "$tmp/p.svg" || fail "plant svg"
for k in '"solver": "fem"' '"height": ' '"tip_deflection": ' '"from": "fem", "to": "relax"'; do
    grep -q "$k" "$tmp/p.json" || fail "plant json lacks $k"
done
# segment by segment against run's plants (x1 y1 z1: run's columns 7-9 at %.9g)
same() { # $1 solver in p.csv, $2 run's segments csv
    awk -F, -v s="$1" 'NR == FNR { if (FNR > 1) { x[$1] = $7; y[$1] = $8; z[$1] = $9 }; next }
        $1 == s { n++; d = ($6 - x[$2])^2 + ($7 - y[$2])^2 + ($8 - z[$2])^2; if (d > 1e-16) bad++ }
        END { exit bad || n == 0 }' "$2" "$tmp/p.csv"
}
same approx "$tmp/a.csv" || fail "compare approx is not the SolverMethod(2) plant"
same fast "$tmp/f.csv" || fail "compare fast is not the default plant"
! same approx "$tmp/f.csv" || fail "approx and fast grew the same plant"
"$bin" compare "$tmp/h.l" -n 6 --solvers fast | grep -q '^fast ' || fail "plant text"
awk 'BEGIN { RS = "{"; FS = "," }
     /"from": "relax", "to": "fast"/ { split($3, a, ": "); if (a[2] + 0 > 1e-4) bad = 1; seen++ }
     /"from": "fast", "to": "approx"/ { split($3, a, ": "); if (a[2] + 0 < 1e-3) bad = 1; seen++ }
     END { exit bad || seen != 2 }' "$tmp/p.json" || fail "plant distances"
# a built-in tree: -D and -n reach the model, the methods' solver key is set
"$bin" compare fruit-tree -n 2 -D density=700 --seed 3 --solvers fast,approx --json >"$tmp/t.json"
grep -q '"solver": "approx", "segments": [1-9]' "$tmp/t.json" || fail "tree compare"
# a model without mechanics, -D on a spec, a broken define: usage errors, nothing written
set +e
"$bin" compare "$src/models/cpfg-herb-sublsystems.l" -o "$tmp/x.csv" 2>"$tmp/err"; rc=$?
"$bin" compare "$tmp/rod.spec" -D A=1 -o "$tmp/x.csv" 2>/dev/null; rc2=$?
"$bin" compare fruit-tree -D nosuch=1 -o "$tmp/x.csv" 2>/dev/null; rc3=$?
set -e
test $rc -eq 2 && grep -q "declares no mechanics" "$tmp/err" || fail "no mechanics: $rc"
test $rc2 -eq 2 && test $rc3 -eq 2 || fail "-D with a spec / unknown -D: $rc2 $rc3"
test ! -e "$tmp/x.csv" || fail "wrote on a usage error"
echo ok
