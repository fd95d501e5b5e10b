#!/usr/bin/env python3
"""The seed sweep's table, from the logs of `cargo test -- --nocapture` runs
(one per seed) that scripts/seed-sweep.sh collects.

A test fails a seed when libtest says so (`test NAME ... FAILED`), whatever
it printed. Each `seed-sweep:` line is one check of one test, read from the
`.sweep` file beside each log (the tests append whole lines to it; in the log
itself, progress dots and parallel tests' output break lines apart): the deviation
in sigmas (z) and the bound in sigmas. The table gives, per test, the
failures out of the seeds run, the worst z, the narrowest bound and the
worst margin (bound - z, in sigmas). Exit status 1 when any run failed.
"""
import argparse
import re
import sys
from collections import defaultdict
from pathlib import Path

LINE = re.compile(
    r"^seed-sweep: test=(\S+) check=(\S+) z=(\S+) bound_sigmas=(\S+) ok=(true|false)$", re.M
)
FAILED = re.compile(r"^test (\S+) \.\.\. FAILED", re.M)
# libtest's closing list (also under -q): "failures:" then "    name" lines.
FAILURE_LIST = re.compile(r"^failures:\n((?:    \S+\n)+)", re.M)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("logs", nargs="+", type=Path)
    ap.add_argument("--seeds", type=int, required=True)
    ap.add_argument("--isa", default="native")
    ap.add_argument("--out", type=Path)
    a = ap.parse_args()
    runs = defaultdict(int)
    fails = defaultdict(int)
    worst_z = defaultdict(float)
    bound = defaultdict(lambda: float("inf"))
    margin = defaultdict(lambda: float("inf"))
    checks = defaultdict(set)
    other_failures = defaultdict(int)
    for log in a.logs:
        text = log.read_text(errors="replace")
        sweep = log.with_suffix(".sweep")
        lines = sweep.read_text(errors="replace") if sweep.exists() else text
        seen = set()
        for m in LINE.finditer(lines):
            test, check, z, b = m[1], m[2], float(m[3]), float(m[4])
            seen.add(test)
            checks[test].add(check)
            worst_z[test] = max(worst_z[test], z)
            bound[test] = min(bound[test], b)
            margin[test] = min(margin[test], b - z)
        failed = set(m[1] for m in FAILED.finditer(text))
        for block in FAILURE_LIST.finditer(text):
            failed.update(line.strip() for line in block[1].splitlines())
        failed.update(m[1] for m in LINE.finditer(lines) if m[5] != "true")
        for t in seen:
            runs[t] += 1
        for t in failed:
            if t in checks or t in seen:
                fails[t] += 1
            else:
                other_failures[t] += 1
    # A test reports a line only from the checks it reaches; "runs" counts
    # the seeds whose log holds one (one-sided checks log only a margin).
    rows = [
        "| test | checks | failures | worst z | narrowest bound | worst margin |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for t in sorted(checks):
        rows.append(
            f"| `{t}` | {len(checks[t])} | {fails[t]}/{runs[t]} | {worst_z[t]:.2f} | "
            f"{bound[t]:.2f} | {margin[t]:.2f} |"
        )
    total = sum(fails.values()) + sum(other_failures.values())
    lines = [
        f"Seed sweep: {a.seeds} seeds, Embree kernels {a.isa}, {len(checks)} seeded "
        f"statistical tests, {total} failed runs. z is a check's deviation in its own "
        "measured sigmas; the bound and the margin are in sigmas too.",
        "",
        *rows,
    ]
    for t, k in sorted(other_failures.items()):
        lines.append(f"\nAlso failed (no seed-sweep line): `{t}` in {k} runs")
    text = "\n".join(lines) + "\n"
    sys.stdout.write(text)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(text)
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
