#!/usr/bin/env bash
# Output files through the tool: every format from `cambium demo`, checked by outside readers
# (xmllint for SVG, assimp for OBJ/PLY, the Khronos validator for glTF when it is installed under
# build/tools/gltf by .ci/validate-outputs.sh), usage errors (exit 2), job failures (exit 1) that
# name the path and leave nothing behind (missing directory, full disk), and the progress line
# that stays quiet when stderr is not a terminal.
set -u
bin=$1
fail=0
t=$(mktemp -d "$PWD/cli_output_files.XXXXXX")
trap 'rm -rf "$t"' EXIT
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; fi; }

# every format, one run
"$bin" demo --segments 300 --size 160x120 --color-by stress \
  -o "$t/t.obj" -o "$t/t.ply" -o "$t/t.glb" -o "$t/t.png" -o "$t/t.svg" -o "$t/t.csv" 2>"$t/err"
check '[ $? -eq 0 ]' "demo with six outputs exits 0"
for e in obj mtl ply glb png svg csv; do
  check '[ -s "$t/t.$e" ]' "t.$e written"
done
check '[ ! -s "$t/err" ]' "quiet stderr when it is not a terminal (got: $(head -c 200 "$t/err"))"
check '[ -z "$(find "$t" -name ".*tmp*")" ]' "no temporary files left"
check 'head -c 8 "$t/t.png" | od -An -tx1 | grep -q "89 50 4e 47 0d 0a 1a 0a"' "PNG signature"
check 'xmllint --noout "$t/t.svg"' "SVG is well-formed XML"
for e in obj ply; do
  out=$(assimp info "$t/t.$e" 2>&1)
  check '[ $? -eq 0 ] && echo "$out" | grep -Eq "Faces: +[1-9]"' "assimp loads t.$e"
done
# the animation
"$bin" demo --segments 200 --frames 4 -o "$t/anim.glb" 2>"$t/err"
check '[ $? -eq 0 ] && [ -s "$t/anim.glb" ]' "animated .glb written"
val="$CBM_SOURCE/build/tools/gltf/node_modules"
if [ -d "$val/gltf-validator" ]; then
  check 'NODE_PATH="$val" node "$CBM_SOURCE/.ci/gltf-validate.js" "$t/t.glb" "$t/anim.glb"' \
    "Khronos validator accepts the .glb files"
else
  echo "note: gltf-validator not installed (.ci/validate-outputs.sh installs it)"
fi
# views and backgrounds
for v in front side top iso 1,-1,0.5; do
  "$bin" demo --segments 100 --size 64 --view "$v" --background transparent -o "$t/v.svg" \
    -o "$t/v.png" 2>/dev/null
  check '[ $? -eq 0 ] && xmllint --noout "$t/v.svg"' "view $v"
done
# progress forced on (as on a terminal)
CBM_PROGRESS=1 "$bin" demo --segments 50 --frames 3 -o "$t/p.csv" 2>"$t/err"
check 'grep -q "step 3/3" "$t/err"' "progress line shows the steps when on a terminal"

# usage errors: exit 2, nothing written
"$bin" demo --segments 10 2>/dev/null; check '[ $? -eq 2 ]' "no output is a usage error"
"$bin" demo --view sideways -o "$t/u.png" 2>/dev/null; check '[ $? -eq 2 ]' "bad --view"
"$bin" demo --color-by colour -o "$t/u.png" 2>/dev/null; check '[ $? -eq 2 ]' "bad --color-by"
"$bin" demo --size 5 -o "$t/u.png" 2>/dev/null; check '[ $? -eq 2 ]' "bad --size"
"$bin" demo -o "$t/u.stl" 2>/dev/null; check '[ $? -eq 2 ]' "unknown extension"
check '[ ! -e "$t/u.png" ] && [ ! -e "$t/u.stl" ]' "usage errors write nothing"

# job failures: exit 1, the message names the path, nothing left behind
"$bin" demo --segments 10 -o "$t/no/such/dir/x.glb" 2>"$t/err"
check '[ $? -eq 1 ] && grep -q "no/such/dir/x.glb" "$t/err"' "missing directory reported"
mkdir "$t/full"
for e in obj ply glb png svg csv; do
  (trap '' XFSZ; ulimit -f 4; "$bin" demo --segments 2000 --size 300 -o "$t/full/x.$e") 2>"$t/err"
  rc=$?
  check '[ $rc -eq 1 ] && grep -q "full/x.$e" "$t/err"' "full disk reported for .$e (rc $rc)"
done
check '[ -z "$(ls -A "$t/full")" ]' "full disk leaves nothing ($(ls -A "$t/full"))"

# devices are written in place: /dev/full reports the full disk and stays a device
for e in ply glb png svg csv; do
  "$bin" demo --segments 10 --size 32 -o "$e:/dev/full" 2>"$t/err" >/dev/null
  check '[ $? -eq 1 ] && grep -q "/dev/full: .*No space left" "$t/err"' "/dev/full reported ($e)"
done
# FORMAT:PATH and stdout
"$bin" demo --segments 50 --size 32 -o png:- > "$t/stdout.png"
check '[ $? -eq 0 ] && head -c 4 "$t/stdout.png" | grep -q PNG' "png:- writes a PNG to stdout"
check '[ -c /dev/full ] && [ -c /dev/null ]' "devices left in place"

"$bin" demo --help >/dev/null; check '[ $? -eq 0 ]' "demo --help"
[ $fail -eq 0 ] && echo "output_files: all passed"
exit $fail
