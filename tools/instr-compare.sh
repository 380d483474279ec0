#!/usr/bin/env bash
# Instructions executed by two cambium binaries on the small runs of tools/peers-compare.sh: every
# oracle model of ../shared/oracles/vlab with the side files of its peer command, writing the
# string (-o c.str) and the geometry (-o c.glb), and the L+C bodies that compute
# (bench/lc/compute.l, bench/lc/bodies.l, native code from a warm cache). Counted by valgrind's
# callgrind (the whole process, the dynamic loader included), which a loaded machine does not
# disturb as it does wall time. Prints a Markdown table: before, after, after / before.
#
# Usage: tools/instr-compare.sh BEFORE AFTER [FILTER]   (two cambium binaries; from the
# repository root; FILTER: only the runs whose name contains it)
# Environment: CBM_SHARED (default ../shared). Skips (exit 0, with a message) without valgrind.
set -uo pipefail
# shellcheck source=tools/oracle-command.sh
. "$(dirname "$0")/oracle-command.sh"
[ $# -ge 2 ] || { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
before=$(realpath "$1") after=$(realpath "$2") filter=${3:-}
root=$(pwd)
[ -f bench/lc/compute.l ] || { echo "instr-compare: run from the repository root" >&2; exit 2; }
command -v valgrind >/dev/null || { echo "instr-compare: skipped: no valgrind"; exit 0; }
shared=${CBM_SHARED:-$(realpath ..)/shared}
work=$(mktemp -d "${TMPDIR:-/tmp}/instr-compare.XXXXXX")
trap 'rm -rf "$work"' EXIT
export XDG_CACHE_HOME=$work/cache

# instructions of one run of binary $1 in directory $2 with the arguments after them
count() {
    local bin=$1 dir=$2
    shift 2
    (cd "$dir" && "$bin" "$@" >/dev/null 2>&1) || { echo fail; return; } # warms the cache
    (cd "$dir" && valgrind --tool=callgrind --callgrind-out-file="$work/cg.out" "$bin" "$@" \
        2>&1 >/dev/null | sed -n 's/.*Collected : *\([0-9]*\).*/\1/p')
}

# name dir args...
row() {
    local name=$1 dir=$2
    shift 2
    case $name in *"$filter"*) ;; *) return ;; esac
    local b a
    b=$(count "$before" "$dir" "$@")
    a=$(count "$after" "$dir" "$@")
    awk -v n="$name" -v b="$b" -v a="$a" 'BEGIN {
        if (b + 0 > 0 && a + 0 > 0) printf "| %s | %.1f M | %.1f M | %.3f |\n", n, b / 1e6, a / 1e6, a / b
        else printf "| %s | %s | %s | - |\n", n, b, a }'
}

echo "| run | before | after | after / before |"
echo "|---|---|---|---|"
oracles=$shared/oracles/vlab
if [ -d "$oracles" ]; then
    for o in "$oracles"/*/; do
        o=${o%/}
        name=$(basename "$o")
        cmdline=$(oracle_command "$o")
        [ -n "$cmdline" ] || continue
        read -r -a words <<<"$cmdline"
        oracle_files "${words[@]}"
        d=$work/$name
        cp -r "$o/model" "$d" && chmod -R u+w "$d"
        row "oracle $name, string" "$d" run "${files[@]}" -o c.str
        row "oracle $name, geometry" "$d" run "${files[@]}" -o c.glb
    done
else
    echo "instr-compare: no $oracles: the oracle models are skipped" >&2
fi
for m in compute bodies; do
    row "bench/lc/$m.l, string" "$root" run "bench/lc/$m.l" -o "$work/$m.str"
done
