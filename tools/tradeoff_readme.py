#!/usr/bin/env python3
"""Prints the trade section of docs/rendering.md (markdown) from `bench tradeoff --json`
outputs, so no figure in it is typed by hand.

    python3 tools/tradeoff_readme.py "NAME@@COMMAND@@DIR/tradeoff.json" ... > section.md

NAME titles the scene, COMMAND is the command that produced the file (shown
verbatim). A contender "wins" a level when its error is more than 5 % below
the next one's, "ties" within 5 %. The verdicts are given for the paper's
adaptive counts against the other modes, and, where the file has it (studies
since the fourth contender), for `importance` against the best of the others;
older files, with three modes, print as they did."""
import json, sys

TIE = 0.05


def verdict(level, key="errors", who="adaptive", against=None):
    """`who`'s verdict at a level, against the contenders in `against` (all
    the others when None)."""
    errs = {m: e for m, e in level[key].items() if against is None or m in against or m == who}
    errs = sorted(errs.items(), key=lambda kv: kv[1])
    ad = dict(errs).get(who)
    if ad is None:
        return "has no value", "outside its measured range"
    if len(errs) < 2:
        return "has no rival", "the others are outside their measured ranges"
    (m0, e0), (m1, e1) = errs[0], errs[1]
    if m0 == who:
        word = "wins" if e1 > e0 * (1 + TIE) else "ties"
        return word, f"x{e1 / e0:.2f} below {m1}"
    word = "loses" if ad > e0 * (1 + TIE) else "ties"
    return word, f"x{ad / e0:.2f} of {m0}"


def contenders(d):
    seen = []
    for g in d["groups"]:
        if g["mode"] not in seen:
            seen.append(g["mode"])
    return seen


def section(name, label, d):
    r = d["reference"]
    out = [f"**{name}** — `{label}` ({d['elapsed_s']:.0f} s, {d['threads']} threads). "
           f"Reference: path tracer, {r['spp']} spp; its noise {r['noise']:.3f} (indirect), "
           f"{r['image_noise']:.3f} (image), {r['points_noise']:.3f} (points).", ""]
    out.append("| mode | N_MAX | time (s) | map MB | (a) indirect: mean / bias / spread | (b) image | (c) points: mean / bias / spread |")
    out.append("|---|---|---|---|---|---|---|")
    for g in d["groups"]:
        i, p = g["indirect"], g["points"]
        out.append(f"| {g['mode']} | {g['n_max']} | {g['time_s']:.3f} | {g['map_bytes'] / 1e6:.2f} | "
                   f"{i['mean']:.3f} / {i['bias']:.3f} / {i['spread']:.3f} | {g['image']['mean']:.3f} | "
                   f"{p['mean']:.3f} / {p['bias']:.3f} / {p['spread']:.3f} |")
    out.append("")
    modes = contenders(d)
    paper = [m for m in modes if m != "importance"]
    for name, key, unit in [("equal time", "equal_time", "s"), ("equal memory", "equal_memory", "MB")]:
        parts = []
        for lv in d[key]:
            at = lv["at"] / 1e6 if unit == "MB" else lv["at"]
            w, how = verdict(lv, against=paper)
            wp, howp = verdict(lv, "points_errors", against=paper)
            part = f"at {at:.3g} {unit} adaptive **{w}** on indirect ({how}), {wp} on points ({howp})"
            if "importance" in modes:
                wi, howi = verdict(lv, who="importance")
                wpi, howpi = verdict(lv, "points_errors", who="importance")
                part += f"; importance **{wi}** on indirect ({howi}), {wpi} on points ({howpi})"
            parts.append(part)
        out.append(f"- {name}: " + "; ".join(parts) + ".")
    shares = [f"{g['mode']} {g['n_max']}: {g['read_share']:.2f} ({g.get('read_share_pixels', 0):.3f})"
              for g in d["groups"] if "read_share" in g]
    if shares:
        out.append("- share of stored photons read (by pixels and gather rays alone): " + ", ".join(shares) + ".")
    fall = []
    for m in modes:
        gs = [g for g in d["groups"] if g["mode"] == m]
        if len(gs) >= 2:
            fall.append(f"{m} {100 * (1 - gs[-1]['indirect']['mean'] / gs[0]['indirect']['mean']):.0f} %")
    out.append("- indirect error fall, smallest to largest budget: " + ", ".join(fall) + ".")
    t = d["estimate_tracking"]
    out.append(f"- half-map error estimate: true / estimated points error over {t['runs']} runs: "
               f"median {t['median_ratio']:.2f} (min {t['min_ratio']:.2f}, max {t['max_ratio']:.2f}).")
    smallest = min(min(x["indirect_rel_rmse"] for x in d["runs"]), 1e9)
    out.append(f"- reference noise / smallest indirect error: {r['noise'] / smallest:.2f} (must be < 0.33).")
    return "\n".join(out) + "\n"


def main():
    for arg in sys.argv[1:]:
        name, label, path = arg.split("@@")
        with open(path) as f:
            print(section(name, label, json.load(f)))


if __name__ == "__main__":
    main()
