#!/usr/bin/env python3
"""The README table of an A/B comparison from tools/ab_trace_vs_raw.sh outputs.

usage: python3 tools/ab_table.py FILE...   (one file per thread count, named
*one_thread*, *two_threads*, or anything: the row is labelled by the file)

Each input line is `A|B of_raw tracer_ns added_ns`, A and B alternating by
round. Prints one row per file: rounds, the median "of raw" of A and of B, and
the median and range of B/A over paired rounds.
"""
import statistics
import sys


def row(path):
    runs = {"A": [], "B": []}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 4:
                runs[parts[0]].append(float(parts[1]))
    pairs = [b / a for a, b in zip(runs["A"], runs["B"])]
    label = path.rsplit("/", 1)[-1].rsplit(".", 1)[0].replace("_", " ")
    return "| {} | {} | {:.3f} | {:.3f} | {:.2f} ({:.2f}–{:.2f}) |".format(
        label,
        len(pairs),
        statistics.median(runs["A"]),
        statistics.median(runs["B"]),
        statistics.median(pairs),
        min(pairs),
        max(pairs),
    )


def main():
    print("| threads | rounds | of raw, before (median) | of raw, after (median) "
          "| after / before, paired rounds (median, range) |")
    print("|---|---|---|---|---|")
    for path in sys.argv[1:]:
        print(row(path))


if __name__ == "__main__":
    main()
