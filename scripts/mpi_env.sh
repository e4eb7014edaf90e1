#!/bin/sh
# Installs (once) what the `mpi` feature builds and runs with: Debian's OpenMPI (the library,
# its headers and `mpirun`) and libclang, which the `mpi` crate's bindgen step needs.
# Idempotent: returns at once when `mpirun` and the headers are there.
#
# Usage: scripts/mpi_env.sh        (as root, or with sudo available)
set -eu
# One installer at a time (.ci/run starts one early; the MPI tests call it too).
exec 9>/tmp/linkspace-mpi-env.lock
flock 9
if command -v mpirun >/dev/null 2>&1 && [ -e /usr/lib/x86_64-linux-gnu/openmpi/include/mpi.h ] && ls /usr/lib/llvm-*/lib/libclang.so* >/dev/null 2>&1; then
  exit 0
fi
SUDO=
[ "$(id -u)" = 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends libopenmpi-dev openmpi-bin libclang-dev pkg-config >/dev/null
