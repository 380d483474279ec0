#!/bin/bash
# cambium run with only .glb scene outputs: straight segments are instances of one unit cylinder
# (EXT_mesh_gpu_instancing), a fraction of the triangles' bytes; --glb-mesh, or any other scene
# output beside the .glb, keeps the triangles; --every's animation is instanced too.
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# the quadratic Koch island, 2 steps: 4 x 8^2 = 256 segments
cat > "$T/k.l" <<'L'
Lsystem: 1
derivation length: 2
Axiom: F-F-F-F
F --> F+F-F-FF+F+F-F
endlsystem
L
printf 'angle increment: 90\ninitial line width: 2 pixels\ninitial color: 1\n' > "$T/k.v"

size() { wc -c < "$1"; }
"$BIN" run "$T/k.l" "$T/k.v" -o "$T/i.glb" || fail "run -o i.glb"
grep -aq '"extensionsRequired":\["EXT_mesh_gpu_instancing"\]' "$T/i.glb" || fail "instanced"
grep -aq '"count":256,"type":"VEC4"' "$T/i.glb" || fail "256 rotations"
"$BIN" run "$T/k.l" "$T/k.v" --glb-mesh -o "$T/m.glb" || fail "run --glb-mesh"
grep -aq 'EXT_mesh_gpu_instancing' "$T/m.glb" && fail "--glb-mesh keeps the triangles"
[ "$(size "$T/i.glb")" -lt $(($(size "$T/m.glb") / 8)) ] || fail "instances under 1/8 of the mesh"
# beside another mesh output the scene keeps the triangles for both
"$BIN" run "$T/k.l" "$T/k.v" -o "$T/b.glb" -o "$T/b.obj" || fail "run -o b.glb -o b.obj"
cmp -s "$T/b.glb" "$T/m.glb" || fail "the .glb beside an .obj is the triangles'"
[ "$(grep -c '^f ' "$T/b.obj")" -eq $((256 * 16)) ] || fail "8-sided tubes in the obj"
# the growth animation of --every
"$BIN" run "$T/k.l" "$T/k.v" --every 1 -o "$T/e.glb" || fail "--every"
grep -aq 'EXT_mesh_gpu_instancing' "$T/e.glb" || fail "the animation is instanced"
grep -aq '"name":"growth"' "$T/e.glb" || fail "the growth animation"
exit 0
