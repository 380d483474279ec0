#!/usr/bin/env python3
"""Regenerates the reference numbers of tests/test_dyn_benchmark.c from the peer, PyElastica.

The case is PyElastica's own example DynamicCantileverCase (examples/DynamicCantileverCase/
dynamic_cantilever.py, the function simulate_dynamic_cantilever_with, as its
dynamic_cantilever_phase_space.py calls it): a Cosserat rod of 1 m, radius 2 cm, E = 1e5 Pa,
100 elements, clamped, no gravity, no damping, started with the first Euler-Bernoulli mode's
velocity (5 mm/s at the tip), position Verlet for 300 s. This script calls that function
unchanged and measures the tip history it records (30 frames a second) the way the test measures
ours: the period from the zero crossings after t = 0 (linear interpolation; twice the mean
spacing of all crossings) and the largest deflection. The example's own FFT peak is printed too:
its bin is 2 pi / 300 rad/s wide, 8 % of the frequency, too coarse to test against.

Usage: PYELASTICA=/path/to/PyElastica tools/pyelastica-cantilever.py [RHO[:N_ELEM[:SECONDS]] ...]
Default: 500:100:300 2000:100:300 5000:100:300 (the phase-space script's function defaults, three
of its densities) and 500:200:100 (the visualization script's case). The checkout must hold elastica/ and examples/; the Python
must have numpy, scipy, numba and tqdm (Debian: python3-numpy python3-scipy python3-numba
python3-tqdm python3-typing-extensions). Without them the script says so and exits 0.
A 300 s case costs 600,000 steps of the peer (a minute or two of CPU).
"""
import contextlib
import math
import os
import sys


def skip(why):
    print(f"pyelastica-cantilever: skipped: {why}")
    sys.exit(0)


def crossings_period(times, w):
    """Twice the mean spacing of the sign changes of w after the first sample."""
    cross = []
    for i in range(2, len(w)):
        a, b = w[i - 1], w[i]
        if (a > 0.0) != (b > 0.0):
            t0, t1 = times[i - 1], times[i]
            cross.append(t0 + (t1 - t0) * a / (a - b))
    if len(cross) < 2:
        return float("nan"), len(cross)
    return 2.0 * (cross[-1] - cross[0]) / (len(cross) - 1), len(cross)


def main():
    root = os.environ.get("PYELASTICA")
    if not root:
        skip("set PYELASTICA to a PyElastica checkout (elastica/ and examples/)")
    case = os.path.join(root, "examples", "DynamicCantileverCase")
    if not os.path.isfile(os.path.join(case, "dynamic_cantilever.py")):
        skip(f"no examples/DynamicCantileverCase/dynamic_cantilever.py under {root}")
    sys.path.insert(0, root)
    sys.path.insert(0, case)
    try:
        import numpy  # noqa: F401
        import elastica  # noqa: F401
        from dynamic_cantilever import simulate_dynamic_cantilever_with
    except ImportError as e:
        skip(f"the peer does not import here ({e})")

    cases = []
    for arg in sys.argv[1:] or ["500:100:300", "2000:100:300", "5000:100:300", "500:200:100"]:
        f = arg.split(":")
        cases.append((float(f[0]), int(f[1]) if len(f) > 1 else 100, float(f[2]) if len(f) > 2 else 300.0))
    print("density_kg_m3,n_elem,duration_s,period_s,amplitude_m,crossings,fft_omega_rad_s,eb_period_s,eb_amplitude_m")
    for rho, n_elem, duration in cases:
        # the example prints its own summary: keep stdout for the table
        with contextlib.redirect_stdout(sys.stderr):
            r = simulate_dynamic_cantilever_with(
                density=rho, n_elem=n_elem, final_time=duration, mode=0
            )
        h = r["recorded_history"]
        times = [float(t) for t in h["time"]]
        w = [float(x) for x in h["deflection"]]
        period, n = crossings_period(times, w)
        omega = r["theoretical_frequency"]
        print(
            f"{rho:g},{n_elem},{duration:g},{period:.7f},{max(w):.8f},{n},{r['simulated_frequency']:.6f},"
            f"{2 * math.pi / omega:.7f},{r['theoretical_amplitude']:.8f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
