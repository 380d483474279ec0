#!/usr/bin/env bash
# What a model prints (printf) goes to stdout, to stderr when an output is written to stdout, and
# nowhere with --no-print; the written string is not touched by it.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/p.l" <<'MODEL'
#include <lpfgall.h>
derivation length: 2;
module A(int);
EndEach: { printf("step done\n"); }
Axiom: A(1);
A(i): { printf("A(%d)\n", i); produce A(i + 1); }
MODEL
"$bin" run "$tmp/p.l" >"$tmp/out" 2>"$tmp/err"
printf 'A(1)\nstep done\nA(2)\nstep done\n' >"$tmp/want"
head -4 "$tmp/out" | cmp - "$tmp/want"
test ! -s "$tmp/err"
"$bin" run "$tmp/p.l" -o str:- >"$tmp/str" 2>"$tmp/err"
printf 'A(3)\n' | cmp - "$tmp/str"
cmp "$tmp/err" "$tmp/want"
"$bin" run "$tmp/p.l" --no-print -o "$tmp/x.str" >"$tmp/out" 2>"$tmp/err"
! grep -q 'A(' "$tmp/out"
test ! -s "$tmp/err"
printf 'A(3)\n' | cmp - "$tmp/x.str"
# a bad format is a model error with its location, exit status 1, no output file
printf '#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\nA(i): { printf("%%d %%d", i); produce A(i); }\n' >"$tmp/bad.l"
if "$bin" run "$tmp/bad.l" -o "$tmp/bad.str" 2>"$tmp/err"; then exit 1; else test $? -eq 1; fi
grep -q 'bad.l:4:9: error: printf: the format has 2 conversions, 1 argument given' "$tmp/err"
test ! -e "$tmp/bad.str"
echo ok
