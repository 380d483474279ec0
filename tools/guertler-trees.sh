#!/usr/bin/env bash
# Gürtler's trees (models/guertler-*.l): grows each with all four bending methods, the statics'
# solvers (METHOD 0 relax, 1 fast) over seeds 1-SEEDS, approx (2) and fem (3) over seeds
# 1-METHOD_SEEDS (the sympodial tree has no randomness: one seed), measures every tree with
# `cambium info --json` and writes the spread (median, min-max) of segments, height, crown
# width, base diameter, the lowest point of any segment end (below 0: below the ground) and the
# share of segments that pass through another into docs/models.md between
# `<!-- guertler-trees: begin -->` and `<!-- guertler-trees: end -->` (and warns of a tree that
# reaches below the ground), and draws the pictures docs/images/guertler-*.png (seed 1, fast
# solver; the beech also with approx and fem), so the figures and pictures cannot drift from
# the models.
#
# Usage (from the repository root, after `make`):
#   tools/guertler-trees.sh            rewrite the table and the pictures
#   tools/guertler-trees.sh --print    print the table on stdout, change nothing
# SEEDS=N (default 20), METHOD_SEEDS=N (default 5: the table in docs/models.md was made so),
# CAMBIUM=path/to/cambium (default build/bin/cambium). Needs python3.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CAMBIUM:-build/bin/cambium}
nseeds=${SEEDS:-20}
mseeds=${METHOD_SEEDS:-5}
doc=docs/models.md
[ -x "$bin" ] || { echo "guertler-trees: $bin not found (run make first)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

models="guertler-spruce guertler-sympodial"
[ -f models/guertler-beech.l ] && models="$models guertler-beech"
for m in $models; do
    for method in 0 1 2 3; do
        for s in $(seq 1 "$nseeds"); do
            # the sympodial tree has no randomness: one seed says it all
            if [ "$m" = guertler-sympodial ] && [ "$s" -gt 1 ]; then break; fi
            # approx and fem: a few seeds
            if [ "$method" -ge 2 ] && [ "$s" -gt "$mseeds" ]; then break; fi
            "$bin" run "models/$m.l" -D SEED="$s" -D METHOD="$method" \
                -o "segments:$tmp/t.csv" >"$tmp/t.txt"
            if grep -q ' [1-9][0-9]* unconverged' "$tmp/t.txt"; then
                echo "guertler-trees: $m seed $s method $method: unconverged equilibria" >&2
            fi
            "$bin" info --json "$tmp/t.csv" >"$tmp/$m-$method-$s.json"
            if grep -q '"lowest_m":-' "$tmp/$m-$method-$s.json"; then
                echo "guertler-trees: $m seed $s method $method: a segment ends below the ground" >&2
            fi
        done
    done
done

python3 - "$tmp" "$nseeds" $models >"$tmp/table.md" <<'EOF'
import json, sys, glob, statistics
tmp, nseeds, models = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print("| model | solver | seeds | segments | height (m) | crown width (m) | base diameter (cm) | lowest point (m) | crossing segments (%) |")
print("|---|---|---|---|---|---|---|---|---|")
def spread(v, f):
    return (f % statistics.median(v)) + " (" + (f % min(v)) + "–" + (f % max(v)) + ")"
for m in models:
    for method, name in ((1, "fast"), (0, "relax"), (2, "approx"), (3, "fem")):
        rows = [json.load(open(p))["measures"] for p in sorted(glob.glob(f"{tmp}/{m}-{method}-*.json"))]
        if not rows:
            continue
        print(f"| `{m}` | {name} | {len(rows)} | "
              + spread([r["segments"] for r in rows], "%d") + " | "
              + spread([r["height_m"] for r in rows], "%.2f") + " | "
              + spread([r["crown_width_m"] for r in rows], "%.2f") + " | "
              + spread([100 * r["base_diameter_m"] for r in rows], "%.1f") + " | "
              + spread([r["lowest_m"] for r in rows], "%.3f") + " | "
              + spread([100 * r["intersecting_fraction"] for r in rows], "%.1f") + " |")
EOF

if [ "${1:-}" = --print ]; then
    cat "$tmp/table.md"
    exit 0
fi
python3 - "$doc" "$tmp/table.md" <<'EOF'
import sys
doc, table = sys.argv[1], open(sys.argv[2]).read()
s = open(doc).read()
b, e = "<!-- guertler-trees: begin -->\n", "<!-- guertler-trees: end -->"
i, j = s.index(b) + len(b), s.index(e)
open(doc, "w").write(s[:i] + table + s[j:])
EOF
"$bin" run models/guertler-spruce.l -o docs/images/guertler-spruce.png --view front --size 600x700
"$bin" run models/guertler-sympodial.l -o docs/images/guertler-sympodial.png --view front --size 700x600
if [ -f models/guertler-beech.l ]; then
    "$bin" run models/guertler-beech.l -o docs/images/guertler-beech.png --size 700x700
    "$bin" run models/guertler-beech.l -o docs/images/guertler-beech-front.png --view front --size 600x600
    "$bin" run models/guertler-beech.l -o docs/images/guertler-beech-top.png --view top --size 600x600
    "$bin" run models/guertler-beech.l -D METHOD=2 -o docs/images/guertler-beech-approx.png --view front --size 600x600
    "$bin" run models/guertler-beech.l -D METHOD=3 -o docs/images/guertler-beech-fem.png --view front --size 600x600
fi
echo "guertler-trees: table in $doc, pictures in docs/images/" >&2
