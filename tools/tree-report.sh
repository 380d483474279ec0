#!/usr/bin/env bash
# Where the shipped trees stand against real trees: grows every built-in tree model of
# `cambium grow` for its own years (its default seed), measures the final tree as a forester
# would (`cambium info --json` on the summary, docs/models.md "Measured realism") and writes the
# table into docs/models.md between the lines `<!-- tree-report: begin -->` and
# `<!-- tree-report: end -->`, so the figures there always come from the code. Branch
# intersections are also measured over seeds 1-SEEDS (default 5; 0: not) for every model (the
# real-wood ones also with the thesis' upright roll, stem_frame = 0, to show what it does), and
# for every model in the language (models/*.l: its segments table, the mechanical one or the
# turtle's; over seeds 1-LC_SEEDS, default 3, for the models with a SEED) a second table between
# `<!-- tree-report-lc: begin -->` and `<!-- tree-report-lc: end -->`.
#
# Usage (from the repository root, after `make`):
#   tools/tree-report.sh            rewrite both tables in docs/models.md
#   tools/tree-report.sh --lc       rewrite only the second (the models in the language)
#   tools/tree-report.sh --print    print the tables on stdout, change nothing (with --lc: the
#                                   second)
# CAMBIUM=path/to/cambium overrides the tool (default build/bin/cambium).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CAMBIUM:-build/bin/cambium}
nseeds=${SEEDS:-5}
doc=docs/models.md
print=0 only_lc=0
for a in "$@"; do
    case $a in
    --print) print=1 ;;
    --lc) only_lc=1 ;;
    *) echo "tree-report: unknown option $a (--print, --lc)" >&2; exit 2 ;;
    esac
