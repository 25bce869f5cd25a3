#!/usr/bin/env bash
# Builds the Python package as a manylinux_2_28 abi3 wheel (CPython ≥ 3.9, x86-64, glibc
# ≥ 2.28) with HDF5 inside (FCLIB .hdf5 problems, VTKHDF frames, HDF5 histories) into
# target/wheels/ (issue 37). maturin drives cargo with zig as the C compiler and linker,
# so the wheel links against an older glibc than this machine's; HDF5 is compiled from
# its sources (hdf5-metno-sys' `static`) by a CMake from PyPI (Debian bookworm's is too
# old for it). The tools go into target/wheel-tools/; exit code 3 if they cannot be
# installed (no network), any other failure is the build's. About six minutes on two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
tools=target/wheel-tools
if ! { python3 -m venv "$tools" \
       && "$tools/bin/pip" install -q 'maturin==1.16.0' 'ziglang==0.17.1' 'cmake==4.4.5'; }; then
  echo "build_wheel.sh: maturin, ziglang or cmake could not be installed from PyPI" >&2
  exit 3
fi
cd python
PATH="$PWD/../$tools/bin:$PATH" maturin build --release --zig --compatibility manylinux_2_28 \
  --features hdf5 -o ../target/wheels
