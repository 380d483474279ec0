#!/usr/bin/env bash
# --timing: `cambium run` on an L+C model with mechanics splits the derivation into rewriting and
# the mechanics operations; `cambium grow` reports derivation (equilibrium, rings), interpretation
# (scene building) and writing. Only the presence of the phases is checked, never a time.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" run "$CBM_SOURCE/models/jirasek-s-branch.l" -o "$tmp/s.svg" --timing 2>"$tmp/run.err" >/dev/null
grep -q '^run: derive [0-9.]* s (rewriting [0-9.]* s, equilibrium [0-9.]* s of which solver [0-9.]* s in [1-9][0-9]* passes, rings and ageing [0-9.]* s, other mechanics [0-9.]* s; 60 mechanics operations, [0-9]* on a kept plant), interpret [0-9.]* s, write [0-9.]* s, total' "$tmp/run.err"
# a model without mechanics keeps the short form
"$bin" run "$CBM_SOURCE/tests/lsys/abop-2.8a.l" -n 2 --timing 2>"$tmp/plain.err" >/dev/null
grep -q '^run: derive [0-9.]* s, interpret' "$tmp/plain.err"
"$bin" grow -y 1 --quiet --timing -o "$tmp/t.svg" -o "$tmp/t.json" --size 100 2>"$tmp/grow.err"
grep -q '^grow: wrote .*t.svg in [0-9.]* s' "$tmp/grow.err"
grep -q '^grow: 1 years, [0-9]* segments: derive [0-9.]* s (equilibrium [0-9.]* s in [0-9]* passes, rings and ageing [0-9.]* s, growth and the rest [-0-9.]* s), interpret [0-9.]* s, write [0-9.]* s, total [0-9.]* s; peak' "$tmp/grow.err"
# the statics solves counted by the solver stage that converged
grep -q '^run: solves by converged stage: newton [1-9][0-9]*' "$tmp/run.err"
grep -q '^grow: solves by converged stage: newton [1-9][0-9]*' "$tmp/grow.err"
if grep -q 'solves by converged stage' "$tmp/plain.err"; then exit 1; fi
