#!/usr/bin/python3
"""Plots of the speed vs accuracy study (bench/trade_study.cpp output in DIR):

  pareto.png          error against frame time, one panel per opacity, with the Pareto front
  error_vs_voxel.png  error against voxel size, one panel per opacity
  side_by_side.png    exact | axis | basic | unsorted | wboit (the side_*.png panels) at opacity 0.05
  flicker.png         flicker above exact's and error change, per mode and camera motion

Usage: scripts/plot_trade.py DIR [NAME]
       scripts/plot_trade.py --docs-copy PNG DIR...   the DIRs' side_by_side.png stacked, as a compact
                                                       palette PNG of at most 300 KB (for the README)
"""
import csv
import os
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The reference, the baselines, then ours; one colour each, the same in every plot.
MODES = ["unsorted", "additive", "wboit", "basic", "axis", "axis+diag", "segsort"]
COLOURS = {"unsorted": "tab:gray", "additive": "tab:brown", "wboit": "tab:purple", "basic": "tab:blue",
           "axis": "tab:red", "axis+diag": "tab:orange", "segsort": "black"}
SIDE_PANELS = ["exact", "axis", "basic", "unsorted", "wboit"]


def colour(mode):
    return COLOURS.get(mode, "tab:green")  # random:N


def mode_order(modes):
    return sorted(modes, key=lambda m: (MODES.index(m) if m in MODES else len(MODES), m))


