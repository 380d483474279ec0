#!/usr/bin/env bash
# The L+C dialect's dynamics (docs/language.md, "Mechanics"): Frequency(k) of a uniform
# cantilever against Euler-Bernoulli (beta_1 L = 1.875104, beta_2 L = 4.694091; modes 1, 2 are
# the two planes of mode 1), Sway() with no wind (nothing moves), in a steady log-profile wind
# (the peak is the static drag deflection, integral of w(z) z^2 (3L - z) / 6EI by quadrature),
# with gusts (more than steady), and the argument errors.
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/rod.l" <<'L'
#include <lpfgall.h>
derivation length: 40;
module I(MechSegment);
module A(int);
mechanics: I;
MechSegment S()
{
    MechSegment s;
    s.length = 0.025; s.a = 0.01; s.b = 0.01; s.E = 1e10; s.density = 600;
    return s;
}
Start: { Gravity(0, 0, 0); }
Axiom: A(40);
A(n): { if (n > 0) produce I(S()) A(n - 1); produce; }
End: {
    Equilibrium();
    printf("f %.9g %.9g %.9g\n", Frequency(1), Frequency(2), Frequency(3));
    printf("still %.9g\n", Sway(0.2, 0.002, 0, 0));
    printf("steady %.9g\n", Sway(0.2, 0.002, 20, 0));
    printf("gusty %.9g\n", Sway(2, 0.002, 20, 0.3));
}
L
"$bin" run "$tmp/rod.l" >"$tmp/out"
awk '
$1 == "f" { f1 = $2; f2 = $3; f3 = $4 }
$1 == "still" { still = $2 }
$1 == "steady" { steady = $2 }
$1 == "gusty" { gusty = $2 }
END {
    pi = 3.141592653589793; c = 0.5 * 0.01 * sqrt(1e10 / 600)
    r1 = 1.875104068711961^2 / (2 * pi) * c; r2 = 4.694091132974175^2 / (2 * pi) * c
    e1 = (f1 - r1) / r1; e2 = (f3 - r2) / r2; if (e1 < 0) e1 = -e1; if (e2 < 0) e2 = -e2
    if (e1 > 1e-3 || e2 > 3e-3 || (f2 - f1) / f1 > 1e-8) { print "frequencies", f1, f2, f3, r1, r2; exit 1 }
    if (still != 0) { print "still", still; exit 1 }
    EI = 1e10 * pi * 1e-8 / 4; N = 20000; s = 0
    for (i = 0; i < N; i++) { z = (i + 0.5) / N; U = (z > 0.1) ? 20 * log(z / 0.1) / log(100) : 0
        s += 0.5 * 1.226 * 0.02 * U * U * z * z * (3 - z) / (6 * EI) / N }
    e = (steady - s) / s; if (e < 0) e = -e
    if (e > 2e-3) { print "steady", steady, "static", s; exit 1 }
    if (!(gusty > steady)) { print "gusty", gusty, "steady", steady; exit 1 }
}' "$tmp/out"
# errors: a file:line:col diagnostic, exit 1
for bad in 'Frequency(0)' 'Frequency(1.5)' 'Sway(0, 0.01, 1, 0)' 'Sway(1, 2, 1, 0)' 'Sway(1, 0.01, -1, 0)'; do
    sed "s/printf(\"still.*/printf(\"%g\\\\n\", $bad);/" "$tmp/rod.l" >"$tmp/bad.l"
    set +e
    "$bin" run "$tmp/bad.l" >/dev/null 2>"$tmp/err"
    rc=$?
    set -e
    test $rc -eq 1 || { echo "exit $rc for $bad"; cat "$tmp/err"; exit 1; }
    grep -q 'bad.l:[0-9]*:[0-9]*: error' "$tmp/err" || { echo "no diagnostic for $bad"; cat "$tmp/err"; exit 1; }
done
# run -o sway:FILE: the last Sway() call's motion as grow --sway writes it. The gusty call (2 s,
# dt 2 ms) gives 51 frames (0, 0.04, ..., 2 s) of the one tracked tip (the stem's), all within
# the printed peak; a model whose last call is the steady one writes the static drag deflection
# in every frame (the printed peak, 1e-6).
"$bin" run "$tmp/rod.l" -o "sway:$tmp/sway.glb" -o "sway:$tmp/sway.csv" >"$tmp/out2"
head -c 4 "$tmp/sway.glb" | grep -q glTF
grep -aq '"path":"rotation"' "$tmp/sway.glb"
test "$(head -1 "$tmp/sway.csv")" = "t_s,wind_m_s,axis,order,segment,dx_m,dy_m,dz_m"
gusty=$(awk '$1 == "gusty" { print $2 }' "$tmp/out2")
awk -F, -v peak="$gusty" 'NR > 1 { n++; d = sqrt($6 * $6 + $7 * $7 + $8 * $8); if (d > m) m = d
    if ($4 != 0 || $5 != 39) { print "row", $0; exit 1 } }
    END { if (n != 51) { print "rows", n; exit 1 }
          if (!(m <= peak * (1 + 1e-9) && m > 0.3 * peak)) { print "max", m, "peak", peak; exit 1 } }' "$tmp/sway.csv"
sed 's/printf("gusty.*//' "$tmp/rod.l" >"$tmp/steady.l"
"$bin" run "$tmp/steady.l" -o "sway:$tmp/steady.csv" >"$tmp/out3"
steady=$(awk '$1 == "steady" { print $2 }' "$tmp/out3")
awk -F, -v s="$steady" 'NR > 1 { n++; d = sqrt($6 * $6 + $7 * $7 + $8 * $8)
    e = (d - s) / s; if (e < 0) e = -e; if (e > 1e-6) { print "frame", $1, d, "static", s; exit 1 } }
    END { if (n != 6) { print "rows", n; exit 1 } }' "$tmp/steady.csv"
# a model that never calls Sway(): exit 1, a message, nothing written
sed 's/printf("\(still\|steady\|gusty\).*//' "$tmp/rod.l" >"$tmp/nosway.l"
set +e
"$bin" run "$tmp/nosway.l" -o "sway:$tmp/none.csv" >/dev/null 2>"$tmp/err"
rc=$?
set -e
test $rc -eq 1 || { echo "exit $rc without Sway()"; cat "$tmp/err"; exit 1; }
grep -q 'no Sway()' "$tmp/err"
test ! -e "$tmp/none.csv" && test ! -e "$tmp/none.csv.part"
# a wrong extension is a usage error (exit 2)
set +e
"$bin" run "$tmp/rod.l" -o "sway:$tmp/x.png" >/dev/null 2>"$tmp/err"
rc=$?
set -e
test $rc -eq 2 || { echo "exit $rc for sway:x.png"; cat "$tmp/err"; exit 1; }
test ! -e "$tmp/x.png"
