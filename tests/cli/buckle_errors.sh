#!/usr/bin/env bash
# cambium buckle: bad usage exits 2 naming the option; a column that never buckles within the
# segment limit is a job failure (exit 1) with a message.
set -uo pipefail
bin=$1
fail() { echo "FAIL: $*"; exit 1; }
"$bin" buckle --E 1e10 --density 600 --radius 0.05 2>"err.$$"; test $? -eq 2 || fail "missing --segment"
grep -q -- "--segment is required" "err.$$" || fail "missing option not named"
"$bin" buckle --E -1 --density 600 --radius 0.05 --segment 0.1 2>"err.$$"; test $? -eq 2 || fail "negative E"
grep -q -- "--E must be positive" "err.$$" || fail "negative E not named"
"$bin" buckle --E abc --density 600 --radius 0.05 --segment 0.1 2>"err.$$"; test $? -eq 2 || fail "bad number"
"$bin" buckle --E 1e10 --density 600 --radius 0.05 --segment 0.1 --wobble 2>"err.$$"; test $? -eq 2 || fail "unknown option"
"$bin" buckle --E 1e10 --density 600 --radius 0.05 --segment 0.1 --max-segments 20 2>"err.$$"
test $? -eq 1 || fail "limit should exit 1"
grep -q "still stands at 20 segments" "err.$$" || fail "limit message"
rm -f "err.$$"
echo ok
