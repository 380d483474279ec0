#!/usr/bin/env bash
# Regenerates the figures docs/models.md quotes for the built-in tree models from
# `cambium grow MODEL --seeds 1-N` runs, so that the docs cannot drift from what the tool grows:
# the text between the markers <!-- figures:NAME begin --> and <!-- figures:NAME end --> in
# docs/models.md is replaced, and the pictures of the models in docs/images/ are redrawn.
#
# Usage: tools/models-figures.sh [CAMBIUM [SEEDS [THESIS_SEEDS [LC_SEEDS]]]]   (from the
# repository root; defaults build/bin/cambium and 50 seeds for the real-wood and for the thesis
# presets (the latter slower), 10 seeds of the L+C fruit tree models/taylor-hell-fruit-tree.l
# (`cambium run` has no --seeds: one run a seed, measured by `cambium info`). About 15 minutes on a busy 2-core machine. REUSE=1 keeps the
# statistics already in out/figures/ for the same seeds. LC_ONLY=1 redoes only the L+C fruit
# tree's table and picture (the native models' --seeds runs are the slow part). Needs python3 (JSON to Markdown).
# fruit-tree-thesis-high-mor is left out: it grows past 20,000 segments in 10 years (30 s a
# seed).
set -euo pipefail
bin=${1:-build/bin/cambium}
seeds=${2:-50}
thesis_seeds=${3:-50}
lc_seeds=${4:-10}
doc=docs/models.md
out=out/figures
mkdir -p "$out"
test -f "$doc" || { echo "run from the repository root" >&2; exit 2; }

models="fruit-tree fruit-tree-unfair fruit-tree-low-mor fruit-tree-high-mor poplar-wild
poplar-crooked fruit-tree-thesis fruit-tree-thesis-unfair fruit-tree-thesis-low-mor
poplar-wild-thesis poplar-crooked-thesis"
for m in $models; do
    [ "${LC_ONLY:-0}" = 1 ] && break
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

# the L+C fruit tree (real wood by default, the thesis' constants in -thesis.l), seed by seed
lc=models/taylor-hell-fruit-tree.l
for v in real thesis; do
    m=$lc
    [ $v = thesis ] && m=models/taylor-hell-fruit-tree-thesis.l
    for s in $(seq 1 "$lc_seeds"); do
        f=$out/lc-$v-$s.json
        if [ "${REUSE:-0}" = 1 ] && [ -s "$f" ]; then continue; fi
        echo "models-figures: $m, seed $s" >&2
        "$bin" run "$m" -D SEED="$s" -o "$out/lc-$v-$s.str" -o "segments:$out/lc-$v-$s.csv" \
            >/dev/null
        # the Year module: Year(year, phase, broken, shed)
        broken=$(head -1 "$out/lc-$v-$s.str" | sed -n 's/^Year([0-9]*,[0-9]*,\([0-9]*\),.*/\1/p')
        "$bin" info --json "$out/lc-$v-$s.csv" |
            sed "s/^{/{\"broken\":${broken:-0},/" >"$f"
        rm -f "$out/lc-$v-$s.str" "$out/lc-$v-$s.csv"
    done
done

python3 - "$doc" "$out" "$seeds" "$lc_seeds" "${LC_ONLY:-0}" $models <<'EOF'
import json, sys, re
doc, out, seeds, lc_seeds, lc_only = (sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]),
                                       sys.argv[5] == "1")
models = [] if lc_only else sys.argv[6:]
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

def quart(v):
    v = sorted(v)
    def q(p):
        x = p * (len(v) - 1)
        i = int(x)
        return v[i] if i + 1 >= len(v) else v[i] + (x - i) * (v[i + 1] - v[i])
    return q(0.5), q(0.25), q(0.75), v[0], v[-1]

