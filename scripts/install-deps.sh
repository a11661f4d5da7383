#!/usr/bin/env bash
# Install every Debian package that floe's build, tests and benchmarks need.
# Idempotent; runs apt-get directly as root, through sudo otherwise.
#   scripts/install-deps.sh          build + tests (CGAL and assimp for meshes: FLOE_WITH_CGAL,
#                                    FLOE_WITH_ASSIMP; GLPK for a test)
#   scripts/install-deps.sh --bench  also the peer codes used by bench/ (LIGGGHTS, nanoflann)
set -euo pipefail
pkgs=(build-essential cmake pkg-config libfyaml-dev libjson-c-dev python3 python3-vtk9
      g++ libcgal-dev libgmp-dev libmpfr-dev libassimp-dev libglpk-dev)
pkgs+=(libsuitesparse-dev)   # CHOLMOD: implicit Newmark-beta (FLOE_WITH_CHOLMOD)
pkgs+=(libnetcdf-dev)        # gridded velocity fields from NetCDF files (FLOE_WITH_NETCDF)
pkgs+=(libshp-dev)           # floes and coastlines from ESRI shapefiles (FLOE_WITH_SHAPELIB)
pkgs+=(libopenmpi-dev openmpi-bin libtrilinos-zoltan-dev)  # MPI domain decomposition (FLOE_WITH_MPI)
pkgs+=(clang)                # the scene fuzzer (scripts/fuzz.sh, libFuzzer)
pkgs+=(python3-matplotlib)   # scripts/plot_fsd.py (floe size distribution PNG; its test skips without)
pkgs+=(python3-numpy python3-cffi python3-pytest)   # the Python package python/ (FLOE_BUILD_PYTHON)
if [[ "${1:-}" == "--bench" ]]; then
  pkgs+=(g++ libnanoflann-dev liggghts time)   # time: GNU time, peak RSS in bench/memory
fi
if [[ $(id -u) -eq 0 ]]; then SUDO=(); else SUDO=(sudo); fi
missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if (( ${#missing[@]} )); then
  if (( ${#SUDO[@]} )) && ! command -v sudo >/dev/null 2>&1; then
    echo "install-deps: missing packages: ${missing[*]}; run this script as root (no sudo here)" >&2
    exit 1
  fi
  echo "install-deps: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  "${SUDO[@]}" apt-get update -qq
  "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "install-deps: all packages present" >&2
fi
