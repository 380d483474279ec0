#!/usr/bin/env bash
# Runs cambium and the peers (vlab's cpfg and lpfg) side by side on this machine and prints a
# Markdown table of whole-process wall time and peak resident set: paired runs, interleaved
# (cambium first in odd rounds, the peer first in even ones, so drift in the machine's load
# falls on both), the median of each and the median of the paired ratios. The runs:
#   - the quadratic Koch curve at 8 steps, in both dialects (cpfg's and lpfg's oracle models);
#   - ABOP fig. 2.8 at 11, 12 and 13 steps (tests/lsys/abop-2.8a.l with a view file written here);
#   - with geometry, the Koch curve at 6 steps and fig. 2.8 at 10 (at 8 and 13 steps the meshes
#     of 10^7 tubes would take gigabytes);
#   - every oracle model of ../shared/oracles/vlab at its own derivation length, with the side
#     files of the peer command in its ref/commands.txt;
# each "string" (only the derived string is written: cpfg -str, lpfg -out NAME.str, cambium
# -o NAME.str) and "geometry" (cpfg -ray, lpfg -out NAME.obj, cambium -o NAME.glb, its fastest mesh writer).
# lpfg compiles the model once (l2c and the C++ compiler) before the timed runs, which reuse it
# (-o lsys.so): its compile is excluded, as in ../shared/peers/README.md.
#
# Usage: tools/peers-compare.sh [-n RUNS] [-k FILTER] [-o TABLE.md]   (from the repository root)
#   -n RUNS    paired runs per case (default 5)
#   -k FILTER  only the cases whose name contains FILTER (e.g. koch, fig2.8, oracle)
#   -o FILE    also write the table to FILE
# Environment: CAMBIUM (default build/bin/cambium), CBM_SHARED (default ../shared),
# PEERS_ENV (default /tmp/peers/env.sh: puts cpfg, vlabcpp, lpfg on PATH with lpfg's variables).
# Skips (exit 0, with a message) when the peers or the oracle models are absent.
set -uo pipefail
# shellcheck source=tools/oracle-command.sh
. "$(dirname "$0")/oracle-command.sh"

runs=5
filter=
table_out=
while getopts "n:k:o:h" opt; do
    case $opt in
    n) runs=$OPTARG ;;
    k) filter=$OPTARG ;;
    o) table_out=$OPTARG ;;
    *) sed -n '2,25p' "$0" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done

