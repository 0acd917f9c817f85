#!/usr/bin/env python3
"""A sweep manifest as the engines see it: one run per line after the header (id, rtsim
arguments, output path relative to the sweep's folder), numbered from 1 as worker.sh takes them.

As a command, `manifest.py invalidate MANIFEST OUTDIR RTSIM` keeps a sweep folder to one model:
OUTDIR/rtsim.sha256 names the rtsim binary its results came from; when RTSIM is another binary,
every run's outputs (stats, .status, .err) move to OUTDIR/previous-<old hash>/ so that the sweep
runs them again rather than mixing two models in one results.csv. Both engines call it."""
import hashlib
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


def finished(outdir, run):
    """A run is finished when its stats file exists and is not empty (rtsim writes it whole)."""
    p = pathlib.Path(outdir) / run.output
    return p.exists() and p.stat().st_size > 0


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


if __name__ == "__main__":
    if len(sys.argv) != 5 or sys.argv[1] != "invalidate":
        sys.exit("usage: manifest.py invalidate MANIFEST OUTDIR RTSIM")
    invalidate(*sys.argv[2:])
