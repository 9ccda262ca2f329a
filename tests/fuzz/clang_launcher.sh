#!/usr/bin/env bash
# Compiler and linker launcher for the file reader fuzz targets (tests/CMakeLists.txt): the
# project may be built with GCC, which has no libFuzzer, so the command CMake gives for these
# targets is run with clang instead. Usage, as CMake calls it:
#   clang_launcher.sh CLANG [PREFIX...] -- PROJECT_COMPILER ARGS...
# PREFIX (e.g. ccache) comes before clang; PROJECT_COMPILER is dropped.
set -euo pipefail
clang=$1
shift
prefix=()
while [[ $# -gt 0 && "$1" != "--" ]]; do
  prefix+=("$1")
  shift
done
shift 2  # "--" and the project's compiler
exec "${prefix[@]}" "$clang" "$@"
