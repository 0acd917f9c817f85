#!/usr/bin/env bash
# Installs rtunit's build and test dependencies from Debian 12 packages. Idempotent: does
# nothing (not even apt-get update) when everything is already installed.
set -euo pipefail
packages=(
  build-essential cmake pkg-config python3
  libsystemc-dev            # SystemC 2.3.4 with TLM-2.0 (the timing model)
  libembree-dev             # Embree 3: BVH builder and golden reference
  libglm-dev
  libboost-program-options-dev
  libgtest-dev googletest
  libassimp-dev zlib1g-dev  # glTF/OFF meshes through Assimp; gzip for .ply.gz
  nlohmann-json3-dev        # statistics and configuration files
  libstb-dev                # PNG output
  libabsl-dev               # Abseil flat hash maps (cache tags, MSHRs)
  parallel                  # the sweeps' local engine, which the test suite runs (tests/sweep_*_test.sh)
  libtinyobjloader-dev      # LumiBench's OBJ loader: the tests check rtunit's triangulation against it
  python3-pandas            # statistics as DataFrames (scripts/python/rtunit_stats): the main job's summary and its test
)
# Options, any number of them together (scripts/setup.sh --reports --fuzz):
#   --reports: also what the experiment reports need (matplotlib);
#   --slurm: also Slurm's controller, node daemon and client (scripts/sweep/test_slurm.sh starts a
#            throw-away cluster with them; the packages' own services are not started);
#   --fuzz: also clang and its libFuzzer runtime (scripts/fuzz.sh).
for option in "$@"; do
  case $option in
    --reports) packages+=(python3-matplotlib gawk) ;;
    --slurm) packages+=(slurmctld slurmd slurm-client) ;;
    --fuzz) packages+=(clang libclang-rt-14-dev) ;;
    *) echo "setup: unknown option '$option' (allowed: --reports, --slurm, --fuzz, any of them together)" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "setup: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null; then
    echo "setup: failed: installing packages needs root, and sudo is not installed." >&2
    echo "setup: what to do: run as root, or install these yourself: apt-get install ${missing[*]}" >&2
    exit 1
  fi
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
# Another apt or dpkg (unattended upgrades, a second terminal) holds its lock: wait for it, up to
# RTU_APT_WAIT seconds (default 600) in all, saying so, rather than failing at once. Any other
# failure names the step and what to do.
wait_limit=${RTU_APT_WAIT:-600}
waited=0 start=$SECONDS
apt_step() {  # apt_step NAME ARGS...: runs apt-get ARGS, retrying while a lock is held
  local name=$1 log rc
  shift
  log=$(mktemp)
  while true; do
    rc=0
    # apt-get in the background, its last line of progress said every 15 s (a large install
    # takes minutes, and a silent terminal looks hung).
    $SUDO apt-get -o DPkg::Lock::Timeout=10 "$@" >"$log" 2>&1 &
    local pid=$! said=$SECONDS
    while kill -0 "$pid" 2>/dev/null; do
      sleep 1
      if [ $((SECONDS - said)) -ge 15 ]; then
        said=$SECONDS
        echo "setup: $name: working ($((SECONDS - start)) s): $(grep -a -E '^(Get:|Unpacking|Setting up|Fetched)' "$log" | tail -n 1 | cut -c1-100)" >&2
      fi
    done
    wait "$pid" || rc=$?
    if [ $rc -eq 0 ]; then rm -f "$log"; return 0; fi
    if grep -q -e "Could not get lock" -e "Unable to acquire the dpkg frontend lock" -e "Unable to lock directory" "$log" \
       && [ "$waited" -lt "$wait_limit" ]; then
      echo "setup: $name: another package manager holds apt's lock ($(grep -o -a -m1 'process [0-9][0-9]*' "$log" || echo 'process unknown')); waiting (${waited} of ${wait_limit} s)" >&2
      sleep 10
      waited=$((SECONDS - start))
      continue
    fi
    echo "setup: failed at step '$name' (apt-get $*, exit $rc). Its last lines:" >&2
    tail -n 8 "$log" | sed 's/^/  /' >&2
    rm -f "$log"
    if [ "$waited" -ge "$wait_limit" ]; then
      echo "setup: what to do: apt's lock was still held after ${wait_limit} s; wait for the other package manager to finish (or set RTU_APT_WAIT=SECONDS) and rerun." >&2
    elif [ "$name" = "update" ]; then
      echo "setup: what to do: check the network and /etc/apt/sources.list, then rerun." >&2
    else
      echo "setup: what to do: install the packages by hand to see the full error: apt-get install ${missing[*]}" >&2
    fi
    exit 1
  done
}
# Package scripts must not start services (Slurm's daemons, for one): a policy-rc.d that forbids
# it, only if there is none already, removed afterwards only if we made it.
policy=/usr/sbin/policy-rc.d made_policy=""
if [ ! -e "$policy" ]; then
  printf '#!/bin/sh\nexit 101\n' | $SUDO tee "$policy" >/dev/null && $SUDO chmod +x "$policy" && made_policy=1
  trap 'if [ -n "$made_policy" ]; then $SUDO rm -f "$policy"; fi' EXIT
fi
apt_step update update -qq
apt_step install install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: installed ${#missing[@]} packages" >&2
