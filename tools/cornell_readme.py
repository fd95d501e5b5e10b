#!/usr/bin/env python3
"""Prints the sweep tables of docs/reproduction.md (markdown) from `bench cornell` output
folders, so no figure in them is typed by hand.

    python3 tools/cornell_readme.py time DIR ...   # the time table
    python3 tools/cornell_readme.py claims DIR     # claims.md without its title

DIR is a `bench-out/cornell-<timestamp>/` folder (summary.json, claims.md)."""
import json
import os
import sys


def time_table(dirs):
    out = ["| scene | mode | trace (s) | kd-trees (s) | densities (s) | runs | wall clock (s) |",
           "|---|---|---|---|---|---|---|"]
    for d in dirs:
        r = json.load(open(os.path.join(d, "summary.json")))["results"]
        for t in r["timing"]:
            out.append(f"| {r['scene']} | {t['mode']} | {t['trace_s']:.1f} | {t['build_s']:.1f} | "
                       f"{t['measure_s']:.1f} | {t['runs']} | {r['elapsed_s']:.0f} |")
    return "\n".join(out)


def claims(d):
    lines = open(os.path.join(d, "claims.md")).read().strip().split("\n")
    return "\n".join(lines[1:]).strip()


if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] not in ("time", "claims"):
        sys.exit(__doc__)
    print(time_table(sys.argv[2:]) if sys.argv[1] == "time" else claims(sys.argv[2]))
