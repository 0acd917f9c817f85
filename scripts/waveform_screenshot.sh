#!/usr/bin/env bash
# Makes waveforms/screenshot.png: a real AT trace (cornell, 32x32 path tracing with TTP, warp-buffer slot 0
# of SM 0 traced) opened with waveforms/rtunit.gtkw in GTKWave, zoomed to fit, on a virtual X
# display (Xvfb), captured with xwd and converted by ImageMagick. Needs build/rtsim and the
# Debian packages gtkwave xvfb x11-apps imagemagick.
# Usage: scripts/waveform_screenshot.sh [OUT.png (default waveforms/screenshot.png)]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-waveforms/screenshot.png}
for tool in gtkwave Xvfb xwd convert; do
  command -v "$tool" >/dev/null || { echo "waveform_screenshot: $tool not found (apt-get install gtkwave xvfb x11-apps imagemagick)" >&2; exit 2; }
done
[ -x build/rtsim ] || { echo "waveform_screenshot: build/rtsim not found (scripts/build.sh)" >&2; exit 2; }
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$tmp"; }
trap cleanup EXIT
build/rtsim --scene cornell --fidelity at --prefetcher ttp --width 32 --height 32 --vcd "$tmp/wave.vcd" --trace-warp 0:0 -q
# A display number of its own: Xvfb writes the one it took to the descriptor given.
exec 3>"$tmp/display"
Xvfb -displayfd 3 -screen 0 1600x1000x24 -nolisten tcp >"$tmp/xvfb.log" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -s "$tmp/display" ] && break; sleep 0.1; done
export DISPLAY=":$(head -1 "$tmp/display")"
gtkwave --rcvar 'do_initial_zoom_fit 1' "$tmp/wave.vcd" waveforms/rtunit.gtkw >"$tmp/gtkwave.log" 2>&1 &
pids+=($!)
sleep 6  # GTKWave loads the trace and draws it
xwd -root -silent >"$tmp/shot.xwd"
convert "$tmp/shot.xwd" "$out"
echo "wrote $out"
