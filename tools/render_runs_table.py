#!/usr/bin/env python3
"""Markdown table of `adaptive-pm bench render` runs (their JSON outputs):
per run, the photon render's settings, the row the run timed at the target
(its `photon_time_to_target_s`: the fastest row that reached it until
5a890dc, each budget's fewest spp there since, the fastest budget's), the
path tracer's extrapolated time and the ratio.

Usage: python3 tools/render_runs_table.py RUN.json [RUN.json ...]
"""
import json
import sys


def timed_at_target(res, target):
    """The row whose total time is the run's time to the target."""
    hits = [r for r in res["photon"] if r["rel_rmse"] <= target]
    timed = res.get("photon_time_to_target_s")
    chosen = [r for r in hits if r["total_s"] == timed]
    if chosen:
        return chosen[0]
    return min(hits, key=lambda r: r["total_s"]) if hits else None


def main(paths):
    print("| run | final gather | k | N_MAX | spp | relRMSE | photon s | path s | photon / path | reruns' photon / path | median | bias per channel |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for path in paths:
        with open(path) as f:
            d = json.load(f)
        res = d["result"]
        best = timed_at_target(res, 0.03)
        name = path.rsplit("/", 1)[-1].removesuffix(".json")
        if best is None:
            print(f"| {name} | {d['final_gather']} | {d['k']} | | | not reached | | | | | | |")
            continue
        bias = " / ".join(f"{100 * b:+.2f} %" for b in best["bias"])
        path_s = res["path_time_to_target_s"]
        reruns = ", ".join(f"1/{1 / r['ratio']:.1f}" for r in res.get("reruns", []))
        median = res.get("median_ratio")
        median = f"1/{1 / median:.1f}" if median else ""
        print(
            f"| {name} | {d['final_gather']} | {d['k']} | {best['n_max']} | {best['spp']} "
            f"| {100 * best['rel_rmse']:.2f} % | {best['total_s']:.2f} | {path_s:.1f} "
            f"| 1/{path_s / best['total_s']:.1f} | {reruns} | {median} | {bias} |"
        )


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
