#!/usr/bin/env bash
# cambium run on Taylor-Hell's fruit tree in the L+C dialect. The thesis' constants
# (models/taylor-hell-fruit-tree-thesis.l, or -D THESIS_WOOD=1): two years grow the same 127
# internodes as the native model (the same bud fates before the first fruit), the picture and the
# string are written; a bad parameter stops the run with exit 1 and the call named. The real-wood
# default (models/taylor-hell-fruit-tree.l), over seeds: no seed collapses, spurs bear leaves and
# apples from year 4, reaction wood stays within its bound a/b <= 1.5 (without it, seed 1 reaches
# 2.4 in 4 years).
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
m="$CBM_SOURCE/models/taylor-hell-fruit-tree-thesis.l"
"$bin" run "$m" -D YEARS=2 -o "$tmp/tree.str" -o "$tmp/tree.svg"
test -s "$tmp/tree.svg"
head -1 "$tmp/tree.str" | grep -q '^Year(1,4,0,0)$'
test "$(grep -c '^I({' "$tmp/tree.str")" -eq 127
test "$(grep -c '^Apex(' "$tmp/tree.str")" -eq 38
set +e
"$bin" run "$m" -D KAPPA=0 -D YEARS=1 -o "$tmp/bad.str" 2>"$tmp/err"
rc=$?
set -e
test "$rc" -eq 1
grep -q 'RingRate(kappa in (0, 1\]' "$tmp/err"
test ! -e "$tmp/bad.str"

# the same model through the switch on the real-wood file
"$bin" run "$CBM_SOURCE/models/taylor-hell-fruit-tree.l" -D THESIS_WOOD=1 -D YEARS=2 \
    -o "$tmp/switch.str"
test "$(grep -c '^I({' "$tmp/switch.str")" -eq 127

# real wood, seeds 1-5, 4 years (the first crop): every seed grows a tree of a few hundred
# internodes over 1 m high (no collapse), every seed has spur rosettes, most bear apples on them
r="$CBM_SOURCE/models/taylor-hell-fruit-tree.l"
fruiting=0
for seed in 1 2 3 4 5; do
    "$bin" run "$r" -D SEED=$seed -D YEARS=4 -o "$tmp/r$seed.str" -o "segments:$tmp/r$seed.csv"
    n=$(grep -c '^I({' "$tmp/r$seed.str")
    test "$n" -ge 300 || { echo "seed $seed: $n internodes" >&2; exit 1; }
    grep -q '^Leaf([^)]*,4)$' "$tmp/r$seed.str" || { echo "seed $seed: no spur rosette" >&2; exit 1; }
    grep -q '^Fruit(' "$tmp/r$seed.str" && fruiting=$((fruiting + 1))
    # height over 1 m; no section flatter than the reaction-wood bound 1.5 (+ the table's 9 digits)
    awk -F, -v s=$seed 'NR > 1 { if ($8 > h) h = $8; r = $10 / $11; if (r < 1) r = 1 / r
            if (r > m) m = r }
        END { if (h < 1 || m > 1.5 + 1e-6) { print "seed " s ": height " h ", a/b " m > "/dev/stderr"; exit 1 } }' \
        "$tmp/r$seed.csv"
done
test "$fruiting" -ge 4

# the bound is the dialect's ReactionBound; a bound below 1 is refused with the call named
set +e
"$bin" run "$r" -D RW_MAX_ASPECT=0.5 -D YEARS=1 -o "$tmp/bad2.str" 2>"$tmp/err2"
rc=$?
set -e
test "$rc" -eq 1
grep -q 'ReactionBound(max a/b' "$tmp/err2"
test ! -e "$tmp/bad2.str"
