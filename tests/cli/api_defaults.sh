#!/usr/bin/env bash
# Every definition struct of the public API (typedef struct cbm_*_def in include/cambium, and the
# two named otherwise, cbm_bend_spec and cbm_write_options) has its defaults function declared,
# `CBM_API cbm_X_def cbm_X_def_default(void);`, so a program sets only the fields it cares about
# (STYLE: def structs with _def_default()).
set -euo pipefail
src=${CBM_SOURCE:?}
n=0
for d in $(cat "$src"/include/cambium/*.h | grep -o 'typedef struct cbm_[a-z0-9_]*_def\b' | awk '{print $3}' | sort -u) cbm_bend_spec cbm_write_options; do
    n=$((n + 1))
    grep -q "CBM_API $d ${d}_default(void);" "$src"/include/cambium/*.h ||
        { echo "FAIL: $d has no ${d}_default(void)"; exit 1; }
done
[ "$n" -ge 12 ] || { echo "FAIL: found only $n def structs"; exit 1; }
echo "ok: $n def structs, each with its _default()"
