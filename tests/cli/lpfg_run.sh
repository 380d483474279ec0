#!/bin/bash
# cambium run on lpfg's oracle models (L+C dialect): a picture and a glTF scene, the turtle
# drawing lpfg's modules (Sphere0, SetColor, RollL/RollR, func(name, x) from the .fset).
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SHARED=${CBM_SHARED:?}
O=$SHARED/oracles/vlab
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
if [ ! -d "$O/lpfg-sympodial/model" ]; then
    # 77: CTest's SKIP_RETURN_CODE; CI (CBM_REQUIRE_ORACLES=1) must not skip
    [ "${CBM_REQUIRE_ORACLES:-0}" = 0 ] || fail "$O is absent and CBM_REQUIRE_ORACLES is set"
    echo "SKIP: $O is absent (the oracle data of ../shared)"
    exit 77
fi

M=$O/lpfg-sympodial/model
"$BIN" run "$M/lsystem.l" "$M/view.v" "$M/material.mat" "$M/functions.fset" --size 64 --ao 0 \
  --supersample 1 -o "$T/s.png" -o "$T/s.glb" -o "$T/s.json" || fail "run lpfg-sympodial"
[ "$(head -c 4 "$T/s.png" | tail -c 3)" = "PNG" ] || fail "png signature"
[ "$(head -c 4 "$T/s.glb")" = "glTF" ] || fail "glb magic"
[ -s "$T/s.png" ] && [ -s "$T/s.glb" ] || fail "empty outputs"
# lpfg's mesh of this model spans 2.898 in height (cylinders and spheres): ours, to the
# turtle's positions (no radii), 2.8923
grep -q '"max":\[1.418[0-9]*,2.892[0-9]*,' "$T/s.json" || fail "box: $(grep -o '"box":{[^}]*}' "$T/s.json" | tail -1)"

M=$O/lpfg-hormone-up/model
"$BIN" run "$M/lsystem.l" "$M/view.v" "$M/color.map" --size 32 --ao 0 --supersample 1 \
  -o "$T/h.png" -o "$T/h.glb" || fail "run lpfg-hormone-up"
[ "$(head -c 4 "$T/h.glb")" = "glTF" ] || fail "glb magic (hormone-up)"

# an unknown function name is an error naming it, and no file is left behind
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(0);\nA(x): { produce A(func(nosuch, 0.5)); }\n' \
  > "$T/bad.l"
"$BIN" run "$T/bad.l" "$O/lpfg-sympodial/model/functions.fset" -o "$T/bad.png" 2> "$T/err"
[ $? -eq 1 ] || fail "unknown function: exit status"
grep -q "nosuch" "$T/err" || fail "unknown function not named: $(cat "$T/err")"
[ ! -e "$T/bad.png" ] || fail "partial output"
echo "ok"
