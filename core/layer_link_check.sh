#!/bin/sh
# The linker launcher of the link checks (core/CMakeLists.txt): runs the link of
# lumistage_FOLDER_links and, when it fails, says what the undefined references above it mean.
# Usage: layer_link_check.sh FOLDER LINK-COMMAND...
folder=$1
shift
"$@" && exit 0
cat >&2 <<MESSAGE
lumistage_${folder}_links: a file of core/${folder}/ uses code (each undefined reference above)
that lumistage_${folder} does not link. Find where that code is defined:
- in a folder of core/ below ${folder} that ${folder}'s line in core/layers.txt does not name:
  add that folder to the line (check it with: cmake -P core/check_layers.cmake);
- in a folder above ${folder}: move the code down into core/${folder}/ or a folder below it;
  never reorder core/layers.txt to make room;
- in a third-party library: link it in core/${folder}/CMakeLists.txt.
MESSAGE
exit 1
