#!/usr/bin/env python3
"""Compares the statistics of two rtsim runs key by key (scripts/regress.sh).

Usage: compare.py OLD.json NEW.json [--rename RULES.json]

Every leaf of OLD (dotted path, list items as [i]) must be in NEW with the identical value, after
the optional rename rules: a JSON list of [regex, replacement] pairs applied in order to OLD's
paths (re.sub; an empty replacement drops the key). Keys that measure the machine rather than the
model (wall times, rates per second, resident memory) are not compared. Prints one line per
difference and exits 1 if there is any; keys only NEW has are counted, not listed.
"""
import json
import re
import sys

VOLATILE = re.compile(r"^(provenance|time_s|simulation_rate|speed|memory_mb\.peak_resident|timing\.sampling\.prepass_threads|error_estimate\.check\.(fidelity_s|at_s|wall_s))(\.|$)")


def flatten(j, prefix="", out=None):
    out = {} if out is None else out
    if isinstance(j, dict):
        for k, v in j.items():
            flatten(v, f"{prefix}.{k}" if prefix else k, out)
    elif isinstance(j, list):
        for i, v in enumerate(j):
            flatten(v, f"{prefix}[{i}]", out)
    else:
        out[prefix] = j
    return out


def main():
    args = sys.argv[1:]
    rules = []
    if "--rename" in args:
        i = args.index("--rename")
        rules = json.load(open(args[i + 1]))
        del args[i:i + 2]
    old, new = (flatten(json.load(open(p))) for p in args[:2])
    diffs, compared = [], 0
    for path, value in old.items():
        if VOLATILE.search(path):
            continue
        target = path
        for pattern, repl in rules:
            target = re.sub(pattern, repl, target)
        if not target:
            continue
        compared += 1
        if target not in new:
            diffs.append(f"  {path}: missing in new (as {target})")
        elif new[target] != value:
            diffs.append(f"  {path}: {value!r} -> {new[target]!r}" + (f" (as {target})" if target != path else ""))
    mapped = set()
    for path in old:
        t = path
        for pattern, repl in rules:
            t = re.sub(pattern, repl, t)
        mapped.add(t)
    added = [p for p in new if p not in mapped and not VOLATILE.search(p)]
    print(f"{compared} values compared, {len(diffs)} differ, {len(added)} new keys")
    for d in diffs[:40]:
        print(d)
    if len(diffs) > 40:
        print(f"  ... {len(diffs) - 40} more")
    sys.exit(1 if diffs else 0)


if __name__ == "__main__":
    main()
