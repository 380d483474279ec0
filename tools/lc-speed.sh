#!/usr/bin/env bash
# The L+C dialect side by side with lpfg: whole-process wall time (and peak RSS) of
# `cambium run MODEL -o out.str` against `lpfg -b -o lsys.so -out out.str` with lpfg's model
# compiled once beforehand (its compile excluded, as docs/performance.md compares), median of
# paired runs (cambium then lpfg, alternating, so both see the same machine load).
#
# Models: the lpfg oracle models (../shared/oracles/vlab/lpfg-*), the 8-step quadratic Koch
# curve of that oracle, bench/lc/compute.l (production bodies that compute: a 400-term
# series in a function per module per step) and bench/lc/bodies.l (the same series in the
# production body itself). models/taylor-hell-fruit-tree.l needs the mechanics built-ins
# lpfg does not have, and models/taylor-hell-pendula.l (the A.4 listing) its vector built-ins,
# so they are timed for cambium alone, with native code and with the register code.
#
# Usage: tools/lc-speed.sh [CAMBIUM [RUNS]]   (from the repository root; defaults
# build/bin/cambium and 5 paired runs). Skips (exit 0 with a message) when the peers are not
# built: it needs /tmp/peers/env.sh (../shared/peers/README.md) or PEERS_ENV pointing to it.
set -uo pipefail
bin=$(realpath "${1:-build/bin/cambium}")
runs=${2:-5}
env=${PEERS_ENV:-/tmp/peers/env.sh}
shared=${CBM_SHARED:-$(realpath ..)/shared}
oracles=$shared/oracles/vlab
root=$(pwd)
test -f bench/lc/compute.l || { echo "run from the repository root" >&2; exit 2; }
if [ ! -f "$env" ]; then
    echo "lc-speed: SKIP: the peers are not built ($env is absent; ../shared/peers/README.md)"
    exit 0
fi
# shellcheck source=/dev/null
. "$env"
command -v lpfg >/dev/null || { echo "lc-speed: SKIP: lpfg is not on PATH after $env"; exit 0; }
[ -d "$oracles" ] || { echo "lc-speed: SKIP: $oracles is absent"; exit 0; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# cambium's native code of the models' functions goes to a cache of this run (docs/cli.md,
# --no-native); a first run of each model fills it, as lpfg's first run compiles its model
export XDG_CACHE_HOME=$tmp/cache

# wall seconds (bash's microsecond clock around the process: /usr/bin/time's %e counts in
# hundredths, too coarse for runs of 10 ms) and peak RSS (MB) of one command, "s mb"
measure() {
    local t0 t1
    t0=$EPOCHREALTIME
    /usr/bin/time -f "%M" -o "$tmp/t" "$@" >/dev/null 2>"$tmp/err" || {
        echo "FAIL"; return; }
    t1=$EPOCHREALTIME
    awk -v a="$t0" -v b="$t1" '{printf "%.4f %.0f", b - a, $1 / 1024}' "$tmp/t"
}
median() { sort -n | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

# name dir sidefiles...: the model dir is copied (lpfg writes next to the model)
compare() {
    local name=$1 dir=$2
    shift 2
    local w=$tmp/run-$name
    cp -r "$dir" "$w" && chmod -R u+w "$w"
    # the first run compiles the model into lsys.so (lpfg exits 0 even when that fails)
    (cd "$w" && lpfg -b -out "$w/peer.str" lsystem.l "$@" >"$w/compile.log" 2>&1)
    if [ ! -s "$w/lsys.so" ] || [ ! -s "$w/peer.str" ]; then
        printf "| %s | lpfg cannot run it (%s) |\n" "$name" "$(grep -m1 -i error "$w/compile.log")"
        return
    fi
    (cd "$w" && "$bin" run lsystem.l "$@" -o "$w/ours.str" >/dev/null 2>&1)
    : >"$w/c" && : >"$w/p" && : >"$w/cm" && : >"$w/pm"
    for _ in $(seq "$runs"); do
        read -r s m <<<"$(cd "$w" && measure "$bin" run lsystem.l "$@" -o "$w/ours.str")"
        echo "$s" >>"$w/c" && echo "$m" >>"$w/cm"
        read -r s m <<<"$(cd "$w" && measure lpfg -b -o "$w/lsys.so" -out "$w/peer.str" lsystem.l "$@")"
        echo "$s" >>"$w/p" && echo "$m" >>"$w/pm"
    done
    local c p
    c=$(median <"$w/c") p=$(median <"$w/p")
    printf "| %s | %s | %s | %s | %s | %.2f |\n" "$name" "$c" "$(median <"$w/cm")" "$p" \
        "$(median <"$w/pm")" "$(awk -v c="$c" -v p="$p" 'BEGIN {print c / p}')"
}

echo "cambium $bin, lpfg $(command -v lpfg); $runs paired runs; $(nproc) cores, $(uname -m)"
echo "| model | cambium s | cambium MB | lpfg s | lpfg MB | cambium / lpfg |"
echo "|---|---|---|---|---|---|"
for m in "$oracles"/lpfg-*/model; do
    n=$(basename "$(dirname "$m")")
    sides=$(cd "$m" && ls -- *.map *.mat *.v *.a *.fset 2>/dev/null | tr '\n' ' ')
    # shellcheck disable=SC2086
    compare "$n" "$m" $sides
done
mkdir -p "$tmp/koch8" && cp "$oracles"/lpfg-quadratic-koch/model/* "$tmp/koch8/" &&
    chmod u+w "$tmp"/koch8/* &&
    sed -i 's/^derivation length: *[0-9]*;/derivation length: 8;/' "$tmp/koch8/lsystem.l" &&
    compare koch-8-steps "$tmp/koch8" color.map view.v anim.a
mkdir -p "$tmp/compute" && cp "$root/bench/lc/compute.l" "$tmp/compute/lsystem.l" &&
    compare compute "$tmp/compute"
mkdir -p "$tmp/bodies" && cp "$root/bench/lc/bodies.l" "$tmp/bodies/lsystem.l" &&
    compare bodies "$tmp/bodies"
# cambium alone, native code (after a first run that compiles it) and the register code
for f in taylor-hell-fruit-tree taylor-hell-pendula; do
    "$bin" run "$root/models/$f.l" -o "$tmp/$f.str" >/dev/null 2>&1
    : >"$tmp/n" && : >"$tmp/r"
    for _ in $(seq "$runs"); do
        read -r s _ <<<"$(measure "$bin" run "$root/models/$f.l" -o "$tmp/$f.str")"
        echo "$s" >>"$tmp/n"
        read -r s _ <<<"$(measure "$bin" run "$root/models/$f.l" --no-native -o "$tmp/$f.str")"
        echo "$s" >>"$tmp/r"
    done
    printf "| %s (cambium alone: native code %s s, register code %s s) | - | - | - | - | - |\n" \
        "$f" "$(median <"$tmp/n")" "$(median <"$tmp/r")"
done
