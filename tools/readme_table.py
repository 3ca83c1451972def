#!/usr/bin/env python3
"""Keep README.md's main table equal to the committed run it quotes.

The "Main result" table is results/default/summary.csv's rows for one tree, in the csv's order.
Each row's label is the method and its variant's parameters (a trailing "(...)" note is allowed);
every other cell is formatted from the csv. The paragraph above the table names the code version
and the benchmark's duration, which are checked against results/default/meta.json.

  tools/readme_table.py            check; exit 1 listing every difference
  tools/readme_table.py --write    rewrite the table (and the version and duration) in place

Exit 2 on a missing file or a README without the table.
"""
import argparse
import csv
import datetime
import json
import os
import re
import sys

TABLE_HEADER = "| method | GPU memory (MB)"
TREE = "broadleaf_s1"  # the tree the README's table describes


def fail_input(message):
    print(f"readme_table: {message}", file=sys.stderr)
    sys.exit(2)


def number(row, key, digits):
    try:
        return f"{float(row[key]):.{digits}f}"
    except (KeyError, ValueError):
        fail_input(f"summary.csv: column '{key}' missing or not a number for {row.get('variant')}")


def label(row):
    """`method` `key` value, ... from a variant such as method[a=1,b=true]."""
    text = f"`{row['method']}`"
    match = re.fullmatch(r"[^\[]+\[(.*)\]", row["variant"])
    if not match:
        return text
    parts = []
    for pair in match.group(1).split(","):
        key, _, value = pair.partition("=")
        parts.append(f"`{key}`" if value == "true" else f"`{key}` {value}")
    return text + " " + ", ".join(parts)


def cells(row):
    speedup = (f"{number(row, 'speedup_vs_polygonal_n100', 2)}× "
               f"[{number(row, 'speedup_q25_n100', 2)}–{number(row, 'speedup_q75_n100', 2)}]")
    return [
        number(row, "memory_total_mb", 2),
        number(row, "bake_s", 2),
        number(row, "psnr", 2),
        number(row, "flip", 3),
        " / ".join(number(row, f"psnr_d{d}", 1) for d in ("1.5", "4", "12")),
        f"{number(row, 'psnr_closeup', 1)} / {number(row, 'flip_closeup', 3)}",
        f"{round(float(number(row, 'leaf_geometry_fraction', 6)) * 100):.0f} %",
        speedup,
        number(row, "forest_flip_n100", 3),
        number(row, "popping_dolly_peak", 2),
    ]


def duration_text(meta):
    def parse(stamp):
        return datetime.datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ")

    seconds = int((parse(meta["finished"]) - parse(meta["started"])).total_seconds())
    return f"{seconds // 60} min {seconds % 60} s"


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readme", default=os.path.join(root, "README.md"))
    parser.add_argument("--results", default=os.path.join(root, "results", "default"))
    parser.add_argument("--write", action="store_true", help="rewrite README in place")
    args = parser.parse_args()

    summary_path = os.path.join(args.results, "summary.csv")
    meta_path = os.path.join(args.results, "meta.json")
    for path in (args.readme, summary_path, meta_path):
        if not os.path.isfile(path):
            fail_input(f"{path}: no such file")
    with open(summary_path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r.get("tree") == TREE]
    if not rows:
        fail_input(f"{summary_path}: no rows for tree '{TREE}'")
    with open(meta_path) as f:
        meta = json.load(f)
    with open(args.readme) as f:
        lines = f.read().split("\n")

    header = [i for i, line in enumerate(lines) if line.startswith(TABLE_HEADER)]
    if len(header) != 1:
        fail_input(f"{args.readme}: expected one table starting '{TABLE_HEADER}'")
    first = header[0] + 2
    table_end = first
    while table_end < len(lines) and lines[table_end].startswith("|"):
        table_end += 1

    problems = []
    old_rows = lines[first:table_end]
    new_rows = []
    for k, row in enumerate(rows):
        expected_label = label(row)
        old_label = old_rows[k].split(" | ")[0][2:] if k < len(old_rows) else ""
        # A note in parentheses after the generated label is kept.
        note_match = re.search(r" \([^()]*\)$", old_label)
        note = note_match.group(0) if note_match else ""
        new = "| " + " | ".join([expected_label + note] + cells(row)) + " |"
        if k >= len(old_rows) or old_rows[k] != new:
            problems.append(f"row {k + 1} ({row['variant']}):\n  README: "
                            f"{old_rows[k] if k < len(old_rows) else '(missing)'}\n  results: {new}")
        new_rows.append(new)
    for extra in old_rows[len(rows):]:
        problems.append(f"row not in results: {extra}")

    # The paragraph before the table names the run's code version and duration.
    version = meta.get("code_version", "")[:7]
    duration = duration_text(meta)
    intro = "\n".join(lines[:header[0]])
    intro_new = re.sub(r"code at [0-9a-f]{7}[0-9a-f+.]*", f"code at {version}", intro, count=1)
    intro_new = re.sub(r"the benchmark itself \d+ min \d+ s", f"the benchmark itself {duration}",
                       intro_new, count=1)
    if f"code at {version}" not in intro:
        problems.append(f"README names another code version; the run's is {version}")
    if f"the benchmark itself {duration}" not in intro:
        problems.append(f"README names another duration; the run took {duration}")

    if args.write:
        out = intro_new.split("\n") + lines[header[0]:first] + new_rows + lines[table_end:]
        temporary = args.readme + ".tmp"
        with open(temporary, "w") as f:
            f.write("\n".join(out))
        os.replace(temporary, args.readme)
        print(f"readme_table: {len(problems)} difference(s) written to {args.readme}")
        return 0
    if problems:
        print(f"readme_table: {args.readme} differs from {args.results}:", file=sys.stderr)
        for problem in problems:
            print(problem, file=sys.stderr)
        print("run tools/readme_table.py --write after rerunning results/default", file=sys.stderr)
        return 1
    print(f"readme_table: {len(rows)} rows match {summary_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
