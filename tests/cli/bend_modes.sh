#!/usr/bin/env bash
# cambium bend --modes and the motion keys: frequencies_hz of a thin uniform cantilever against
# Euler-Bernoulli (beta_1 L = 1.875104, both planes), gravity lowering an upright rod's and
# raising a hanging rod's, the motion CSV's columns and energy, and the errors.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/rod.spec" <<'SPEC'
length = 1
segments = 100
radius = 0.001
E = 1e10
density = 600
gravity = 0
SPEC
"$bin" bend "$tmp/rod.spec" --modes 4 --json >"$tmp/m.json"
grep -q '"frequencies_hz": \[' "$tmp/m.json"
f=$(grep -o '"frequencies_hz": \[[^]]*\]' "$tmp/m.json" | sed 's/.*\[//; s/\]//; s/,//g')
set -- $f
test $# -eq 4
awk -v a="$1" -v b="$2" -v c="$3" 'BEGIN {
    pi = 3.14159265358979323846; bl = 1.875104068711961
    ref = bl * bl / (2 * pi) * 0.5 * 0.001 * sqrt(1e10 / 600)
    for (i = 0; i < 2; i++) { x = (i ? b : a); r = (x - ref) / ref; if (r < 0) r = -r
        if (r > 1e-4) { printf "f1 %.9g expected %.9g\n", x, ref; exit 1 } }
    if (!(c > 6 * a)) { print "mode 3 not above mode 1"; exit 1 }
}'
first() { grep -o '"frequencies_hz": \[[^,]*' | sed 's/.*\[//'; }
printf 'length = 1\nsegments = 50\nradius = 0.005\nangle = 0\ngravity = 0\n' >"$tmp/h0.spec"
printf 'length = 1\nsegments = 50\nradius = 0.005\nangle = 90\n' >"$tmp/up.spec"
printf 'length = 1\nsegments = 50\nradius = 0.005\nangle = -90\n' >"$tmp/down.spec"
f0=$("$bin" bend "$tmp/h0.spec" --modes 1 --json | first)
fu=$("$bin" bend "$tmp/up.spec" --modes 1 --json | first)
fd=$("$bin" bend "$tmp/down.spec" --modes 1 --json | first)
awk -v a="$f0" -v u="$fu" -v d="$fd" 'BEGIN { if (!(u < a && d > a)) { print a, u, d; exit 1 } }'
# motion: the CSV header, one row per step plus t = 0, energy constant without damping
cat >"$tmp/mo.spec" <<'SPEC'
length = 1
segments = 20
radius = 0.01
duration = 0.5
dt = 0.001
initial_tip_load = 2
impulse_time = 0.2
impulse_force = 10
SPEC
"$bin" bend "$tmp/mo.spec" -o "$tmp/motion.csv" -o "$tmp/s.json"
head -1 "$tmp/motion.csv" | grep -qx 't,tip_x,tip_y,tip_z,kinetic_J,potential_J'
test "$(wc -l <"$tmp/motion.csv")" -eq 502
grep -q '"motion_rows": 501' "$tmp/s.json"
# before the impulse the energy is that of the release; the impulse changes it (its work
# F dt v has the sign of the tip's velocity), after it the energy is constant again
awk -F, 'NR == 2 { e0 = $5 + $6; if (!($6 > 0) || $5 != 0) { print "start"; exit 1 } }
    NR > 2 && $1 < 0.195 { e = $5 + $6; r = (e - e0) / e0; if (r < 0) r = -r
        if (r > 1e-10) { print "drift " r " at " $1; exit 1 } }
    $1 > 0.21 && $1 < 0.212 { e1 = $5 + $6 }
    $1 > 0.3 { e = $5 + $6; r = (e - e1) / e1; if (r < 0) r = -r
        if (r > 1e-10) { print "drift after the impulse " r " at " $1; exit 1 } }
    END { r = (e1 - e0) / e0; if (r < 0) r = -r; if (!(r > 1e-4)) { print "impulse did no work"; exit 1 } }' "$tmp/motion.csv"
# more modes than degrees of freedom (3 per segment): the rest are null; a massless rod refused
printf 'length = 1\nsegments = 1\nradius = 0.01\n' >"$tmp/one.spec"
"$bin" bend "$tmp/one.spec" --modes 4 --json | grep -q '"frequencies_hz": \[[0-9.e+-]*, [0-9.e+-]*, [0-9.e+-]*, null\]'
printf 'length = 1\nsegments = 2\nradius = 0.01\ndensity = 0\n' >"$tmp/zero.spec"
if "$bin" bend "$tmp/zero.spec" --modes 2 2>"$tmp/err"; then exit 1; fi
grep -q 'has no mass' "$tmp/err"
# errors: time keys without duration, bad --modes
printf 'dt = 0.01\n' >"$tmp/bad.spec"
if "$bin" bend "$tmp/bad.spec" 2>"$tmp/err"; then exit 1; fi
grep -q 'need duration > 0' "$tmp/err"
set +e
"$bin" bend "$tmp/rod.spec" --modes 0 2>/dev/null
test $? -eq 2
set -e
# grow --modes: the tree's lowest frequencies, ascending
"$bin" grow -y 3 --quiet --modes 4 >"$tmp/grow.txt"
grep -q 'lowest 4 natural frequencies (Hz):' "$tmp/grow.txt"
sed 's/.*(Hz)://' "$tmp/grow.txt" | tr ' ' '\n' | grep . >"$tmp/gf"
test "$(wc -l <"$tmp/gf")" -eq 4
sort -g -c "$tmp/gf"
# grow -o wind:FILE.csv: the stem's row first, then one per first-order branch
"$bin" grow -y 3 --quiet -o "wind:$tmp/wind.csv"
head -1 "$tmp/wind.csv" | grep -qx 'axis,order,first_segment,critical_wind_m_s,weakest_segment,height_m'
sed -n 2p "$tmp/wind.csv" | grep -q '^stem,0,0,'
test "$(grep -c '^branch,1,' "$tmp/wind.csv")" -ge 1
set +e
"$bin" grow -y 1 -o wind:x.json 2>/dev/null
test $? -eq 2
set -e
echo ok
