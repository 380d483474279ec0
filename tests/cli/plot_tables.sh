#!/usr/bin/env bash
# cambium plot: CSV and JSON tables to PNG and SVG (pngfix and xmllint when installed, one
# <g class="series"> per y column, the same bytes twice), gaps from empty cells, and the errors:
# bad usage exits 2 naming the option or column, a malformed table exits 1 with file:line.
set -uo pipefail
bin=$1
fail() { echo "FAIL: $*"; exit 1; }
d=$(mktemp -d plot.XXXXXX)
trap 'rm -rf "$d"' EXIT
cat >"$d/t.csv" <<'CSV'
# a comment line
t,"load, N",deflection
0,0,0
1,2.5,0.1
2,5,
3,7.5,0.45
4,10,0.8
CSV
"$bin" plot "$d/t.csv" -x t -y 2,deflection --style both --title "Bend & test" -o "$d/a.svg" \
  -o "$d/a.png" || fail "plot csv"
test "$(grep -c '<g class="series">' "$d/a.svg")" -eq 2 || fail "two series expected"
grep -q '>load, N</text>' "$d/a.svg" || fail "quoted column name in the legend"
grep -q '>Bend &amp; test</text>' "$d/a.svg" || fail "title"
if command -v xmllint >/dev/null; then xmllint --noout "$d/a.svg" || fail "xmllint"; fi
if command -v pngfix >/dev/null; then pngfix "$d/a.png" >/dev/null || fail "pngfix"; fi
"$bin" plot "$d/t.csv" -x t -y 2,deflection --style both --title "Bend & test" -o "$d/b.svg" \
  -o "$d/b.png" || fail "plot again"
cmp -s "$d/a.svg" "$d/b.svg" || fail "svg bytes differ between runs"
cmp -s "$d/a.png" "$d/b.png" || fail "png bytes differ between runs"
# two panels, log axis, explicit format
"$bin" plot "$d/t.csv" -x t -y deflection --panel 2 --logy --xrange 0:5 -o "svg:$d/c.out" \
  || fail "panels"
test "$(grep -c 'class="axes"' "$d/c.out")" -eq 2 || fail "two panels expected"
# JSON: the first array of objects
cat >"$d/g.json" <<'JSON'
{"model": "x", "nested": {"skip": [1, 2, {"a": 1}]},
 "years": [{"year": 1, "height_m": 0.5, "name": "a"},
           {"year": 2, "height_m": 0.9, "extra": 3},
           {"year": 3, "height_m": null}]}
JSON
"$bin" plot "$d/g.json" -x year -y height_m -o "$d/g.svg" || fail "plot json"
grep -q '>height_m</text>' "$d/g.svg" || fail "json column as y label"
# usage errors: exit 2, named
"$bin" plot "$d/t.csv" -y nope -o "$d/x.svg" 2>"$d/err"; test $? -eq 2 || fail "unknown column"
grep -q "no column 'nope'" "$d/err" || fail "unknown column not named"
"$bin" plot "$d/t.csv" -y 1 -o "$d/x.pdf" 2>"$d/err"; test $? -eq 2 || fail "pdf output"
grep -q "png or .svg" "$d/err" || fail "bad output not named"
"$bin" plot "$d/t.csv" -o "$d/x.svg" 2>"$d/err"; test $? -eq 2 || fail "no -y"
"$bin" plot "$d/t.csv" -y 1 --xrange 5:1 -o "$d/x.svg" 2>"$d/err"; test $? -eq 2 || fail "empty range"
"$bin" plot "$d/t.csv" -y 1 --wobble -o "$d/x.svg" 2>"$d/err"; test $? -eq 2 || fail "unknown option"
# data errors: exit 1 with file:line, no output
printf 'a,b\n1,2\n3\n' >"$d/bad.csv"
"$bin" plot "$d/bad.csv" -y a -o "$d/x.svg" 2>"$d/err"; test $? -eq 1 || fail "ragged csv"
grep -q "bad.csv:3: 1 cells where the header names 2 columns" "$d/err" || fail "ragged row not located"
printf '{"rows": [{"a": 1}, {"a": }]}' >"$d/bad.json"
"$bin" plot "$d/bad.json" -y a -o "$d/x.svg" 2>"$d/err"; test $? -eq 1 || fail "bad json"
grep -q "bad.json:1:" "$d/err" || fail "bad json not located"
"$bin" plot "$d/missing.csv" -y a -o "$d/x.svg" 2>"$d/err"; test $? -eq 1 || fail "missing file"
test ! -e "$d/x.svg" || fail "an output was left after an error"
echo ok
