#!/usr/bin/env bash
# make fuzz: builds the libFuzzer harnesses of tests/fuzz (preset "fuzz": clang, ASan + UBSan)
# and runs each for FUZZ_SECONDS (first argument, default 60), FUZZ_JOBS of them at a time
# (second argument, default 1). Each starts from the committed seed corpus and a working corpus
# in build/fuzz/corpus/<target>; a crash input lands in build/fuzz/crashes/<target>/. Prints the
# executions per target and exits non-zero when any target crashed.
set -euo pipefail
seconds=${1:-60}
jobs=${2:-1}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
tools/install-deps.sh tools/fuzz-packages.txt
mkdir -p build
cmake --preset fuzz > build/fuzz-configure.log 2>&1 || { cat build/fuzz-configure.log; exit 1; }
cmake --build --preset fuzz -j "$(nproc)"
targets=(config tree_loader captures camera_path asset_loader)
mkdir -p build/fuzz/logs
run_one() {
  local target=$1 seconds=$2
  local corpus=build/fuzz/corpus/$target crashes=build/fuzz/crashes/$target
  mkdir -p "$corpus" "$crashes"
  # The committed seeds and every input that once found a bug start each run.
  local inputs=("tests/fuzz/corpus/$target")
  [[ -d tests/fuzz/regressions/$target ]] && inputs+=("tests/fuzz/regressions/$target")
  # Mesa (the asset loader bakes its seed assets through OSMesa) keeps allocations until exit.
  local leaks=1
  [[ $target == asset_loader ]] && leaks=0
  if ASAN_OPTIONS="detect_leaks=$leaks:abort_on_error=1" \
     LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0" \
     build/fuzz/bin/fuzz_"$target" -max_total_time="$seconds" -timeout=60 -rss_limit_mb=6144 \
       -detect_leaks=$leaks -print_final_stats=1 -artifact_prefix="$crashes/" \
       "$corpus" "${inputs[@]}" > "build/fuzz/logs/$target.log" 2>&1; then
    status=ok
  else
    status=CRASH
  fi
  local runs
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "build/fuzz/logs/$target.log" |
         grep -o '[0-9]*$' | tail -1)
  printf 'fuzz %-12s %-5s %10s executions in %ss (log build/fuzz/logs/%s.log)\n' \
    "$target" "$status" "${runs:-?}" "$seconds" "$target"
  [[ $status == ok ]]
}
export -f run_one
printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c "run_one {} $seconds"
