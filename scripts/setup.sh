#!/usr/bin/env bash
# Installs the Debian packages vproto needs (only those missing), then configures
# and builds the release preset. Safe to run again: it does nothing that is done.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libeigen3-dev
  libsuitesparse-dev libopenblas-dev libassimp-dev libosmesa6-dev libpng-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libxxhash-dev
  libfreetype-dev fonts-dejavu-core ffmpeg libpetsc-real-dev openmpi-bin
)
# one dpkg-query for all of them (one per package took 0.85 s of the README's first command)
installed=" $(dpkg-query -W -f='${Package} ${Status}\n' "${packages[@]}" 2>/dev/null |
  awk '$2 == "install" && $3 == "ok" && $4 == "installed" { printf "%s ", $1 }' || true)"
missing=()
for p in "${packages[@]}"; do
  [[ "$installed" == *" $p "* ]] || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

preset="${VPROTO_PRESET:-release}"
[ -f "build/$preset/build.ninja" ] || cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset"
