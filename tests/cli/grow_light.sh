#!/usr/bin/env bash
# cambium grow --light: the light of every leaf of the grown tree (docs/light.md): the table,
# its bounds under the uniform overcast sky (no leaf gets more than an unshaded horizontal one,
# none less than nothing), determinism, the picture coloured by light, and the errors.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" grow -y 3 --summer --seed 2 --light uoc,samples=1 -o light:"$tmp/l.csv" >"$tmp/out.txt"
grep -q '^light (uoc, 72 sources, 1x1 samples): ' "$tmp/out.txt"
head -1 "$tmp/l.csv" | grep -q '^part,segment,order,cx_m,cy_m,cz_m,area_m2,light_m2,relative_light$'
rows=$(($(wc -l <"$tmp/l.csv") - 1))
[ "$rows" -gt 10 ] || { echo "FAIL: only $rows leaf rows"; exit 1; }
awk -F, 'NR > 1 && ($9 < 0 || $9 > 1 + 1e-9 || $7 <= 0) { print "FAIL: " $0; bad = 1 }
         NR > 1 && $9 < 0.999 { shaded++ }
         END { if (bad || shaded == 0) exit 1 }' "$tmp/l.csv"
# same seed, same light
"$bin" grow -y 3 --summer --seed 2 --light uoc,samples=1 -o light:"$tmp/m.csv" --quiet
cmp "$tmp/l.csv" "$tmp/m.csv"
# --color-by light asks for the light pass (soc) and paints the leaves
"$bin" grow -y 2 --summer --color-by light -o "$tmp/p.png" --size 120 --ao 0 >"$tmp/out2.txt"
test -s "$tmp/p.png"
grep -q '^light (soc, ' "$tmp/out2.txt"
# errors: unknown sky, bad item, a light table that is not .csv
for bad in "--light sun" "--light soc,rings=0" "--light soc,foo" "-o light:$tmp/l.txt"; do
    if "$bin" grow -y 1 $bad --quiet -o "$tmp/x.csv" 2>"$tmp/err.txt"; then
        echo "FAIL: accepted $bad"; exit 1
    fi
    grep -q 'light' "$tmp/err.txt" || { echo "FAIL: $bad: $(cat "$tmp/err.txt")"; exit 1; }
    test ! -e "$tmp/x.csv"
done
echo ok
