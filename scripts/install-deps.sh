#!/usr/bin/env bash
# Installs the Debian 12 packages docunfold needs. Idempotent: does nothing
# when everything is present. As root it runs apt-get; otherwise it prints the
# exact command to run and exits 1.
#   scripts/install-deps.sh          check, install what is missing (root)
#   scripts/install-deps.sh --list   print the package list
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake pkg-config
  # images, features, freetype text rendering (synth), LSD, DeepFlow
  libopencv-dev libopencv-contrib-dev
  # linear algebra everywhere
  libeigen3-dev
  # self-describing JSON files; command lines
  nlohmann-json3-dev libcli11-dev
  # .glb export of meshes
  libtinygltf-dev
  # k-d trees for nearest points (SfM points, footpoints)
  libnanoflann-dev
  # structure from motion
  colmap
  # fonts for synth's pages
  fonts-dejavu-core fonts-dejavu-extra fonts-liberation2 fonts-freefont-ttf
  # JSON Schema validation of every file the pipeline reads or writes
  python3 python3-jsonschema
  # tests
  googletest libgtest-dev
)

if [[ "${1:-}" == "--list" ]]; then
  printf '%s\n' "${packages[@]}"
  exit 0
fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

cmd="apt-get install -y --no-install-recommends ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
  echo "docunfold: missing Debian packages; run as root:" >&2
  echo "  apt-get update && $cmd" >&2
  exit 1
fi
echo "docunfold: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
# A fresh machine may have no package lists yet.
if ! apt-get install -y --no-install-recommends "${missing[@]}" >/dev/null 2>&1; then
  apt-get update -qq
  apt-get install -y --no-install-recommends "${missing[@]}"
fi
