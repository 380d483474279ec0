#!/usr/bin/env bash
# The main job on the built-in default: the general fruit tree of Taylor-Hell (2005) grown for
# 10 years with full mechanics. Usage: run-default.sh CAMBIUM OUTDIR
set -euo pipefail
bin=$1
out=$2
mkdir -p "$out"
"$bin" --version
# --summer: the tenth year stops at the end of its summer, so the tree has its leaves and fruit
"$bin" grow fruit-tree -y 10 --summer --timing \
    -o "$out/fruit-tree.png" -o "$out/fruit-tree.glb" \
    -o "$out/fruit-tree-segments.csv" -o "$out/fruit-tree.json"
echo "cambium: the fruit tree in its tenth summer:"
echo "  picture      $out/fruit-tree.png"
echo "  mesh (glTF)  $out/fruit-tree.glb"
echo "  segments     $out/fruit-tree-segments.csv"
echo "  summary      $out/fruit-tree.json (year by year)"
