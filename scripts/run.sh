#!/usr/bin/env bash
# The main job: sets up, builds (showing its progress), then path-traces the built-in `wknd`
# scene (128x128, 2 spp) on the RT-unit model in AT under the `paper` preset (the TTP authors'
# setup) twice, without and with TTP, and prints a short table of the two. Writes the frame
# (checked ray by ray against Embree), both runs' stats, a chart and the TTP run's waveforms.
# Extra arguments go to both rtsim runs and replace the defaults they name, e.g.
#   scripts/run.sh --scene bunny --assets ../shared/scenes/bunny
#   scripts/run.sh --config mobile --width 64 --height 64
set -euo pipefail
cd "$(dirname "$0")/.."
for a in "$@"; do
  case $a in
    --prefetcher|--prefetcher=*|--stats|--stats=*|--vcd|--vcd=*|--image|--image=*|--fidelity|--fidelity=*)
      echo "run: $a is set by scripts/run.sh itself (AT, without and with TTP, outputs in out/); run build/rtsim directly to choose it" >&2
      exit 2 ;;
  esac
done
given() {  # given OPTION: whether the caller's arguments set it
  local a
  for a in "${ARGS[@]}"; do [ "$a" = "$1" ] || [ "${a%%=*}" = "$1" ] && return 0; done
  return 1
}
ARGS=("$@")
defaults=()
given --scene || defaults+=(--scene wknd)
given --workload || given --rays || defaults+=(--workload pt)
given --config || defaults+=(--config paper)

echo "run: [1/4] setting up (Debian packages; nothing to do when they are installed)" >&2
scripts/setup.sh --reports
echo "run: [2/4] building rtsim (Release) in build/" >&2
# CMake's progress lines and any error; the whole output with scripts/build.sh.
if ! scripts/build.sh rtsim 2>&1 | sed -u -n -E '/^\[ *[0-9]+%\]|[Ee]rror/s/^/  /p'; then
  echo "run: the build failed (the lines above); scripts/build.sh shows its whole output" >&2
  exit 1
fi
mkdir -p out
common=(--fidelity at "${defaults[@]}" "$@")
echo "run: [3/4] simulating the baseline (AT, checked against Embree): build/rtsim ${common[*]}" >&2
build/rtsim "${common[@]}" --verify --stats out/baseline.json --image out/frame.png -q
echo "run: [3/4] simulating with TTP (AT, with waveforms): ... --prefetcher ttp" >&2
build/rtsim "${common[@]}" --prefetcher ttp --stats out/ttp.json --vcd out/ttp.vcd -q
echo "run: [4/4] summary" >&2
/usr/bin/python3 scripts/run_summary.py out/baseline.json out/ttp.json out/ttp_vs_baseline.png
cat <<DONE

Wrote:
  out/frame.png            the rendered frame
  out/baseline.json        statistics of the baseline run (rtsim --stats-schema explains every key)
  out/ttp.json             statistics of the TTP run
  out/ttp_vs_baseline.png  cycles, L1 misses and DRAM reads of the two runs
  out/ttp.vcd              waveforms of the TTP run; open them with
                           gtkwave --rcvar 'do_initial_zoom_fit 1' out/ttp.vcd waveforms/rtunit.gtkw
DONE
