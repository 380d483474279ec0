#!/bin/bash
# cambium run with cpfg's pixel lines: pictures alone get lines (small files, no tubes in the SVG),
# a mesh output beside them gets tubes in every output, sizes and widths in pixels, and a failed
# picture leaves no file.
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

# a mesh output beside the pictures: tubes everywhere, as before
"$BIN" run "$T/k.l" "$T/k.v" --view front --size 200 -o "$T/b.svg" -o "$T/b.obj" \
  || fail "run with a picture and a mesh"
grep -q '<line ' "$T/b.svg" && fail "tubes, not lines, when a mesh is asked"
[ "$(grep -c '<path ' "$T/b.svg")" -gt 256 ] || fail "tubes in the svg"
[ "$(grep -c '^f ' "$T/b.obj")" -eq $((256 * 16)) ] || fail "8-sided tubes in the obj"

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
