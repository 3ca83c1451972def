#!/usr/bin/env python3
"""Figures from benchmark runs. For each results/<name>/ with summary.csv and meta.json, writes
paper_figures/<name>/:

  fps_vs_trees.png      FPS vs forest size per method (log-log)
  speedup_vs_trees.png  speedup vs polygonal per forest size, bars: interquartile range of blocks
  psnr_vs_distance.png  PSNR per distance ring; the close-up ring as its own marker
  psnr_vs_fragments.png PSNR against fragment-shader invocations per pixel of the views
  speedup_vs_flip.png   forest speedup against the FLIP of the forest frames
  memory_vs_psnr.png    GPU memory vs PSNR with the Pareto front (less memory, more PSNR)
  memory_curves.png     methods swept over their memory knob: close-up PSNR and FLIP vs memory
  bake_time.png         bake time per method variant
  comparison_grid.png   rows: views; columns: reference then each variant, each image above its
                        per-pixel error heat map (with a scale bar)       [needs images/]
  crops.png             close-ups of the nearest view, as the papers' Figs. 10 and 12 [images/]
  popping_<tree>.png    per-frame and temporal error along the dolly and orbit [popping.csv]
  captions.md           what each figure shows, with the config, commit and renderer

Reads only what canopy-bench wrote (CSV, JSON, PNG). Figures whose inputs are missing (images are
not committed) are skipped with a note."""
import csv
import json
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from cycler import cycler  # noqa: E402

# Ten colours solid, then the same ten dashed: runs have more than ten variants, and a repeated
# colour made two methods one line.
matplotlib.rcParams["axes.prop_cycle"] = cycler(linestyle=["-", "--"]) * cycler(
    color=plt.get_cmap("tab10").colors)


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


class ImageIndex:
    """The file-system names of a run's tree and variant labels, as canopy-bench wrote them
    (names.json), so they are read rather than derived a second time: the folders of images/,
    and the names figures take."""

    def __init__(self, run_dir):
        path = run_dir / "names.json"
        data = json.loads(path.read_text()) if path.exists() else {"trees": {}, "variants": {}}
        self.trees, self.variants = data["trees"], data["variants"]
        self.variants.setdefault("reference", "reference")

    def tree_name(self, tree):
        return self.trees.get(tree)

    def tree_dir(self, run_dir, tree):
        return run_dir / "images" / self.trees[tree] if tree in self.trees else None

    def variant_dir(self, tree_dir, variant):
        return tree_dir / self.variants[variant] if variant in self.variants else None


def finish_panel(axis, tree, xlabel, ylabel, log_x=False, log_y=False):
    """The labels, scales, grid and legend every per-tree panel gets."""
    if log_x:
        axis.set_xscale("log")
    if log_y:
        axis.set_yscale("log")
    axis.set_xlabel(xlabel)
    axis.set_ylabel(ylabel)
    axis.set_title(tree)
    axis.grid(True, which="both", alpha=0.3)
    # Below the panel: variant names with their parameters are long, and inside the axes the
    # legend hid the curves.
    legend = axis.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.16),
                         frameon=False)
    legend.set_in_layout(False)  # the panel keeps its size; the saved image grows to hold it


def save_figure(fig, path):
    fig.tight_layout()
    legends = [axis.get_legend() for axis in fig.axes if axis.get_legend() is not None]
    fig.savefig(path, dpi=150, bbox_inches="tight", bbox_extra_artists=legends)
    plt.close(fig)


def plot_per_tree(rows, trees, prefix, xlabel, ylabel, log_y, path, extra=None):
    """One panel per tree, one line per method variant, x from the column suffix (log scale).
    `extra(axis, row, colour)` may add a variant's further marks in its line's colour."""
    fig, axes = plt.subplots(1, len(trees), figsize=(4.2 * len(trees), 3.6), squeeze=False)
    for axis, tree in zip(axes[0], trees):
        for row in (r for r in rows if r["tree"] == tree):
            points = series(row, prefix)
            if points:
                line, = axis.plot([p[0] for p in points], [p[1] for p in points], marker="o",
                                  label=row["variant"])
                if extra:
                    extra(axis, row, line.get_color())
        finish_panel(axis, tree, xlabel, ylabel, log_x=True, log_y=log_y)
    save_figure(fig, path)


