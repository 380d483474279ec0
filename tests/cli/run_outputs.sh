#!/bin/bash
# cambium run end to end: ABOP models through the turtle into every output format, --every,
# run.json, query modules, errors without partial files, the limit stop, and cambium info.
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SRC=${CBM_SOURCE:?}
M=$SRC/tests/lsys
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# every format from one run (small pictures to stay fast)
"$BIN" run "$M/abop-2.8a.l" "$M/abop-2.8a.v" -n 5 --size 64 --ao 0 --supersample 1 \
  -o "$T/t.str" -o "$T/t.json" -o "$T/t.obj" -o "$T/t.ply" -o "$T/t.glb" -o "$T/t.png" \
  -o "$T/t.svg" -o "$T/t.csv" || fail "run with every output"
[ "$(wc -l < "$T/t.str")" -eq 2182 ] || fail "2182 modules after 5 steps of fig. 2.8a"
[ "$(head -c 4 "$T/t.glb")" = "glTF" ] || fail "glb magic"
[ "$(head -c 4 "$T/t.png" | tail -c 3)" = "PNG" ] || fail "png signature"
head -c 200 "$T/t.ply" | grep -q "^format binary_little_endian" || fail "ply header"
[ "$(grep -c '^f ' "$T/t.obj")" -gt 1000 ] || fail "obj faces"
[ -f "$T/t.mtl" ] || fail "obj material library"
grep -q "</svg>" "$T/t.svg" || fail "svg end"
command -v xmllint > /dev/null && { xmllint --noout "$T/t.svg" || fail "svg not well-formed"; }
# one csv row per part: 3 branches per apex per step plus the trunk
[ "$(tail -n +2 "$T/t.csv" | wc -l)" -gt 300 ] || fail "csv rows"
# run.json: a row per step 0..5 with modules, primitives and the box
for s in 0 1 2 3 4 5; do grep -q "\"step\":$s," "$T/t.json" || fail "json step $s"; done
grep -q '"step":5,"modules":2182,' "$T/t.json" || fail "json modules of step 5"
grep -q '"primitives":' "$T/t.json" || fail "json primitives"
grep -q '"box":{"min":\[' "$T/t.json" || fail "json box"
if command -v python3 > /dev/null; then
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert len(d['steps'])==6" \
    "$T/t.json" || fail "json not valid or wrong rows"
fi

# --every: numbered files NAME.STEP.EXT, one animation for .glb
"$BIN" run "$M/abop-2.8a.l" -n 4 --every 2 --size 32 --ao 0 --supersample 1 \
  -o "$T/e.png" -o "$T/e.glb" -o "$T/e.str" || fail "--every"
for s in 0000 0002 0004; do
  [ -f "$T/e.$s.png" ] || fail "missing e.$s.png"
  [ -f "$T/e.$s.str" ] || fail "missing e.$s.str"
done
[ ! -f "$T/e.0002.glb" ] || fail "no numbered glb with --every"
"$BIN" info "$T/e.glb" | grep -q "1 animations" || fail "glb animation: $("$BIN" info "$T/e.glb")"
# off the K grid the last step still ends the animation
"$BIN" run "$M/abop-2.8a.l" -n 3 --every 2 -o "$T/g.glb" -o "$T/g.json" || fail "--every 2 of 3"
grep -q '"step":3,' "$T/g.json" || fail "last step row"

# query modules are filled by the turtle (heading +y, as cpfg)
printf 'Lsystem: 1\nderivation length: 1\nAxiom: F(1)?P(0,0,0)A\nA --> F(2)?P(0,0,0)\nendlsystem\n' \
  > "$T/q.l"
"$BIN" run "$T/q.l" -o "$T/q.str" || fail "query model"
[ "$(tr -d '\n' < "$T/q.str")" = "F(1)?P(0,1,0)F(2)?P(0,3,0)" ] || fail "query: $(cat "$T/q.str")"

# summary without -o: derives and interprets, writes nothing
out=$(cd "$T" && "$BIN" run "$M/abop-1.24c.l") || fail "summary"
echo "$out" | grep -q "4 steps, .* modules, .*box" || fail "summary: $out"

# FORMAT:PATH to stdout
"$BIN" run "$M/abop-1.24a.l" -n 1 -o obj:- | grep -q "^v " || fail "obj:- to stdout"
"$BIN" run "$M/abop-1.24a.l" -n 1 -o str:- | head -1 | grep -qx "F" || fail "str:- to stdout"

# an error at interpretation (a parameter becomes infinite): exit 1, no file at all
printf 'Lsystem: 1\nderivation length: 3\nAxiom: A(0)\nA(n) : n == 2 --> F(1/(n-2))A(n+1)\nA(n) --> F(1)A(n+1)\nendlsystem\n' \
  > "$T/inf.l"
