#!/usr/bin/env bash
# The L+C dialect's SwayDrag(duration, dt, wind, gust, coherence, leaf area per kg)
# (docs/language.md, "Mechanics"; docs/dynamics.md, "Drag of leaves and fruit"): a vertical
# uniform cantilever (1 m, r 1 cm, E 10 GPa, no gravity) with 10 g of leaves (5 m^2/kg: 0.05 m^2)
# at the node 0.525 m up and a fruit sphere (radius 4 cm) at the tip, in a steady log-profile wind
# of 20 m/s at 10 m. The peak is the tip's static deflection: the wood's drag (quadrature, as in
# lc_dynamics.sh) plus the fruit's 1/2 rho 0.47 pi r^2 U(1)^2 at the tip (F L^3 / 3EI) plus the
# leaves' 1/2 rho 1.17 A U^2 (U / 5)^(-2/3) at a = 0.525 m (F a^2 (3L - a) / 6EI). Sway() on the
# same model keeps the wood's drag alone; a gust field gives the same peak twice (the seed).
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/rod.l" <<'L'
#include <lpfgall.h>
derivation length: 40;
module I(MechSegment);
module A(int);
module Leaf(double);
module Fruit(double, double);
mechanics: I;
mass: Leaf;
mass: Fruit(mass, radius);
MechSegment S()
{
    MechSegment s;
    s.length = 0.025; s.a = 0.01; s.b = 0.01; s.E = 1e10; s.density = 600;
    return s;
}
Start: { Gravity(0, 0, 0); }
Axiom: A(40);
A(n): {
    if (n == 20) produce I(S()) Leaf(0.01) A(n - 1);
    if (n > 1) produce I(S()) A(n - 1);
    if (n == 1) produce I(S()) Fruit(0.2, 0.04) A(n - 1);
    produce;
}
End: {
    Equilibrium();
    printf("steady %.9g\n", Sway(0.2, 0.002, 20, 0));
    printf("drag %.9g\n", SwayDrag(0.2, 0.002, 20, 0, 0, 5));
    printf("field %.9g %.9g\n", SwayDrag(1, 0.002, 20, 0.3, 10, 5), SwayDrag(1, 0.002, 20, 0.3, 10, 5));
}
L
"$bin" run "$tmp/rod.l" >"$tmp/out"
awk '
$1 == "steady" { steady = $2 }
$1 == "drag" { drag = $2 }
$1 == "field" { f1 = $2; f2 = $3 }
END {
    pi = 3.141592653589793; EI = 1e10 * pi * 1e-8 / 4; N = 20000; s = 0
    for (i = 0; i < N; i++) { z = (i + 0.5) / N; U = (z > 0.1) ? 20 * log(z / 0.1) / log(100) : 0
        s += 0.5 * 1.226 * 0.02 * U * U * z * z * (3 - z) / (6 * EI) / N }
    Ut = 20 * log(10) / log(100); Ff = 0.5 * 1.226 * 0.47 * pi * 0.04 * 0.04 * Ut * Ut
    a = 0.525; Ua = 20 * log(a / 0.1) / log(100)
    Fl = 0.5 * 1.226 * 1.17 * 0.05 * Ua * Ua * exp(-2 / 3 * log(Ua / 5))
    ref = s + Ff / (3 * EI) + Fl * a * a * (3 - a) / (6 * EI)
    e = (drag - ref) / ref; if (e < 0) e = -e
    printf "SwayDrag peak %.6e m, hand %.6e m (wood %.4e, fruit %.4e N, leaves %.4e N), rel %.2e\n", drag, ref, s, Ff, Fl, e
    if (e > 2e-3) exit 1
    e = (steady - s) / s; if (e < 0) e = -e
    if (e > 2e-3) { print "steady", steady, "wood", s; exit 1 }
    if (!(f1 == f2 && f1 > drag)) { print "field", f1, f2; exit 1 }
}' "$tmp/out"
# errors: a file:line:col diagnostic, exit 1
for bad in 'SwayDrag(1, 0.01, 1, 0, -1, 0)' 'SwayDrag(1, 0.01, 1, 0, 0, -5)' 'SwayDrag(1, 0.01, 1, 0, 0)'; do
    sed "s/printf(\"steady.*/printf(\"%g\\\\n\", $bad);/" "$tmp/rod.l" >"$tmp/bad.l"
    set +e
    "$bin" run "$tmp/bad.l" >/dev/null 2>"$tmp/err"
    rc=$?
    set -e
    test $rc -eq 1 || { echo "exit $rc for $bad"; cat "$tmp/err"; exit 1; }
    grep -q 'bad.l:[0-9]*:[0-9]*: error' "$tmp/err" || { echo "no diagnostic for $bad"; cat "$tmp/err"; exit 1; }
done
