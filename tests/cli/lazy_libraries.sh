#!/usr/bin/env bash
# Embree and cairo are loaded when first needed (src/core/dynlib.h), not at the start: the tool
# does not link them, a run that writes a mesh does not map them, a run that renders a picture
# of tubes with a legend maps both (the loader's own account of the objects it maps, LD_DEBUG=files),
# and a plot maps cairo alone.
set -euo pipefail
bin=${1:?}
src=${CBM_SOURCE:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
if command -v readelf >/dev/null && grep -q __asan_init <<<"$(readelf -s "$bin")"; then
    echo "skip: a sanitizer build links Embree from the start (cmake/warnings.cmake says why)"
    exit 77
fi
if command -v readelf >/dev/null; then
    needed=$(readelf -d "$bin" | grep NEEDED || true)
    for lib in embree tbb cairo stdc++; do
        ! grep -q "$lib" <<<"$needed" || fail "the tool links $lib: $needed"
    done
fi
# the objects the dynamic loader maps during a run (the tool's output discarded)
mapped() { LD_DEBUG=files LD_DEBUG_OUTPUT="$tmp/ld" "$bin" "$@" >/dev/null 2>&1; cat "$tmp"/ld.*; rm -f "$tmp"/ld.*; }
model=$src/tests/lsys/abop-2.8a.l
m=$(mapped run "$model" -n 4 -o "$tmp/a.glb")
[ -s "$tmp/a.glb" ] || fail "no a.glb"
grep -q 'file=libc\.so' <<<"$m" || { echo "skip: LD_DEBUG=files says nothing here"; exit 77; }
! grep -qE 'file=lib(embree3|cairo)' <<<"$m" || fail "a mesh run maps Embree or cairo"
m=$(mapped demo --segments 50 --color-by order -o "$tmp/a.png")
[ -s "$tmp/a.png" ] || fail "no a.png"
grep -q 'file=libembree3' <<<"$m" || fail "a render did not load Embree"
grep -q 'file=libcairo' <<<"$m" || fail "a render with a legend did not load cairo"
printf 'x,y\n1,2\n2,3\n' >"$tmp/t.csv"
m=$(mapped plot "$tmp/t.csv" -y y -o "$tmp/p.svg")
[ -s "$tmp/p.svg" ] || fail "no p.svg"
grep -q 'file=libcairo' <<<"$m" || fail "a plot did not load cairo"
! grep -q 'file=libembree3' <<<"$m" || fail "a plot loaded Embree"
echo "ok: Embree and cairo mapped only by the runs that use them"
