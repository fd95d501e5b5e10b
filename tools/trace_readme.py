#!/usr/bin/env python3
"""Prints a table of docs/performance.md (markdown) from `adaptive-pm trace ... --json`
outputs, one row per file, so no figure in it is typed by hand.

    python3 tools/trace_readme.py FILE.json ...

With `--raw M1,M2,...` (raw Embree Mrays/s, one per file, from `bench rays`)
a column gives the tracer's share of it."""
import json
import sys


def main(args):
    raw = None
    if args[:1] == ["--raw"]:
        raw = [float(x) for x in args[1].split(",")]
        args = args[2:]
    if not args or (raw and len(raw) != len(args)):
        sys.exit(__doc__)
    head = ["emitted", "stored", "threads", "map MB", "peak RSS MB", "peak / map",
            "trace s", "rays", "Mrays/s", "kd-tree s"] + (["of raw"] if raw else [])
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for i, f in enumerate(args):
        try:
            d = json.load(open(f))
            d["rays"], d["rays_per_s"], d["map_bytes"], d["peak_rss_bytes"], d["build_s"]
        except (OSError, ValueError, KeyError) as e:
            sys.exit(f"{f}: not the JSON of `adaptive-pm trace --json` ({e})")
        mrays = d["rays_per_s"] / 1e6
        row = [f"{d['emitted']:,}", f"{d['stored']:,}", str(d["threads"]),
               f"{d['map_bytes'] / 1e6:,.0f}", f"{d['peak_rss_bytes'] / 1e6:,.0f}",
               f"{d['peak_rss_bytes'] / d['map_bytes']:.3f}", f"{d['trace_s']:.1f}",
               f"{d['rays']:.3g}", f"{mrays:.2f}", f"{d['build_s']:.1f}"]
        if raw:
            row.append(f"{mrays / raw[i]:.2f}")
        out.append("| " + " | ".join(row) + " |")
    print("\n".join(out))


if __name__ == "__main__":
    main(sys.argv[1:])
