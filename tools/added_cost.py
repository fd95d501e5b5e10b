#!/usr/bin/env python3
"""The tracer's added cost per ray over raw Embree, from rounds of
`adaptive-pm bench rays SCENE --json` (roundK_rays.json) and
`adaptive-pm trace SCENE --mode classic -n N --threads T --json`
(roundK_trace_Tt.json) run one after the other in one folder:
`1/tracer_rate - 1/raw_rate`, per thread count.

Usage: python3 tools/added_cost.py DIR
"""
import glob
import json
import os
import sys


def main(folder):
    print("| round | threads | raw (Mrays/s) | tracer (Mrays/s) | of raw | added ns per ray (aggregate) | added ns per ray and thread |")
    print("|---|---|---|---|---|---|---|")
    for rays_path in sorted(glob.glob(os.path.join(folder, "round*_rays.json"))):
        name = os.path.basename(rays_path).split("_")[0]
        with open(rays_path) as f:
            rays = json.load(f)
        raw = {1: rays["one_thread"]["raw_mrays_per_s"], rays["threads"]: rays["raw_mrays_per_s"]}
        for t in sorted(raw):
            path = os.path.join(folder, f"{name}_trace_{t}t.json")
            if not os.path.exists(path):
                continue
            with open(path) as f:
                tracer = json.load(f)["rays_per_s"] / 1e6
            added = 1e3 / tracer - 1e3 / raw[t]
            print(f"| {name} | {t} | {raw[t]:.2f} | {tracer:.2f} | {tracer / raw[t]:.2f} | {added:.0f} | {added * t:.0f} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
