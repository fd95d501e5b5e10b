#!/usr/bin/env python3
"""Where the tracer reaches 0.8 of raw Embree: the Cornell box with every
triangle split into 4^L (`examples/trace_vs_raw.rs`, SPLIT = L), the same
photons and paths with dearer rays. For each L it runs ROUNDS alternating
raw/trace rounds and keeps their whole output; `print` makes the markdown
table from those files: per file, the round with the median ratio (a row
of one round, so its columns agree) and the range of the ratio over all
rounds (this machine drifts by tens of percent between minutes).

Run from the repository root:

    cargo build --release --example trace_vs_raw
    python3 tools/ray_cost_sweep.py run N_MAX THREADS ROUNDS DIR L [L ...]
    python3 tools/ray_cost_sweep.py print DIR"""
import os
import subprocess
import sys

BINARY = "target/release/examples/trace_vs_raw"


def run(n_max, threads, rounds, out, levels):
    os.makedirs(out, exist_ok=True)
    for level in levels:
        cmd = [BINARY, str(n_max), str(threads), str(rounds), str(level)]
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        with open(os.path.join(out, f"split{level}_t{threads}.txt"), "w") as f:
            f.write("$ " + " ".join(cmd) + "\n" + text)
        print(f"split {level}, {threads} thread(s) done", file=sys.stderr)


def parse(path):
    lines = open(path).read().splitlines()
    triangles, threads = lines[1].split(" triangles, ")
    # Round rows have 8 fields; the closing summary line has more.
    rows = (l.split() for l in lines[3:])
    rounds = [[float(x) for x in f] for f in rows if len(f) == 8 and f[0].isdigit()]
    if not rounds:
        sys.exit(f"{path}: no rounds")
    by_ratio = sorted(rounds, key=lambda r: r[4])
    r = by_ratio[len(by_ratio) // 2]
    return {
        "triangles": int(triangles),
        "threads": int(threads.split()[0]),
        "rounds": len(rounds),
        "raw": r[1], "trace": r[3], "ratio": r[4],
        "low": by_ratio[0][4], "high": by_ratio[-1][4],
        "raw_ns": r[5], "trace_ns": r[6], "added_ns": r[7],
    }


def table(out):
    names = sorted(f for f in os.listdir(out) if f.startswith("split") and f.endswith(".txt"))
    if not names:
        sys.exit(f"{out}: no split*_t*.txt")
    runs = sorted((parse(os.path.join(out, f)) for f in names),
                  key=lambda r: (r["threads"], r["triangles"]))
    head = ["triangles", "threads", "rounds", "raw Mrays/s", "tracer Mrays/s", "of raw",
            "of raw, all rounds", "raw ns/ray", "tracer ns/ray", "added ns/ray"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in runs:
        print(f"| {r['triangles']} | {r['threads']} | {r['rounds']} | {r['raw']:.2f} | "
              f"{r['trace']:.2f} | **{r['ratio']:.3f}** | {r['low']:.3f}–{r['high']:.3f} | "
              f"{r['raw_ns']:.0f} | {r['trace_ns']:.0f} | {r['added_ns']:.0f} |")
    print("\neach row is the round with the median ratio; ns per ray are per thread")


if __name__ == "__main__":
    if len(sys.argv) >= 7 and sys.argv[1] == "run":
        run(int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5],
            [int(l) for l in sys.argv[6:]])
        table(sys.argv[5])
    elif len(sys.argv) == 3 and sys.argv[1] == "print":
        table(sys.argv[2])
    else:
        sys.exit(__doc__)
