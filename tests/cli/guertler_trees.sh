#!/usr/bin/env bash
# Gürtler's trees in models/ (docs/models.md, "Gürtler's three trees"): each derives with both
# solvers (METHOD 0 relax, 1 fast) over a few seeds without collapse, and an architectural
# property is measured on its segments table:
#   spruce: every whorl node carries 5-8 first-order laterals, whorl sizes vary over seeds, the
#     lowest whorl's branches droop below their insertion, E rises with age (base > new shoot);
#   sympodial: 2^k axes of order k, branch angles 30 deg, the tree stands lower than on rigid wood;
#   beech: the carbon balance decides: thrice the wood's respiration sheds more branches and
#     leaves a thinner stem, the leader's branches alternate sides (distichous); at ten years a broad
#     crown (width over 0.8 of the height), a plausible height, bounded segments varying with
#     the seed;
# and the two solvers give the same tree (height within 1 %).
set -euo pipefail
bin=$1
src=${CBM_SOURCE:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
info() { "$bin" info --json "$1" | sed -n "s/.*\"$2\":\([^,}]*\).*/\1/p"; }

sizes=""
for seed in 1 2 3; do
    for method in 0 1; do
        out="$tmp/sp-$seed-$method"
        "$bin" run "$src/models/guertler-spruce.l" -D YEARS=5 -D SEED=$seed -D METHOD=$method \
            -o "segments:$out.csv" >"$out.txt"
        grep -q ' 0 unconverged equilibria' "$out.txt"
        h=$(info "$out.csv" height_m)
        w=$(info "$out.csv" crown_width_m)
        # five years of leader (0.84 m with the seedling): no collapse, a crown
        awk -v h="$h" -v w="$w" 'BEGIN { exit !(h > 0.75 && h < 0.9 && w > 0.3) }'
        echo "$h" >"$out.h"
    done
    awk -v a="$(cat "$tmp/sp-$seed-0.h")" -v b="$(cat "$tmp/sp-$seed-1.h")" \
        'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d < 0.01 * a) }'
    csv="$tmp/sp-$seed-0.csv"
    # first-order laterals per stem node: whorl nodes (4 or more) carry 5-8; at least 3 whorls
    # flushed in 5 years (the last year's buds have no shoot yet)
    w=$(awk -F, 'NR > 1 { ord[$1] = $3; if ($3 == 1 && ord[$2] == 0) n[$2]++ }
        END { for (p in n) if (n[p] >= 4) print n[p] }' "$csv")
    test "$(echo "$w" | wc -l)" -ge 3
    echo "$w" | awk '$1 < 5 || $1 > 8 { exit 1 }'
    sizes="$sizes $w"
    # E grows with age: the trunk's base (5 rings) is stiffer than the newest shoot's wood
    awk -F, 'NR == 2 { base = $13 } NR > 1 && $3 == 0 { top = $13 } END { exit !(base > 2 * top) }' "$csv"
    # the lowest whorl droops: its laterals' tips lie below their insertion
    awk -F, 'NR > 1 { ord[$1] = $3; y0[$1] = $5; root[$1] = ($3 == 1 && ord[$2] == 0) ? $1 : root[$2]
                      if ($3 == 1) tip[root[$1]] = $8 }
        END { low = -1; for (r in tip) if (low < 0 || y0[r] < y0[low]) low = r
              exit !(tip[low] < y0[low]) }' "$csv"
done
# the whorl size is stochastic (thesis prob_n over n_subap)
test "$(echo $sizes | tr ' ' '\n' | sort -u | wc -l)" -ge 2

for method in 0 1; do
    out="$tmp/sy-$method"
    "$bin" run "$src/models/guertler-sympodial.l" -D ORDERS=6 -D METHOD=$method \
        -o "segments:$out.csv" >"$out.txt"
    grep -q ' 0 unconverged equilibria' "$out.txt"
    # 2^k axes of order k (k = 1..6), each NSUB = 5 internodes
    for k in 1 2 3 4 5 6; do
        test "$(awk -F, -v k=$k 'NR > 1 && $3 == k' "$out.csv" | wc -l)" -eq $((5 * (1 << k)))
    done
    "$bin" info "$out.csv" | grep -q 'branch angles of 126 laterals: median 30 deg'
    info "$out.csv" height_m >"$out.h"
done
awk -v a="$(cat "$tmp/sy-0.h")" -v b="$(cat "$tmp/sy-1.h")" \
    'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d < 0.01 * a) }'
# the wood bends: real wood stands lower (3.68 m) than nearly rigid wood (3.74 m)
"$bin" run "$src/models/guertler-sympodial.l" -D ORDERS=6 -D E_WOOD=1e14 -o "segments:$tmp/rigid.csv" >/dev/null
awk -v a="$(cat "$tmp/sy-0.h")" -v b="$(info "$tmp/rigid.csv" height_m)" 'BEGIN { exit !(a < b - 0.03) }'

for seed in 1 2; do
    for method in 0 1; do
        out="$tmp/be-$seed-$method"
        "$bin" run "$src/models/guertler-beech.l" -D YEARS=5 -D SEED=$seed -D METHOD=$method \
            -o "segments:$out.csv" >"$out.txt"
        grep -q ' 0 unconverged equilibria' "$out.txt"
        h=$(info "$out.csv" height_m)
        # five years: about a metre (1.1-1.3 m; the crown's weight, now that the buds flush the
        # spring after they are set, bends it lower than before), the crown wider than 0.25 m
        awk -v h="$h" -v w="$(info "$out.csv" crown_width_m)" 'BEGIN { exit !(h > 0.9 && w > 0.25) }'
        echo "$h" >"$out.h"
    done
    awk -v a="$(cat "$tmp/be-$seed-0.h")" -v b="$(cat "$tmp/be-$seed-1.h")" \
        'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d < 0.01 * a) }'
    # distichous: the first-order laterals of consecutive stem nodes point to opposite sides
    # (azimuths more than 120 deg apart) on at least 70 % of pairs (the leader's plane turns
    # between years; some weak buds stay dormant, so not every node has a lateral)
    awk -F, 'function az(i) { return atan2($9 - $6, $7 - $4) * 180 / 3.14159265 }
        NR > 1 { ord[$1] = $3; if ($3 == 0) node[$1] = ++nodes }
        NR > 1 && $3 == 1 && ord[$2] == 0 { a = az(); any++
            if (any > 1 && node[$2] == last_node + 1) {
                d = a - last; if (d < 0) d = -d; if (d > 180) d = 360 - d
                n++; if (d > 120) opp++ }
            last = a; last_node = node[$2] }
        END { exit !(any >= 6 && n >= 4 && opp >= 0.7 * n) }' "$tmp/be-$seed-0.csv"
    # the carbon balance: thrice the wood's respiration sheds branches, the stem grows thinner
    "$bin" run "$src/models/guertler-beech.l" -D YEARS=5 -D SEED=$seed -D MAINT=1e-6 \
        -o "segments:$tmp/starved.csv" >"$tmp/starved.txt"
    # (with light a shaded shoot may starve and go at the chosen respiration too: 0-1 branches
    # at 5 years on seeds 1-2, 4-5 when starved)
    shed() { sed -n 's/.* \([0-9][0-9]*\) branches shed.*/\1/p' "$1"; }
    test "$(shed "$tmp/starved.txt")" -gt "$(shed "$tmp/be-$seed-0.txt")"
    awk -v a="$(info "$tmp/be-$seed-0.csv" base_diameter_m)" -v b="$(info "$tmp/starved.csv" base_diameter_m)" \
        'BEGIN { exit !(b < 0.95 * a) }'
done

# the beech at ten years (its last summer) over seeds 1-3 stays in a plausible envelope: a
# ten-year open-grown beech stands about 3-4 m (the leader's law gives 3.0-3.4 m: 2.5-4.5 m);
# its crown is broad, width at least 0.8 of the height (the slender sapling of before measured
# 0.63 and 0.69 on seeds 1-2); no NaN in the
# measures; segments bounded (no runaway: 3,000-4,700 measured on seeds 1-20 with light, where
# shaded shoots weaken and some are shed; 4,300-7,700 before; 1,500-12,000 allowed; without the
# orders' falling vigour they ran to 70,000) and varying with the seed. With light the height is
# 2.66-3.19 m on seeds 1-20 and the crown 0.9-1.2 times the height
counts=""
for seed in 1 2 3; do
    out="$tmp/b10-$seed"
    "$bin" run "$src/models/guertler-beech.l" -D SEED=$seed -o "segments:$out.csv" >"$out.txt"
    grep -q ' 0 unconverged equilibria' "$out.txt"
    "$bin" info --json "$out.csv" >"$out.json"
    ! grep -qi 'nan' "$out.json"
    h=$(info "$out.csv" height_m)
    w=$(info "$out.csv" crown_width_m)
    n=$(info "$out.csv" segments)
    awk -v h="$h" -v w="$w" -v n="$n" \
        'BEGIN { exit !(h > 2.5 && h < 4.5 && w > 0.8 * h && n > 1500 && n < 12000) }'
    counts="$counts $n"
done
test "$(echo $counts | tr ' ' '\n' | sort -u | wc -l)" -ge 2

# the method: a value SolverMethod() does not know is an error naming the place, and nothing is written
if "$bin" run "$src/models/guertler-sympodial.l" -D METHOD=9 -o "$tmp/bad.str" 2>"$tmp/err"; then exit 1; fi
grep -q 'error: .*SolverMethod(n): n is 0 \.\.' "$tmp/err"
test ! -e "$tmp/bad.str"
