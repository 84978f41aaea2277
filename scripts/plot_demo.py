#!/usr/bin/python3
"""The figures of penumbra-demo's report.json: front.png first (frame time and memory against the
error to the reference for the engine family, its Pareto front and the adaptive rule at equal error),
then a bar chart: median frame time (with p10-p90 whiskers) of the
fixed and the adaptive resolution per technique, and of the engine baselines when the run has
them, annotated with the speedup over the fixed map, the adaptive cascades most frames had and the worst
SSIM; flicker along the path (flicker.png), error against the reference against frame time per
configuration (error.png) and the texels each configuration draws along the path (path.png).
Usage: plot_demo.py REPORT.json OUTDIR (writes front, demo, flicker, error and path .png/.svg)."""
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
    bars = max(2 + len(shown_baselines(t)) for t in techniques)
    fig, ax = plt.subplots(figsize=(1.8 + 0.95 * bars * len(techniques), 4.2))
    width = 0.76 / bars
    colours = ["#8c8c8c", "#2b7bba", "#d9a441", "#8e5ea2"]
    for i, t in enumerate(techniques):
        # fixed, adaptive, then the engine baselines (a larger single map, the cascades).
        series = [(f"fixed {t['fixed']['resolution_texels']}$^2$", t["fixed"]), ("adaptive", t["adaptive"])]
        series += [(b["name"], b) for b in shown_baselines(t)]
        for j, (label, row) in enumerate(series):
            ms = row["frame_ms"]
            x = i + (j - (len(series) - 1) / 2) * width
            ax.bar(x, ms["median"], width, color=colours[j % len(colours)], label=label if i == 0 else None)
            ax.errorbar(x, ms["median"], yerr=[[ms["median"] - ms["p10"]], [ms["p90"] - ms["median"]]], color="black", capsize=3)
        cascades = t["adaptive"]["cascades_most_frames"]  # every cascade, as most frames had them
        top = max(row["frame_ms"]["p90"] for _, row in series)
        note = f"{t['speedup_median']:.2f}x vs fixed\n{cascades}$^2$ vs {t['fixed']['resolution_texels']}$^2$\n"
        note += f"SSIM >= {t['image']['ssim_min']:.4f}"
        if "speedup_vs_engine_median" in t:
            note += f"\n{t['speedup_vs_engine_median']:.2f}x vs {t['engine_baseline']}"
        ax.annotate(note, (i, top), textcoords="offset points", xytext=(0, 6), ha="center", fontsize=8)
    ax.set_xticks(range(len(techniques)), [t["technique"] for t in techniques])
    ax.set_ylabel(f"frame time, ms ({report.get('frame_time_method', '')})")
    w, h = report.get("image_px", [0, 0])
    ax.set_title(f"{report.get('scene', '')} {w}x{h}, {report.get('path_frames', 0)} path frames: median, p10-p90", fontsize=9)
    ax.margins(y=0.35)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=4, fontsize=8)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{sys.argv[2]}/demo.{ext}", dpi=110)
    plot_front(report, techniques, sys.argv[2])
    plot_flicker(report, techniques, sys.argv[2])
    plot_error(report, techniques, sys.argv[2])
    plot_path(report, techniques, sys.argv[2])


MARKERS = ["o", "s", "^", "v", "D", "x", "P"]


def shown_baselines(t):
    """The engine configurations the bar chart and path.png show: the engine baseline and those on
    the time front (a sweep measures a dozen; the rest are in report.json and front.png)."""
    return [b for b in t.get("baselines", [])
            if b["name"] == t.get("engine_baseline") or b.get("on_front", {}).get("time") or len(t["baselines"]) <= 4]


def engine_points(t):
    """(name, error, ms, texels allocated) of the engine family: the fixed map and every baseline."""
    rows = [(f"fixed-{t['fixed']['resolution_texels']}", t["fixed"])] + [(b["name"], b) for b in t.get("baselines", [])]
    return [(name, row["reference_error"]["rmse_mean"], row["frame_ms"]["median"], row["texels_allocated"])
            for name, row in rows if row.get("reference_error")]


