#!/bin/sh
# README's main table must be results/default's numbers; the checker must also catch a drift.
set -u
root=$(cd "$(dirname "$0")/../.." && pwd)
tool="$root/tools/readme_table.py"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

python3 "$tool" || { echo "FAIL: README.md's main table differs from results/default"; exit 1; }

# One PSNR cell changed by 0.01 dB must be reported (exit 1).
sed '/^| `polygonal` |/s/| 100.00 |/| 99.99 |/' "$root/README.md" > "$scratch/README.md"
cmp -s "$root/README.md" "$scratch/README.md" && { echo "FAIL: the drift fixture was not made"; exit 1; }
python3 "$tool" --readme "$scratch/README.md" 2>/dev/null
[ $? -eq 1 ] || { echo "FAIL: a changed PSNR cell was not reported"; exit 1; }

# --write repairs it.
python3 "$tool" --readme "$scratch/README.md" --write >/dev/null &&
  cmp -s "$root/README.md" "$scratch/README.md" || { echo "FAIL: --write did not restore"; exit 1; }

# A missing results folder is bad input: exit 2.
python3 "$tool" --results "$scratch/none" 2>/dev/null
[ $? -eq 2 ] || { echo "FAIL: a missing results folder did not exit 2"; exit 1; }
echo "readme_table: ok"
