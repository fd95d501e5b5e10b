#!/usr/bin/env python3
"""The tracer's ray rate against raw Embree at 1 and 2 threads, in rounds:
each round runs `adaptive-pm bench rays cornell --json` and then the
classic trace at 1 and 2 threads, right after, so that each ratio compares
two rates measured a few seconds apart (this machine's speed drifts by tens
of percent between minutes). Prints a markdown table, one row per round,
and the medians.

    python3 tools/trace_rounds.py run BINARY N_MAX ROUNDS DIR
    python3 tools/trace_rounds.py print DIR

`run` keeps every JSON in DIR (rays_R.json, trace1_R.json, trace2_R.json);
`print` prints the table again from them."""
import json
import os
import statistics
import subprocess
import sys


def run(binary, n_max, rounds, out):
    os.makedirs(out, exist_ok=True)
    for r in range(1, rounds + 1):
        jobs = [("rays", [binary, "bench", "rays", "cornell", "--json"])]
        for t in (1, 2):
            jobs.append((f"trace{t}", [binary, "trace", "cornell", "--mode", "classic",
                                       "--n-max", str(n_max), "--threads", str(t), "--json"]))
        for name, cmd in jobs:
            text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
            with open(os.path.join(out, f"{name}_{r}.json"), "w") as f:
                f.write(text)
            print(f"round {r}: {name} done", file=sys.stderr)


def table(out):
    rows, ratios = [], {1: [], 2: []}
    r = 1
    while os.path.exists(os.path.join(out, f"rays_{r}.json")):
        load = lambda name: json.load(open(os.path.join(out, f"{name}_{r}.json")))
        rays = load("rays")
        raw = {1: rays["one_thread"]["raw_mrays_per_s"], 2: rays["raw_mrays_per_s"]}
        if rays["threads"] != 2:
            sys.exit(f"round {r}: bench rays ran on {rays['threads']} threads, not 2")
        cells = [str(r)]
        checks = set()
        for t in (1, 2):
            d = load(f"trace{t}")
            rate = d["rays_per_s"] / 1e6
            ratios[t].append(rate / raw[t])
            checks.add(d["checksum"])
            cells += [f"{raw[t]:.2f}", f"{d['trace_s']:.2f}", f"{rate:.2f}", f"{rate / raw[t]:.3f}"]
        cells.append(", ".join(sorted(checks)))
        rows.append(cells)
        r += 1
    if not rows:
        sys.exit(f"{out}: no rays_1.json")
    head = ["round", "raw 1T", "trace s 1T", "Mrays/s 1T", "of raw 1T",
            "raw 2T", "trace s 2T", "Mrays/s 2T", "of raw 2T", "checksum"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for cells in rows:
        print("| " + " | ".join(cells) + " |")
    print(f"\nmedian of raw: {statistics.median(ratios[1]):.3f} on 1 thread, "
          f"{statistics.median(ratios[2]):.3f} on 2 threads")


def main(args):
    if args[:1] == ["run"] and len(args) == 5:
        run(args[1], int(args[2]), int(args[3]), args[4])
        table(args[4])
    elif args[:1] == ["print"] and len(args) == 2:
        table(args[1])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
