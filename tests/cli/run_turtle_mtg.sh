#!/bin/bash
# cambium run -o x.mtg / -o segments:x.csv on a model without mechanics: the segments the turtle
# draws, linked by its branches; a model that draws nothing gives a valid file without a plant; a
# failed write leaves no file.
set -u
BIN=$1
SRC=${CBM_SOURCE:?}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
tab=$'\t'

# one step of F --> F[+F]F[-F]F: the whole file below the TOPO line
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -n 1 -o "$T/a.mtg" -o "segments:$T/a.csv" ||
    fail "run -o a.mtg"
grep -q "^CODE:${tab}FORM-A$" "$T/a.mtg" || fail "FORM-A header"
want="/P1/A1/S1${tab}${tab}0${tab}0${tab}0
${tab}+A2/S1${tab}1${tab}1${tab}3
^<S2${tab}${tab}2${tab}0${tab}5
${tab}+A3/S1${tab}3${tab}1${tab}8
^<S3${tab}${tab}4${tab}0${tab}10"
got=$(sed -n '/^TOPO/,$p' "$T/a.mtg" | tail -n +2 | cut -f1-5)
[ "$got" = "$want" ] || fail "topology: $got"
[ "$(sed -n 2p "$T/a.csv")" = "0,-1,0,0,0,128,0,0,0,0,1,0,1,1,1" ] || fail "csv row 0"
[ "$(cut -d, -f1-4 "$T/a.csv" | tail -n +2 | tr '\n' ' ')" = "0,-1,0,0 1,0,1,1 2,0,0,0 3,2,1,1 4,2,0,0 " ] ||
    fail "csv topology"

# five steps: one S line per F, one lateral axis per '['
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -o "$T/b.mtg" -o "segments:$T/b.csv" -o "$T/b.str" ||
    fail "run 5 steps"
nf=$(grep -c '^F$' "$T/b.str")
nb=$(grep -c '^\[$' "$T/b.str")
[ "$(grep -cE "(^|${tab})(/P1/A1/S1|\+A[0-9]+/S1|\^<S[0-9]+)${tab}" "$T/b.mtg")" -eq "$nf" ] ||
    fail "S lines != $nf"
[ "$(grep -cE '\+A[0-9]+/S1' "$T/b.mtg")" -eq "$nb" ] || fail "laterals != $nb"
[ "$(wc -l < "$T/b.csv")" -eq $((nf + 1)) ] || fail "csv rows"
awk -F, 'NR > 1 && ($1 != NR - 2 || $2 >= $1) { print "bad row " NR; exit 1 }' "$T/b.csv" ||
    fail "csv parents first"

# an L+C model without mechanics: lpfg's turtle (colour 1), SB/EB branches
printf '#include <lpfgall.h>\nmodule A(int);\nAxiom: F(1) SB() Left(30) F(2) EB() F(1) A(1);\n' \
    > "$T/lc.l"
"$BIN" run "$T/lc.l" -o "segments:$T/lc.csv" || fail "run lc.l"
[ "$(tail -n +2 "$T/lc.csv" | tr '\n' ' ')" = "0,-1,0,0,0,1,0,0,0,0,1,0,1,1,1 \
1,0,1,1,3,1,0,1,0,-1,2.73205081,0,1,1,2 2,0,0,0,5,1,0,1,0,0,2,0,1,1,1 " ] || fail "L+C segments"

# nothing drawn: a valid file, no plant
printf 'Lsystem: 1\nderivation length: 1\nAxiom: A\nA --> f[+f]\nendlsystem\n' > "$T/none.l"
"$BIN" run "$T/none.l" -o "$T/none.mtg" || fail "run none.l"
[ "$(tail -1 "$T/none.mtg" | cut -f1-2)" = "TOPO${tab}id" ] || fail "empty MTG ends at TOPO"
grep -q '^MTG:$' "$T/none.mtg" || fail "empty MTG header"

# a write that fails: exit 1, no file
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -n 1 -o "$T/missing/a.mtg" 2> "$T/err"
[ $? -eq 1 ] || fail "bad path: exit 1 expected"
[ ! -e "$T/missing/a.mtg" ] || fail "partial file"
grep -q 'missing' "$T/err" || fail "message names the path"
echo ok
