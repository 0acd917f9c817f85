#!/usr/bin/env python3
"""scripts/sampling_bias.py on hand-made grids whose biases are known: a bias only where a cell's
mean lies beyond Student's 95 % quantile times its standard error, the largest one per workload
kind, both kinds of folder (bench_sampling_grid.py's and speed_error.sh's, its frame size from its
manifest) read, and a folder limited to the scenes named after it (DIR:SCENE,...)."""
import json, os, subprocess, sys, tempfile

script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "sampling_bias.py")


def put(path, cycles):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump({"cycles": cycles}, f)


with tempfile.TemporaryDirectory() as tmp:
    grid = f"{tmp}/grid"
    os.makedirs(grid)
    with open(f"{grid}/summary.json", "w") as f:
        json.dump({"grid": {"fidelity": "interval", "workloads": ["pt", "primary"], "sizes": [64], "presets": ["mobile"],
                            "scenes": ["a", "b"], "rates": ["0.1"], "seeds": 3}}, f)
    # a: +3 % on every draw, spread 0.1 % (standard error 0.06 %): biased.
    put(f"{grid}/a_64_mobile_full.json", 1000)
    for s, c in enumerate([1029, 1030, 1031], 1):
        put(f"{grid}/a_64_mobile_0.1_{s}.json", c)
    # b: a mean of +5 % but a spread of 10 % (standard error 5.8 %, t 4.30): noise, not bias.
    put(f"{grid}/b_64_mobile_full.json", 1000)
    for s, c in enumerate([950, 1050, 1150], 1):
        put(f"{grid}/b_64_mobile_0.1_{s}.json", c)
    # a's primary rays: -5 %, biased; two draws only of b's primary rays at -20 %: too few to tell.
    put(f"{grid}/a-primary_64_mobile_full.json", 2000)
    for s, c in enumerate([1899, 1900, 1901], 1):
        put(f"{grid}/a-primary_64_mobile_0.1_{s}.json", c)
    put(f"{grid}/b-primary_64_mobile_full.json", 1000)
    for s, c in enumerate([800, 801], 1):
        put(f"{grid}/b-primary_64_mobile_0.1_{s}.json", c)
    # speed_error.sh's layout: c at 25 %, +4 % with a spread of 0.5 %, the largest path-tracing bias.
    speed = f"{tmp}/speed"
    os.makedirs(speed)
    with open(f"{speed}/manifest.tsv", "w") as f:
        f.write("id\targs\toutput\nat_base/c\t--scene c --fidelity at --workload pt --width 384 --height 384 --spp 2\tat_base/c.json\n")
    put(f"{speed}/at_base/c.json", 10000)
    for d, c in [("at_s25_base", 10350), ("at_s25_seed2_base", 10400), ("at_s25_seed3_base", 10450)]:
        put(f"{speed}/{d}/c.json", c)
    # d in the same folder: +9 %, biased, but left out where the folder is limited to c.
    put(f"{speed}/at_base/d.json", 10000)
    for d, c in [("at_s25_base", 10890), ("at_s25_seed2_base", 10900), ("at_s25_seed3_base", 10910)]:
        put(f"{speed}/{d}/d.json", c)
    out = f"{tmp}/bias.json"
    every = subprocess.run([sys.executable, script, out, grid, speed], capture_output=True, text=True, env=dict(os.environ, COMMIT="test"))
    assert every.returncode == 0, every.stderr
    with open(out) as f:
        assert json.load(f)["bias"]["other"]["cell"] == "d pt 384 mobile at 0.25"
    p = subprocess.run([sys.executable, script, out, grid, speed + ":c"], capture_output=True, text=True, env=dict(os.environ, COMMIT="test"))
    assert p.returncode == 0, p.stderr
    with open(out) as f:
        b = json.load(f)
    assert b["measured_on"] == "test"
    other, primary = b["bias"]["other"], b["bias"]["primary"]
    assert abs(other["value"] - 0.04) < 1e-12, other
    assert other["cell"] == "c pt 384 mobile at 0.25", other
    assert "path tracing 384x384, mobile, c, AT" in b["grids"][1], b["grids"]
    assert (other["cells"], other["runs"], other["biased_cells"]) == (3, 9, 2), other
    assert abs(primary["value"] - 0.05) < 1e-12, primary
    assert primary["cell"] == "a primary 64 mobile interval 0.1", primary
    assert (primary["cells"], primary["runs"], primary["biased_cells"]) == (1, 3, 1), primary
    assert "b pt 64" not in p.stdout, p.stdout  # noise is not listed as a bias
print("sampling_bias.py: the biases of the hand-made grids found")
