#!/usr/bin/env python3
"""Figures from committed runs: for each results/<name>/summary.csv, writes
paper_figures/<name>/fps_vs_trees.png, psnr_vs_distance.png and captions.md (config, commit,
renderer). Reads only the CSV and meta.json that canopy-bench wrote."""
import csv
import json
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def series(row, prefix):
    """Columns like psnr_d1.5 -> [(1.5, value), ...] sorted by key."""
    points = []
    for key, value in row.items():
        match = re.fullmatch(re.escape(prefix) + r"([0-9.]+)", key)
        if match and number(value) is not None:
            points.append((float(match.group(1)), float(value)))
    return sorted(points)


def plot_per_tree(rows, trees, prefix, xlabel, ylabel, log_y, path):
    """One panel per tree, one line per method variant, x from the column suffix (log scale)."""
    fig, axes = plt.subplots(1, len(trees), figsize=(4.2 * len(trees), 3.6), squeeze=False)
    for axis, tree in zip(axes[0], trees):
        for row in (r for r in rows if r["tree"] == tree):
            points = series(row, prefix)
            if points:
                axis.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=row["variant"])
        axis.set_xscale("log")
        if log_y:
            axis.set_yscale("log")
        axis.set_xlabel(xlabel)
        axis.set_ylabel(ylabel)
        axis.set_title(tree)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def make_figures(run_dir: Path, out_root: Path):
    summary = run_dir / "summary.csv"
    meta_path = run_dir / "meta.json"
    if not summary.exists() or not meta_path.exists():
        return False
    meta = json.loads(meta_path.read_text())
    rows = list(csv.DictReader(summary.open()))
    out = out_root / run_dir.name
    out.mkdir(parents=True, exist_ok=True)
    renderer = meta.get("gl", {}).get("renderer", "unknown")
    trees = sorted({row["tree"] for row in rows})

    plot_per_tree(rows, trees, "fps_n", "trees in the forest", "FPS (median frame time)", True,
                  out / "fps_vs_trees.png")
    plot_per_tree(rows, trees, "psnr_d", "camera distance (bounding radii)", "PSNR over coverage union (dB)",
                  False, out / "psnr_vs_distance.png")

    caption = (
        f"# Figures of run `{run_dir.name}`\n\n"
        f"Config `{meta.get('experiment')}` (hash `{meta.get('config_hash')}`), commit `{meta.get('git_commit')}`, "
        f"renderer `{renderer}` ({meta.get('gl', {}).get('backend')}), CPU `{meta.get('cpu')}`.\n\n"
        "- `fps_vs_trees.png`: FPS = 1000 / median frame time along the forest orbit, log-log.\n"
        "- `psnr_vs_distance.png`: mean PSNR over the views of each distance ring "
        "(polygonal against itself is at the 100 dB cap).\n"
    )
    (out / "captions.md").write_text(caption)
    print(f"{out}: fps_vs_trees.png, psnr_vs_distance.png, captions.md")
    return True


def main():
    results = Path(sys.argv[1] if len(sys.argv) > 1 else "results")
    out_root = Path(__file__).resolve().parent
    made = [make_figures(run, out_root) for run in sorted(p for p in results.iterdir() if p.is_dir())]
    if not any(made):
        print(f"no runs with summary.csv and meta.json under {results}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
