#!/usr/bin/env bash
# Two cambium binaries write the same bytes: every oracle model of ../shared/oracles/vlab (cpfg
# and L+C) at its own derivation length, written as .str, .glb, .obj and .ply, and the demo tree
# (`cambium demo`, a still and an animation) in the same formats; `cmp` of each pair of files.
# For changes that must not move an output (docs/performance.md).
#
# Usage: tools/same-outputs.sh BEFORE AFTER   (two cambium binaries; from the repository root)
# Environment: CBM_SHARED (default ../shared). Prints one line per difference and a count; exit 1
# when a file differs or a run fails with one binary only. Skips the oracle models (with a
# message) when ../shared is absent.
set -uo pipefail
# shellcheck source=tools/oracle-command.sh
. "$(dirname "$0")/oracle-command.sh"
[ $# -eq 2 ] || { sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
before=$(realpath "$1") after=$(realpath "$2")
shared=${CBM_SHARED:-$(realpath ..)/shared}
work=$(mktemp -d "${TMPDIR:-/tmp}/same-outputs.XXXXXX")
trap 'rm -rf "$work"' EXIT
export XDG_CACHE_HOME=$work/cache
compared=0 differ=0

# name dir args... : runs both binaries in copies of dir with the args, then cmp's every output
check() {
    local name=$1 dir=$2
    shift 2
    local ext rb ra
    for ext in str glb obj ply; do
        for side in before after; do
            rm -rf "${work:?}/$side" && cp -r "$dir" "$work/$side" && chmod -R u+w "$work/$side"
        done
        (cd "$work/before" && "$before" "$@" -o "out.$ext" >/dev/null 2>&1)
        rb=$?
        (cd "$work/after" && "$after" "$@" -o "out.$ext" >/dev/null 2>&1)
        ra=$?
        if [ $rb -ne $ra ]; then
            echo "DIFFERS: $name .$ext: exit status $rb before, $ra after"
            differ=$((differ + 1))
        elif [ $rb -eq 0 ]; then
            compared=$((compared + 1))
            cmp -s "$work/before/out.$ext" "$work/after/out.$ext" ||
                { echo "DIFFERS: $name .$ext"; differ=$((differ + 1)); }
        fi
    done
}

oracles=$shared/oracles/vlab
if [ -d "$oracles" ]; then
    for o in "$oracles"/*/; do
        o=${o%/}
        cmdline=$(oracle_command "$o")
        [ -n "$cmdline" ] || continue
        read -r -a words <<<"$cmdline"
        oracle_files "${words[@]}"
        check "$(basename "$o")" "$o/model" run "${files[@]}"
    done
else
    echo "same-outputs: no $oracles: the oracle models are skipped"
fi
mkdir -p "$work/empty"
check "demo tree" "$work/empty" demo --segments 400 --seed 3
check "demo animation" "$work/empty" demo --segments 200 --seed 5 --frames 3
echo "same-outputs: $compared pairs of files compared, $differ differ"
[ $differ -eq 0 ]