def lc_table():
    rows = ["| L+C fruit tree, 10 years | segments | height (m) | crown width (m) | "
            "base diameter (cm) | trunk ⌀ at 1.3 m (cm; the seeds whose trunk reaches it) | "
            "segments broken | "
            "segments intersecting (%) |",
            "|---|---|---|---|---|---|---|---|"]
    for v, name in (("real", "`taylor-hell-fruit-tree.l` (real wood)"),
                    ("thesis", "`taylor-hell-fruit-tree-thesis.l`")):
        J = [json.load(open(f"{out}/lc-{v}-{s}.json")) for s in range(1, lc_seeds + 1)]
        M = [j["measures"] for j in J]
        def c(vals, f):
            md, q1, q3, lo, hi = quart(vals)
            return f"{f(md)} [{f(q1)}–{f(q3)}] ({f(lo)}–{f(hi)})"
        n = lambda x: f"{x:,.0f}"
        m2 = lambda x: f"{x:.2f}"
        cm = lambda x: f"{100 * x:.1f}"
        pc = lambda x: f"{100 * x:.2f}"
        dbh = [m["diameter_m"] if m["diameter_at"] != "base" else float("nan") for m in M]
        dbh = [d for d in dbh if d == d]
        rows.append(f"| {name} | {c([m['segments'] for m in M], n)} | "
                    f"{c([m['height_m'] for m in M], m2)} | {c([m['crown_width_m'] for m in M], m2)} | "
                    f"{c([m['base_diameter_m'] for m in M], cm)} | "
                    f"{c(dbh, cm) if dbh else '– (below 1.3 m)'} | "
                    f"{c([j['broken'] for j in J], n)} | "
                    f"{c([m['intersecting_fraction'] for m in M], pc)} |")
    return "\n".join(rows)

blocks = {"lc-fruit-tree": lc_table()}
if not lc_only:
    blocks["fruit-tree-years"] = years_table("fruit-tree")
    blocks["presets"] = summary_table([m for m in models if "thesis" not in m])
    blocks["thesis-presets"] = summary_table([m for m in models if "thesis" in m])
text = open(doc).read()
for name, body in blocks.items():
    pat = re.compile(rf"(<!-- figures:{name} begin -->\n).*?(<!-- figures:{name} end -->)", re.S)
    if not pat.search(text):
        sys.exit(f"{doc}: no <!-- figures:{name} begin/end --> markers")
    text = pat.sub(lambda mo: mo.group(1) + body + "\n" + mo.group(2), text)
open(doc, "w").write(text)
EOF

# the pictures: the default seed, the tenth summer
"$bin" run models/taylor-hell-fruit-tree.l -D STOP_SUMMER=1 --size 600 \
    -o docs/images/taylor-hell-fruit-tree.png >/dev/null
if [ "${LC_ONLY:-0}" = 1 ]; then
    echo "models-figures: $doc (the L+C table) and its picture updated" >&2
    exit 0
fi
"$bin" grow fruit-tree --summer --size 600 --quiet -o docs/images/fruit-tree.png
"$bin" grow fruit-tree-thesis --summer --size 600 --quiet -o docs/images/fruit-tree-thesis.png
# the variations at their median seed: the seed of 1-N whose final height and segments are
# nearest the medians (in quartile spreads), so that the picture shows the typical tree, not one
# drawn by the default seed's luck (the unfair tree's leader bends over in some seeds, not others)
median_seed() {
    python3 - "$out/$1.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
last = d["years"][-1]
def z(f, k):
    st = last[k]
    return abs(f[k] - st["median"]) / max(st["q3"] - st["q1"], 1e-9 * abs(st["median"]) + 1e-12)
best = min(d["final"], key=lambda f: (z(f, "height_m") + z(f, "segments"), f["seed"]))
print(best["seed"])
PY
}
for m in fruit-tree-unfair poplar-wild poplar-crooked; do
    s=$(median_seed $m)
    echo "models-figures: $m drawn at its median seed $s" >&2
    "$bin" grow $m -D seed="$s" --summer --size 400 --quiet -o docs/images/$m.png
    sed -i "s/<!-- figures:seed:$m -->[0-9]*/<!-- figures:seed:$m -->$s/" "$doc"
done
echo "models-figures: $doc and docs/images/ updated (statistics in $out/)" >&2
