#!/bin/bash
# cambium run with cpfg's spline cylinders {(n, r) ... }(n): a closed B-spline through the four
# corners of the unit square (0,0) (0,1) (-1,1) (-1,0), drawn as a tube of width 0.2 through
# the whole chain: parser, engine, turtle, OBJ writer. Four pieces (one per control point),
# the curve's top at y = 46/48 (the top piece at t = 1/2), the tube 0.1 above it.
set -u
BIN=$1
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

cat > "$T/s.l" <<'L'
Lsystem: 1
derivation length: 1
Axiom: A
A --> !(0.2) {(4,8) . f(1) +(90) f(1) +(90) f(1) }(4)
endlsystem
L
printf 'line style: cylinder\n' > "$T/s.v"
"$BIN" run "$T/s.l" "$T/s.v" -o "$T/s.json" -o "$T/s.obj" || fail "run"
grep -q '"primitives":4' "$T/s.json" || fail "4 cylinder pieces expected: $(cat "$T/s.json")"
# the closed curve's largest y is at the middle of the top piece, t = 1/2 of the window
# (0,0) (0,1) (-1,1) (-1,0): y = 46/48; with the radius 0.1 the tube reaches 1.0583
ymax=$(awk '$1 == "v" { if ($3 > m) m = $3 } END { printf "%.4f", m }' "$T/s.obj")
[ "$ymax" = "1.0583" ] || fail "top of the tube at $ymax, 1.0583 expected"
# four pieces of 8 bands of 8 sides, 2 triangles each
nf=$(grep -c '^f ' "$T/s.obj")
[ "$nf" = "512" ] || fail "$nf faces, 512 expected"
echo ok
