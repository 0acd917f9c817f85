#!/usr/bin/env python3
"""The Slurm engine of the sweeps (docs/sweeps.md): runs a manifest's unfinished runs as Slurm job
arrays, one array task per run, each task `worker.sh MANIFEST INDEX OUTDIR` as on one machine.

- Runs are grouped by the time and memory they need (estimated from their frame size, fidelity
  and sample rate; request_for) and each group is cut into arrays of at most the cluster's
  MaxArraySize tasks (`scontrol show config`); `--max-parallel K` adds `%K` to every array.
- Resumable: finished runs (stats written) are never submitted again, nor are runs whose array task
  is still queued or running (OUTDIR/slurm/submitted.tsv records every submission). A changed rtsim
  binary has already moved old results aside (manifest.py invalidate, called by run.sh); tasks run
  a copy of the binary made at submission (OUTDIR/slurm/rtsim-<hash>), so rebuilding while a sweep
  is queued does not mix two models.
- Waits (polling squeue) and reports every failed run with its exit status, its Slurm log and its
  rtsim messages; `--failed-only` submits again only runs that were submitted and failed.
  `--no-wait` returns after submitting (exit 75); the same command later waits for what is still
  queued, submits nothing twice, and collects.
Usage: slurm.py MANIFEST OUTDIR [--max-parallel K] [--partition P] [--account A] [--qos Q]
       [--sbatch-arg ARG]... [--time-per-run MIN] [--mem-per-run MB] [--no-wait] [--failed-only]
       [--poll S]
Environment: RTSIM (default build/rtsim), SHARED (passed to the tasks as it is).
Exit status: 0 every run finished, 1 some runs failed (listed), 2 bad usage or Slurm refused a
submission, 75 submitted and not waited for (--no-wait)."""
import argparse
import json
import math
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import manifest  # noqa: E402

EXIT_PENDING = 75

# Seconds of simulation per path (pixel sample), the slowest seen per fidelity in the error grid
# (docs/accuracy.md: six scenes, primary and path-traced frames of 64-512 pixels, seed 1, on this
# project's 2-core machine; the party scene is the slowest in each). The request is 3x the
# estimate plus loading, rounded up to a step of TIME_STEPS.
SECONDS_PER_PATH = {"functional": 2e-4, "interval": 7e-4, "lt": 1.1e-3, "at": 2.7e-3}
LOAD_S = 120
TIME_STEPS = [5, 10, 20, 30, 60, 120, 240, 480, 960, 1440, 2880, 5760]
# Memory: about 0.75 KB per path for the functional run's rays and hits (a 512x512 primary frame
# took 390 MB, a 1024x1024 2 spp path-traced one 1.4 GB), plus the scene (party: 160 MB in all).
# The request is twice that plus 400 MB, rounded up to a power of two, at least 512 MB.
BYTES_PER_PATH = 768
BASE_MB = 400


def option(words, name, default):
    for i, w in enumerate(words[:-1]):
        if w == name:
            return words[i + 1]
    return default


def request_for(args):
    """(minutes, megabytes) to ask for one run of rtsim with these arguments."""
    w = shlex.split(args)
    paths = int(option(w, "--width", 128)) * int(option(w, "--height", 128)) * int(option(w, "--spp", 2))
    fidelity = option(w, "--fidelity", "functional")
    cost = SECONDS_PER_PATH.get(fidelity, SECONDS_PER_PATH["at"])
    if "--sample" in w:  # the drawn clusters in detail, and the functional pre-pass over the frame
        cost = min(1.0, float(option(w, "--sample", 1)) + 0.1) * cost + SECONDS_PER_PATH["functional"]
    if "--check-error" in w:  # the checked clusters again in AT
        cost += SECONDS_PER_PATH["at"] / 2
    seconds = 3 * paths * cost + LOAD_S
    minutes = next((m for m in TIME_STEPS if m * 60 >= seconds), math.ceil(seconds / 60))
    mb = BASE_MB + 2 * paths * BYTES_PER_PATH / 2**20
    return minutes, max(512, 2 ** math.ceil(math.log2(mb)))


