#!/usr/bin/env bash
# cambium run writes the mechanical segments of an L+C model as an MTG and as a CSV table; a
# model without mechanics writes the turtle's segments instead (tests/cli/run_turtle_mtg.sh).
set -euo pipefail
bin=$1
src=${CBM_SOURCE:-.}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" run "$src/models/jirasek-hanging.l" -o "$tmp/h.mtg" -o "segments:$tmp/h.csv" -o "$tmp/h.str"
nseg=$(grep -c '^I(' "$tmp/h.str")
test "$nseg" -gt 20
# CSV: header + one row per segment, ids in order, parents before children
test "$(wc -l <"$tmp/h.csv")" -eq $((nseg + 1))
head -1 "$tmp/h.csv" | grep -q '^id,parent,order,x0_m,'
awk -F, 'NR > 1 && ($1 != NR - 2 || $2 >= $1) { print "bad row " NR; exit 1 }' "$tmp/h.csv"
# 3 laterals of order 1, the stem of order 0
test "$(awk -F, 'NR > 1 && $3 == 1 && prev != 1 { n++ } NR > 1 { prev = $3 } END { print n }' "$tmp/h.csv")" -eq 3
# MTG: FORM-A header, one S line per segment, 3 lateral axes
grep -q '^CODE:	FORM-A' "$tmp/h.mtg"
test "$(grep -cE '(^|	)(/P1/A1/S1|\+A[0-9]+/S1|\^<S[0-9]+)	' "$tmp/h.mtg")" -eq "$nseg"
test "$(grep -cE '\+A[0-9]+/S1' "$tmp/h.mtg")" -eq 3
# no mechanics: the turtle's segments (none here), a valid file without the mechanical features
printf '#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n' >"$tmp/plain.l"
"$bin" run "$tmp/plain.l" -o "$tmp/p.mtg"
grep -q '^CODE:	FORM-A' "$tmp/p.mtg"
grep -q '^TOPO	id	order	module	color	' "$tmp/p.mtg"
if grep -q 'stress' "$tmp/p.mtg"; then exit 1; fi
echo ok
