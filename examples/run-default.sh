#!/usr/bin/env bash
# The main job on the built-in default. Usage: run-default.sh CAMBIUM OUTDIR
set -euo pipefail
bin=$1
out=$2
mkdir -p "$out"
"$bin" --version
echo "cambium: no main job yet"
