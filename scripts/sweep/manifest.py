#!/usr/bin/env python3
"""A sweep manifest as the engines see it: one run per line after the header (id, rtsim
arguments, output path relative to the sweep's folder), numbered from 1 as worker.sh takes them.

As a command, `manifest.py invalidate MANIFEST OUTDIR RTSIM` keeps a sweep folder to one model:
OUTDIR/rtsim.sha256 names the rtsim binary its results came from; when RTSIM is another binary,
every run's outputs (stats, .status, .err) move to OUTDIR/previous-<old hash>/ so that the sweep
runs them again rather than mixing two models in one results.csv. Both engines call it.
`manifest.py finished MANIFEST OUTDIR INDEX` exits 0 when run INDEX is finished (worker.sh skips it);
`manifest.py not-run MANIFEST OUTDIR` prints how many runs are still to run (run.sh)."""
import hashlib
import json
import os
import pathlib
import shutil
import sys
from dataclasses import dataclass


@dataclass
class Run:
    index: int   # 1-based, as worker.sh takes it
    id: str
    args: str
    output: str  # stats path relative to the sweep folder


def read(path):
    runs = []
    with open(path) as f:
        lines = f.read().splitlines()
    if not lines or lines[0].split("\t") != ["id", "args", "output"]:
        sys.exit(f"manifest: {path}: line 1 must be the header 'id<TAB>args<TAB>output'")
    for n, line in enumerate(lines[1:], start=1):
        fields = line.split("\t")
        if len(fields) != 3:
            sys.exit(f"manifest: {path}: line {n + 1}: {len(fields)} tab-separated fields, 3 expected (id, args, output)")
        runs.append(Run(n, *fields))
    return runs


# Per stats file, (mtime, size) -> interrupted: the Slurm engine asks finished() of every run at
# each poll, and a file rtsim has written (whole, by rename) is read once, not at every poll.
_interrupted_seen = {}


def interrupted(stats):
    """rtsim stopped by SIGINT or SIGTERM writes its statistics so far with "interrupted": true
    (docs/robustness.md): a file that is there but is not the run's result."""
    st = stats.stat()
    key = (st.st_mtime_ns, st.st_size)
    seen = _interrupted_seen.get(stats)
    if seen and seen[0] == key:
        return seen[1]
    try:
        result = json.loads(stats.read_text()).get("interrupted") is True
    except ValueError:  # not rtsim's JSON (rtsim writes its stats whole, atomically)
        result = True
    _interrupted_seen[stats] = (key, result)
    return result


def finished(outdir, run):
    """A run is finished when its stats file exists, is not empty (rtsim writes it whole) and is not
    of a run stopped on the way."""
    p = pathlib.Path(outdir) / run.output
    return p.exists() and p.stat().st_size > 0 and not interrupted(p)


# rtsim's exit status when stopped by SIGINT / SIGTERM (128 + the signal; rtsim --help).
STOPPED_EXITS = (130, 143)


def not_run(outdir, run):
    """Still to run: neither finished nor failed on its own. A run that failed (an exit status other
    than a stop, without stats) has run, and the collector lists it; one stopped by a signal, or with
    no exit status at all (its worker was killed too), has not."""
    if finished(outdir, run):
        return False
    stats, status, _ = outputs(outdir, run)
    if not status.exists() or (stats.exists() and stats.stat().st_size > 0):
        return True
    try:
        return json.loads(status.read_text())["exit"] in STOPPED_EXITS
    except (ValueError, KeyError):
        return True


def outputs(outdir, run):
    base = pathlib.Path(outdir) / run.output
    return [base, base.with_name(base.name + ".status"), base.with_name(base.name + ".err")]


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def invalidate(manifest, outdir, rtsim):
    outdir = pathlib.Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    new = sha256(rtsim)
    stamp = outdir / "rtsim.sha256"
    old = stamp.read_text().strip() if stamp.exists() else ""
    if old and old != new:
        aside = outdir / f"previous-{old[:12]}"
        moved = 0
        for run in read(manifest):
            for p in outputs(outdir, run):
                if p.exists():
                    dest = aside / p.relative_to(outdir)
                    dest.parent.mkdir(parents=True, exist_ok=True)
                    shutil.move(str(p), str(dest))
                    moved += 1
        if moved:
            print(f"sweep: rtsim has changed since the runs in {outdir}: running all again "
                  f"(the old runs are in {aside})", file=sys.stderr)
    stamp.write_text(new + "\n")
    return new


USAGE = "usage: manifest.py invalidate MANIFEST OUTDIR RTSIM | finished MANIFEST OUTDIR INDEX | not-run MANIFEST OUTDIR"

if __name__ == "__main__":
    cmd, args = (sys.argv[1], sys.argv[2:]) if len(sys.argv) > 1 else ("", [])
    if cmd == "invalidate" and len(args) == 3:
        invalidate(*args)
    elif cmd == "finished" and len(args) == 3:
        runs = read(args[0])
        index = int(args[2])
        if not 1 <= index <= len(runs):
            sys.exit(f"manifest: {args[0]} has no run {index} (1 to {len(runs)})")
        sys.exit(0 if finished(args[1], runs[index - 1]) else 1)
    elif cmd == "not-run" and len(args) == 2:
        print(sum(not_run(args[1], r) for r in read(args[0])))
    else:
        sys.exit(USAGE)
