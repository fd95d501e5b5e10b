#!/usr/bin/env bash
# Checks that the workspace's declared `rust-version` is at least every
# dependency's (normal and build dependencies, all features, host target),
# reading `cargo metadata`. Prints the dependencies that set the floor.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo metadata --locked --format-version 1 --all-features --filter-platform "$(rustc -vV | sed -n 's/^host: //p')" \
  | python3 -c "$(cat <<'PY'
import json, sys

def ver(s):
    return tuple(int(x) for x in (s or "0").split(".")) + (0,) * (3 - len((s or "0").split(".")))

meta = json.load(sys.stdin)
pkgs = {p["id"]: p for p in meta["packages"]}
nodes = {n["id"]: n for n in meta["resolve"]["nodes"]}
members = set(meta["workspace_members"])

# Walk normal and build edges from each member: what a user of that crate
# compiles. Each member's floor is its own dependencies' (the bench crate's
# criterion and kiddo do not raise the library's).
def closure(root):
    seen, todo = set(), [root]
    while todo:
        pid = todo.pop()
        if pid in seen:
            continue
        seen.add(pid)
        for d in nodes[pid]["deps"]:
            if any(k["kind"] in (None, "build") for k in d["dep_kinds"]):
                todo.append(d["pkg"])
    return [pkgs[i] for i in seen - members]

bad = False
for pid in sorted(members):
    p = pkgs[pid]
    deps = closure(pid)
    floor = max((ver(d.get("rust_version")) for d in deps), default=(0, 0, 0))
    setters = sorted(f"{d['name']} {d['version']}" for d in deps if d.get("rust_version") and ver(d["rust_version"]) == floor)
    print(f"check-msrv: {p['name']}: {len(deps)} dependencies; the highest rust-version among them is {'.'.join(map(str, floor))} ({', '.join(setters)})")
    declared = p.get("rust_version")
    if declared is None or ver(declared) < floor:
        print(f"check-msrv: {p['name']} declares rust-version {declared}, below its dependencies' {'.'.join(map(str, floor))}", file=sys.stderr)
        bad = True
    else:
        print(f"check-msrv: {p['name']} rust-version {declared}: ok")
sys.exit(1 if bad else 0)
PY
)"
