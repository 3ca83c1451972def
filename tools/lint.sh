#!/usr/bin/env bash
# Static checks a contributor runs before a pull request (make lint; CI runs it too):
# clang-format (no change needed), clang-tidy (.clang-tidy, over the compile database of the
# release build) and function length in bench/ and viewer/ (tools/check-function-length.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build/release}
mapfile -t sources < <(git ls-files 'common/*.cpp' 'common/*.h' 'methods/*.cpp' 'methods/*.h' \
                                     'bench/*.cpp' 'bench/*.h' 'viewer/*.cpp' 'viewer/*.h' \
                                     'tests/*.cpp' 'tests/*.h')
echo "lint: clang-format on ${#sources[@]} files"
clang-format --dry-run --Werror "${sources[@]}"
echo "lint: function length (bench, viewer)"
tools/check-function-length.sh bench viewer
mapfile -t units < <(printf '%s\n' "${sources[@]}" | grep '\.cpp$' | grep -v '^tests/')
echo "lint: clang-tidy on ${#units[@]} files (${build}/compile_commands.json)"
# The compile commands carry GCC-only flags (-Wno-restrict) and -Werror; clang would make the
# unknown option an error of every file.
run-clang-tidy -quiet -p "$build" -j "$(nproc)" -extra-arg=-Wno-unknown-warning-option \
  "${units[@]}" > "$build/clang-tidy.log" 2>&1 || {
  grep -E "warning:|error:" "$build/clang-tidy.log" | sort -u | head -50
  echo "lint: clang-tidy found problems (all in $build/clang-tidy.log)" >&2
  exit 1
}
echo "lint: clean"
