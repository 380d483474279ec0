#!/usr/bin/env bash
# cambium run ... -o motion:PATH.csv -o motion:PATH.glb: the drawn parts of Taylor-Hell's linked
# pendula (models/taylor-hell-pendula.l, 14 links, a segment and a sphere each) recorded after
# step 0, every --motion-every steps and at the last step; the table's rows, the glTF's container
# and animation; bad uses refused with exit status 2 and nothing written.
set -euo pipefail
bin=${1:?}
src=${CBM_SOURCE:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
model="$src/models/taylor-hell-pendula.l"
"$bin" run "$model" -n 45 --motion-every 10 --step-time 0.0025 -o "motion:$tmp/m.csv" \
    -o "motion:$tmp/m.glb"
# frames after steps 0 10 20 30 40 45: 6 frames x 28 parts + the header
rows=$(wc -l <"$tmp/m.csv")
[ "$rows" -eq $((6 * 28 + 1)) ] || { echo "FAIL: $rows rows"; exit 1; }
head -1 "$tmp/m.csv" | grep -qx 'frame,step,time_s,part,kind,x0,y0,z0,x1,y1,z1' ||
    { echo "FAIL: header"; exit 1; }
grep -q '^5,45,0.1125,27,sphere,' "$tmp/m.csv" || { echo "FAIL: last frame"; exit 1; }
# step 0: the first link lies along +x from the origin (its initial angle is 0)
grep -q '^0,0,0,0,segment,0,0,0,1,0,0$' "$tmp/m.csv" || { echo "FAIL: first row"; exit 1; }
[ "$(head -c 4 "$tmp/m.glb")" = "glTF" ] || { echo "FAIL: not a glb"; exit 1; }
grep -aq '"animations"' "$tmp/m.glb" || { echo "FAIL: no animation"; exit 1; }
grep -aq '"path":"rotation"' "$tmp/m.glb" || { echo "FAIL: no rotation channel"; exit 1; }
# refused: a motion that is not .csv or .glb; a bad --motion-every; a bad --step-time
for bad in "-o motion:$tmp/x.png" "--motion-every 0 -o motion:$tmp/x.csv" \
    "--step-time -1 -o motion:$tmp/x.csv"; do
    # shellcheck disable=SC2086
    if "$bin" run "$model" -n 2 $bad 2>"$tmp/err"; then
        echo "FAIL: accepted $bad"; exit 1
    fi
    [ ! -e "$tmp/x.csv" ] && [ ! -e "$tmp/x.png" ] || { echo "FAIL: wrote for $bad"; exit 1; }
done
echo "ok: motion table and animation"
