#!/usr/bin/env bash
# Installs the Debian packages tomograin needs, and only those that are missing.
# Idempotent: when everything is present it runs no apt-get at all.
#   scripts/install_deps.sh            build + test dependencies
#   scripts/install_deps.sh --bench    also the side-by-side peers (LIGGGHTS, Chromium)
#   scripts/install_deps.sh --campaign also Snakemake and a one-node SLURM cluster
#                                      (workflow/, bench/campaign/, tests/workflow/)
set -euo pipefail

pkgs=(
  # build
  build-essential cmake pkg-config
  # libraries (see docs/architecture.md for what each is used for)
  libopencv-dev libcgal-dev libeigen3-dev libhdf5-dev zlib1g-dev libtiff-dev libgmp-dev libmpfr-dev
  libgtest-dev libbenchmark-dev libcli11-dev libtomlplusplus-dev libfmt-dev nlohmann-json3-dev libxxhash-dev libdeflate-dev
  # sanitizer + fuzzing toolchain (tests/fuzz)
  clang libclang-rt-14-dev
  # file checks in tests (tiffinfo) and the Python side of tests, reports and benches
  libtiff-tools python3 python3-numpy python3-scipy python3-skimage python3-h5py python3-tifffile
  python3-matplotlib
  # headless browser for the report test
  chromium
)
if [[ "${1:-}" == "--bench" ]]; then
  pkgs+=(liggghts openmpi-bin hyperfine)
elif [[ "${1:-}" == "--campaign" ]]; then
  # Snakemake 7.21 runs campaigns (workflow/Snakefile); slurm-wlm + munge for
  # bench/campaign/slurm_test.sh's cluster on localhost.
  pkgs+=(snakemake slurm-wlm munge)
fi

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  exit 0
fi

echo "install_deps: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "install_deps: need root (or sudo) to install: ${missing[*]}" >&2; exit 2
  fi
fi
export DEBIAN_FRONTEND=noninteractive
# A new machine has empty package lists: refresh them once before installing.
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