def plot_front(report, techniques, outdir):
    """front.png, the first figure: per technique, frame time and memory against the error to the
    reference, every engine configuration (grey), the Pareto front through the undominated ones,
    and the adaptive rule with the engine's cost at its error (the headline's ratios)."""
    with_front = [t for t in techniques if "headline" in t.get("equal_error", {})]
    if not with_front:
        return
    fig, axes = plt.subplots(len(with_front), 2, figsize=(10.5, 3.9 * len(with_front)), squeeze=False)
    for row_axes, t in zip(axes, with_front):
        eq = t["equal_error"]
        points = {name: (err, ms, tex) for name, err, ms, tex in engine_points(t)}
        adaptive_err = eq["adaptive_error"]
        adaptive = t["adaptive"]
        for ax, key, cost_index, adaptive_cost, unit, label in (
                (row_axes[0], "time", 1, adaptive["frame_ms"]["median"], "ms", "frame time, ms (median over the path)"),
                (row_axes[1], "memory", 2, adaptive["texels_allocated"] / 1e6, "texels", "Mtexels allocated")):
            scale = 1.0 if key == "time" else 1e-6
            front = eq[key]["front"]
            for name, p in points.items():
                on = name in front
                ax.plot(p[0], p[cost_index] * scale, "o", color="#444444" if on else "#bbbbbb", ms=6 if on else 5)
                ax.annotate(name.replace("-cascades", "c").replace("fixed-", ""), (p[0], p[cost_index] * scale), fontsize=6,
                            xytext=(4, 3), textcoords="offset points", color="#444444" if on else "#999999")
            fx = [points[n][0] for n in front]
            fy = [points[n][cost_index] * scale for n in front]
            ax.plot(fx, fy, "-", color="#444444", lw=1.2, label="engine Pareto front")
            ratio = eq[key]["ratio"]
            at = eq[key][f"front_{unit}"] * scale
            ax.plot([adaptive_err, adaptive_err], [adaptive_cost, at], ":", color="#2b7bba", lw=1.2)
            ax.plot(adaptive_err, at, "x", color="#444444", ms=7, label="engine at equal error")
            bound = {"more_accurate_than_front": ">= ", "less_accurate_than_front": "<= "}.get(eq[key]["position"], "")
            ax.plot(adaptive_err, adaptive_cost, "*", color="#2b7bba", ms=13,
                    label=f"adaptive: {bound}{ratio['median']:.2f}x [{ratio['ci95'][0]:.2f}, {ratio['ci95'][1]:.2f}]"
                          f" {'speedup' if key == 'time' else 'memory ratio'}")
            ax.set_xlabel("visibility RMSE against the reference (mean over the reference frames)", fontsize=8)
            ax.set_ylabel(label, fontsize=8)
            ax.set_yscale("log")
            ax.set_title(f"{t['technique']}: {'time' if key == 'time' else 'memory'} against error", fontsize=9)
            ax.legend(fontsize=7, loc="upper right")
    w, h = report.get("image_px", [0, 0])
    fig.suptitle(f"{report.get('scene', '')} {w}x{h}, {report.get('path_frames', 0)} path frames, engine family "
                 f"{report.get('engine_family', '')}: adaptive against the engine front at equal error (lower left is better)",
                 fontsize=9)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{outdir}/front.{ext}", dpi=110)


def consecutive_pairs(report):
    """The path frames t whose frame t - 1 was visited just before: where flicker is measured, one
    value per pair, in order. A short path's stations are separate runs of such frames."""
    frames = report.get("path_frame_index", [])
    return [frames[j] for j in range(1, len(frames)) if frames[j] == frames[j - 1] + 1]


def plot_flicker(report, techniques, outdir):
    """flicker.png: mean |visibility change| at reprojected pixels from frame t - 1 to t, per
    configuration, one line per run of consecutive frames (a short path's stations are not joined).
    The world-fixed map of the tables is left out: on the outdoor town it lies above the cascades,
    so it bounds nothing there."""
    with_flicker = [t for t in techniques if any(f["mean_abs_per_frame"] for f in t.get("flicker", []))]
    if not with_flicker:
        return
    pairs = consecutive_pairs(report)
    fig, axes = plt.subplots(1, len(with_flicker), figsize=(5.6 * len(with_flicker), 3.8), squeeze=False)
    for ax, t in zip(axes[0], with_flicker):
        shown = {"adaptive", "adaptive, no hysteresis", f"fixed-{t['fixed']['resolution_texels']}"}
        shown |= {b["name"] for b in shown_baselines(t)}
        for k, f in enumerate(c for c in t["flicker"] if c["configuration"] in shown):
            ys = f["mean_abs_per_frame"]
            xs = pairs if len(pairs) == len(ys) else list(range(1, len(ys) + 1))
            # NaN between runs, so that a line never joins two stations.
            px, py = [], []
            for i, (x, y) in enumerate(zip(xs, ys)):
                if i > 0 and x != xs[i - 1] + 1:
                    px.append(float("nan"))
                    py.append(float("nan"))
                px.append(x)
                py.append(y)
            ax.plot(px, py, "-", marker=MARKERS[k % len(MARKERS)], ms=4, alpha=0.85, lw=max(1.6 - 0.15 * k, 0.6),
                    label=f"{f['configuration']} ({f['resolution_changes']} res. changes)")
        ax.set_title(t["technique"], fontsize=9)
        ax.set_xlabel("path frame t (pair t - 1, t)" if len(pairs) else "consecutive frame pair")
        ax.set_ylabel("mean |V(t) - V(t-1)|, reprojected")
        ax.legend(fontsize=7)
    fig.suptitle(f"{report.get('scene', '')}: flicker along the path", fontsize=9)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{outdir}/flicker.{ext}", dpi=110)


