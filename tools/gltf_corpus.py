#!/usr/bin/env python3
"""Runs `adaptive-pm scene FILE --json` over every .gltf and .glb under a
folder and tallies what happened: read, refused with a message (exit 1), or
anything else (a panic's exit 101, a signal, a timeout), which is a bug.

Where a file has the Khronos glTF-Validator's report beside it
(FILE.report.json, as in the validator's own test/ folder), the files the
validator finds no error in but the loader refuses are listed with the
reason, grouped.

    python3 tools/gltf_corpus.py DIR [BINARY]

BINARY defaults to target/release/adaptive-pm. Exits 1 if any file ended
other than read or refused.
"""
import collections
import json
import os
import re
import subprocess
import sys


def run(binary, path):
    try:
        p = subprocess.run([binary, "scene", path, "--json"], capture_output=True,
                           text=True, timeout=60)
    except subprocess.TimeoutExpired:
        return "timeout", ""
    err = p.stderr.strip().splitlines()
    message = err[-1] if err else ""
    if p.returncode == 0:
        return "read", ""
    if p.returncode == 1 and "panicked" not in p.stderr:
        return "refused", message
    return f"exit {p.returncode}", message


def reason(message):
    """The message without the file's path and indices, to group by."""
    m = re.sub(r"`[^`]*`", "`_`", message)
    m = re.sub(r"\d+(\.\d+)?", "N", m)
    return m.split(": ", 2)[-1][:110]


def main():
    folder = sys.argv[1]
    binary = sys.argv[2] if len(sys.argv) > 2 else "target/release/adaptive-pm"
    files = sorted(os.path.join(d, f) for d, _, fs in os.walk(folder) for f in fs
                   if f.endswith((".gltf", ".glb")))
    tally = collections.Counter()
    valid_refused = collections.Counter()
    bad = []
    for f in files:
        outcome, message = run(binary, f)
        tally[outcome] += 1
        if outcome not in ("read", "refused"):
            bad.append((f, outcome, message))
        report = f + ".report.json"
        if outcome == "refused" and os.path.exists(report):
            with open(report) as r:
                errors = json.load(r).get("issues", {}).get("numErrors")
            if errors == 0:
                valid_refused[reason(message)] += 1
    print(f"{len(files)} files under {folder}: " +
          ", ".join(f"{n} {k}" for k, n in sorted(tally.items())))
    if valid_refused:
        print("refused although the validator reports no error, by reason:")
        for r, n in valid_refused.most_common():
            print(f"  {n:3}  {r}")
    for f, outcome, message in bad:
        print(f"BUG {outcome}: {f}: {message}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
