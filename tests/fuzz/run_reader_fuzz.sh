#!/usr/bin/env bash
# Fuzzes one file reader's libFuzzer binary (file_reader_fuzz.cpp, built by tests/CMakeLists.txt)
# from its seeds: RUNS inputs drawn from libFuzzer's random seed LUMISTAGE_FUZZ_RANDOM_SEED
# (default 1), so that a test run tries the same inputs on every machine and a red run is the
# code's doing, not the draw's (at most 120 s whatever RUNS). LUMISTAGE_FUZZ_RANDOM_SEED=0 draws
# a new seed each run, to explore. Fails on a crash, a leak, a sanitizer report, a hang (10 s an
# input) or memory past 2 GB; the input that did it is kept in OUT_DIR (crash-*, leak-*, ...), and
# the corpus grows there from one run to the next.
# Usage: run_reader_fuzz.sh BINARY OUT_DIR RUNS SEED...
set -euo pipefail
binary=$1 out=$2 runs=$3
shift 3
mkdir -p "$out/corpus"
seeds=$(IFS=:; echo "$*")
cd "$out"
set +e
LUMISTAGE_FUZZ_SEED_DIR="$out/corpus" LUMISTAGE_FUZZ_SEEDS="$seeds" "$binary" \
  -runs="$runs" -seed="${LUMISTAGE_FUZZ_RANDOM_SEED:-1}" -max_total_time=120 -rss_limit_mb=2048 -timeout=10 -max_len=16384 -print_final_stats=1 \
  -artifact_prefix="$out/" corpus >fuzz.log 2>&1
status=$?
set -e
grep -v -E '^#[0-9]+.*(NEW|REDUCE|pulse)|# Uses:|recommended dictionary' fuzz.log | tail -60
exit "$status"
