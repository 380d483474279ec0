#!/usr/bin/env bash
# Redraws the pictures of Oberlaender's parametric tree that docs/models.md shows: the four
# architecture presets of Table 4 after 6 years with small leaves (so that the branching shows),
# the statistical Cryptomeria at 12 years, and two ober-carbon trees 1.2 m apart after 10 years
# (light competition, E5) with the plot of their carbon tax and height.
#
# Usage: tools/ober-figures.sh [CAMBIUM]   (from the repository root; default build/bin/cambium;
# about a minute on a busy 2-core machine)
set -euo pipefail
bin=${1:-build/bin/cambium}
img=docs/images
test -d "$img" || { echo "run from the repository root" >&2; exit 2; }
for m in massart attims rauh troll; do
    "$bin" grow ober-$m -y 6 -D leafL=2 -D leafW=1 --view front --size 400 --quiet \
        -o "$img/ober-$m.png"
done
"$bin" grow ober-cryptomeria -y 12 --size 500 --quiet -o "$img/ober-cryptomeria.png"
"$bin" grow ober-carbon -y 10 --stand 2x1 --spacing 1.2 --view front --size 500 --quiet \
    -o "$img/ober-carbon-pair.png" -o "plot:$img/ober-carbon-pair-plot.svg"
