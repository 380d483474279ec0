#!/bin/bash
# cambium info on segments tables and grow summaries, and grow --report: the forester's
# measures (docs/models.md, "Measured realism"), the same from the table, the summary and the
# report; branch intersections on a hand-made table; malformed tables name file and line.
set -u
BIN=$1
SRC=${CBM_SOURCE:?}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$BIN" grow -y 3 --quiet --report -o "$T/t.csv" -o "$T/t.json" >"$T/report" || fail "grow --report"
grep -q "^fruit-tree after 3 years:" "$T/report" || fail "report header: $(cat "$T/report")"
for w in "height" "crown width" "self-buckling: trunk E" "pipe model at" "branch angles of" \
    "stress ratio (stress / MOR) of" "intersections:"; do
    grep -q "$w" "$T/report" || fail "report lacks '$w'"
done
"$BIN" info "$T/t.csv" >"$T/csv" || fail "info t.csv"
rows=$(($(wc -l <"$T/t.csv") - 1))
grep -q "mechanical segments table: $rows segments" "$T/csv" || fail "rows: $(head -2 "$T/csv")"
"$BIN" info "$T/t.json" >"$T/json" || fail "info t.json"
grep -q "growth summary of fruit-tree: 3 years recorded" "$T/json" || fail "summary: $(cat "$T/json")"
# the table, the summary and the report agree on what the geometry and the stresses give (the
# table's wood density is inferred from the carried masses, so the buckling line may differ)
for w in "height" "crown width" "pipe model" "branch angles" "stress ratio" "intersections"; do
    a=$(grep "^  $w" "$T/report") b=$(grep "^  $w" "$T/csv") c=$(grep "^  $w" "$T/json")
    [ -n "$a" ] && [ "$a" = "$b" ] && [ "$a" = "$c" ] || fail "'$w' differs: $a | $b | $c"
done
"$BIN" info --json "$T/t.csv" >"$T/m.json" || fail "info --json"
grep -q "^{\"file\":\"$T/t.csv\",\"table\":\"mechanical segments\",\"measures\":{\"segments\":$rows," \
    "$T/m.json" || fail "json: $(head -c 200 "$T/m.json")"
for k in height_m diameter_m crown_width_m buckling_ratio pipe_exponent branch_angle_deg \
    stress_ratio intersecting_fraction; do
    grep -q "\"$k\":" "$T/m.json" || fail "json lacks $k"
done
"$BIN" info --json "$T/t.json" | grep -q '"table":"grow summary","measures":{"segments"' ||
    fail "info --json on the summary"

# a hand-made turtle table: a trunk, its continuation, and a root crossing the trunk
H=id,parent,lateral,order,module,color,x0,y0,z0,x1,y1,z1,width0,width1,length
printf '%s\n0,-1,0,0,0,1,0,0,0,0,2,0,0.2,0.2,2\n1,0,0,0,1,1,0,2,0,0,3,0,0.2,0.1,1\n2,-1,0,0,2,1,-1,1,0.05,1,1,0.05,0.2,0.2,2\n' \
    "$H" >"$T/cross.csv"
"$BIN" info "$T/cross.csv" >"$T/out" || fail "info cross.csv"
grep -q "turtle segments table: 3 segments" "$T/out" || fail "turtle table: $(cat "$T/out")"
grep -q "intersections: 2 segments (66.67 %) pass through a non-adjacent segment, 1 pairs" \
    "$T/out" || fail "crossing: $(grep intersections "$T/out")"
grep -q "height 3.000 m; trunk diameter at breast height (1.3 m) 20.00 cm" "$T/out" ||
    fail "trunk: $(grep height "$T/out")"
# the crossing root moved 0.25 m away: no intersection
sed 's/^2,-1,0,0,2,1,-1,1,0.05,1,1,0.05/2,-1,0,0,2,1,-1,1,0.25,1,1,0.25/' "$T/cross.csv" >"$T/apart.csv"
"$BIN" info "$T/apart.csv" | grep -q "intersections: 0 segments" || fail "apart"

# malformed tables: file and line
printf '%s\n0,-1,0,0,0,1,0,0,0,0,2,0,0.2,0.2,2\n1,0,0,0,1,1,0,2,x,0,3,0,0.2,0.1,1\n' "$H" >"$T/bad.csv"
"$BIN" info "$T/bad.csv" >/dev/null 2>"$T/err"
[ $? -eq 1 ] || fail "bad.csv: status"
grep -q "bad.csv:3:.*: error: field 9 is not a number" "$T/err" || fail "bad.csv: $(cat "$T/err")"
printf '%s\n0,-1,0,0,0,1,0,0,0,0,2,0,0.2,0.2,2\n1,5,0,0,1,1,0,2,0,0,3,0,0.2,0.1,1\n' "$H" >"$T/fwd.csv"
"$BIN" info "$T/fwd.csv" >/dev/null 2>"$T/err" && fail "forward parent accepted"
grep -q "fwd.csv:3: error: segment 1: id 1 or parent 5" "$T/err" || fail "fwd.csv: $(cat "$T/err")"
printf '%s\n0,-1,0,0,0,1,0,0,0,0,2,0\n' "$H" >"$T/short.csv"
"$BIN" info "$T/short.csv" >/dev/null 2>"$T/err" && fail "short row accepted"
grep -q "short.csv:2: error: 12 fields, the column width0 is missing" "$T/err" ||
    fail "short.csv: $(cat "$T/err")"
"$BIN" info --json "$T/t.csv" extra >/dev/null 2>&1
[ $? -eq 2 ] || fail "two files: usage error expected"

# an L-system's turtle segments
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -o "segments:$T/l.csv" || fail "run -o segments:"
"$BIN" info "$T/l.csv" | grep -q "turtle segments table:" || fail "info on the turtle's table"
echo ok
