#!/usr/bin/python3
"""Compares two canopy-bench runs record by record, by record_key.

Usage: compare_records.py EXPECTED_RUN ACTUAL_RUN

Every record must be present once in both, with equal fields, except the ones a second process
measures differently by nature: wall-clock times (keys ending in _s or seconds, or holding _ms),
frame rates and speedups, the repeats a timing needed, and peak memory of the process. Numbers
that are rendered or computed (PSNR, FLIP, coverage, memory, primitives, ...) must be equal.
Exit 0 when they match, 1 with one line per difference otherwise.
"""
import json
import re
import sys

MEASURED = re.compile(
    r"(_s|seconds|_ms|_ms_\w+)$|^(fps|speedup_vs_polygonal|speedup_spread|block_speedups|"
    r"frame_speedups|"
    r"repeats|bake_peak_rss_bytes)$"
)


def without_measured(value):
    if isinstance(value, dict):
        return {k: without_measured(v) for k, v in value.items() if not MEASURED.search(k)}
    if isinstance(value, list):
        return [without_measured(v) for v in value]
    return value


def records(run):
    found = {}
    with open(f"{run}/metrics.jsonl", encoding="utf-8") as lines:
        for number, line in enumerate(lines, 1):
            record = json.loads(line)
            key = record["record_key"]
            if key in found:
                sys.exit(f"{run}/metrics.jsonl:{number}: record {key} appears twice")
            found[key] = without_measured(record)
    return found


def main():
    expected, actual = records(sys.argv[1]), records(sys.argv[2])
    problems = [f"missing: {key}" for key in sorted(expected.keys() - actual.keys())]
    problems += [f"unexpected: {key}" for key in sorted(actual.keys() - expected.keys())]
    for key in sorted(expected.keys() & actual.keys()):
        if expected[key] != actual[key]:
            fields = sorted(
                k
                for k in expected[key].keys() | actual[key].keys()
                if expected[key].get(k) != actual[key].get(k)
            )
            problems.append(f"differs: {key}: {', '.join(fields)}")
    for problem in problems:
        print(problem)
    print(f"{len(expected)} records expected, {len(actual)} found, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
