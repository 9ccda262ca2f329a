#!/usr/bin/env bash
# Builds the message decoder fuzz target with clang (libFuzzer + AddressSanitizer) whatever the
# project's compiler), seeds a corpus with valid messages, and fuzzes RUNS inputs drawn from
# libFuzzer's random seed LUMISTAGE_FUZZ_RANDOM_SEED (default 1: the same inputs on every machine;
# 0: a new seed each run), at most 120 s. Fails on a crash, a leak, a sanitizer report or a build
# failure; the crashing input is kept in OUT_DIR.
# Usage: run_fuzz.sh SOURCE_DIR GENERATED_DIR OUT_DIR [RUNS]
set -euo pipefail
src=$1 generated=$2 out=$3 runs=${4:-2000000}

clang=$(command -v clang++ || command -v clang++-14 || true)
if [[ -z "$clang" ]]; then
  echo "run_fuzz: clang++ not found (packaging/install-deps.sh installs clang)" >&2
  exit 1
fi
mkdir -p "$out/corpus"
binary="$out/message_decoder_fuzz"
# The decoder's sources (tests/CMakeLists.txt's message_decoder_fuzz lists the same), and what
# they include that changes.
sources=(core/net/message_codec.cpp core/net/message_rules.cpp core/net/compact_forms.cpp
         core/imaging/partial_image_codec.cpp core/imaging/cell_colours.cpp
         core/refine/refinement_statistics.cpp core/base/names.cpp
         tests/fuzz/message_decoder_fuzz.cpp)
headers=(core/net/message_codec.h core/net/compact_forms.h core/base/leb128.h
         core/imaging/partial_image_codec.h core/imaging/cell_colours.h
         core/refine/refinement_statistics.h)
# Rebuilt only when a source is newer than the binary: a repeated ctest run fuzzes at once.
stale=0
[[ -x "$binary" && ! "$generated/messages_generated.h" -nt "$binary" ]] || stale=1
for f in "${sources[@]}" "${headers[@]}"; do
  if [[ "$src/$f" -nt "$binary" ]]; then stale=1; fi
done
if [[ $stale == 1 ]]; then
  "$clang" -std=c++20 -O1 -g -fsanitize=fuzzer,address -I"$src" -isystem "$generated" \
    "${sources[@]/#/$src/}" -lzstd -o "$binary.tmp"
  mv "$binary.tmp" "$binary"
fi
cd "$out"
set +e
LUMISTAGE_FUZZ_SEED_DIR="$out/corpus" "$binary" -runs="$runs" \
  -seed="${LUMISTAGE_FUZZ_RANDOM_SEED:-1}" -max_total_time=120 -rss_limit_mb=1024 \
  -timeout=10 -max_len=4096 -print_final_stats=1 -artifact_prefix="$out/" corpus >fuzz.log 2>&1
status=$?
set -e
# The progress lines are noise; the seeds read, the totals and any report are what matter.
grep -v -E '^#[0-9]+.*(NEW|REDUCE|pulse)|# Uses:|recommended dictionary' fuzz.log | tail -60
exit "$status"
