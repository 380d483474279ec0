#!/bin/bash
# cambium run with cpfg sub-L-systems: the string and its homomorphism written one module per
# line, the geometry scaled by ?(id, s), a call to a missing L-system and syntax errors with
# file:line:col (exit 1, nothing written).
set -u
BIN=$1
SRC=${CBM_SOURCE:?}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# the string after 4 steps and its homomorphism (tests/lsys/sublsys-basic.l, worked by hand)
"$BIN" run "$SRC/tests/lsys/sublsys-basic.l" -o "$T/b.str" || fail "run -o"
[ "$(tr -d '\n' < "$T/b.str")" = 'IIIIIIII?(2,0.5)JIB(0)$IIII?(2,0.5)IB(0)$A(0)C(7)' ] ||
    fail "string: $(tr -d '\n' < "$T/b.str")"
[ "$(sed -n 9p "$T/b.str")" = '?(2,0.5)' ] || fail "one module per line: $(sed -n 9p "$T/b.str")"
"$BIN" run "$SRC/tests/lsys/sublsys-basic.l" --homomorphism -o "$T/h.str" || fail "homo"
[ "$(tr -d '\n' < "$T/h.str")" = 'FFFFFFFF?(2,0.5)F(2)fB(0)$FFFF?(2,0.5)fB(0)$A(0)C(7)' ] ||
    fail "homomorphism: $(tr -d '\n' < "$T/h.str")"

# geometry: after 2 steps F(4)?(2,0.25)F(4)$F(4) (B --> F(4) in L-system 2): the segments end
# at y = 4, 4 + 4 * 0.25 = 5 and 9
cat > "$T/g.l" <<'L'
Lsystem: 1
derivation length: 2
Axiom: A
A --> F(4)?(2,0.25)B$F(4)
endlsystem
Lsystem: 2
Axiom: B
B --> F(4)
endlsystem
L
"$BIN" run "$T/g.l" -o "$T/g.obj" || fail "geometry run"
ymax=$(awk '$1 == "v" { if ($3 > m) m = $3 } END { printf "%.3f", m }' "$T/g.obj")
[ "$ymax" = "9.000" ] || fail "scaled geometry: top at $ymax, 9 expected"

# a call to a missing L-system, known only when deriving (the step that reads it): exit 1, and,
# as for every runtime error, nothing written
cat > "$T/m.l" <<'L'
Lsystem: 1
derivation length: 4
Axiom: A(1)
A(x) --> ?(x)B$A(x+1)
endlsystem
Lsystem: 2
Axiom: B
endlsystem
L
"$BIN" run "$T/m.l" -o "$T/m.str" 2> "$T/err"
[ $? -eq 1 ] || fail "missing L-system: exit status"
grep -q "step 4: ?(3, ...) calls a sub-L-system, but no L-system of the file is labelled 3" \
    "$T/err" || fail "missing L-system message: $(cat "$T/err")"
[ ! -e "$T/m.str" ] || fail "output written after a runtime error"

# syntax errors in a sub-L-system: file:line:col, exit 1, no output
printf 'Lsystem: 1\nAxiom: ?(5)A$\nendlsystem\nLsystem: 1\nAxiom: A\nendlsystem\n' > "$T/bad.l"
"$BIN" run "$T/bad.l" -o "$T/bad.str" 2> "$T/err"
[ $? -eq 1 ] || fail "syntax error exit status"
grep -q "bad.l:4:10: error: a second L-system labelled 1" "$T/err" || fail "label: $(cat "$T/err")"
grep -q "bad.l:2:8: error: ?(5, ...) calls a sub-L-system" "$T/err" || fail "call: $(cat "$T/err")"
[ ! -e "$T/bad.str" ] || fail "output written after an error"
# the example model: nine leaves (L-system 2) and a flower (L-system 3) on the shoot; the leaf
# made at step k (1 to 9) has grown min(6, 14 - k) steps: eight are grown (K(6)), one is K(5)
"$BIN" run "$SRC/models/cpfg-herb-sublsystems.l" -o "$T/herb.str" -o "$T/herb.obj" || fail "herb"
[ "$(grep -c '^?(2,0.6)$' "$T/herb.str")" -eq 9 ] || fail "herb: nine leaves"
[ "$(grep -c '^?(3,1.5)$' "$T/herb.str")" -eq 1 ] || fail "herb: one flower"
[ "$(grep -c '^K(6)$' "$T/herb.str")" -eq 8 ] || fail "herb: eight grown leaves"
[ "$(grep -c '^K(5)$' "$T/herb.str")" -eq 1 ] || fail "herb: the youngest leaf"
[ -s "$T/herb.obj" ] || fail "herb: no geometry"
echo ok
