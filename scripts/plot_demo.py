#!/usr/bin/python3
"""Bar chart of penumbra-demo's report.json: median frame time (with p10-p90 whiskers) of the
fixed and the adaptive resolution per technique, annotated with the speedup, the adaptive
resolution range and the worst SSIM. Usage: plot_demo.py REPORT.json OUTDIR (writes demo.png/.svg)."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_demo.py REPORT.json OUTDIR")
    with open(sys.argv[1]) as f:
        report = json.load(f)
    techniques = report.get("techniques", [])
    if not techniques:
        sys.exit(f"{sys.argv[1]}: techniques: empty")
    fig, ax = plt.subplots(figsize=(1.8 + 1.9 * len(techniques), 4.2))
    width = 0.38
    for i, t in enumerate(techniques):
        for j, (key, colour) in enumerate((("fixed", "#8c8c8c"), ("adaptive", "#2b7bba"))):
            ms = t[key]["frame_ms"]
            x = i + (j - 0.5) * width
            ax.bar(x, ms["median"], width, color=colour, label=key if i == 0 else None)
            ax.errorbar(x, ms["median"], yerr=[[ms["median"] - ms["p10"]], [ms["p90"] - ms["median"]]], color="black", capsize=3)
        res = t["adaptive"]["resolution_texels"]
        top = max(t["fixed"]["frame_ms"]["p90"], t["adaptive"]["frame_ms"]["p90"])
        ax.annotate(f"{t['speedup_median']:.2f}x\n{res['min']:.0f}-{res['max']:.0f}$^2$ vs {t['fixed']['resolution_texels']}$^2$\n"
                    f"SSIM >= {t['image']['ssim_min']:.4f}", (i, top), textcoords="offset points", xytext=(0, 6),
                    ha="center", fontsize=8)
    ax.set_xticks(range(len(techniques)), [t["technique"] for t in techniques])
    ax.set_ylabel(f"frame time, ms ({report.get('frame_time_method', '')})")
    w, h = report.get("image_px", [0, 0])
    ax.set_title(f"{report.get('scene', '')} {w}x{h}, {report.get('path_frames', 0)} path frames: median, p10-p90", fontsize=9)
    ax.margins(y=0.35)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{sys.argv[2]}/demo.{ext}", dpi=110)


if __name__ == "__main__":
    main()