root=$(pwd)
cambium=${CAMBIUM:-build/bin/cambium}
shared=${CBM_SHARED:-../shared}
peers_env=${PEERS_ENV:-/tmp/peers/env.sh}
case $cambium in /*) ;; *) cambium=$root/$cambium ;; esac
case $shared in /*) ;; *) shared=$root/$shared ;; esac

skip() { echo "peers-compare: skipped: $*" >&2; exit 0; }
[ -x "$cambium" ] || { echo "peers-compare: no $cambium (run make first)" >&2; exit 2; }
[ -f tests/lsys/abop-2.8a.l ] || { echo "peers-compare: run from the repository root" >&2; exit 2; }
[ -f "$peers_env" ] || skip "no $peers_env (the peers are built as $shared/peers/README.md says)"
# shellcheck disable=SC1090
. "$peers_env"
command -v cpfg >/dev/null || skip "cpfg is not on PATH after $peers_env"
command -v lpfg >/dev/null || skip "lpfg is not on PATH after $peers_env"
[ -x /usr/bin/time ] || skip "/usr/bin/time (Debian package time) is needed for the peak RSS"
oracles=$shared/oracles/vlab
[ -d "$oracles" ] || skip "no oracle models in $oracles"

work=$(mktemp -d "${TMPDIR:-/tmp}/peers-compare.XXXXXX")
trap 'rm -rf "$work"' EXIT

# One timed run in directory $1 of the command after it: prints "SECONDS KB" (wall clock from
# bash's microsecond clock around the process, peak RSS from /usr/bin/time), or "fail".
timed() {
    local dir=$1
    shift
    local t0 t1 rc
    t0=$EPOCHREALTIME
    (cd "$dir" && /usr/bin/time -f %M -o "$work/rss" "$@" >"$work/out" 2>&1)
    rc=$?
    t1=$EPOCHREALTIME
    if [ $rc -ne 0 ]; then
        echo fail
        return
    fi
    awk -v a="$t0" -v b="$t1" -v m="$(tail -1 "$work/rss")" 'BEGIN { printf "%.4f %d\n", b - a, m }'
}

median() { sort -g | awk '{ v[NR] = $1 } END { if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

rows=()
commands=()

# compare NAME PEER CAMBIUM_DIR PEER_DIR -- CAMBIUM ARGS... -- PEER ARGS...
compare() {
    local name=$1 peer=$2 cdir=$3 pdir=$4
    shift 4
    if [ -n "$filter" ] && [[ $name != *"$filter"* ]]; then
        return
    fi
    local -a cargs=() pargs=()
    shift # --
    while [ $# -gt 0 ] && [ "$1" != -- ]; do cargs+=("$1"); shift; done
    shift # --
    pargs=("$@")
    : >"$work/c.t"
    : >"$work/p.t"
    : >"$work/r.t"
    # the files each writes (the argument after -o, -str, -out or -ray): removed before a run,
    # checked after it (lpfg exits with 0 when it cannot load its compiled model)
    local -a outs=()
    local k
    for ((k = 0; k + 1 < ${#cargs[@]}; k++)); do
        [ "${cargs[k]}" = -o ] && outs+=("$cdir/${cargs[k + 1]}")
    done
    for ((k = 0; k + 1 < ${#pargs[@]}; k++)); do
        case ${pargs[k]} in -str | -out | -ray) outs+=("$pdir/${pargs[k + 1]}") ;; esac
    done
    local i c p f
    for ((i = 1; i <= runs; i++)); do
        rm -f "${outs[@]}"
        if ((i % 2)); then
            c=$(timed "$cdir" "$cambium" "${cargs[@]}")
            p=$(timed "$pdir" "${pargs[@]}")
        else
            p=$(timed "$pdir" "${pargs[@]}")
            c=$(timed "$cdir" "$cambium" "${cargs[@]}")
        fi
        for f in "${outs[@]}"; do
            [ -s "$f" ] || { c=fail; p="fail (no $(basename "$f"))"; }
        done
        if [ "$c" = fail ] || [[ $p == fail* ]]; then
            echo "peers-compare: $name: a run failed (cambium: $c, $peer: $p); left out" >&2
            tail -3 "$work/out" >&2
            return
        fi
        echo "$c" >>"$work/c.t"
        echo "$p" >>"$work/p.t"
        echo "$c $p" | awk '{ printf "%.6f %.6f\n", $1 / $3, $2 / $4 }' >>"$work/r.t"
    done
    local cs cm ps pm rs rm
    cs=$(cut -d' ' -f1 "$work/c.t" | median)
    cm=$(cut -d' ' -f2 "$work/c.t" | median)
    ps=$(cut -d' ' -f1 "$work/p.t" | median)
    pm=$(cut -d' ' -f2 "$work/p.t" | median)
    rs=$(cut -d' ' -f1 "$work/r.t" | median)
    rm=$(cut -d' ' -f2 "$work/r.t" | median)
    local row
    row=$(awk -v n="$name" -v peer="$peer" -v cs="$cs" -v cm="$cm" -v ps="$ps" -v pm="$pm" \
        -v rs="$rs" -v rm="$rm" 'BEGIN {
        printf "| %s | %s | %.3f | %.1f | %.3f | %.1f | **%.2f** | %.2f |", n, peer, cs, cm / 1024,
               ps, pm / 1024, rs, rm }')
    echo "$row" >&2
    rows+=("$row")
    local pc="${pargs[*]}"
    commands+=("| $name | \`cambium ${cargs[*]}\` | \`${pc//$work\//}\` |")
}

# A copy of model directory $1 in $work/$2 (the peers write their outputs into the model's
# folder); with $3 = N the derivation length of $4 (the .l file) becomes N in the copy.
copy_model() {
    local src=$1 dst=$work/$2
    rm -rf "$dst"
    mkdir -p "$dst"
    cp -r "$src"/. "$dst"/
    chmod -R u+w "$dst"
    if [ -n "${3:-}" ]; then
        sed -i "s/derivation length: *[0-9]*/derivation length: $3/" "$dst/$4"
    fi
    echo "$dst"
}

# Whether -k FILTER keeps one of the cases named after it (so that lpfg compiles only the models
# of the cases that run)
wanted() {
    local n
    [ -z "$filter" ] && return 0
    for n in "$@"; do [[ $n == *"$filter"* ]] && return 0; done
    return 1
}

# lpfg: compile the model of directory $1 once (untimed; a run without -o leaves lsys.so in the
# model's folder); args after it: the side files
lpfg_compile() {
    local dir=$1
    shift
    (cd "$dir" && rm -f lsys.so && lpfg -b -out compile.str lsystem.l "$@" >compile.log 2>&1)
    [ -f "$dir/lsys.so" ] ||
        { echo "peers-compare: lpfg could not compile $dir/lsystem.l:" >&2; tail -5 "$dir/compile.log" >&2; return 1; }
}

echo "peers-compare: $runs paired runs per case; work folder $work" >&2

# ---- the Koch curve, 8 steps
d=$(copy_model "$oracles/cpfg-quadratic-koch/model" koch-cpfg 8 fractal.l)
compare "Koch curve, 8 steps, string" cpfg "$d" "$d" -- run fractal.l fractal.map fractal.v \
    -o c.str -- cpfg -g -m fractal.map -str p.str fractal.l fractal.v
d=$(copy_model "$oracles/cpfg-quadratic-koch/model" koch-cpfg-6 6 fractal.l)
compare "Koch curve, 6 steps, geometry" cpfg "$d" "$d" -- run fractal.l fractal.map fractal.v \
    -o c.glb -- cpfg -g -m fractal.map -ray p.ray fractal.l fractal.v
