"""rtsim's statistics as pandas DataFrames.

A statistics file (`rtsim --stats FILE.json`) becomes one row whose columns are its keys, dotted
as `rtsim --stats-schema` names them (`cycles`, `timing.l1.demand.miss_rate`, `config.l1.size_kb`,
`provenance.commit`); a list (an interval, the command line) stays one cell. A sweep's output
folder (`scripts/sweep/run.sh MANIFEST OUTDIR`) becomes one row per run that wrote statistics,
with the run's `id` first. The configuration is in the `config.*` columns, so runs group by any
key: `load_sweep(d).groupby("config.prefetch.kind")["cycles"].mean()`.

Files of other rtsim versions load too: a key one file lacks is a missing value (NaN) in its
row, never an error; `value(row, key, default)` reads one with a default.

    import sys; sys.path.insert(0, "scripts/python")
    from rtunit_stats import load, load_sweep, value
"""
import json
import math
import pathlib

import pandas as pd

__all__ = ["flatten", "load", "load_sweep", "value"]


def flatten(stats, prefix=""):
    """A statistics object (parsed JSON) as {dotted key: value}; lists are kept whole."""
    out = {}
    for k, v in stats.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def load(path):
    """One statistics file as a one-row DataFrame (column `file`: its path)."""
    path = pathlib.Path(path)
    with open(path) as f:
        row = flatten(json.load(f))
    row["file"] = str(path)
    return pd.DataFrame([row])


def load_sweep(outdir):
    """Every statistics file under a sweep's output folder, one row each, sorted by `id` (the
    file's path below the folder, without `.json`: the manifest's run id). Files that are not
    statistics (a plan, a status) are left out."""
    outdir = pathlib.Path(outdir)
    rows = []
    for path in sorted(outdir.rglob("*.json")):
        try:
            with open(path) as f:
                stats = json.load(f)
        except (OSError, json.JSONDecodeError):
            continue
        if not isinstance(stats, dict) or "rays" not in stats or "scene" not in stats:
            continue
        row = {"id": str(path.relative_to(outdir).with_suffix(""))}
        row.update(flatten(stats))
        rows.append(row)
    frame = pd.DataFrame(rows)
    return frame.sort_values("id", kind="stable").reset_index(drop=True) if rows else frame


def value(row, key, default=None):
    """`row[key]` of a DataFrame row (or a dict), or `default` where the key is absent or missing
    (a file of another rtsim version)."""
    try:
        v = row[key]
    except (KeyError, IndexError):
        return default
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return default
    return v
