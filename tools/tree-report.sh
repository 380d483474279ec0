#!/usr/bin/env bash
# Where the shipped trees stand against real trees: grows every built-in tree model of
# `cambium grow` for its own years (its default seed), measures the final tree as a forester
# would (`cambium info --json` on the summary, docs/models.md "Measured realism") and writes the
# table into docs/models.md between the lines `<!-- tree-report: begin -->` and
# `<!-- tree-report: end -->`, so the figures there always come from the code.
#
# Usage (from the repository root, after `make`):
#   tools/tree-report.sh            rewrite the table in docs/models.md
#   tools/tree-report.sh --print    print the table on stdout, change nothing
# CAMBIUM=path/to/cambium overrides the tool (default build/bin/cambium).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CAMBIUM:-build/bin/cambium}
doc=docs/models.md
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

models=$("$bin" grow --help | sed -n 's/^built-in models: *//p')
[ -n "$models" ] || { echo "tree-report: no built-in models listed by grow --help" >&2; exit 1; }
table="| model | years | segments | height (m) | trunk ⌀ (cm) | crown width (m) | H / H_cr | pipe exponent: median (quartiles) | branch angle (°): median (quartiles) | stress ratio: median, 90 %, share > 0.5 | segments intersecting |
|---|---|---|---|---|---|---|---|---|---|---|"
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
    table="$table
$row"
done

if [ "${1:-}" = --print ]; then
    printf '%s\n' "$table"
    exit 0
fi
grep -q '^<!-- tree-report: begin -->$' "$doc" && grep -q '^<!-- tree-report: end -->$' "$doc" ||
    { echo "tree-report: $doc lacks the tree-report markers" >&2; exit 1; }
printf '%s\n' "$table" >"$tmp/table"
awk -v tf="$tmp/table" '
    /^<!-- tree-report: begin -->$/ { print; while ((getline l < tf) > 0) print l; skip = 1; next }
    /^<!-- tree-report: end -->$/ { skip = 0 }
    !skip { print }' "$doc" >"$tmp/doc"
cp "$tmp/doc" "$doc"
echo "tree-report: $doc updated ($(wc -w <<<"$models") models)"