"$BIN" run "$T/inf.l" -o "$T/inf.png" -o "$T/inf.str" 2> "$T/err"
[ $? -eq 1 ] || fail "interpretation error exit status"
grep -q "inf" "$T/err" || fail "message: $(cat "$T/err")"
[ -z "$(ls "$T" | grep '^inf\.\(png\|str\)')" ] || fail "files left after an error"
[ -z "$(ls -A "$T" | grep -v '^\(t\|e\|g\|q\|inf\)\.' | grep -v '^err$')" ] ||
  fail "stray files: $(ls -A "$T")"

# a limit stop writes the last complete step's geometry and exits 1
"$BIN" run "$M/abop-2.8a.l" --max-modules 1000 -o "$T/l.obj" -o "$T/l.str" 2> "$T/err"
[ $? -eq 1 ] || fail "limit exit status"
[ "$(wc -l < "$T/l.str")" -eq 724 ] || fail "last complete step (724 modules)"
[ "$(grep -c '^f ' "$T/l.obj")" -gt 0 ] || fail "geometry of the last complete step"

# the memory limit: a clear message, exit 1, no file (4 MB: the instanced .glb of 9 steps
# needs about 8 MB, the triangles 20 MB and more)
"$BIN" run "$M/abop-2.8a.l" -n 9 --max-memory 4 -o "$T/big.glb" 2> "$T/err"
[ $? -eq 1 ] || fail "memory limit exit status"
grep -q "memory limit is 4 MB" "$T/err" || fail "memory message: $(cat "$T/err")"
[ ! -e "$T/big.glb" ] || fail "file left after running out of memory"

# cambium info on the model and the outputs
"$BIN" info "$M/abop-2.8a.l" | grep -q "productions: 3" || fail "info model"
"$BIN" info "$M/abop-2.8a.l" | grep -q "derivation length: 8 steps" || fail "info length"
"$BIN" info "$M/abop-2.8a.l" | grep -q "view file: abop-2.8a.v" || fail "info view file"
"$BIN" info "$SRC/models/jirasek-hanging.l" >"$T/info.txt"
grep -q "L+C L-system model" "$T/info.txt" || fail "info L+C dialect"
grep -q "productions: 2$" "$T/info.txt" || fail "info L+C productions"
grep -q "interpretation: 3 productions" "$T/info.txt" || fail "info L+C interpretation"
grep -q "mechanics: a module carries" "$T/info.txt" || fail "info L+C mechanics"
"$BIN" info "$SRC/models/cpfg-herb-sublsystems.l" >"$T/info.txt"
grep -q "L-systems: 3 (the main one and 2 sub-L-systems)" "$T/info.txt" || fail "info sub-L-systems"
grep -q "productions: 5$" "$T/info.txt" || fail "info productions of every L-system"
"$BIN" info "$T/t.str" | grep -q "2182 modules" || fail "info str"
"$BIN" info "$T/t.png" | grep -q "64 x 64 pixels" || fail "info png"
"$BIN" info "$T/t.ply" | grep -q "element face" || fail "info ply"
"$BIN" info "$T/t.obj" | grep -q "bounds: x" || fail "info obj"
"$BIN" info "$T/t.glb" | grep -q "glTF 2 binary" || fail "info glb"
"$BIN" info "$T/t.svg" | grep -q "SVG picture: 64 x 64" || fail "info svg"
"$BIN" info "$T/t.csv" | grep -q "columns: id," || fail "info csv"
"$BIN" info "$T/t.json" | grep -q "6 steps recorded; last, step 5: 2182 modules" ||
  fail "info json: $("$BIN" info "$T/t.json")"
"$BIN" info "$T/missing.obj" 2> /dev/null; [ $? -eq 1 ] || fail "info missing file"
"$BIN" info 2> /dev/null; [ $? -eq 2 ] || fail "info usage"

# bad usage: exit 2
"$BIN" run "$M/abop-2.8a.l" -o "$T/x.xyz" 2> /dev/null; [ $? -eq 2 ] || fail "unknown format"
"$BIN" run "$M/abop-2.8a.l" --every 2 -o png:- 2> /dev/null; [ $? -eq 2 ] || fail "--every to stdout"
"$BIN" run "$M/abop-2.8a.l" --size 3 2> /dev/null; [ $? -eq 2 ] || fail "bad --size"
"$BIN" run "$M/abop-2.8a.l" "$T/side.xyz" 2> /dev/null; [ $? -eq 2 ] || fail "unknown side file"
echo ok