def pareto_front(points):
    """Points (memory, psnr, label) not dominated by one with less memory and more PSNR."""
    front, best = [], -np.inf
    for memory, psnr, label in sorted(points, key=lambda p: (p[0], -p[1])):
        if psnr > best:
            front.append((memory, psnr, label))
            best = psnr
    return front


def plot_memory_vs_psnr(rows, trees, path):
    fig, axes = plt.subplots(1, len(trees), figsize=(4.6 * len(trees), 3.8), squeeze=False)
    for axis, tree in zip(axes[0], trees):
        points = []
        for row in rows:
            memory, psnr = number(row.get("memory_total_mb")), number(row.get("psnr"))
            # The reference scores the 100 dB cap against itself: not a point of the trade-off.
            if row["tree"] != tree or memory is None or psnr is None or psnr >= 99.9:
                continue
            points.append((memory, psnr, row["variant"]))
        for memory, psnr, label in points:
            axis.scatter(memory, psnr, s=18)
            axis.annotate(label, (memory, psnr), fontsize=5, xytext=(2, 2), textcoords="offset points")
        front = pareto_front(points)
        if front:
            axis.step([p[0] for p in front], [p[1] for p in front], where="post", color="k",
                      linewidth=1, label="Pareto front")
            axis.legend(fontsize=6)
        axis.set_xscale("log")
        axis.set_xlabel("GPU memory (MB, ledger)")
        axis.set_ylabel("PSNR (dB)")
        axis.set_title(tree)
        axis.grid(True, which="both", alpha=0.3)
    save_figure(fig, path)


def method_of(row, also_memory=()):
    """The method a variant runs, with its non-memory parameters: variants that differ only in the
    method's memory knob draw one curve; so do those that differ only in a knob of `also_memory`,
    unless the variant sets the memory knob too (then each value of it is a curve of its own)."""
    label = row["variant"]
    match = re.search(r"\[(.*)\]$", label)
    if not match:
        return label
    params = match.group(1).split(",")
    sets_knob = any(p.split("=")[0] in MEMORY_KNOBS for p in params)
    dropped = MEMORY_KNOBS if sets_knob else MEMORY_KNOBS | set(also_memory)
    kept = [p for p in params if p.split("=")[0] not in dropped]
    return row["method"] + (f"[{','.join(kept)}]" if kept else "")


# Each method's memory knob (canopy-bench --list-methods; the budget search turns the same ones).
MEMORY_KNOBS = {"density", "hash_resolution", "cell_size", "texture_size", "texels", "atlas_size"}


def plot_memory_curves(rows, trees, path):
    """The multi-layer paper's Fig. 13 as measured curves: for every method swept over its memory
    knob, PSNR and FLIP of the close-up ring (the orbit views when the run has none) against GPU
    memory. False when no method has two memory points."""
    curves = {}
    for row in rows:
        memory = number(row.get("memory_total_mb"))
        psnr = number(row.get("psnr_closeup")) or number(row.get("psnr"))
        flip = number(row.get("flip_closeup")) or number(row.get("flip"))
        if memory is None or psnr is None or psnr >= 99.9:
            continue
        # K moves a cloud method's memory as much as its texture knob (paper_fig13 sweeps both).
        curves.setdefault((row["tree"], method_of(row, {"clusters"})), []).append(
            (memory, psnr, flip))
    curves = {k: sorted(v) for k, v in curves.items() if len(v) >= 2}
    if not curves:
        return False
    closeup = any(number(r.get("psnr_closeup")) is not None for r in rows)
    fig, axes = plt.subplots(2, len(trees), figsize=(5.2 * len(trees), 6.4), squeeze=False)
    for column, tree in enumerate(trees):
        for (curve_tree, method), points in curves.items():
            if curve_tree != tree:
                continue
            xs = [p[0] for p in points]
            axes[0][column].plot(xs, [p[1] for p in points], "o-", label=method)
            axes[1][column].plot(xs, [p[2] for p in points], "s--", label=method)
        for row_index, ylabel in enumerate(["PSNR (dB)", "LDR-FLIP (lower is better)"]):
            axis = axes[row_index][column]
            axis.set_xscale("log")
            axis.set_xlabel("GPU memory (MB, ledger)")
            axis.set_ylabel(("close-up " if closeup else "") + ylabel)
            axis.grid(True, which="both", alpha=0.3)
            axis.set_title(tree, fontsize=9)
            axis.legend(fontsize=6)
    save_figure(fig, path)
    return True


