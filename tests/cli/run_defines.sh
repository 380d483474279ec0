#!/bin/bash
# cambium run -D NAME=VALUE: a name the model defines, tests or uses is taken; any other name is
# an error naming it (a misspelt parameter must not be ignored silently), in both dialects.
set -u
BIN=$1
SRC=${CBM_SOURCE:?}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# cpfg dialect: d1 is #defined, dd1 is not
"$BIN" run "$SRC/tests/lsys/abop-2.8a.l" -n 1 -D d1=90 -o "$T/a.str" || fail "-D d1 (defined)"
"$BIN" run "$SRC/tests/lsys/abop-2.8a.l" -n 1 -D dd1=90 -o "$T/b.str" 2>"$T/err"
[ $? -eq 1 ] || fail "-D dd1 should fail with status 1"
grep -q "abop-2.8a.l: error: -D dd1: the model does not define dd1" "$T/err" ||
    fail "message: $(cat "$T/err")"
[ ! -e "$T/b.str" ] || fail "an output was written"
# a name the model tests with #ifdef counts as known
printf '#ifdef BIG\n#define N 3\n#else\n#define N 1\n#endif\nLsystem: 1\nderivation length: 0\nAxiom: F(N)\nendlsystem\n' \
    >"$T/ifdef.l"
"$BIN" run "$T/ifdef.l" -D BIG -o "$T/i.str" || fail "-D BIG (tested by #ifdef)"
[ "$(cat "$T/i.str")" = "F(3)" ] || fail "-D BIG gives $(cat "$T/i.str")"
"$BIN" run "$T/ifdef.l" -D SMALL -o "$T/j.str" 2>"$T/err" && fail "-D SMALL accepted"
grep -q "the model does not define SMALL" "$T/err" || fail "message: $(cat "$T/err")"

# L+C dialect: TROP is #defined, TROPISM is not
m="$SRC/models/jirasek-s-branch.l"
"$BIN" run "$m" -n 1 -D TROP=0.3 -o "$T/c.str" || fail "L+C -D TROP (defined)"
"$BIN" run "$m" -n 1 -D TROPISM=0.3 -o "$T/d.str" 2>"$T/err"
[ $? -eq 1 ] || fail "L+C -D TROPISM should fail with status 1"
grep -q "jirasek-s-branch.l: error: -D TROPISM: the model does not define TROPISM" "$T/err" ||
    fail "L+C message: $(cat "$T/err")"
[ ! -e "$T/d.str" ] || fail "L+C: an output was written"
echo ok
