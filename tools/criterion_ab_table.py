#!/usr/bin/env python3
"""Markdown table of interleaved criterion runs of two builds.

Each input file holds lines `old <median> <unit> ...` and `new <median>
<unit> ...`, one per run of `whole/` (in the order of
benches/analysis.rs), old and new in turn: the format of
docs/analysis_cost_2026-12-05/criterion_interleaved_*.txt. Each old/new
pair is a round; the table gives, per file and round, the before and after
medians of the chosen functions and their ratio.

    python3 tools/criterion_ab_table.py FILE...
"""
import sys

COLUMNS = ["cos^10", "cos^100", "Phong 100", "Cook–Torrance 0.3",
           "Cook–Torrance 0.05", "glTF metal 0.3", "glTF plastic 0.5",
           "rough glass 0.3", "rough glass 0.05"]
SHOWN = ["rough glass 0.3", "rough glass 0.05", "Cook–Torrance 0.3"]
SCALE = {"µs": 1e-3, "ms": 1.0, "s": 1e3}


def medians(fields):
    """Milliseconds of each `<value> <unit>` pair."""
    pairs = zip(fields[0::2], fields[1::2])
    return [float(v) * SCALE[u] for v, u in pairs]


def rounds(path):
    old = None
    with open(path, encoding="utf-8") as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            times = medians(fields[1:])
            if len(times) != len(COLUMNS):
                sys.exit(f"{path}: expected {len(COLUMNS)} times, got: {line.strip()}")
            if fields[0] == "old":
                old = times
            elif fields[0] == "new" and old is not None:
                yield old, times
                old = None


def main(paths):
    if not paths:
        sys.exit(__doc__)
    print("| file | round | " + " | ".join(
        f"{c}: before, after, ratio" for c in SHOWN) + " |")
    print("|---|---|" + "---|" * len(SHOWN))
    for path in paths:
        for k, (old, new) in enumerate(rounds(path), 1):
            cells = []
            for c in SHOWN:
                i = COLUMNS.index(c)
                cells.append(f"{old[i]:.2f}, {new[i]:.2f} ms, {new[i] / old[i]:.2f}")
            name = path.rsplit("/", 1)[-1]
            print(f"| {name} | {k} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
