# bench/lib.sh: sourced by the bench scripts that run `floe run` under mpirun (after they set
# root, the repository). floe_mpi_cli leaves FLOE alone when the caller gave it, otherwise
# builds the CLI of a Release MPI build in BUILD (default build-mpi-bench) and sets FLOE to it.
floe_mpi_cli() {
  [[ -n "${FLOE:-}" ]] && return 0
  local build=${BUILD:-$root/build-mpi-bench}
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF -DFLOE_WITH_MPI=ON >/dev/null
  cmake --build "$build" -j"$(nproc)" --target floe_cli >/dev/null
  FLOE=$build/floe
}
