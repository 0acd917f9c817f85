#!/usr/bin/env python3
"""scripts/sampling_decompose.py on a hand-made grid whose parts are known: a run 10 % high whose
work estimate is 10 % high (all work, no rate), a run 5 % high with the frame's work (all rate),
and a cell without its 99 % sample, which the script makes with the full run's command line, its
--stats replaced and --sample 0.99 added (a stand-in rtsim records what it was given)."""
import json, os, stat, subprocess, sys, tempfile

script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "sampling_decompose.py")


def put(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f)


def sampled(cycles, work):
    return {"cycles": cycles, "timing": {"sampling": {"work_estimate_residence_cycles": work}}}


with tempfile.TemporaryDirectory() as tmp:
    grid = f"{tmp}/grid"
    os.makedirs(grid)
    # Cell a: its 99 % sample is there (work 5000); the rtsim given does not exist and must not run.
    put(f"{grid}/a_64_mobile_full.json", {"cycles": 1000})
    put(f"{grid}/a_64_mobile_near99.json", sampled(1000, 5000))
    put(f"{grid}/a_64_mobile_0.1_1.json", sampled(1100, 5500))  # +10 %: work +10 %, rate 0
    put(f"{grid}/a_64_mobile_0.1_2.json", sampled(1050, 5000))  # +5 %: work 0, rate +5 %
    out = subprocess.run([sys.executable, script, f"{tmp}/no-rtsim", grid], capture_output=True, text=True, check=True).stdout
    row = [l for l in out.splitlines() if "| a 64 mobile 0.1 |" in l]
    assert row == ["| grid | a 64 mobile 0.1 | 2 | +7.5 % | +5.0 % | +2.5 % |"], out
    assert "2 runs: mean |error| 7.50 %, mean |work part| 5.00 %, mean |rate part| 2.50 %" in out, out

    # Cell b has no 99 % sample: the script runs the stand-in with the full run's command line.
    log = f"{tmp}/argv.json"
    fake = f"{tmp}/rtsim"
    with open(fake, "w") as f:
        f.write(f"""#!{sys.executable}
import json, sys
a = sys.argv[1:]
json.dump(a, open({log!r}, "w"))
json.dump({{"timing": {{"sampling": {{"work_estimate_residence_cycles": 2000}}}}}}, open(a[a.index("--stats") + 1], "w"))
""")
    os.chmod(fake, os.stat(fake).st_mode | stat.S_IEXEC)
    put(f"{grid}/b_64_mobile_full.json", {"cycles": 400, "provenance": {"command_line": ["build/rtsim", "--scene", "b", "--stats", "old.json", "-q"]}})
    put(f"{grid}/b_64_mobile_0.25_1.json", sampled(380, 1800))  # -5 %: work -10 %, rate +5.6 %
    out = subprocess.run([sys.executable, script, fake, grid], capture_output=True, text=True, check=True).stdout
    argv = json.load(open(log))
    assert argv[:3] == ["--scene", "b", "-q"] and "old.json" not in argv, argv
    assert argv[argv.index("--sample") + 1] == "0.99" and argv[argv.index("--stats") + 1].endswith("b_64_mobile_near99.json.tmp"), argv
    assert os.path.exists(f"{grid}/b_64_mobile_near99.json")
    assert "| grid | b 64 mobile 0.25 | 1 | -5.0 % | -10.0 % | +5.6 % |" in out, out
print("ok")
