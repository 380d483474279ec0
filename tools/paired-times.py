#!/usr/bin/env python3
"""Paired, alternating timing of several commands on a shared machine (docs/performance.md).

Runs the commands one after the other, N rounds, the order reversed every other round (so that
a drift of the machine's load falls on all), each in DIR after the shell command PRE (e.g. the
removal of the outputs, so that no run replaces a file another wrote); prints for each command
the median wall time, its range, the median CPU time (user + system of the process and its
children) and the median of its paired ratios of wall time to the first command's, then the
load average.

Usage: tools/paired-times.py N DIR PRE -- NAME CMD ARGS... -- NAME CMD ARGS... [...]
e.g.   tools/paired-times.py 15 model "rm -f c.glb p.ray" \\
           -- cpfg cpfg -g -m plant.map -ray p.ray plant.l plant.v \\
           -- before /tmp/base-main/build/bin/cambium run plant.l plant.map plant.v -o c.glb \\
           -- after  $PWD/build/bin/cambium run plant.l plant.map plant.v -o c.glb
"""
import resource
import statistics
import subprocess
import sys
import time


def main(argv):
    if len(argv) < 6 or argv[3] != "--":
        sys.stderr.write(__doc__)
        return 2
    rounds, where, pre = int(argv[0]), argv[1], argv[2]
    cmds, cur = [], None
    for a in argv[3:]:
        if a == "--":
            cur = []
            cmds.append(cur)
        else:
            cur.append(a)
    if any(len(c) < 2 for c in cmds):
        sys.stderr.write("each command needs a name and a program\n")
        return 2
    wall = {c[0]: [] for c in cmds}
    cpu = {c[0]: [] for c in cmds}
    for r in range(rounds):
        for c in cmds if r % 2 == 0 else cmds[::-1]:
            if pre:
                subprocess.run(pre, shell=True, cwd=where, check=False)
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            p = subprocess.run(c[1:], cwd=where, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, check=False)
            t1 = time.perf_counter()
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            if p.returncode != 0:
                sys.stderr.write(f"{c[0]}: exit status {p.returncode}\n")
                return 1
            wall[c[0]].append(t1 - t0)
            cpu[c[0]].append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
    first = cmds[0][0]
    for c in cmds:
        w = wall[c[0]]
        ratios = [a / b for a, b in zip(w, wall[first])]
        print(f"{c[0]:12s} wall median {statistics.median(w) * 1e3:8.2f} ms "
              f"({min(w) * 1e3:.2f}-{max(w) * 1e3:.2f})  CPU median "
              f"{statistics.median(cpu[c[0]]) * 1e3:7.2f} ms  wall / {first}: median "
              f"{statistics.median(ratios):.3f} ({min(ratios):.2f}-{max(ratios):.2f})")
    with open("/proc/loadavg", encoding="ascii") as f:
        print("load average", " ".join(f.read().split()[:3]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