def configurations(t):
    """(name, measured row) of every configuration in the tables: adaptive, fixed, the baselines."""
    rows = [("adaptive", t["adaptive"]), (f"fixed-{t['fixed']['resolution_texels']}", t["fixed"])]
    return rows + [(b["name"], b) for b in t.get("baselines", [])]


def plot_error(report, techniques, outdir):
    """error.png: RMSE of the visibility against the technique's reference against median frame
    time, one point per configuration (lower left is better)."""
    with_error = [t for t in techniques if any(row.get("reference_error") for _, row in configurations(t))]
    if not with_error:
        return
    fig, axes = plt.subplots(1, len(with_error), figsize=(5.2 * len(with_error), 3.8), squeeze=False)
    colours = ["#2b7bba", "#8c8c8c", "#d9a441", "#8e5ea2"]
    for ax, t in zip(axes[0], with_error):
        for j, (name, row) in enumerate(configurations(t)):
            err = row.get("reference_error")
            if not err:
                continue
            ms = row["frame_ms"]
            per_frame = err.get("rmse_per_frame", [err["rmse_mean"]])
            # Vertical bar: the smallest and largest RMSE over the reference frames.
            yerr = [[err["rmse_mean"] - min(per_frame)], [max(per_frame) - err["rmse_mean"]]]
            ax.errorbar(ms["median"], err["rmse_mean"], xerr=[[ms["median"] - ms["p10"]], [ms["p90"] - ms["median"]]],
                        yerr=yerr, fmt=MARKERS[j % len(MARKERS)], color=colours[j % len(colours)], capsize=3,
                        label=f"{name}: {row['texels_rendered']['median'] / 1e6:.1f} Mtexels")
        ax.set_xlabel(f"frame time, ms ({report.get('frame_time_method', '')}; median, p10-p90)")
        ax.set_ylabel("visibility RMSE vs reference\n(mean; bar: min-max over the frames)", fontsize=8)
        ax.set_ylim(bottom=0)
        ax.set_title(t["technique"], fontsize=9)
        ax.legend(fontsize=6, loc="best", framealpha=0.85,
                  title=f"reference: {t.get('reference', {}).get('description', '')[:60]}", title_fontsize=5)
    fig.suptitle(f"{report.get('scene', '')}: error against the reference at {with_error[0].get('reference', {}).get('frames', 0)}"
                 " frames against frame time", fontsize=9)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{outdir}/error.{ext}", dpi=110)


def plot_path(report, techniques, outdir):
    """path.png: texels drawn per frame along the path by every configuration (the adaptive rule
    with and without hysteresis follows the view; the fixed maps and cascades stay put)."""
    frames = report.get("path_frame_index", [])
    with_path = [t for t in techniques if t.get("along_path")]
    if not with_path or len(frames) < 2:
        return
    fig, axes = plt.subplots(1, len(with_path), figsize=(5.6 * len(with_path), 3.8), squeeze=False)
    for ax, t in zip(axes[0], with_path):
        shown = {"adaptive", "adaptive, no hysteresis", f"fixed-{t['fixed']['resolution_texels']}"}
        shown |= {b["name"] for b in shown_baselines(t)}
        rows = [row for row in t["along_path"] if row["configuration"] in shown]
        for k, row in enumerate(rows):
            style = "--" if "no hysteresis" in row["configuration"] else "-"
            # Distinct markers and thinning lines: equal series (4096² and 4 × 2048² both draw
            # 16.8 Mtexels) stay visible one over the other.
            ax.plot(frames, [v / 1e6 for v in row["texels"]], style, marker=MARKERS[k % len(MARKERS)], ms=max(7 - k, 3), alpha=0.8,
                    lw=max(2.2 - 0.25 * k, 0.6), label=row["configuration"])
        ax.set_yscale("log")
        if report.get("path") == "short":
            ax.set_xlabel(f"path frame\n({len(frames)} frames: stations of consecutive frames along the "
                          f"{report.get('path_length', len(frames))}-frame path)", fontsize=8)
        else:
            ax.set_xlabel(f"frame of the {report.get('path_length', len(frames))}-frame {report.get('path', '')} path")
        ax.set_ylabel("Mtexels drawn per frame")
        ax.set_title(t["technique"], fontsize=9)
        ax.legend(fontsize=7)
    fig.suptitle(f"{report.get('scene', '')}: shadow-map texels along the path", fontsize=9)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{outdir}/path.{ext}", dpi=110)


if __name__ == "__main__":
    main()
