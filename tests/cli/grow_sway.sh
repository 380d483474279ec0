#!/usr/bin/env bash
# cambium grow --sway: the animated glTF (node translation and rotation channels), the tips'
# displacement table (header, one row per frame and tracked tip, the stem's tip blown downwind,
# nothing moves without wind, the same run twice the same table) and the usage errors.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" grow fruit-tree -y 2 --quiet --sway 1 --wind 12 -o "$tmp/sway.glb" -o "$tmp/motion.csv"
head -c 4 "$tmp/sway.glb" | grep -q glTF
grep -aq '"animations"' "$tmp/sway.glb"
grep -aq '"path":"rotation"' "$tmp/sway.glb"
grep -aq '"path":"translation"' "$tmp/sway.glb"
test "$(head -1 "$tmp/motion.csv")" = "t_s,wind_m_s,axis,order,segment,dx_m,dy_m,dz_m"
# 26 frames (0, 0.04, ..., 1 s) of every tracked tip; one stem tip (order 0)
awk -F, 'NR > 1 { n[$1]++; if ($4 == 0) s++ } END {
    f = 0; for (t in n) f++
    if (f != 26) { print "frames", f; exit 1 }
    if (s != 26) { print "stem rows", s; exit 1 } }' "$tmp/motion.csv"
# the stem's tip leans downwind (+x) on average, more than it moves across
awk -F, 'NR > 1 && $4 == 0 { x += $6; z += ($8 < 0 ? -$8 : $8) } END {
    if (!(x > 0 && x > z)) { print "downwind", x, "across", z; exit 1 } }' "$tmp/motion.csv"
# the same run, the same table; motion:FILE.csv names it explicitly
"$bin" grow fruit-tree -y 2 --quiet --sway 1 --wind 12 -o "motion:$tmp/again.csv"
cmp "$tmp/motion.csv" "$tmp/again.csv"
# drag on the leaves and fruit (--organ-area): a steady wind blows the stem's tip further
# downwind than the wood's drag alone (the organs' load adds to it in the same direction)
"$bin" grow fruit-tree -y 2 --quiet --sway 0.2 --wind 12 --gust 0 -o "$tmp/wood.csv"
"$bin" grow fruit-tree -y 2 --quiet --sway 0.2 --wind 12 --gust 0 --organ-area 5 -o "$tmp/leaves.csv"
w=$(awk -F, 'NR > 1 && $4 == 0 && $1 == 0 { print $6 }' "$tmp/wood.csv")
l=$(awk -F, 'NR > 1 && $4 == 0 && $1 == 0 { print $6 }' "$tmp/leaves.csv")
awk -v w="$w" -v l="$l" 'BEGIN { if (!(w > 0 && l > 1.2 * w)) { print "wood", w, "leaves", l; exit 1 } }'
# --sway-modes: the modal motion of the lowest 30 modes follows the full one (the stem's tip
# within 1 % of its largest displacement at every frame (measured 0.04 %, 1.3 % with 10 modes; docs/dynamics.md, "Modal reduction")
"$bin" grow fruit-tree -y 2 --quiet --sway 1 --wind 12 --sway-modes 30 -o "$tmp/modal.csv"
paste -d, "$tmp/motion.csv" "$tmp/modal.csv" | awk -F, 'NR > 1 && $4 == 0 {
    d = ($6 - $14) ^ 2 + ($7 - $15) ^ 2 + ($8 - $16) ^ 2; u = $6 ^ 2 + $7 ^ 2 + $8 ^ 2
    if (d > dm) dm = d; if (u > um) um = u }
    END { if (!(um > 0 && dm <= 1e-4 * um)) { print "modal error", sqrt(dm), "of", sqrt(um); exit 1 } }'
# --sway-modes with a gust field (--gust-coherence): the field's drag projected per grid point;
# the stem's tip within 2 % of the full motion's with the same field at every frame (measured
# 0.03 % with 30 modes; docs/dynamics.md, "Modal reduction")
"$bin" grow fruit-tree -y 2 --quiet --sway 1 --wind 12 --gust-coherence 8 --gust-grid 4 -o "$tmp/ffull.csv"
"$bin" grow fruit-tree -y 2 --quiet --sway 1 --wind 12 --gust-coherence 8 --gust-grid 4 --sway-modes 30 -o "$tmp/fmodal.csv"
paste -d, "$tmp/ffull.csv" "$tmp/fmodal.csv" | awk -F, 'NR > 1 && $4 == 0 {
    d = ($6 - $14) ^ 2 + ($7 - $15) ^ 2 + ($8 - $16) ^ 2; u = $6 ^ 2 + $7 ^ 2 + $8 ^ 2
    if (d > dm) dm = d; if (u > um) um = u }
    END { if (!(um > 0 && dm <= 4e-4 * um)) { print "modal field error", sqrt(dm), "of", sqrt(um); exit 1 }
          printf "modal field: %.3g %% of the largest tip displacement\n", 100 * sqrt(dm / um) }'
# no wind: nothing moves
"$bin" grow fruit-tree -y 2 --quiet --sway 0.2 --wind 0 -o "$tmp/still.csv"
awk -F, 'NR > 1 && ($6 != 0 || $7 != 0 || $8 != 0) { print; exit 1 }' "$tmp/still.csv"
# usage errors (exit 2) and no output written
expect2() {
    set +e
    "$bin" grow fruit-tree -y 1 --quiet "$@" 2>"$tmp/err"
    rc=$?
    set -e
    test $rc -eq 2 || { echo "exit $rc for $*"; cat "$tmp/err"; exit 1; }
}
expect2 --wind 5 -o "$tmp/x.csv"
expect2 -o "motion:$tmp/x.csv"
expect2 --sway 0 -o "$tmp/x.glb"
expect2 --sway -1 -o "$tmp/x.glb"
expect2 --sway 1
expect2 --sway 1 --wind abc -o "$tmp/x.glb"
expect2 --sway 0.01 --sway-dt 0.1 -o "$tmp/x.glb"
expect2 --sway 1 -o "motion:$tmp/x.png"
expect2 --organ-area 5 -o "$tmp/x.csv"
expect2 --sway-modes 10 -o "$tmp/x.csv"
expect2 --sway 1 --sway-modes 2.5 -o "$tmp/x.glb"
expect2 --sway 1 --organ-area -1 -o "$tmp/x.glb"
test ! -e "$tmp/x.csv" && test ! -e "$tmp/x.glb"
