#!/bin/bash
# cambium run with cpfg's pixel lines: pictures get lines (no tubes in the SVG, widths in pixels),
# alone or beside a mesh output (which gets tubes), with --every too; cylinders stay tubes; a
# failed picture leaves no file.
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# the quadratic Koch island, 2 steps: 4 x 8^2 = 256 segments, pixel lines 2 pixels wide
cat > "$T/k.l" <<'L'
Lsystem: 1
derivation length: 2
Axiom: F-F-F-F
F --> F+F-F-FF+F+F-F
endlsystem
L
printf 'angle increment: 90\ninitial line width: 2 pixels\ninitial color: 1\n' > "$T/k.v"

# pictures alone: lines
"$BIN" run "$T/k.l" "$T/k.v" --view front --size 200 -o "$T/a.png" -o "$T/a.svg" \
  || fail "run with pictures"
[ "$(head -c 4 "$T/a.png" | tail -c 3)" = "PNG" ] || fail "png signature"
[ "$(grep -c '<line ' "$T/a.svg")" -eq 256 ] || fail "256 <line> elements"
grep -q '<path ' "$T/a.svg" && fail "no triangles in a picture of lines"
grep -q 'stroke-width="2"' "$T/a.svg" || fail "lines 2 pixels wide"
command -v xmllint > /dev/null && { xmllint --noout "$T/a.svg" || fail "svg not well-formed"; }

# a mesh output beside the pictures: tubes in the mesh, lines in the pictures (the same
# picture as without the mesh)
"$BIN" run "$T/k.l" "$T/k.v" --view front --size 200 -o "$T/b.svg" -o "$T/b.obj" -o "$T/b.png" \
  || fail "run with pictures and a mesh"
[ "$(grep -c '^f ' "$T/b.obj")" -eq $((256 * 16)) ] || fail "8-sided tubes in the obj"
cmp -s "$T/a.svg" "$T/b.svg" || fail "the svg beside a mesh differs"
cmp -s "$T/a.png" "$T/b.png" || fail "the png beside a mesh differs"
# with --every, the numbered pictures and the animation too
"$BIN" run "$T/k.l" "$T/k.v" --every 1 --size 64 -o "$T/e.svg" -o "$T/e.glb" || fail "--every"
[ "$(grep -c '<line ' "$T/e.0002.svg")" -eq 256 ] || fail "lines in e.0002.svg"
[ "$(grep -c '<line ' "$T/e.0000.svg")" -eq 4 ] || fail "lines in e.0000.svg"
[ "$(head -c 4 "$T/e.glb")" = "glTF" ] || fail "animation beside numbered pictures"
# cylinders stay tubes in pictures
{ cat "$T/k.v"; printf 'line style: cylinder\n'; } > "$T/cyl.v"
"$BIN" run "$T/k.l" "$T/cyl.v" --size 64 -o "$T/cyl.svg" || fail "cylinders"
grep -q '<line ' "$T/cyl.svg" && fail "cylinders drawn as lines"
[ "$(grep -c '<path ' "$T/cyl.svg")" -gt 256 ] || fail "cylinders as tubes"

# a picture that cannot be written leaves nothing and fails with status 1
"$BIN" run "$T/k.l" "$T/k.v" -o "$T/missing/c.png" 2> "$T/err"
[ $? -eq 1 ] || fail "exit status 1 on an unwritable picture"
[ -e "$T/missing/c.png" ] && fail "partial file"
ls "$T" | grep -q '^c\.' && fail "stray file"
# a picture beyond the memory limit (the sample grid alone is 92 MB): status 1, no file
"$BIN" run "$T/k.l" "$T/k.v" --max-memory 20 -o "$T/d.png" 2> "$T/err"
[ $? -eq 1 ] || fail "exit status 1 beyond the memory limit"
grep -q "out of memory" "$T/err" || fail "out-of-memory message"
[ -e "$T/d.png" ] && fail "partial file beyond the memory limit"
echo "ok"
