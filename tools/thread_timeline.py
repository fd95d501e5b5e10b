#!/usr/bin/env python3
"""How busy each thread of a run was, window by window, from a `perf`
recording at a fixed rate (`-F`; on a machine without hardware counters
perf samples by the CPU clock):

    perf record -F 999 -o P -- adaptive-pm render cornell --map M --spp 72 --out x.exr
    perf script -i P -F tid,time | python3 tools/thread_timeline.py [WINDOW_S [CORES]]

Prints, per window (0.1 s by default), the samples of each thread that had
any, busiest first: at 999 Hz a thread busy for a whole 0.1 s window has
about 100. A window where one thread shows 100 and no other shows any is a
window where the other cores sat idle. The last line gives the share of
CORES (default: this machine's) that sat idle from the first window where
two threads ran to the run's end, its tail included.
"""
import collections
import os
import sys


def read_samples(lines):
    """(tid, seconds) of each `perf script -F tid,time` line."""
    out = []
    for line in lines:
        fields = line.split()
        if len(fields) < 2 or not fields[1].endswith(":"):
            continue
        try:
            out.append((int(fields[0]), float(fields[1][:-1])))
        except ValueError:
            continue
    return out


def main(window, cores):
    samples = read_samples(sys.stdin)
    if not samples:
        sys.exit("no samples: pipe `perf script -F tid,time` into this")
    t0 = min(t for _, t in samples)
    windows = collections.defaultdict(collections.Counter)
    for tid, t in samples:
        windows[int((t - t0) / window)][tid] += 1
    for k in sorted(windows):
        counts = sorted(windows[k].values(), reverse=True)
        print(f"{k * window:7.2f} s  " + " ".join(f"{c:4d}" for c in counts))
    # A window's capacity: `cores` threads at the busiest thread's count.
    # From the first window with two threads busy to the last one (the
    # run's tail included), the share of that capacity no thread used.
    busiest = max(max(c.values()) for c in windows.values())
    parallel = [k for k in sorted(windows) if len(windows[k]) >= 2]
    if parallel and cores > 1:
        span = range(parallel[0], max(windows) + 1)
        used = sum(min(sum(windows[k].values()), cores * busiest) for k in span)
        # The last window is only as long as the run lasted into it.
        last = (max(t for _, t in samples) - t0) / window - max(windows)
        capacity = cores * busiest * (len(span) - 1 + last)
        print(f"idle share of {cores} cores from the first parallel window on: "
              f"{1 - used / capacity:.1%}")


if __name__ == "__main__":
    try:
        if len(sys.argv) > 3:
            raise ValueError
        window = float(sys.argv[1]) if len(sys.argv) > 1 else 0.1
        cores = int(sys.argv[2]) if len(sys.argv) > 2 else (os.cpu_count() or 1)
        if not (window > 0 and cores >= 1):
            raise ValueError
    except ValueError:
        sys.exit(__doc__ + "\nWINDOW_S must be a positive number of seconds, CORES a count of 1 or more")
    main(window, cores)
