#!/usr/bin/env python3
"""Pareto plots of a penumbra-bench run: frame time against visibility error, one figure per scene.

usage: plot_bench.py BENCH_CSV OUT_DIR   (writes OUT_DIR/pareto-<scene>.png and .svg)

One panel per technique; one line per variant (filter radius), its points labelled with the
shadow-map resolution. Filled markers lie on the variant's Pareto front (no other row of the
same variant is both faster and more accurate, the `pareto` column); hollow ones do not.
Adaptive rows are drawn as stars, the sun's virtual shadow map as diamonds (pages marked by
the rule) and squares (by the footprint), labelled with their resident pages. The dashed line is
the scene's unshadowed frame time.
Error bars span the fastest to the slowest frame.
"""
import csv
import math
import re
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

ERROR_FLOOR = 1e-6  # errors of exactly 0 (the reference itself) are drawn here on the log axis


def read_rows(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no rows")
    for r in rows:
        for key in ("frame_ms_median", "frame_ms_min", "frame_ms_max", "floor_ms", "mean_abs"):
            r[key] = float(r[key])
        r["resolution_texels"] = int(r["resolution_texels"])
        r["pareto"] = r["pareto"] == "1"
        r["adaptive"] = r["adaptive"] == "1"
        r["virtual_pages"] = r.get("virtual_pages", "")  # older runs have no virtual rows
    return rows


def safe_name(scene):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", scene)


def plot_scene(scene, rows, out_dir):
    techniques = list(OrderedDict.fromkeys(r["technique"] for r in rows))
    cols = min(len(techniques), 4)
    nrows = math.ceil(len(techniques) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.6 * nrows), squeeze=False)
    floor = rows[0]["floor_ms"]
    method = rows[0]["timing_method"]
    for ax, technique in zip(axes.flat, techniques):
        t_rows = [r for r in rows if r["technique"] == technique]
        variants = list(OrderedDict.fromkeys(r["variant"] for r in t_rows))
        for i, variant in enumerate(variants):
            color = plt.cm.viridis(i / max(len(variants) - 1, 1)) if len(variants) > 1 else "tab:blue"
            v_rows = sorted((r for r in t_rows if r["variant"] == variant and not r["adaptive"] and not r["virtual_pages"]),
                            key=lambda r: r["resolution_texels"])
            extra = [r for r in t_rows if r["variant"] == variant and (r["adaptive"] or r["virtual_pages"])]
            xs = [r["frame_ms_median"] for r in v_rows]
            ys = [max(r["mean_abs"], ERROR_FLOOR) for r in v_rows]
            ax.plot(xs, ys, "-", color=color, lw=1, alpha=0.6, label=variant)
            for r in v_rows + extra:
                x, y = r["frame_ms_median"], max(r["mean_abs"], ERROR_FLOOR)
                ax.errorbar(x, y, xerr=[[x - r["frame_ms_min"]], [r["frame_ms_max"] - x]], fmt="none",
                            ecolor=color, elinewidth=0.6, alpha=0.6)
                marker = {"rule": "D", "footprint": "s"}.get(r["virtual_pages"], "*" if r["adaptive"] else "o")
                size = 11 if r["adaptive"] else 7 if r["virtual_pages"] else 6
                ax.plot(x, y, marker, ms=size, color=color, mfc=color if r["pareto"] else "white", mew=1.2)
                if r["virtual_pages"]:
                    label = f"virtual {r['virtual_pages']} {r['pages_resident']}p"
                else:
                    label = f"adaptive {r['resolution_texels']}" if r["adaptive"] else str(r["resolution_texels"])
                below = r["virtual_pages"] == "footprint"  # apart from the rule's label when the two coincide
                ax.annotate(label, (x, y), textcoords="offset points", xytext=(4, -9 if below else 3), fontsize=6.5, color="0.25")
        ax.axvline(floor, color="0.4", ls="--", lw=0.8)
        ax.text(floor, 0.02, " unshadowed", transform=ax.get_xaxis_transform(), fontsize=6.5, color="0.4", va="bottom")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{technique} (vs {t_rows[0]['reference_kind'].replace('_', ' ')})", fontsize=9)
        ax.set_xlabel(f"frame time, ms ({method}, median; bars min-max)", fontsize=7.5)
        ax.set_ylabel("mean |visibility error|", fontsize=7.5)
        ax.tick_params(which="both", labelsize=7)
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
        if len(variants) > 1:
            ax.legend(fontsize=6.5, loc="upper right")
    for ax in list(axes.flat)[len(techniques):]:
        ax.set_visible(False)
    w, h = rows[0]["width_px"], rows[0]["height_px"]
    fig.suptitle(f"penumbra-bench: {scene}, {w}x{h}; filled = Pareto front of its variant", fontsize=10)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{out_dir}/pareto-{safe_name(scene)}.{ext}", dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    rows = read_rows(sys.argv[1])
    for scene in OrderedDict.fromkeys(r["scene"] for r in rows):
        plot_scene(scene, [r for r in rows if r["scene"] == scene], sys.argv[2])


if __name__ == "__main__":
    main()
