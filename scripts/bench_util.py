"""What the benchmark scripts that run rtsim on the shared scenes share (bench_error_grid.py,
bench_sensitivity.py, bench_sampling_grid.py) and the scripts that read their folders: the
scenes' arguments, a preset with its prefetcher, a grid's axes, one resumable run, and a sampling
grid's runs."""
import glob
import os
import re
import subprocess

SCENES_DIR = os.environ.get("SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "scenes"))


def scene_args(shared=SCENES_DIR):
    """rtsim's arguments per scene name: mesh (the Stanford bunny as a bare mesh, automatic camera),
    the built-in cornell and wknd, and the LumiBench scenes under `shared`."""
    sc = {"mesh": f"--scene {shared}/bunny/stanford-bunny.obj", "cornell": "--scene cornell", "wknd": "--scene wknd"}
    for n in ("bunny", "ship", "bath", "sprng", "party"):
        sc[n] = f"--scene {n} --assets {shared}/{n}"
    return sc


def config_args(config):
    """`NAME` or `NAME+PREFETCHER` as rtsim's --config (and --prefetcher) arguments."""
    name, _, pf = config.partition("+")
    return f"--config {name}" + (f" --prefetcher {pf}" if pf else "")


def grid_env(sizes, presets, seeds, fid):
    """A grid's axes from the environment, with these defaults where a variable is not set: SIZES
    (comma-separated frame sides), PRESETS, SEEDS (how many) from FIRST_SEED (1), FID, WORKLOADS
    (pt). Returns (sizes, presets, seeds, fid, workloads)."""
    first = int(os.environ.get("FIRST_SEED", "1"))
    return ([int(x) for x in os.environ.get("SIZES", sizes).split(",")], os.environ.get("PRESETS", presets).split(","),
            range(first, first + int(os.environ.get("SEEDS", seeds))), os.environ.get("FID", fid),
            os.environ.get("WORKLOADS", "pt").split(","))


def cell_name(scene, workload):
    """A grid run's name: the scene, and the workload where it is not path tracing."""
    return scene if workload == "pt" else f"{scene}-{workload}"


def run_stats(rtsim, path, args, skip=False):
    """rtsim ARGS with its statistics in PATH, unless PATH exists (or `skip`): written under
    PATH.tmp and renamed when rtsim succeeds, so a killed run leaves no PATH. Returns (exit
    status, the end of stderr)."""
    if os.path.exists(path) or skip:
        return 0, ""
    p = subprocess.run(f"{rtsim} {args} --stats {path}.tmp -q", shell=True, capture_output=True, text=True)
    if p.returncode == 0:
        os.rename(path + ".tmp", path)
    return p.returncode, p.stderr.strip()[-300:]


def sampling_grid_runs(folder):
    """The sampled runs of a folder of bench_sampling_grid.py whose cell has its full run, in name
    order: (sampled run's path, full run's path, (name, size, preset, rate)) each, `name` the
    scene, with -WORKLOAD where the workload is not path tracing."""
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        m = re.match(r"(.+)_(\d+)_([\w+]+)_([0-9.]+)_(\d+)$", os.path.basename(path)[:-5])
        if not m:
            continue
        name, size, preset, rate, _ = m.groups()
        full = os.path.join(folder, f"{name}_{size}_{preset}_full.json")
        if os.path.exists(full):
            yield path, full, (name, size, preset, rate)
