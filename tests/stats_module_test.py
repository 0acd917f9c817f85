#!/usr/bin/python3
"""scripts/python/rtunit_stats on rtsim's own files: one file as a row, a sweep's folder as rows
with the configuration as columns (grouped by a key), files of another version (keys missing)
loaded with missing values, and scripts/run_summary.py printing "n/a" for what a file lacks.
Usage: stats_module_test.py RTSIM SOURCE_DIR"""
import json
import math
import os
import subprocess
import sys
import tempfile

rtsim, src = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(src, "scripts", "python"))
from rtunit_stats import load, load_sweep, value  # noqa: E402

failed = []


def check(what, ok):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failed.append(what)


with tempfile.TemporaryDirectory() as tmp:
    os.makedirs(f"{tmp}/out/e")
    for name, kb in (("a", 16), ("b", 32)):
        subprocess.run([rtsim, "--scene", "cornell", "--width", "16", "--height", "16", "--fidelity", "interval", "--set",
                        f"l1.size_kb={kb}", "-q", "--stats", f"{tmp}/out/e/{name}.json"], check=True)
    with open(f"{tmp}/out/e/plan.json", "w") as f:  # not a statistics file: left out
        json.dump({"plan": 1}, f)
    one = load(f"{tmp}/out/e/a.json")
    check("a file is one row", len(one) == 1)
    row = one.iloc[0]
    with open(f"{tmp}/out/e/a.json") as f:
        raw = json.load(f)
    check("its dotted keys hold the file's values", value(row, "timing.l1.demand.miss_rate") == raw["timing"]["l1"]["demand"]["miss_rate"]
          and value(row, "cycles") == raw["cycles"])
    check("the configuration is in config.* columns", value(row, "config.l1.size_kb") == 16)
    check("the provenance's commit is a column", value(row, "provenance.commit") == raw["provenance"]["commit"])
    check("a list stays one cell", list(value(row, "provenance.command_line")) == raw["provenance"]["command_line"])
    sweep = load_sweep(f"{tmp}/out")
    check("a sweep is a row per statistics file, by id", list(sweep["id"]) == ["e/a", "e/b"])
    by_l1 = sweep.groupby("config.l1.size_kb")["cycles"].first()
    check("and groups by a configuration key", list(by_l1.index) == [16, 32])
    # A file of an older rtsim: no provenance, no L1 section.
    del raw["provenance"], raw["timing"]["l1"]
    with open(f"{tmp}/out/e/c.json", "w") as f:
        json.dump(raw, f)
    old = load(f"{tmp}/out/e/c.json").iloc[0]
    check("a key an older file lacks reads as the default", value(old, "timing.l1.demand.miss_rate", "none") == "none")
    mixed = load_sweep(f"{tmp}/out")
    c = mixed[mixed["id"] == "e/c"].iloc[0]
    check("and as a missing value in a sweep with newer files", math.isnan(c["provenance.commit"]) and len(mixed) == 3)
    summary = subprocess.run(["/usr/bin/python3", os.path.join(src, "scripts", "run_summary.py"), f"{tmp}/out/e/a.json",
                              f"{tmp}/out/e/c.json", f"{tmp}/chart.png"], capture_output=True, text=True)
    check("run_summary.py takes the older file (exit 0) and says n/a for what it lacks",
          summary.returncode == 0 and "n/a" in summary.stdout)
print(f"{len(failed)} failed")
sys.exit(1 if failed else 0)
