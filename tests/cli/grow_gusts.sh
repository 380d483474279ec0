#!/usr/bin/env bash
# grow's gust field and organ drag (docs/dynamics.md, "Gust field", "Drag of leaves and fruit";
# docs/cli.md): --organ-drag lowers the stem's critical wind (the leaves and fruit add drag);
# --sway with --gust-coherence runs, and the same seed writes the same table; the options'
# errors.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" grow fruit-tree -y 5 --quiet -o "wind:$tmp/w0.csv"
"$bin" grow fruit-tree -y 5 --quiet --organ-drag -o "wind:$tmp/w1.csv"
s0=$(awk -F, '$1 == "stem" { print $4 }' "$tmp/w0.csv")
s1=$(awk -F, '$1 == "stem" { print $4 }' "$tmp/w1.csv")
awk -v a="$s0" -v b="$s1" 'BEGIN { if (!(b > 0 && b < a)) { print "stem", a, "with organs", b; exit 1 } }'
for k in 1 2; do
    "$bin" grow fruit-tree -y 4 --quiet --sway 0.5 --gust-coherence 10 --gust-grid 4 --organ-drag \
        -o "$tmp/s$k.csv"
done
cmp "$tmp/s1.csv" "$tmp/s2.csv"
test "$(wc -l <"$tmp/s1.csv")" -gt 2
# errors: a usage message, exit 2
for bad in "--gust-coherence 10" "--gust-grid 4" "--organ-drag" "--sway 1 --organ-drag --organ-area 1" \
    "--sway 1 --gust-grid 1" "--sway 1 --gust-grid 17" "--sway 1 --gust-coherence -1"; do
    set +e
    # shellcheck disable=SC2086
    "$bin" grow fruit-tree -y 1 --quiet $bad -o "$tmp/x.csv" >/dev/null 2>"$tmp/err"
    rc=$?
    set -e
    test $rc -eq 2 || { echo "exit $rc for $bad"; cat "$tmp/err"; exit 1; }
    grep -q 'cambium grow:' "$tmp/err" || { echo "no message for $bad"; cat "$tmp/err"; exit 1; }
done
