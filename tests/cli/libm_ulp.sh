#!/bin/bash
# The libm marks of lpfg_bodies_match_walker (tests/test_lpfg.c) checked both ways: the test run
# with every transcendental result of libm moved by 1 ULP (tests/cli/libm_ulp_shim.c, preloaded)
# must find the marked models' strings changed and every other model's digest still equal.
# Needs the system's cc and glibc's LD_PRELOAD; skipped (77) without them or under a sanitizer
# whose runtime must come first.
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SRC=${CBM_SOURCE:?}
TEST=$(dirname "$BIN")/test_lpfg
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
skip() { echo "SKIP: $*"; exit 77; }
[ -x "$TEST" ] || skip "no test_lpfg beside $BIN"
command -v cc >/dev/null || skip "no C compiler (cc) for the shim"
ldd --version 2>&1 | grep -qiE "glibc|gnu libc" || skip "not glibc"
cc -O2 -shared -fPIC -o "$T/shim.so" "$SRC/tests/cli/libm_ulp_shim.c" -ldl -lm ||
    { echo "FAIL: cannot build the shim"; exit 1; }
CBM_LIBM_MOVED=1 LD_PRELOAD="$T/shim.so" "$TEST" lpfg_bodies_match_walker >"$T/out" 2>&1
rc=$?
grep -q "runtime does not come first" "$T/out" && skip "a sanitizer's runtime must be preloaded first"
if [ $rc -ne 0 ] && [ $rc -ne 77 ]; then
    echo "FAIL: lpfg_bodies_match_walker with libm moved by 1 ULP (status $rc):"
    sed 's/^/    /' "$T/out" | head -20
    exit 1
fi
echo "ok: the libm marks hold with libm moved by 1 ULP"