def read_rows(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in ("voxel_mm", "opacity", "rmse", "ssim", "frame_ms"):
            r[k] = float(r[k])
        r["voxel_dependent"] = r["voxel_dependent"] == "1"
    return [r for r in rows if r["mode"] != "exact"]


def configs(rows, opacity):
    """(mode, voxel or None) -> (median frame ms, mean RMSE) over the views at one opacity."""
    groups = defaultdict(list)
    for r in rows:
        if r["opacity"] == opacity:
            groups[(r["mode"], r["voxel_mm"] if r["voxel_dependent"] else None)].append(r)
    return {k: (statistics.median(r["frame_ms"] for r in g), statistics.fmean(r["rmse"] for r in g))
            for k, g in groups.items()}


def pareto(points):
    """The points not beaten in both time and error, by increasing time."""
    front, best = [], float("inf")
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


def plot_pareto(rows, opacities, name, out):
    fig, axes = plt.subplots(1, len(opacities), figsize=(5.2 * len(opacities), 4.6), squeeze=False)
    for ax, opacity in zip(axes[0], opacities):
        cfg = configs(rows, opacity)
        for mode in mode_order({m for m, _ in cfg}):
            pts = sorted((v if v is not None else 0, t, e) for (m, v), (t, e) in cfg.items() if m == mode)
            ax.scatter([p[1] / 1000 for p in pts], [p[2] for p in pts], color=colour(mode), label=mode, s=28, zorder=3)
            for v, t, e in pts:
                if v:
                    ax.annotate(f"{v:g}", (t / 1000, e), textcoords="offset points", xytext=(4, 3), fontsize=7,
                                color=colour(mode))
        front = pareto(list(cfg.values()))
        ax.step([t / 1000 for t, _ in front], [e for _, e in front], where="post", color="black", lw=0.8,
                ls="--", label="Pareto front", zorder=2)
        ax.set_title(f"opacity {opacity:g}")
        ax.set_xlabel("frame time, s (llvmpipe, median over views)")
        ax.set_ylabel("RMSE vs exact (8-bit levels)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f"{name}: error against frame time (labels: voxel size, mm)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_error_vs_voxel(rows, opacities, name, out):
    fig, axes = plt.subplots(1, len(opacities), figsize=(5.2 * len(opacities), 4.6), squeeze=False)
    for ax, opacity in zip(axes[0], opacities):
        cfg = configs(rows, opacity)
        voxels = sorted({v for _, v in cfg if v is not None})
        for mode in mode_order({m for m, _ in cfg}):
            pts = sorted((v, e) for (m, v), (_, e) in cfg.items() if m == mode)
            if pts[0][0] is None:  # the same picture at every voxel size
                ax.axhline(pts[0][1], color=colour(mode), ls=":", label=f"{mode} (any voxel size)")
            else:
                ax.plot([v for v, _ in pts], [e for _, e in pts], marker="o", color=colour(mode), label=mode)
        ax.set_xscale("log", base=2)
        ax.set_xticks(voxels)
        ax.set_xticklabels([f"{v:g}" for v in voxels])
        ax.set_title(f"opacity {opacity:g}")
        ax.set_xlabel("voxel size, mm")
        ax.set_ylabel("RMSE vs exact (8-bit levels, mean over views)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f"{name}: error against voxel size")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_side_by_side(directory, name, out):
    import numpy as np

    images = [plt.imread(os.path.join(directory, f"side_{m}.png"))[:, :, :3] for m in SIDE_PANELS]
    # The same crop for every panel: the lit pixels of any, plus a margin.
    lit = np.any(np.stack([img.max(axis=2) > 4 / 255 for img in images]), axis=0)
    rows, cols = np.nonzero(lit.any(axis=1))[0], np.nonzero(lit.any(axis=0))[0]
    if len(rows):
        margin = 6
        top, bottom = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, lit.shape[0])
        left, right = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, lit.shape[1])
        images = [img[top:bottom, left:right] for img in images]
    h, w = images[0].shape[:2]
    dpi = 100
    fig, axes = plt.subplots(1, len(images), figsize=(len(images) * w / dpi, (h + 40) / dpi), dpi=dpi)
    for ax, img, mode in zip(axes, images, SIDE_PANELS):
        ax.imshow(img, interpolation="nearest")
        ax.set_title(f"{name}: {mode}" if mode == SIDE_PANELS[0] else mode, fontsize=12, color="white")
        ax.axis("off")
    fig.patch.set_facecolor("black")
    fig.subplots_adjust(left=0, right=1, bottom=0, top=h / (h + 40), wspace=0.01)
    fig.savefig(out, dpi=dpi, facecolor="black")
    plt.close(fig)


def plot_flicker(path, name, out):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["mode"] != "exact"]
    motions = list(dict.fromkeys(r["motion"] for r in rows))
    fig, axes = plt.subplots(1, len(motions), figsize=(6.5 * len(motions), 0.45 * len(rows) + 1.5), squeeze=False)
    for ax, motion in zip(axes[0], motions):
        sel = [r for r in rows if r["motion"] == motion]
        y = range(len(sel))
        ax.barh([i - 0.2 for i in y], [float(r["flicker_minus_exact"]) for r in sel], height=0.4,
                color=[colour(r["mode"].split(" ")[0]) for r in sel], alpha=0.45, label="flicker − exact's")
        ax.barh([i + 0.2 for i in y], [float(r["error_change"]) for r in sel], height=0.4,
                color=[colour(r["mode"].split(" ")[0]) for r in sel], label="error change")
        ax.set_yticks(list(y))
        ax.set_yticklabels([r["mode"] for r in sel])
        ax.axvline(0, color="black", lw=0.8)
        ax.invert_yaxis()
        ax.set_xlabel("8-bit levels (mean over pixels and frame pairs)")
        ax.set_title(motion)
        ax.legend(fontsize=8)
    fig.suptitle(f"{name}: flicker (pale: frame-to-frame difference minus exact's; solid: error change)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def docs_copy(directories, dst, max_bytes=300_000):
    """The side-by-side pictures of the datasets, one above the other at one width, as a palette PNG shrunk
    until it is small enough for the repository."""
    from PIL import Image

    rows = [Image.open(os.path.join(d, "side_by_side.png")).convert("RGB") for d in directories]
    width = min(r.width for r in rows)
    rows = [r.resize((width, r.height * width // r.width), Image.LANCZOS) if r.width != width else r for r in rows]
    img = Image.new("RGB", (width, sum(r.height for r in rows)))
    top = 0
    for r in rows:
        img.paste(r, (0, top))
        top += r.height
    while True:
        img.quantize(colors=256, dither=Image.Dither.NONE).save(dst, optimize=True)
        if os.path.getsize(dst) <= max_bytes or img.width < 400:
            return
        img = img.resize((img.width * 3 // 4, img.height * 3 // 4), Image.LANCZOS)


def main(argv):
    args = [a for a in argv[1:] if not a.startswith("--")]
    if "--docs-copy" in argv:
        if len(args) < 2:
            sys.exit(__doc__)
        docs_copy(args[1:], args[0])
        return
    if not args:
        sys.exit(__doc__)
    directory = args[0]
    name = args[1] if len(args) > 1 else os.path.basename(os.path.normpath(directory))
    rows = read_rows(os.path.join(directory, "results.csv"))
    opacities = sorted({r["opacity"] for r in rows}, reverse=True)
    plot_pareto(rows, opacities, name, os.path.join(directory, "pareto.png"))
    plot_error_vs_voxel(rows, opacities, name, os.path.join(directory, "error_vs_voxel.png"))
    side = os.path.join(directory, "side_by_side.png")
    plot_side_by_side(directory, name, side)
    if os.path.exists(os.path.join(directory, "flicker.csv")):
        plot_flicker(os.path.join(directory, "flicker.csv"), name, os.path.join(directory, "flicker.png"))


if __name__ == "__main__":
    main(sys.argv)
