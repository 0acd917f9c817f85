#!/usr/bin/env bash
# Sampling on large frames against Zatel's mark (<1 % cycle error at a 10x speed-up): for each
# scene, path tracing SIZExSIZE at 2 spp, the full AT run, the full interval run, and the
# interval fidelity sampled at RATE with sample seeds 1-DRAWS. The runs go one after another,
# each on one core (the sampling pre-pass with --threads 1); the speed-up is AT's wall time over
# the run's, whole processes (scene loading and BVH build included in both). Prints a table:
# each run's cycle error against AT, its 95 % interval's half-width and whether it holds AT's
# cycles. docs/sampling.md quotes its figures.
# Usage: scripts/bench_sampling_large.sh [--scenes a,b] [--size N] [--rate R] [--draws N] [--fidelity interval|at|lt] [--plan]
#   defaults: bunny,ship,sprng; 512; 0.1; 3; interval. Takes about 1.5x the full AT runs' time
#   (about 70 s per scene at 512x512 here).
# --plan: as the runs of a sweep over configurations of one frame after its first: a sampled run
#   with TTP (another configuration) writes the frame's sample plan (--sample-plan, the functional
#   pre-pass), and the sampled draws read it. The table's speed-ups are then of the draws; the
#   plan-writing run's own is printed below it.
set -euo pipefail
cd "$(dirname "$0")/.."
scenes=bunny,ship,sprng size=512 rate=0.1 draws=3 fidelity=interval plan=0
while [ $# -gt 0 ]; do
  case $1 in
    --scenes) scenes=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --draws) draws=$2; shift 2 ;;
    --fidelity) fidelity=$2; shift 2 ;;
    --plan) plan=1; shift ;;
    *) echo "error: unknown option '$1' (allowed: --scenes --size --rate --draws --fidelity --plan)" >&2; exit 2 ;;
  esac
done
shared=${SHARED:-../shared/scenes}
scripts/build.sh >/dev/null
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
IFS=, read -r -a list <<<"$scenes"
for s in "${list[@]}"; do
  args=(--scene "$s" --workload pt --width "$size" --height "$size" --spp 2 -q)
  case $s in
    wknd|cornell) ;;
    ref|ref-full) args+=(--assets "$shared/dragon") ;;
    *) args+=(--assets "$shared/$s") ;;
  esac
  timed() {  # NAME rtsim-args...: stats in $out/NAME.json, start and end times in $out/NAME.wall
    local name=$1; shift
    date +%s.%N >"$out/$name.wall"
    build/rtsim "${args[@]}" "$@" --stats "$out/$name.json"
    date +%s.%N >>"$out/$name.wall"
  }
  echo "$s ${size}x${size}: AT, interval, $draws sampled $fidelity runs at $rate" >&2
  timed "$s.at" --fidelity at
  timed "$s.interval" --fidelity interval
  reuse=()
  if [ "$plan" = 1 ]; then
    timed "$s.planrun" --fidelity "$fidelity" --prefetcher ttp --sample "$rate" --threads 1 --sample-plan "$out/$s.plan"
    reuse=(--sample-plan "$out/$s.plan")
  fi
  for d in $(seq 1 "$draws"); do
    timed "$s.sample$d" --fidelity "$fidelity" --sample "$rate" --sample-seed "$d" --threads 1 "${reuse[@]}"
  done
done
/usr/bin/python3 - "$out" "$scenes" "$draws" "$size" "$rate" "$fidelity" "$plan" <<'PY'
import json, pathlib, sys
out, scenes, draws, size, rate, fid = pathlib.Path(sys.argv[1]), sys.argv[2].split(","), int(sys.argv[3]), sys.argv[4], float(sys.argv[5]), sys.argv[6]
plan = sys.argv[7] == "1"
def load(n):
    start, end = map(float, (out / f"{n}.wall").read_text().split())
    return json.loads((out / f"{n}.json").read_text()), end - start
print(f"{size}x{size}, 2 spp; {fid} sampled at {rate * 100:g} %, sample seeds 1-{draws}; errors against the full AT run"
      + ("; the draws read the sample plan a first run (with TTP) wrote" if plan else "") + "\n")
print("| scene | AT cycles (wall s) | full interval run | sampled: cycle error | half-width | holds AT's cycles | speed-up over AT |")
print("|---|---|---|---|---|---|---|")
for s in scenes:
    at, at_w = load(f"{s}.at")
    iv, _ = load(f"{s}.interval")
    c = at["cycles"]
    errs, hws, cover, sus = [], [], [], []
    for d in range(1, draws + 1):
        j, w = load(f"{s}.sample{d}")
        lo, hi = j["timing"]["sampling"]["cycles_ci95"]
        errs.append(100 * (j["cycles"] / c - 1))
        hws.append(100 * (hi - lo) / 2 / j["cycles"])
        cover.append(lo <= c <= hi)
        sus.append(at_w / w)
    print(f"| {s} | {c} ({at_w:.1f}) | {100 * (iv['cycles'] / c - 1):+.2f} % | " + ", ".join(f"{e:+.2f} %" for e in errs) +
          f" (mean abs. {sum(abs(e) for e in errs) / len(errs):.2f} %) | {min(hws):.1f}-{max(hws):.1f} % | {sum(cover)} of {draws} | "
          f"{min(sus):.1f}-{max(sus):.1f}x |")
if plan:
    print()
    for s in scenes:
        _, at_w = load(f"{s}.at")
        _, w = load(f"{s}.planrun")
        print(f"{s}: the first run (TTP, writing the plan) took {w:.1f} s, {at_w / w:.1f}x AT's {at_w:.1f} s.")
PY
