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

  --tracks A.json B.json [--keys table_s,reference_s,tracker_start_s]

also reads, after each run, the track file each command wrote (its
`timing`, docs/track-format.md) and prints the same three figures for each
key and for their sum: the estimate's own clock for its steps, e.g. the
fixed costs of issue 28 (the default keys).
"""
import argparse
import json
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
    p.add_argument("--tracks", nargs=2, metavar=("A_JSON", "B_JSON"),
                   help="the track files the commands write: their timing keys are printed too")
    p.add_argument("--keys", default="table_s,reference_s,tracker_start_s",
                   help="with --tracks: timing keys printed, and their sum "
                        "(default table_s,reference_s,tracker_start_s)")
    args = p.parse_args(argv)
    keys = [k for k in args.keys.split(",") if k]
    if args.tracks and not keys:
        p.error("--keys: name at least one timing key")
    if args.n < 1:
        p.error(f"-n must be at least 1, got {args.n}")
    if args.warmup < 0:
        p.error(f"--warmup must be 0 or more, got {args.warmup}")
    commands = {"A": shlex.split(args.a), "B": shlex.split(args.b)}
    for name, cmd in commands.items():
        if not cmd:
            p.error(f"--{name.lower()}: empty command")
    figures = {"A": [], "B": []}
    steps: dict = {"A": [], "B": []}
    tracks = dict(zip(("A", "B"), args.tracks or ()))
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
                if tracks:
                    got = _timing(tracks[name], keys)
                    if isinstance(got, str):
                        print(f"paired: command {name}: {got}", file=sys.stderr)
                        return 1
                    steps[name].append(got)
    print(f"{args.n} pairs after {args.warmup} warm-up pair(s) on {os.cpu_count()} CPUs "
          f"(min median max)")
    for k, what in enumerate(("wall s", "cpu s", "peak MB")):
        a = [f[k] for f in figures["A"]]
        b = [f[k] for f in figures["B"]]
        ratio = [x / y for x, y in zip(a, b)]
        print(f"{what:7s} A {spread(a)}   B {spread(b)}   A/B {spread(ratio)}")
    if tracks:
        width = max(len(k) for k in keys + ["sum of keys"])
        for k, what in enumerate(keys + ["sum of keys"]):
            a = [f[k] for f in steps["A"]]
            b = [f[k] for f in steps["B"]]
            ratio = [x / y if y else float("nan") for x, y in zip(a, b)]
            print(f"{what:{width}s} A {spread(a)}   B {spread(b)}   A/B {spread(ratio)}")
    return 0


def _timing(path, keys):
    """The keys' values in the track file's timing, and their sum; or why
    not (a message naming the file or the key)."""
    try:
        with open(path) as f:
            timing = json.load(f).get("timing") or {}
    except (OSError, ValueError) as e:
        return f"cannot read the track {path}: {e}"
    missing = [k for k in keys if not isinstance(timing.get(k), (int, float))]
    if missing:
        return f"the track {path} has no timing {', '.join(missing)}"
    values = [float(timing[k]) for k in keys]
    return values + [sum(values)]


if __name__ == "__main__":
    sys.exit(main())
