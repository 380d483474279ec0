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