d=$(copy_model "$oracles/lpfg-quadratic-koch/model" koch-lpfg 8 lsystem.l)
if wanted "Koch curve (L+C), 8 steps, string" && lpfg_compile "$d" color.map view.v anim.a; then
    compare "Koch curve (L+C), 8 steps, string" lpfg "$d" "$d" -- run lsystem.l color.map \
        view.v anim.a -o c.str -- lpfg -b -o "$d/lsys.so" -out p.str lsystem.l color.map view.v anim.a
fi
d=$(copy_model "$oracles/lpfg-quadratic-koch/model" koch-lpfg-6 6 lsystem.l)
if wanted "Koch curve (L+C), 6 steps, geometry" && lpfg_compile "$d" color.map view.v anim.a; then
    compare "Koch curve (L+C), 6 steps, geometry" lpfg "$d" "$d" -- run lsystem.l color.map \
        view.v anim.a -o c.glb -- lpfg -o "$d/lsys.so" -out p.obj lsystem.l color.map view.v anim.a
fi

# ---- ABOP fig. 2.8 at 11-13 steps, with the tropism of the figure (ABOP p. 60) in a view file
for n in 10 11 12 13; do
    d=$work/fig28-$n
    mkdir -p "$d"
    sed "s/derivation length: *[0-9]*/derivation length: $n/" tests/lsys/abop-2.8a.l >"$d/fig28.l"
    printf 'angle increment: 45\ninitial line width: 1 pixels\ntropism direction: 0,-1,0\ninitial elasticity: 0.22\n' >"$d/fig28.v"
    cp "$oracles/cpfg-quadratic-koch/model/fractal.map" "$d/fig28.map" # cpfg -g needs a colour map
    if [ "$n" -gt 10 ]; then
        compare "ABOP fig. 2.8, $n steps, string" cpfg "$d" "$d" -- run fig28.l fig28.map fig28.v \
            -o c.str -- cpfg -g -m fig28.map -str p.str fig28.l fig28.v
    else
        compare "ABOP fig. 2.8, $n steps, geometry" cpfg "$d" "$d" -- run fig28.l fig28.map fig28.v \
            -o c.glb -- cpfg -g -m fig28.map -ray p.ray fig28.l fig28.v
    fi
done

# ---- the oracle models, with their peer's own command (ref/commands.txt, second line)
for o in "$oracles"/*/; do
    o=${o%/}
    name=$(basename "$o")
    cmdline=$(oracle_command "$o")
    [ -n "$cmdline" ] || continue
    d=$(copy_model "$o/model" "oracle-$name")
    read -r -a words <<<"$cmdline"
    peer=${words[0]}
    # the model and side files of the command, without its options and outputs
    oracle_files "${words[@]}"
    if [ "$peer" = cpfg ]; then
        mapopt=()
        model=
        sides=()
        for f in "${files[@]}"; do
            case $f in
            *.map) mapopt=(-m "$f"); sides+=("$f") ;;
            *.mat) mapopt=(-M "$f"); sides+=("$f") ;;
            *.l) [ -z "$model" ] && model=$f || sides+=("$f") ;;
            *) sides+=("$f") ;;
            esac
        done
        view=${sides[${#sides[@]} - 1]}
        compare "oracle $name, string" cpfg "$d" "$d" -- run "$model" "${sides[@]}" -o c.str -- \
            cpfg -g "${mapopt[@]}" -str p.str "$model" "$view"
        compare "oracle $name, geometry" cpfg "$d" "$d" -- run "$model" "${sides[@]}" -o c.glb -- \
            cpfg -g "${mapopt[@]}" -ray p.ray "$model" "$view"
    else
        sides=("${files[@]:1}")
        wanted "oracle $name, string" "oracle $name, geometry" || continue
        lpfg_compile "$d" "${sides[@]}" || continue
        compare "oracle $name, string" lpfg "$d" "$d" -- run lsystem.l "${sides[@]}" -o c.str -- \
            lpfg -b -o "$d/lsys.so" -out p.str lsystem.l "${sides[@]}"
        compare "oracle $name, geometry" lpfg "$d" "$d" -- run lsystem.l "${sides[@]}" -o c.glb -- \
            lpfg -o "$d/lsys.so" -out p.obj lsystem.l "${sides[@]}"
    fi
done

cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1)
{
    echo "Machine: $(nproc) cores, ${cpu:-unknown CPU}, $(uname -sr); load average at the end:" \
        "$(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M UTC'); $runs paired runs" \
        "per case (tools/peers-compare.sh -n $runs)."
    echo
    echo "| run | peer | cambium s | cambium MB | peer s | peer MB | time ratio | memory ratio |"
    echo "|---|---|---|---|---|---|---|---|"
    printf '%s\n' "${rows[@]}"
    echo
    echo "Times and memory are medians; the ratios (cambium / peer) are the medians of the paired"
    echo "runs' ratios (below 1: cambium is faster or smaller)."
    echo
    echo "| run | cambium command | peer command |"
    echo "|---|---|---|"
    printf '%s\n' "${commands[@]}"
} >"$work/table.md"
cat "$work/table.md"
[ -z "$table_out" ] || cp "$work/table.md" "$table_out"