def plot_bake_time(rows, path):
    labels = [f"{r['tree']} · {r['variant']}" for r in rows if number(r.get("bake_s")) is not None]
    values = [number(r["bake_s"]) for r in rows if number(r.get("bake_s")) is not None]
    fig, axis = plt.subplots(figsize=(7, 0.22 * len(labels) + 1.2))
    axis.barh(range(len(values)), values, color="tab:green")
    axis.set_yticks(range(len(values)), labels, fontsize=6)
    axis.invert_yaxis()
    axis.set_xscale("log")
    axis.set_xlabel("bake time (s, CPU + upload-free)")
    axis.grid(True, axis="x", which="both", alpha=0.3)
    save_figure(fig, path)


def plot_scatter_per_tree(rows, trees, points_of, xlabel, ylabel, log_x, path):
    """One panel per tree; points_of(row) gives (x, y, marker label) points of a variant."""
    fig, axes = plt.subplots(1, len(trees), figsize=(4.6 * len(trees), 3.8), squeeze=False)
    drawn = False
    for axis, tree in zip(axes[0], trees):
        for row in (r for r in rows if r["tree"] == tree):
            points = [p for p in points_of(row) if p[0] is not None and p[1] is not None]
            if not points:
                continue
            drawn = True
            mark = axis.plot([p[0] for p in points], [p[1] for p in points], marker="o",
                             linestyle="-" if len(points) > 1 else "none", label=row["variant"])[0]
            for x, y, label in points:
                if label:
                    axis.annotate(label, (x, y), fontsize=5, xytext=(2, 2), textcoords="offset points",
                                  color=mark.get_color())
        finish_panel(axis, tree, xlabel, ylabel, log_x=log_x)
    save_figure(fig, path)
    return drawn


def forest_sizes(rows):
    return sorted({int(m.group(1)) for r in rows for k in r
                   if (m := re.fullmatch(r"speedup_vs_polygonal_n([0-9]+)", k))})


def plot_speedup_vs_trees(rows, trees, path):
    """Speedup per forest size with the interquartile range of the interleaved blocks."""
    fig, axes = plt.subplots(1, len(trees), figsize=(4.2 * len(trees), 3.6), squeeze=False)
    sizes = forest_sizes(rows)
    for axis, tree in zip(axes[0], trees):
        for row in (r for r in rows if r["tree"] == tree):
            xs, ys, low, high = [], [], [], []
            for n in sizes:
                speedup = number(row.get(f"speedup_vs_polygonal_n{n}"))
                q25, q75 = number(row.get(f"speedup_q25_n{n}")), number(row.get(f"speedup_q75_n{n}"))
                if speedup is None:
                    continue
                xs.append(n)
                ys.append(speedup)
                # The geometric mean may fall outside the per-camera IQR (skewed ratios): the bar
                # then covers the IQR only on the side that reaches past the point.
                low.append(max(0.0, speedup - q25) if q25 is not None else 0.0)
                high.append(max(0.0, q75 - speedup) if q75 is not None else 0.0)
            if xs:
                axis.errorbar(xs, ys, yerr=[low, high], marker="o", capsize=3, label=row["variant"])
        axis.axhline(1.0, color="k", linewidth=0.8)
        finish_panel(axis, tree, "trees in the forest", "speedup vs polygonal (same run)",
                     log_x=True, log_y=True)
    save_figure(fig, path)


def load_rgb(path):
    image = mpimg.imread(path)
    return image[..., :3].astype(np.float64)


