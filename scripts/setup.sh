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
)
# --reports: also what the experiment sweeps and reports need (GNU parallel, matplotlib).
if [ "${1:-}" = "--reports" ]; then packages+=(parallel python3-matplotlib gawk); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "setup: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