def slurm(cmd, check=True):
    try:
        p = subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit(f"slurm: '{cmd[0]}' not found: the Slurm engine needs the Slurm client commands (sbatch, squeue, scontrol)")
    if check and p.returncode:
        print(f"slurm: {' '.join(cmd)} failed (exit {p.returncode}): {p.stderr.strip()}", file=sys.stderr)
        sys.exit(2)
    return p


def max_array_size():
    """Tasks one array may hold: indices 0 .. MaxArraySize - 1 (Slurm's default MaxArraySize is 1001)."""
    out = slurm(["scontrol", "show", "config"]).stdout
    m = re.search(r"^MaxArraySize\s*=\s*(\d+)", out, re.M)
    return int(m.group(1)) if m else 1001


def queued_tasks(jobs):
    """(job id, task index) of the given array jobs still queued or running."""
    if not jobs:
        return set()
    p = slurm(["squeue", "-h", "-r", "-u", str(os.getuid()), "-o", "%F %K"])
    out = set()
    for line in p.stdout.split("\n"):
        parts = line.split()
        if len(parts) == 2 and parts[0] in jobs and parts[1].isdigit():
            out.add((parts[0], int(parts[1])))
    return out


class Book:
    """OUTDIR/slurm/submitted.tsv: per submitted task its job, index in the array, run and log."""

    def __init__(self, outdir):
        self.dir = pathlib.Path(outdir) / "slurm"
        self.path = self.dir / "submitted.tsv"
        self.rows = []  # (job, task, run index, log)
        if self.path.exists():
            for line in self.path.read_text().splitlines():
                job, task, index, log = line.split("\t")
                self.rows.append((job, int(task), int(index), log))

    def add(self, job, indices):
        with open(self.path, "a") as f:
            for task, index in enumerate(indices):
                log = str(self.dir / "logs" / f"{job}_{task}.log")
                self.rows.append((job, task, index, log))
                f.write(f"{job}\t{task}\t{index}\t{log}\n")

    def latest(self):
        """Per run index, its last submission (job, task, log)."""
        return {index: (job, task, log) for job, task, index, log in self.rows}