done
[ -x "$bin" ] || { echo "tree-report: $bin not found (run make first)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# a number of the measures object: top-level key, or KEY.FIELD of a quantile object
num() {
    local json=$1 key=$2
    if [[ $key == *.* ]]; then
        sed -n "s/.*\"${key%%.*}\":{[^}]*\"${key#*.}\":\([^,}]*\).*/\1/p" <<<"$json"
    else
        sed -n "s/.*\"measures\":{.*\"$key\":\([^,}]*\).*/\1/p" <<<"$json"
    fi
}
# median (quartiles) of a quantile object, "–" when it is empty
mq() {
    local json=$1 key=$2 f=$3
    local m
    m=$(num "$json" "$key.median")
    if [ -z "$m" ] || [ "$m" = null ]; then printf '–'; return; fi
    LC_ALL=C printf "$f ($f–$f)" "$m" "$(num "$json" "$key.q25")" "$(num "$json" "$key.q75")"
}
# printf with a format, "–" for a missing value (JSON null)
fmt() {
    local f=$1 v=$2
    if [ -z "$v" ] || [ "$v" = null ]; then printf '–'; else LC_ALL=C printf "$f" "$v"; fi
}

table=""
if [ "$only_lc" = 0 ]; then
models=$("$bin" grow --help | sed -n 's/^built-in models: *//p')
[ -n "$models" ] || { echo "tree-report: no built-in models listed by grow --help" >&2; exit 1; }
# intersecting fraction (%) of model $1 over seeds 1-nseeds, extra grow options after it:
# "median (min–max)"
over_seeds() {
    local m=$1
    shift
    local fr=()
    for s in $(seq 1 "$nseeds"); do
        "$bin" grow "$m" -D seed="$s" "$@" --quiet -o "$tmp/s.json"
        fr+=("$(num "$("$bin" info --json "$tmp/s.json")" intersecting_fraction)")
    done
    printf '%s\n' "${fr[@]}" | sort -g | awk '{ v[NR] = 100 * $1 }
        END { md = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
              printf "%.2f (%.2f–%.2f)", md, v[1], v[NR] }'
}
seeds_head=""
seeds_sep=""
if [ "$nseeds" -gt 0 ]; then
    seeds_head=" segments intersecting (%), seeds 1–$nseeds: median (range) | the same with the thesis' upright roll (stem_frame = 0) |"
    seeds_sep="---|---|"
fi
table="| model | years | segments | height (m) | trunk ⌀ (cm) | crown width (m) | H / H_cr | pipe exponent: median (quartiles) | branch angle (°): median (quartiles) | stress ratio: median, 90 %, share > 0.5 | segments intersecting |$seeds_head
|---|---|---|---|---|---|---|---|---|---|---|$seeds_sep"
for m in $models; do
    "$bin" grow "$m" --quiet -o "$tmp/$m.json"
    j=$("$bin" info --json "$tmp/$m.json")
    years=$(sed -n 's/.*"years_grown":\([0-9]*\).*/\1/p' "$tmp/$m.json")
    at=$(num "$j" diameter_at | tr -d '"')
    dia=$(fmt '%.1f' "$(awk -v d="$(num "$j" diameter_m)" 'BEGIN{print d*100}')")
    [ "$at" = base ] && dia="$dia (base)"
    row="| \`$m\` | $years | $(num "$j" segments) | $(fmt '%.2f' "$(num "$j" height_m)") | $dia"
    row="$row | $(fmt '%.2f' "$(num "$j" crown_width_m)") | $(fmt '%.2f' "$(num "$j" buckling_ratio)")"
    row="$row | $(mq "$j" pipe_exponent '%.2f') | $(mq "$j" branch_angle_deg '%.0f')"
    share=$(num "$j" stress_above_half)
    row="$row | $(fmt '%.3f' "$(num "$j" stress_ratio.median)"), $(fmt '%.3f' "$(num "$j" stress_ratio.q90)"), $(fmt '%.1f %%' "$(awk -v s="$share" 'BEGIN{print s*100}')")"
    frac=$(num "$j" intersecting_fraction)
    row="$row | $(fmt '%.1f %%' "$(awk -v s="$frac" 'BEGIN{print s*100}')") |"
    if [ "$nseeds" -gt 0 ]; then
        if [ "$m" = fruit-tree-thesis-high-mor ]; then
            row="$row – (23,000 segments, 30 s a seed) | – |" # as tools/models-figures.sh
        else
            row="$row $(over_seeds "$m") |"
            if grep -q '^stem_frame *= *1' <<<"$("$bin" grow "$m" --params)"; then
                row="$row $(over_seeds "$m" -D stem_frame=0) |"
            else
                row="$row (it is) |"
            fi
        fi
    fi
    table="$table
$row"
done
fi

# every model in the language (models/*.l): its segments table, mechanical or the turtle's, from
# the model as shipped, and over seeds 1-LC_SEEDS (default 3; -D SEED=s) for the models that
# draw random numbers from a SEED
lc_seeds=${LC_SEEDS:-3}
lc="| model (\`cambium run\`) | table | segments | segments intersecting | seeds 1–$lc_seeds: segments intersecting (%), median (range) |
|---|---|---|---|---|"
for f in models/*.l; do
    "$bin" run "$f" -o "segments:$tmp/lc.csv" >/dev/null
    j=$("$bin" info --json "$tmp/lc.csv")
    kind=$(sed -n 's/.*"table":"\([a-z]*\) segments".*/\1/p' <<<"$j")
    frac=$(num "$j" intersecting_fraction)
    seeds="– (no random numbers)"
    if grep -q '^#define SEED ' "$f" && [ "$lc_seeds" -gt 0 ]; then
        fr=()
        for s in $(seq 1 "$lc_seeds"); do
            "$bin" run "$f" -D SEED="$s" -o "segments:$tmp/lc.csv" >/dev/null
            fr+=("$(num "$("$bin" info --json "$tmp/lc.csv")" intersecting_fraction)")
        done
        seeds=$(printf '%s\n' "${fr[@]}" | sort -g | awk '{ v[NR] = 100 * $1 }
            END { md = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
                  printf "%.2f (%.2f–%.2f)", md, v[1], v[NR] }')
    fi
    lc="$lc
| \`$f\` | $kind | $(num "$j" segments) | $(fmt '%.1f %%' "$(awk -v s="$frac" 'BEGIN{print s*100}')") ($(num "$j" intersecting_segments)) | $seeds |"
done

if [ "$print" = 1 ]; then
    [ -n "$table" ] && printf '%s\n\n' "$table"
    printf '%s\n' "$lc"
    exit 0
fi
# replaces the lines between <!-- NAME: begin --> and <!-- NAME: end --> with a file
put() {
    local name=$1 file=$2
    grep -q "^<!-- $name: begin -->\$" "$doc" && grep -q "^<!-- $name: end -->\$" "$doc" ||
        { echo "tree-report: $doc lacks the $name markers" >&2; exit 1; }
    awk -v tf="$file" -v b="<!-- $name: begin -->" -v e="<!-- $name: end -->" '
        $0 == b { print; while ((getline l < tf) > 0) print l; skip = 1; next }
        $0 == e { skip = 0 }
        !skip { print }' "$doc" >"$tmp/doc"
    cp "$tmp/doc" "$doc"
}
printf '%s\n' "$lc" >"$tmp/lc"
put tree-report-lc "$tmp/lc"
if [ "$only_lc" = 0 ]; then
    printf '%s\n' "$table" >"$tmp/table"
    put tree-report "$tmp/table"
    echo "tree-report: $doc updated ($(wc -w <<<"$models") models, $(ls models/*.l | wc -l) in the language)"
else
    echo "tree-report: $doc updated ($(ls models/*.l | wc -l) models in the language)"
fi
