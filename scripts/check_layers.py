#!/usr/bin/env python3
"""Checks the layering of the source tree (README, Layout): model <- workloads <- sampling <- platforms,
and model <- tlm <- platforms.

- model/ includes only model/ (and no SystemC); workloads/ includes model/ and workloads/;
  sampling/ includes model/, workloads/ and sampling/ (no SystemC: it is plain C++);
  tlm/ includes model/ and tlm/ (never workloads/ or sampling/); platforms/ may include all;
- the files named in PLAIN include no SystemC header (directly or through project headers);
- the project's include graph has no cycle.
Prints what breaks a rule and exits 1, else prints a one-line summary. Usage: check_layers.py"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
LAYERS = ["model", "workloads", "sampling", "tlm", "platforms"]
ALLOWED = {"model": {"model"}, "workloads": {"model", "workloads"}, "sampling": {"model", "workloads", "sampling"},
           "tlm": {"model", "tlm"}, "platforms": {"model", "workloads", "sampling", "tlm", "platforms"}}
PLAIN = ["platforms/interval_run.h", "platforms/interval_run.cpp", "platforms/timing_run.h", "platforms/simulation.h"]
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)
SYSTEMC = re.compile(r"^(systemc|tlm|tlm_utils/|sysc/)")


def resolve(src, name):
    """The project file an include names, or None (a system header)."""
    for base in (src.parent, ROOT, ROOT / "model"):
        f = (base / name).resolve()
        if f.is_file() and ROOT in f.parents:
            return f
    return None


def main():
    files = [f for layer in LAYERS for f in sorted((ROOT / layer).glob("*")) if f.suffix in (".h", ".cpp", ".in")]
    graph, system, errors = {}, {}, []
    for f in files:
        text = f.read_text(errors="replace")
        layer = f.relative_to(ROOT).parts[0]
        graph[f], system[f] = [], []
        for kind, name in INCLUDE.findall(text):
            target = resolve(f, name) if kind == '"' else None
            if target is None:
                system[f].append(name)
                if layer in ("model", "workloads", "sampling") and SYSTEMC.match(name):
                    errors.append(f"{f.relative_to(ROOT)}: {layer}/ includes SystemC <{name}>")
                continue
            graph[f].append(target)
            to = target.relative_to(ROOT).parts[0]
            if to in LAYERS and to not in ALLOWED[layer]:
                errors.append(f"{f.relative_to(ROOT)}: {layer}/ includes {target.relative_to(ROOT)}")

    def reaches_systemc(f, seen):
        if f in seen:
            return False
        seen.add(f)
        return any(SYSTEMC.match(n) for n in system.get(f, [])) or any(reaches_systemc(t, seen) for t in graph.get(f, []))

    for name in PLAIN:
        if reaches_systemc(ROOT / name, set()):
            errors.append(f"{name}: includes SystemC, directly or through a project header")
    # Cycles: depth-first search with colours.
    state = {}

    def visit(f, path):
        state[f] = 1
        for t in graph.get(f, []):
            if state.get(t) == 1:
                cycle = path[path.index(t):] + [t] if t in path else [f, t]
                errors.append("include cycle: " + " -> ".join(str(x.relative_to(ROOT)) for x in cycle))
            elif t not in state:
                visit(t, path + [t])
        state[f] = 2

    for f in files:
        if f not in state:
            visit(f, [f])
    for e in errors:
        print(e)
    if errors:
        sys.exit(1)
    print(f"layers: {len(files)} files, {sum(len(v) for v in graph.values())} project includes, no cycle, "
          "model <- workloads <- sampling <- platforms and model <- tlm <- platforms respected")


if __name__ == "__main__":
    main()