def describe_failure(outdir, run, log):
    _, status, err = manifest.outputs(outdir, run)
    if status.exists():
        st = json.loads(status.read_text())
        what = f"rtsim exit {st['exit']} after {st['wall_s']} s"
    else:
        what = "no exit status: the task did not finish (time or memory limit, or the node failed?)"
    lines = [f"  {run.id}: {what}", f"    Slurm log: {log}"]
    if err.exists() and err.stat().st_size:
        lines.append(f"    rtsim's messages: {err}: {err.read_text().strip().splitlines()[-1][:200]}")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description="Runs a sweep manifest as Slurm job arrays.")
    ap.add_argument("manifest")
    ap.add_argument("outdir")
    ap.add_argument("--max-parallel", type=int, default=0, help="at most K tasks of each array at once (%%K)")
    ap.add_argument("--partition")
    ap.add_argument("--account")
    ap.add_argument("--qos")
    ap.add_argument("--sbatch-arg", action="append", default=[], help="any other sbatch option, as one word")
    ap.add_argument("--time-per-run", type=int, help="minutes per run instead of the estimate")
    ap.add_argument("--mem-per-run", type=int, help="MB per run instead of the estimate")
    ap.add_argument("--no-wait", action="store_true")
    ap.add_argument("--failed-only", action="store_true", help="submit only runs that were submitted and failed")
    ap.add_argument("--poll", type=float, default=5.0, help="seconds between squeue polls")
    a = ap.parse_args()
    if a.max_parallel < 0:
        sys.exit("slurm: --max-parallel must be >= 0 (0: no limit)")

    outdir = pathlib.Path(a.outdir).resolve()
    runs = manifest.read(a.manifest)
    by_index = {r.index: r for r in runs}
    book = Book(outdir)
    (book.dir / "logs").mkdir(parents=True, exist_ok=True)
    latest = book.latest()
    in_flight = queued_tasks({job for job, _, _ in latest.values()})
    flying = {i for i, (job, task, _) in latest.items() if (job, task) in in_flight}
    todo = [r for r in runs if not manifest.finished(outdir, r) and r.index not in flying]
    if a.failed_only:
        todo = [r for r in todo if r.index in latest]

    # The tasks run a copy of the binary (same bytes: same results), named by its hash.
    rtsim = pathlib.Path(os.environ.get("RTSIM", HERE.parent.parent / "build" / "rtsim")).resolve()
    snapshot = book.dir / f"rtsim-{manifest.sha256(rtsim)[:16]}"
    if todo and not snapshot.exists():
        shutil.copy2(rtsim, str(snapshot) + ".tmp")
        os.replace(str(snapshot) + ".tmp", snapshot)

    groups = {}
    for r in todo:
        minutes, mb = request_for(r.args)
        groups.setdefault((a.time_per_run or minutes, a.mem_per_run or mb), []).append(r.index)
    size = max_array_size() if todo else 0
    submitted = []
    for (minutes, mb), indices in sorted(groups.items()):
        for start in range(0, len(indices), size):
            chunk = indices[start:start + size]
            listing = book.dir / f"list-{len(book.rows)}.txt"
            listing.write_text("".join(f"{i}\n" for i in chunk))
            array = f"0-{len(chunk) - 1}" + (f"%{a.max_parallel}" if a.max_parallel else "")
            cmd = ["sbatch", "--parsable", f"--array={array}", f"--time={minutes}", f"--mem={mb}M",
                   "--cpus-per-task=1", "--ntasks=1", f"--job-name=rtsim-sweep:{outdir.name}",
                   f"--output={book.dir / 'logs' / '%A_%a.log'}", f"--export=ALL,RTSIM={snapshot}"]
            cmd += [f"--{k}={v}" for k, v in (("partition", a.partition), ("account", a.account), ("qos", a.qos)) if v]
            cmd += a.sbatch_arg
            cmd += [str(HERE / "slurm_task.sh"), str(HERE / "worker.sh"), str(pathlib.Path(a.manifest).resolve()), str(listing), str(outdir)]
            job = slurm(cmd).stdout.strip().split(";")[0]
            if not job.isdigit():
                sys.exit(f"slurm: sbatch printed '{job}', not a job id")
            book.add(job, chunk)
            submitted.append((job, len(chunk), minutes, mb))
    done = sum(manifest.finished(outdir, r) for r in runs)
    print(f"slurm: {len(runs)} runs: {done} finished, {len(flying)} still queued or running, "
          f"{sum(n for _, n, _, _ in submitted)} submitted now", file=sys.stderr)
    for job, n, minutes, mb in submitted:
        print(f"slurm:   job {job}: {n} tasks, {minutes} min and {mb} MB each", file=sys.stderr)

    latest = book.latest()
    waiting = {(job, task) for i, (job, task, _) in latest.items() if not manifest.finished(outdir, by_index[i])}
    if a.no_wait and waiting:
        print("slurm: not waiting (--no-wait); run the same command again to wait for them and collect "
              "(it submits nothing twice)", file=sys.stderr)
        return EXIT_PENDING
    jobs = {job for job, _ in waiting}
    last = None
    while True:
        left = queued_tasks(jobs) & waiting
        if not left:
            break
        done = sum(manifest.finished(outdir, r) for r in runs)
        line = f"slurm: waiting: {done} of {len(runs)} runs finished, {len(left)} tasks queued or running"
        if line != last:
            print(line, file=sys.stderr)
            last = line
        time.sleep(a.poll)

    failed = [r for r in runs if r.index in latest and not manifest.finished(outdir, r)]
    never = [r for r in runs if r.index not in latest and not manifest.finished(outdir, r)]
    if failed:
        print(f"slurm: {len(failed)} runs failed:", file=sys.stderr)
        for r in failed:
            print(describe_failure(outdir, r, latest[r.index][2]), file=sys.stderr)
        print("slurm: to submit only those again, add --failed-only to the same command", file=sys.stderr)
    if never:
        print(f"slurm: {len(never)} runs were never submitted (--failed-only); run without it to submit them", file=sys.stderr)
    return 1 if failed or never else 0


if __name__ == "__main__":
    sys.exit(main())
