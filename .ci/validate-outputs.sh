#!/usr/bin/env bash
# Validates the files the writers produce with outside tools: the Khronos glTF validator (npm
# gltf-validator, installed into build/tools/gltf), assimp (OBJ, PLY), xmllint (SVG), libpng's
# pngfix (PNG). Usage: .ci/validate-outputs.sh [CAMBIUM]   (default build/bin/cambium)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/bin/cambium}
val=build/tools/gltf
if [ ! -d "$val/node_modules/gltf-validator" ]; then
  if ! command -v npm >/dev/null; then
    sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends npm >&2
  fi
  mkdir -p "$val"
  (cd "$val" && npm install --silent --no-audit --no-fund gltf-validator >/dev/null)
fi
out=build/ci-outputs
rm -rf "$out"
mkdir -p "$out"
"$bin" demo --segments 3000 -o "$out/tree.glb" -o "$out/tree.obj" -o "$out/tree.ply" \
  -o "$out/tree.svg" -o "$out/tree.png" -o "$out/tree.csv"
"$bin" demo --segments 3000 --frames 6 --color-by order -o "$out/growth.glb"
"$bin" demo --segments 500 --color-by stress --no-ground -o "$out/stress.glb" -o "$out/stress.obj" \
  -o "$out/stress.ply"
for v in front side top; do
  "$bin" demo --segments 800 --view "$v" --color-by age -o "$out/$v.svg" -o "$out/$v.png"
done
# cambium run: ABOP models through the turtle into every format, and a growth animation
"$bin" run tests/lsys/abop-2.8a.l tests/lsys/abop-2.8a.v -n 6 -o "$out/run-2.8a.glb" \
  -o "$out/run-2.8a.obj" -o "$out/run-2.8a.ply" -o "$out/run-2.8a.svg" -o "$out/run-2.8a.png" \
  -o "$out/run-2.8a.csv"
"$bin" run tests/lsys/abop-2.8a.l tests/lsys/abop-2.8a.v -n 6 --every 2 --color-by order \
  -o "$out/run-2.8a-growth.glb"
# only .glb outputs: the segments as instances of a unit cylinder or frustum (EXT_mesh_gpu_instancing)
"$bin" run tests/lsys/abop-2.8a.l tests/lsys/abop-2.8a.v -n 6 -o "$out/run-2.8a-instances.glb"
"$bin" run tests/lsys/abop-1.24c.l tests/lsys/abop-1.24c.v --view front -o "$out/run-1.24c.glb" -o "$out/run-1.24c.obj" \
  -o "$out/run-1.24c.ply" -o "$out/run-1.24c.svg" -o "$out/run-1.24c.png"
"$bin" run tests/lsys/abop-1.27.l tests/lsys/abop-1.27.v -o "$out/run-1.27.glb" -o "$out/run-1.27.obj" -o "$out/run-1.27.ply"
"$bin" run tests/lsys/abop-2.8a.l -n 7 --color-by order -o "$out/run-lines.svg" -o "$out/run-lines.png"
# cambium run: the motion of Taylor-Hell's linked pendula as a node-TRS animation (gltf_frames.c)
"$bin" run models/taylor-hell-pendula.l -n 2000 --motion-every 10 --step-time 0.0025 \
  -o "motion:$out/run-pendula-motion.glb" -o "motion:$out/run-pendula-motion.csv"
# cambium plot: a column plot of the parts table, both formats
"$bin" plot "$out/tree.csv" -x age_years -y stress_ratio --panel order --style points \
  -o "$out/plot-parts.svg" -o "$out/plot-parts.png"
# predefined surfaces (petals, calyxes) placed as instances of one mesh each: the lilac of the
# vlab oracles, where ../shared is present (CI has it)
lilac=../shared/oracles/vlab/cpfg-lilac/model
if [ -d "$lilac" ]; then
  absbin=$(realpath "$bin") absout=$(realpath "$out")
  (cd "$lilac" && "$absbin" run plant.l materials.mat plant.v -o "$absout/run-lilac-surfaces.glb")
else
  echo "== $lilac absent: the surface instances are not validated"
fi
echo "== glTF validator"
"$bin" grow fruit-tree -y 3 --quiet --sway 2 --wind 15 -o "$out/grow-sway.glb" -o "$out/grow-sway.csv"
NODE_PATH="$val/node_modules" node .ci/gltf-validate.js "$out"/*.glb
echo "== assimp"
for f in "$out"/*.obj "$out"/*.ply; do
  faces=$(assimp info "$f" | sed -n 's/^Faces: *//p')
  echo "$f: $faces faces"
  [ "${faces:-0}" -gt 0 ]
done
echo "== xmllint"
xmllint --noout "$out"/*.svg && echo "$(ls "$out"/*.svg | wc -l) SVG files well-formed"
echo "== pngfix"
for f in "$out"/*.png; do pngfix "$f" >/dev/null && echo "$f: ok"; done
