#!/usr/bin/env bash
# Fails when a function in the given folders (default: bench viewer) spans more than MAX lines
# (default 80), as universal-ctags measures it (ctags --fields=+ne: from the signature's first
# line to the closing brace). A function that grows past what one person can hold in mind is
# split along its data flow.
set -euo pipefail
max=${MAX_FUNCTION_LINES:-80}
folders=("$@")
((${#folders[@]})) || folders=(bench viewer)
cd "$(dirname "$0")/.."
ctags --fields=+ne --kinds-C++=f --extras=-F -R -o - "${folders[@]}" |
  awk -F'\t' -v max="$max" '
    { line = ""; end = "";
      for (i = 4; i <= NF; i++) {
        if ($i ~ /^line:/) line = substr($i, 6);
        if ($i ~ /^end:/) end = substr($i, 5);
      }
      if (line != "" && end != "" && end - line + 1 > max) {
        printf "%s:%s: %s spans %d lines (at most %d)\n", $2, line, $1, end - line + 1, max;
        long++;
      } }
    END { exit long > 0 }'