def pick_views(view_dir, count):
    """Up to `count` view keys: one per orbit distance ring (nearest first, elevation 30° where
    there is one), then one of the close-up ring ("closeup_" keys) if the run has it."""
    keys = sorted(p.stem for p in view_dir.glob("*.png"))
    closeup = [k for k in keys if k.startswith("closeup_")]
    def distance(key):
        match = re.match(r"d([0-9.]+)_", key)
        return float(match.group(1)) if match else 0.0
    by_distance = {}
    for key in keys:
        if not key.startswith("closeup_"):
            by_distance.setdefault(distance(key), []).append(key)
    chosen = []
    for d in sorted(by_distance):
        options = by_distance[d]
        chosen.append(next((k for k in options if "_e30_" in k), options[len(options) // 2]))
    if closeup:
        chosen = chosen[:max(count - 1, 0)] + [next((k for k in closeup if "_e30_" in k), closeup[0])]
    return chosen[:count]


def crop_view(view_dir):
    """The view crops are cut from: a close-up if the run has them (leaf scale), else the nearest."""
    keys = pick_views(view_dir, 99)
    return [k for k in keys if k.startswith("closeup_")][:1] or keys[:1]


def comparison_grid(run_dir, index, tree, variants, path, views=4):
    """Each view: a row of images (reference, methods) and a row of error maps under them."""
    tree_dir = index.tree_dir(run_dir, tree)
    if tree_dir is None or not (tree_dir / "reference").is_dir():
        return False
    reference_dir = tree_dir / "reference"
    variants = [v for v in variants if index.variant_dir(tree_dir, v) and index.variant_dir(tree_dir, v).is_dir()]
    keys = pick_views(reference_dir, views)
    if not keys or not variants:
        return False
    columns = 1 + len(variants)
    fig, axes = plt.subplots(2 * len(keys), columns, figsize=(1.9 * columns, 3.8 * len(keys)),
                             squeeze=False)
    heat = None
    for r, key in enumerate(keys):
        reference = load_rgb(reference_dir / f"{key}.png")
        axes[2 * r][0].imshow(reference)
        axes[2 * r][0].set_title(f"reference\n{key}", fontsize=6)
        axes[2 * r + 1][0].axis("off")
        for c, variant in enumerate(variants, start=1):
            image_path = index.variant_dir(tree_dir, variant) / f"{key}.png"
            if not image_path.exists():
                axes[2 * r][c].axis("off")
                axes[2 * r + 1][c].axis("off")
                continue
            image = load_rgb(image_path)
            error = np.abs(image - reference).mean(axis=2)
            mse = np.mean((image - reference) ** 2)
            axes[2 * r][c].imshow(image)
            axes[2 * r][c].set_title(f"{variant}\nframe PSNR {10 * np.log10(1 / max(mse, 1e-12)):.1f} dB",
                                     fontsize=6)
            heat = axes[2 * r + 1][c].imshow(error, cmap="inferno", vmin=0.0, vmax=0.5)
        for axis in axes[2 * r]:
            axis.set_xticks([]), axis.set_yticks([])
        for axis in axes[2 * r + 1]:
            axis.set_xticks([]), axis.set_yticks([])
    if heat is not None:
        bar = fig.colorbar(heat, ax=axes.ravel().tolist(), shrink=0.3, pad=0.01)
        bar.set_label("mean |RGB error| (sRGB, 0–1)", fontsize=7)
    fig.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(fig)
    return True


def crops(run_dir, index, tree, variants, path, size=128):
    """The nearest view's centre region at full resolution, reference then each variant."""
    tree_dir = index.tree_dir(run_dir, tree)
    if tree_dir is None or not (tree_dir / "reference").is_dir():
        return False
    reference_dir = tree_dir / "reference"
    keys = crop_view(reference_dir)
    variants = [v for v in variants if index.variant_dir(tree_dir, v)
                and (index.variant_dir(tree_dir, v) / f"{keys[0]}.png").exists()] if keys else []
    if not variants:
        return False
    reference = load_rgb(reference_dir / f"{keys[0]}.png")
    h, w = reference.shape[:2]
    # Centre on the tree: the centroid of pixels that differ from the background corner.
    mask = np.abs(reference - reference[0, 0]).sum(axis=2) > 0.02
    ys, xs = np.nonzero(mask)
    cy, cx = (int(ys.mean()), int(xs.mean())) if len(ys) else (h // 2, w // 2)
    y0, x0 = np.clip(cy - size // 2, 0, h - size), np.clip(cx - size // 2, 0, w - size)
    images = [("reference", reference)] + [(v, load_rgb(index.variant_dir(tree_dir, v) / f"{keys[0]}.png"))
                                          for v in variants]
    fig, axes = plt.subplots(1, len(images), figsize=(2.2 * len(images), 2.5), squeeze=False)
    for axis, (label, image) in zip(axes[0], images):
        axis.imshow(image[y0:y0 + size, x0:x0 + size], interpolation="nearest")
        axis.set_title(label, fontsize=6)
        axis.set_xticks([]), axis.set_yticks([])
    fig.suptitle(f"{tree}, view {keys[0]}, {size}×{size} px crop", fontsize=7)
    save_figure(fig, path)
    return True


def plot_popping(run_dir, index, out):
    """Per tree: PSNR and temporal excess along the dolly (x: distance) and the orbit (x: azimuth),
    with ticks where a method switched level of detail. Returns the files written."""
    popping = run_dir / "popping.csv"
    if not popping.exists():
        return []
    rows = list(csv.DictReader(popping.open()))
    written = []
    for tree in sorted({r["tree"] for r in rows}):
        groups = {}
        for row in (r for r in rows if r["tree"] == tree and r["variant"] != "polygonal"):
            groups.setdefault((row["variant"], row["path"]), []).append(row)
        paths = sorted({key[1] for key in groups})
        fig, axes = plt.subplots(2, len(paths), figsize=(5.5 * len(paths), 6), squeeze=False)
        for column, path_name in enumerate(paths):
            for (variant, p), frames in sorted(groups.items()):
                if p != path_name:
                    continue
                if path_name == "orbit":
                    x = [360.0 * int(f["frame"]) / len(frames) for f in frames]
                else:
                    x = [number(f["distance"]) for f in frames]
                axes[0][column].plot(x, [number(f["psnr"]) for f in frames], label=variant, linewidth=1)
                line, = axes[1][column].plot(x, [number(f["temporal_excess"]) for f in frames],
                                             label=variant, linewidth=1)
                switches = [xi for xi, f in zip(x, frames) if f.get("lod_switch") == "1"]
                axes[1][column].scatter(switches, [0] * len(switches), marker="|", color=line.get_color(),
                                        s=80)
            axes[0][column].set_title(f"{tree}: {path_name} path")
            axes[0][column].set_ylabel("frame PSNR vs reference (dB)")
            axes[1][column].set_ylabel("temporal error − reference's (8-bit RMS)")
            xlabel = "azimuth (degrees)" if path_name == "orbit" else "camera distance (bounding radii)"
            for axis in axes[:, column]:
                axis.set_xlabel(xlabel)
                axis.grid(True, alpha=0.3)
                axis.legend(fontsize=6)
        fig.tight_layout()
        if index.tree_name(tree) is None:
            continue
        name = f"popping_{index.tree_name(tree)}.png"
        fig.savefig(out / name, dpi=150)
        plt.close(fig)
        written.append(name)
    return written


def sweep_groups(variants):
    """Variants grouped by the parameter names in their labels ("m[cutoff=0.9]" -> "cutoff"), so an
    ablation gets one crop row per swept parameter (the papers' side-by-side comparisons)."""
    groups = {}
    for variant in variants:
        match = re.search(r"\[(.*)\]$", variant)
        if not match:
            continue
        keys = ",".join(sorted(part.split("=")[0] for part in match.group(1).split(",")))
        groups.setdefault(keys, []).append(variant)
    return {k: v for k, v in groups.items() if len(v) > 1}


def plot_sweep(rows, tree, key, group, path):
    """One numeric parameter's sweep: PSNR (left axis) and FLIP (right axis) against its value,
    each point labelled with the variant's GPU memory and its speedup at the largest forest the
    run timed (the papers' trade-off figures, e.g. the volumetric paper's Fig. 10 for the cutoff;
    a quality/speed curve for LoD knobs). False when the values are not all numbers."""
    forest_sizes = sorted(int(k[len("speedup_vs_polygonal_n"):]) for k in (rows[0] if rows else {})
                          if k.startswith("speedup_vs_polygonal_n"))
    speed_key = f"speedup_vs_polygonal_n{forest_sizes[-1]}" if forest_sizes else None
    points = []
    for row in rows:
        if row["tree"] != tree or row["variant"] not in group:
            continue
        match = re.search(rf"(?:\[|,){re.escape(key)}=([^,\]]+)", row["variant"])
        value = number(match.group(1)) if match else None
        psnr, flip, memory = number(row.get("psnr")), number(row.get("flip")), number(row.get("memory_total_mb"))
        speedup = number(row.get(speed_key)) if speed_key else None
        if value is None or psnr is None:
            return False
        points.append((value, psnr, flip, memory, speedup))
    if len(points) < 2:
        return False
    points.sort()
    fig, axis = plt.subplots(figsize=(5, 3.4))
    xs = [p[0] for p in points]
    axis.plot(xs, [p[1] for p in points], "o-", color="C0", label="PSNR")
    for x, psnr, _, memory, speedup in points:
        label = " ".join(part for part in (
            f"{memory:.0f} MB" if memory is not None else "",
            f"{speedup:.2f}x@{forest_sizes[-1]}" if speedup is not None else "") if part)
        if label:
            axis.annotate(label, (x, psnr), textcoords="offset points", xytext=(0, 6),
                          ha="center", fontsize=7)
    axis.set_xlabel(key)
    axis.set_ylabel("PSNR over coverage union (dB)", color="C0")
    axis.grid(True, alpha=0.3)
    flips = [(p[0], p[2]) for p in points if p[2] is not None]
    if flips:
        right = axis.twinx()
        right.plot([f[0] for f in flips], [f[1] for f in flips], "s--", color="C3", label="FLIP")
        right.set_ylabel("LDR-FLIP (lower is better)", color="C3")
    axis.set_title(f"{tree}: {key} sweep", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)
    return True


def make_figures(run_dir: Path, out_root: Path):
    summary = run_dir / "summary.csv"
    meta_path = run_dir / "meta.json"
    if not summary.exists() or not meta_path.exists():
        return False
    meta = json.loads(meta_path.read_text())
    rows = list(csv.DictReader(summary.open()))
    closeups = meta.get("config", {}).get("views", {}).get("closeups")
    index = ImageIndex(run_dir)
    out = out_root / run_dir.name
    out.mkdir(parents=True, exist_ok=True)
    renderer = meta.get("gl", {}).get("renderer", "unknown")
    trees = sorted({row["tree"] for row in rows})
    made = []

    plot_per_tree(rows, trees, "fps_n", "trees in the forest", "FPS (median frame time)", True,
                  out / "fps_vs_trees.png")
    made.append("- `fps_vs_trees.png`: FPS = 1000 / median frame time along the forest orbit, log-log.")
    plot_speedup_vs_trees(rows, trees, out / "speedup_vs_trees.png")
    made.append("- `speedup_vs_trees.png`: speedup vs `polygonal` per forest size (per-camera ratios, "
                "both timed in turn on the same cameras, summarized as `speedup_vs_polygonal`); "
                "bars: interquartile range of the per-camera ratios.")

    def closeup_marks(axis, row, colour):
        psnr = number(row.get("psnr_closeup"))
        if closeups and psnr is not None:
            axis.scatter([float(closeups.get("distance", 1.5))], [psnr], marker="*", s=90, color=colour,
                         edgecolors="k", linewidths=0.4, zorder=3)

    plot_per_tree(rows, trees, "psnr_d", "camera distance (bounding radii)", "PSNR over coverage union (dB)",
                  False, out / "psnr_vs_distance.png", closeup_marks)
    note = ""
    if closeups:
        note = (f"; stars: the close-up ring ({closeups.get('fov_deg', 8)}° field of view at "
                f"{closeups.get('distance', 1.5)} radii), its own measurement")
    made.append("- `psnr_vs_distance.png`: mean PSNR over the views of each distance ring "
                f"(polygonal against itself is at the 100 dB cap){note}.")

    def fragments_point(row):
        psnr = number(row.get("psnr"))
        return [] if psnr is None or psnr >= 99.9 else [(number(row.get("fragments_per_pixel")), psnr, "")]

    if plot_scatter_per_tree(rows, trees, fragments_point, "fragment-shader invocations per output pixel",
                             "PSNR over coverage union (dB)", True, out / "psnr_vs_fragments.png"):
        made.append("- `psnr_vs_fragments.png`: mean PSNR of the orbit views against what a view cost: "
                    "fragment-shader invocations per output pixel (GL pipeline statistics).")

    def forest_points(row):
        return [(number(row.get(f"forest_flip_n{n}")), number(row.get(f"speedup_vs_polygonal_n{n}")),
                 f"{n}") for n in forest_sizes(rows)]

    if plot_scatter_per_tree(rows, trees, forest_points, "FLIP of the forest frames vs the reference's",
                             "speedup vs polygonal", False, out / "speedup_vs_flip.png"):
        made.append("- `speedup_vs_flip.png`: forest speedup against the mean LDR-FLIP of the forest frames "
                    "scored against the reference's from the same cameras (labels: trees in the forest); "
                    "a method cannot look fast by drawing less without moving right.")
    plot_memory_vs_psnr(rows, trees, out / "memory_vs_psnr.png")
    made.append("- `memory_vs_psnr.png`: GPU memory (ledger) against mean PSNR per variant; the step line "
                "is the Pareto front (no other variant has less memory and more PSNR).")
    plot_bake_time(rows, out / "bake_time.png")
    made.append("- `bake_time.png`: bake time per tree and variant (log scale).")
    if plot_memory_curves(rows, trees, out / "memory_curves.png"):
        made.append("- `memory_curves.png`: each method swept over its memory knob, PSNR (top) and FLIP "
                    "(bottom) of the close-up ring (the orbit views without one) against GPU memory: the "
                    "multi-layer paper's Fig. 13 as measured curves.")
    variants = [v for v in dict.fromkeys(r["variant"] for r in rows) if v != "polygonal"]
    for tree in trees:
        if index.tree_name(tree) is None:
            continue
        tree_variants = [r["variant"] for r in rows if r["tree"] == tree and r["variant"] in variants]
        name = f"comparison_grid_{index.tree_name(tree)}.png"
        if comparison_grid(run_dir, index, tree, tree_variants, out / name):
            made.append(f"- `{name}`: rows of views (one per distance ring, then a close-up), the reference "
                        "then each variant; under each image its per-pixel mean absolute sRGB error "
                        "(colour bar).")
        name = f"crops_{index.tree_name(tree)}.png"
        if crops(run_dir, index, tree, tree_variants, out / name):
            made.append(f"- `{name}`: 128×128-pixel crops at full resolution of a close-up view (or the "
                        "nearest view when the run has no close-up ring).")
        for keys, group in sweep_groups(tree_variants).items():
            name = f"sweep_{index.tree_name(tree)}_{keys.replace(',', '_')}.png"
            if "," not in keys and plot_sweep(rows, tree, keys, group, out / name):
                made.append(f"- `{name}`: mean PSNR and FLIP of the orbit views across the `{keys}` "
                            "sweep, each point labelled with its GPU memory.")
            name = f"crops_{index.tree_name(tree)}_{keys.replace(',', '_')}.png"
            if crops(run_dir, index, tree, group, out / name):
                made.append(f"- `{name}`: the same close-up across the `{keys}` sweep.")
    for name in plot_popping(run_dir, index, out):
        made.append(f"- `{name}`: along the dolly (close to far, log-spaced) and the orbit, per-frame PSNR "
                    "against the reference and the temporal error in excess of the reference's; ticks "
                    "mark frames where the method switched level of detail.")
    if not (run_dir / "images").is_dir():
        made.append("- (image figures skipped: the run's images/ folder is not present)")

    caption = (
        f"# Figures of run `{run_dir.name}`\n\n"
        f"Config `{meta.get('experiment')}` (hash `{meta.get('config_hash')}`), commit `{meta.get('git_commit')}`, "
        f"renderer `{renderer}` ({meta.get('gl', {}).get('backend')}), CPU `{meta.get('cpu')}`.\n\n"
        + "\n".join(made) + "\n"
    )
    (out / "captions.md").write_text(caption)
    print(f"{out}: {len(made)} figure(s)")
    return True


def main():
    results = Path(sys.argv[1] if len(sys.argv) > 1 else "results")
    out_root = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).resolve().parent
    # Runs moved aside by --fresh (<run>.previous-<time>) are history, not figures.
    runs = sorted(p for p in results.iterdir() if p.is_dir() and ".previous-" not in p.name) \
        if results.is_dir() else []
    if (results / "summary.csv").exists():
        runs = [results]
    made = [make_figures(run, out_root) for run in runs]
    if not any(made):
        print(f"no runs with summary.csv and meta.json under {results}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
