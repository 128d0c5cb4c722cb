#!/usr/bin/env python3
"""Two commands timed in turn, A B A B ..., and their ratio pair by pair.

  python3 bench/paired.py [-n RUNS] [--warmup N] --a 'COMMAND A' --b 'COMMAND B'

Each command is one string split as a shell splits words (no shell runs it:
wrap it in `sh -c '...'` for redirections). Each run is a whole process:
wall seconds from its start to its end, CPU seconds (user + system) and peak
memory, as the operating system accounts for the finished child (wait4; it
starts as a copy of this timer, so a peak is never below its ~12 MB). The
machines this runs on drift in speed, so what to quote is the median of the
per-pair ratios A/B, not one run's time: a pair's two runs are seconds
apart and share the machine's state.

Printed: per figure the minimum, median and maximum of A, of B and of A/B.
The commands' exit codes are printed; a command that fails is not timed
again (exit 1). Figures only: nothing is judged.
"""
import argparse
import os
import shlex
import statistics
import subprocess
import sys
import time


def run_once(argv):
    """(wall s, cpu s, peak MB, exit code) of one run of argv, from the
    operating system's accounting of that child alone (wait4)."""
    t0 = time.perf_counter()
    child = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - t0
    child.returncode = os.waitstatus_to_exitcode(status)
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, child.returncode


def spread(values):
    return f"{min(values):8.3f} {statistics.median(values):8.3f} {max(values):8.3f}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-n", type=int, default=5, help="counted pairs (default 5)")
    p.add_argument("--warmup", type=int, default=1, help="pairs run first, not counted (default 1)")
    p.add_argument("--a", required=True, help="command A, one string")
    p.add_argument("--b", required=True, help="command B, one string")
    args = p.parse_args(argv)
    if args.n < 1:
        p.error(f"-n must be at least 1, got {args.n}")
    if args.warmup < 0:
        p.error(f"--warmup must be 0 or more, got {args.warmup}")
    commands = {"A": shlex.split(args.a), "B": shlex.split(args.b)}
    for name, cmd in commands.items():
        if not cmd:
            p.error(f"--{name.lower()}: empty command")
    figures = {"A": [], "B": []}
    for i in range(args.warmup + args.n):
        for name, cmd in commands.items():
            try:
                wall, cpu, peak, code = run_once(cmd)
            except OSError as e:
                print(f"paired: command {name} cannot be started: {e}", file=sys.stderr)
                return 2
            if code != 0:
                print(f"paired: command {name} exited with {code}; not timed further",
                      file=sys.stderr)
                return 1
            if i >= args.warmup:
                figures[name].append((wall, cpu, peak))
    print(f"{args.n} pairs after {args.warmup} warm-up pair(s) on {os.cpu_count()} CPUs "
          f"(min median max)")
    for k, what in enumerate(("wall s", "cpu s", "peak MB")):
        a = [f[k] for f in figures["A"]]
        b = [f[k] for f in figures["B"]]
        ratio = [x / y for x, y in zip(a, b)]
        print(f"{what:7s} A {spread(a)}   B {spread(b)}   A/B {spread(ratio)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
