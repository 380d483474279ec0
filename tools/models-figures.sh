#!/usr/bin/env bash
# Regenerates the figures docs/models.md quotes for the built-in tree models from
# `cambium grow MODEL --seeds 1-N` runs, so that the docs cannot drift from what the tool grows:
# the text between the markers <!-- figures:NAME begin --> and <!-- figures:NAME end --> in
# docs/models.md is replaced, and the pictures of the models in docs/images/ are redrawn.
#
# Usage: tools/models-figures.sh [CAMBIUM [SEEDS [THESIS_SEEDS]]]   (from the repository root;
# defaults build/bin/cambium and 50 seeds for the real-wood and for the thesis presets (the
# latter slower). About 15 minutes on a busy 2-core machine. REUSE=1 keeps the
# statistics already in out/figures/ for the same seeds. Needs python3 (JSON to Markdown).
# fruit-tree-thesis-high-mor is left out: it grows past 20,000 segments in 10 years (30 s a
# seed).
set -euo pipefail
bin=${1:-build/bin/cambium}
seeds=${2:-50}
thesis_seeds=${3:-50}
doc=docs/models.md
out=out/figures
mkdir -p "$out"
test -f "$doc" || { echo "run from the repository root" >&2; exit 2; }

models="fruit-tree fruit-tree-unfair fruit-tree-low-mor fruit-tree-high-mor poplar-wild
poplar-crooked fruit-tree-thesis fruit-tree-thesis-unfair fruit-tree-thesis-low-mor
poplar-wild-thesis poplar-crooked-thesis"
for m in $models; do
    n=$seeds
    case $m in *thesis*) n=$thesis_seeds ;; esac
    if [ "${REUSE:-0}" = 1 ] && [ -f "$out/$m.json" ] &&
        grep -q "\"seeds\":{\"first\":1,\"last\":$n," "$out/$m.json"; then
        echo "models-figures: $m, seeds 1-$n (kept)" >&2
        continue
    fi
    echo "models-figures: $m, seeds 1-$n" >&2
    "$bin" grow "$m" --seeds "1-$n" -o "$out/$m.json" --quiet
done

python3 - "$doc" "$out" "$seeds" $models <<'EOF'
import json, sys, re
doc, out, seeds, models = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
S = {m: json.load(open(f"{out}/{m}.json")) for m in models}

def fmt(v, kind):
    if kind == "m":
        return f"{v:.2f}"
    if kind == "cm":
        return f"{100 * v:.1f}"
    return f"{v:,.0f}"

def cell(st, kind):
    return f"{fmt(st['median'], kind)} [{fmt(st['q1'], kind)}–{fmt(st['q3'], kind)}]"

figs = [("segments", "segments", "n"), ("height_m", "height (m)", "m"),
        ("crown_width_m", "crown width (m)", "m"), ("base_diameter_m", "base diameter (cm)", "cm"),
        ("leaves", "leaves", "n"), ("fruit", "fruit", "n"), ("breaks", "breaks", "n")]

def years_table(m):
    ys = S[m]["years"]
    rows = ["| year | " + " | ".join(str(y["year"]) for y in ys) + " |",
            "|---|" + "---|" * len(ys)]
    for key, name, kind in figs:
        rows.append(f"| {name} | " + " | ".join(cell(y[key], kind) for y in ys) + " |")
    return "\n".join(rows)

def summary_table(ms):
    rows = ["| model | segments | height (m) | crown width (m) | base diameter (cm) | fruit | "
            "breaks in 10 years | collapsed seeds |",
            "|---|---|---|---|---|---|---|---|"]
    for m in ms:
        d = S[m]
        last = d["years"][-1]
        br = sorted(f["breaks_total"] for f in d["final"])
        n = len(br)
        med = br[n // 2] if n % 2 else 0.5 * (br[n // 2 - 1] + br[n // 2])
        rows.append(f"| `{m}` | {cell(last['segments'], 'n')} | {cell(last['height_m'], 'm')} | "
                    f"{cell(last['crown_width_m'], 'm')} | {cell(last['base_diameter_m'], 'cm')} | "
                    f"{cell(last['fruit'], 'n')} | {med:,.0f} [{br[0]}–{br[-1]}] | "
                    f"{len(d['collapsed_seeds'])} of {d['seeds']['count']} |")
    return "\n".join(rows)

blocks = {
    "fruit-tree-years": years_table("fruit-tree"),
    "presets": summary_table([m for m in models if "thesis" not in m]),
    "thesis-presets": summary_table([m for m in models if "thesis" in m]),
}
text = open(doc).read()
for name, body in blocks.items():
    pat = re.compile(rf"(<!-- figures:{name} begin -->\n).*?(<!-- figures:{name} end -->)", re.S)
    if not pat.search(text):
        sys.exit(f"{doc}: no <!-- figures:{name} begin/end --> markers")
    text = pat.sub(lambda mo: mo.group(1) + body + "\n" + mo.group(2), text)
open(doc, "w").write(text)
EOF

# the pictures: the default seed, the tenth summer
"$bin" grow fruit-tree --summer --size 600 --quiet -o docs/images/fruit-tree.png
"$bin" grow fruit-tree-thesis --summer --size 600 --quiet -o docs/images/fruit-tree-thesis.png
"$bin" grow fruit-tree-unfair --summer --size 400 --quiet -o docs/images/fruit-tree-unfair.png
"$bin" grow poplar-wild --summer --size 400 --quiet -o docs/images/poplar-wild.png
"$bin" grow poplar-crooked --summer --size 400 --quiet -o docs/images/poplar-crooked.png
echo "models-figures: $doc and docs/images/ updated (statistics in $out/)" >&2
