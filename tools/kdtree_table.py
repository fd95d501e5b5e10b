#!/usr/bin/env python3
"""Prints the README's kd-tree table (ours against kiddo 6) from criterion's
saved estimates of `cargo bench --bench kdtree` (medians, target/criterion).

Usage: python3 tools/kdtree_table.py [TARGET_DIR]   (default: target)
Run `KDTREE_BENCH_10M=1 cargo bench --bench kdtree -- 'build|queries'` first;
rows whose estimates are missing are left out.
"""
import json
import os
import sys

root = os.path.join(sys.argv[1] if len(sys.argv) > 1 else "target", "criterion")


def median_s(*path):
    f = os.path.join(root, *path, "new", "estimates.json")
    if not os.path.exists(f):
        return None
    with open(f) as fh:
        return json.load(fh)["median"]["point_estimate"] * 1e-9


def fmt(s):
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6)):
        if s >= scale:
            return f"{s / scale:.3g} {unit}" if unit != "s" else f"{s:.2f} s"
    return f"{s * 1e9:.0f} ns"


rows = []
for threads in (1, 2):
    for n, label in ((10_000, "10k"), (100_000, "100k"), (1_000_000, "1M"), (10_000_000, "10M")):
        rows.append((f"build {label}", threads, ("build", "photon_map", f"{n}_{threads}t"),
                     ("build", "kiddo", f"{n}_{threads}t")))
rows.append(("2000 queries k = 50 in 1M", 1, ("queries_of_1M", "nearest_50_photon_map"),
             ("queries_of_1M", "nearest_50_kiddo")))
rows.append(("2000 radius queries (~50 found) in 1M", 1, ("queries_of_1M", "radius_photon_map"),
             ("queries_of_1M", "radius_kiddo")))

print("| | threads | ours | kiddo 6 | ours / kiddo |")
print("|---|---|---|---|---|")
for label, threads, ours, theirs in rows:
    a, b = median_s(*ours), median_s(*theirs)
    if a is None or b is None:
        continue
    print(f"| {label} | {threads} | {fmt(a)} | {fmt(b)} | {a / b:.2f} |")
