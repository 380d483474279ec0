#!/bin/bash
# cambium run: outputs, options, exit statuses and error messages.
set -u
BIN=$1
SRC=${CBM_SOURCE:?}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# the derived string, one module per line
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -o "$T/a.str" || fail "run -o"
[ "$(wc -l < "$T/a.str")" -eq 7811 ] || fail "7811 modules expected"
[ "$(head -3 "$T/a.str" | tr -d '\n')" = "F[+" ] || fail "first modules"

# -n and -D
"$BIN" run "$SRC/tests/lsys/macros.l" -D N=5 -o "$T/m.str" || fail "-D"
[ "$(head -1 "$T/m.str")" = "A(9,4,5)" ] || fail "-D N=5 gives $(head -1 "$T/m.str")"
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -n 2 -o "$T/n.str" || fail "-n"
[ "$(wc -l < "$T/n.str")" -eq 61 ] || fail "-n 2"

# --every writes NAME.STEP.EXT
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" -n 4 --every 2 -o "$T/e.str" || fail "--every"
for s in 0000 0002 0004; do [ -f "$T/e.$s.str" ] || fail "missing e.$s.str"; done
[ "$(wc -l < "$T/e.0002.str")" -eq 61 ] || fail "e.0002"

# --homomorphism
"$BIN" run "$SRC/tests/lsys/decomposition-homomorphism.l" --homomorphism -o "$T/h.str" || fail "homo"
[ "$(tr -d '\n' < "$T/h.str")" = "GGGGGGGGA" ] || fail "homomorphism string"

# float32 switch
"$BIN" run "$SRC/tests/lsys/float64.l" --float32 -o "$T/f.str" || fail "--float32"
[ "$(cat "$T/f.str")" = "B(1.00000012)" ] || fail "float32 gives $(cat "$T/f.str")"

# summary without -o
out=$("$BIN" run "$SRC/tests/lsys/abop-1.24b.l") || fail "summary"
echo "$out" | grep -q "5 steps, 9373 modules" || fail "summary: $out"

# limits: exit 1, the last complete step is written
"$BIN" run "$SRC/tests/lsys/abop-1.24a.l" --max-modules 1000 -o "$T/l.str" 2> "$T/err"
[ $? -eq 1 ] || fail "limit exit status"
grep -q "1000 modules" "$T/err" || fail "limit message: $(cat "$T/err")"
[ "$(wc -l < "$T/l.str")" -eq 311 ] || fail "last complete step (311 modules)"

# syntax errors: file:line:col, exit 1, no output file
printf 'Lsystem: 1\nderivation length: 2\nAxiom: A(\nA --> B(1+)\nendlsystem\n' > "$T/bad.l"
"$BIN" run "$T/bad.l" -o "$T/bad.str" 2> "$T/err"
[ $? -eq 1 ] || fail "syntax error exit status"
grep -q "bad.l:3:10: error: expected an expression" "$T/err" || fail "message: $(cat "$T/err")"
grep -q "bad.l:4:" "$T/err" || fail "second error: $(cat "$T/err")"
[ ! -e "$T/bad.str" ] || fail "output written after an error"

# bad usage: exit 2
"$BIN" run 2>/dev/null; [ $? -eq 2 ] || fail "no model"
"$BIN" run "$SRC/tests/lsys/cut.l" -o "$T/x.unknown" 2>/dev/null; [ $? -eq 2 ] || fail "unknown output"
"$BIN" run "$SRC/tests/lsys/cut.l" -n -3 2>/dev/null; [ $? -eq 2 ] || fail "bad -n"
"$BIN" run "$SRC/tests/lsys/cut.l" --bogus 2>/dev/null; [ $? -eq 2 ] || fail "unknown option"
"$BIN" run "$T/missing.l" 2>/dev/null; [ $? -eq 1 ] || fail "missing model"
echo ok
