#!/usr/bin/python3
"""The figures of penumbra-demo's report.json, the equal-error comparison first:
front.png   per technique, frame time and memory against the error to the reference: the engine
            family, its Pareto front, and the adaptive rule and every virtual shadow map read
            against the front at their own error (the headline's second line, at equal RMSE);
front-flip.png  the same with the perceived difference as the error: LDR-FLIP's mean of the lit
            frames against the reference (PCSS: against PCSS at converged resolution and taps),
            the headline's first line;
demo.png    median frame time (p10-p90 whiskers) per configuration, each bar labelled with its
            error, under the equal-error ratios (the ratio against the fixed map alone compares
            images of different error, so it is not the headline);
error.png   error against frame time, one point per configuration;
flicker.png the mean frame-to-frame change of every configuration, and along the path for the
            few that answer the question (named in the figure);
path.png    the texels each configuration draws along the path.
Every figure draws a configuration in the same colour and marker (style()).
Usage: plot_demo.py REPORT.json OUTDIR (writes front, front-flip, demo, flicker, error and path .png/.svg)."""
import json
import math
import re
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

# The configurations whose name says nothing of a map size (apps/demo/configurations.cpp): the
# rule in red, the virtual maps in greens (the rule's) and pink (the footprint's); the engine
# family below, blues and greys.
NAMED_STYLES = {
    "adaptive": ("#d62728", "*"),
    "adaptive, no hysteresis": ("#ff9896", "*"),
    "virtual rule": ("#74c476", "P"),
    "virtual rule, cached": ("#006d2c", "P"),
    "virtual footprint": ("#e377c2", "X"),
    "floor (world-fixed map)": ("#000000", "."),
}
# The engine family by cascade count: a colour map and a marker each; the shade darkens with the
# map size (1024² light, 8192² dark), so that a sweep's dozen points stay apart.
CASCADE_STYLES = {1: ("Blues", "o"), 2: ("Oranges", "s"), 3: ("Greys", "^"), 4: ("Purples", "D")}


def style(name):
    """(colour as #rrggbb, marker) of the configuration `name`, the same in every figure and run."""
    if name in NAMED_STYLES:
        return NAMED_STYLES[name]
    m = re.fullmatch(r"fixed-(\d+)", name) or re.fullmatch(r"(\d+)x(\d+)-cascades", name)
    if not m:
        return ("#7f7f7f", "v")  # a configuration this script does not know yet: grey, never missing
    cascades, texels = (1, int(m[1])) if name.startswith("fixed-") else (int(m[1]), int(m[2]))
    cmap, marker = CASCADE_STYLES.get(min(cascades, 4), CASCADE_STYLES[4])
    shade = 0.35 + 0.65 * min(max(math.log2(max(texels, 1) / 1024) / 3, 0.0), 1.0)
    return (matplotlib.colors.to_hex(matplotlib.colormaps[cmap](shade)), marker)


def colour(name):
    return style(name)[0]


def tag(artists, name):
    """Marks what was drawn for configuration `name` (a test reads the colours back)."""
    for a in artists if isinstance(artists, (list, tuple)) else [artists]:
        a.configuration = name
    return artists


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_demo.py REPORT.json OUTDIR")
    with open(sys.argv[1]) as f:
        report = json.load(f)
    if not report.get("techniques"):
        sys.exit(f"{sys.argv[1]}: techniques: empty")
    for name, fig in figures(report).items():
        for ext in ("png", "svg"):
            # tight: the legends outside the axes are part of the figure.
            fig.savefig(f"{sys.argv[2]}/{name}.{ext}", dpi=110, bbox_inches="tight")
        plt.close(fig)


def figures(report):
    """{file stem: figure} of every figure the report has data for, front first."""
    techniques = report["techniques"]
    out = {}
    for name, plot in (("front", plot_front), ("front-flip", plot_front_flip), ("demo", plot_demo), ("error", plot_error),
                       ("flicker", plot_flicker), ("path", plot_path)):
        fig = plot(report, techniques)
        if fig is not None:
            out[name] = fig
    return out


def run_line(report):
    w, h = report.get("image_px", [0, 0])
    return f"{report.get('scene', '')} {w}x{h}, {report.get('path_frames', 0)} path frames"


def fixed_name(t):
    return f"fixed-{t['fixed']['resolution_texels']}"


def shown_baselines(t):
    """The engine configurations the bar chart and path.png show: the engine baseline and those on
    the time front (a sweep measures a dozen; the rest are in report.json and front.png)."""
    return [b for b in t.get("baselines", [])
            if b["name"] == t.get("engine_baseline") or b.get("on_front", {}).get("time") or len(t["baselines"]) <= 4]


def configurations(t):
    """(name, measured row) of every configuration in the tables: adaptive, fixed, the baselines,
    the virtual maps."""
    rows = [("adaptive", t["adaptive"]), (fixed_name(t), t["fixed"])]
    return rows + [(b["name"], b) for b in t.get("baselines", [])] + [(v["name"], v) for v in t.get("virtual", [])]


def rmse(row):
    err = row.get("reference_error")
    return err["rmse_mean"] if err else None


def flip_mean(row):
    flip = row.get("flip")
    return flip["mean"] if flip else None


# The two error axes of the front: (report.json's reading, the virtual map's reading, a row's
# error, the axis label ({}: what FLIP was taken against), what the title calls it).
MEASURES = {
    "rmse": ("equal_error", "equal_error", rmse, "visibility RMSE against the reference (mean over the reference frames)", "error"),
    "flip": ("equal_flip", "equal_flip", flip_mean,
             "FLIP of the lit frames against {} (mean over the reference frames)",
             "perceived difference (FLIP)"),
}


def ratio_text(reading, what):
    """'1.18x [1.13, 1.36] speedup', with >= / <= where the error lies beyond the front's ends."""
    bound = {"more_accurate_than_front": ">= ", "less_accurate_than_front": "<= "}.get(reading["position"], "")
    r = reading["ratio"]
    return f"{bound}{r['median']:.2f}x [{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}] {what}"


def equal_error_subjects(t, measure="rmse"):
    """(name, row, error, time reading, memory reading) of what is read against the front: the
    adaptive rule, then every virtual map that has a reading."""
    key, virtual_key = MEASURES[measure][:2]
    eq = t.get(key, {})
    if "headline" not in eq:
        return []
    out = [("adaptive", t["adaptive"], eq["adaptive_error"], eq["time"], eq["memory"])]
    for v in t.get("virtual", []):
        ve = v.get(virtual_key, {})
        if "time" in ve:
            out.append((v["name"], v, ve["error"], ve["time"], ve["memory"]))
    return out


def plot_front_flip(report, techniques):
    """front-flip.png: front.png with the perceived difference (FLIP mean) as the error."""
    return plot_front(report, techniques, "flip")


def plot_front(report, techniques, measure="rmse"):
    """front.png, the first figure: per technique, frame time and memory against the error to the
    reference; every engine configuration (filled where on the front), the front through them, and
    the adaptive rule and the virtual maps each with the engine's cost at its error."""
    reading_key, _, error_of, xlabel, called = MEASURES[measure]
    with_front = [t for t in techniques if equal_error_subjects(t, measure)]
    if not with_front:
        return None
    fig, axes = plt.subplots(len(with_front), 2, figsize=(12, 6.2 * len(with_front)), squeeze=False)
    for row_axes, t in zip(axes, with_front):
        eq = t[reading_key]
        engine = [(fixed_name(t), t["fixed"])] + [(b["name"], b) for b in t.get("baselines", [])]
        points = {name: (error_of(row), row["frame_ms"]["median"], row["texels_allocated"] / 1e6) for name, row in engine
                  if error_of(row) is not None}
        for ax, key, cost_index, unit, label in (
                (row_axes[0], "time", 1, "ms", "frame time, ms (median over the path)"),
                (row_axes[1], "memory", 2, "texels", "shadow-map memory, Mtexels allocated (mean over the path)")):
            front = eq[key]["front"]
            for name, p in points.items():
                c, marker = style(name)
                on = name in front
                tag(ax.plot(p[0], p[cost_index], marker, color=c, mec="#333333" if on else c, mfc=c if on else "none", ms=7), name)
                ax.annotate(name.replace("-cascades", "c").replace("fixed-", ""), (p[0], p[cost_index]), fontsize=6,
                            xytext=(4, 3), textcoords="offset points", color="#333333" if on else "#999999")
            ax.plot([points[n][0] for n in front], [points[n][cost_index] for n in front], "-", color="#555555", lw=1.2,
                    zorder=1, label="engine Pareto front (filled: on it)")
            for name, row, err, time, memory in equal_error_subjects(t, measure):
                reading = time if key == "time" else memory
                cost = row["frame_ms"]["median"] if key == "time" else row["texels_allocated"] / 1e6
                at = reading[f"front_{unit}"] * (1.0 if key == "time" else 1e-6)
                c, marker = style(name)
                ax.plot([err, err], [cost, at], ":", color=c, lw=1.2)
                tag(ax.plot(err, at, "x", color=c, ms=7), name)
                tag(ax.plot(err, cost, marker, color=c, mec="black", mew=0.6, ms=14 if name == "adaptive" else 11,
                            label=f"{name}: {ratio_text(reading, 'speedup' if key == 'time' else 'memory ratio')}"), name)
            ax.plot([], [], "x", color="#555555", label="x: the front at the same error")
            ax.set_xlabel(xlabel.format("converged PCSS" if "converged" in t.get("perceptual", {}).get("target", "") else "the reference"),
                          fontsize=8)
            ax.set_ylabel(label, fontsize=8)
            ax.set_yscale("log")
            ax.set_title(f"{t['technique']}: {'frame time' if key == 'time' else 'memory'} against error; "
                         f"ratio = the front's {'time' if key == 'time' else 'memory'} at equal error / the configuration's",
                         fontsize=8)
            ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    fig.suptitle(f"{run_line(report)}, engine family {report.get('engine_family', '')}:\nthe adaptive rule and the virtual "
                 f"shadow maps against the engine's Pareto front at equal {called} (lower left is better; > 1x favours them)",
                 fontsize=9)
    fig.tight_layout()
    return fig


def plot_demo(report, techniques):
    """demo.png: median frame time (p10-p90) of every configuration measured against the engine,
    each bar labelled with its RMSE against the reference; above each technique the equal-error
    ratios (front.png's), and the fixed map's ratio only with both errors beside it."""
    # The same bars in the same order for every technique: the baselines any technique shows.
    shown = {b["name"] for t in techniques for b in shown_baselines(t)}
    per_technique = []
    for t in techniques:
        rows = [(fixed_name(t), t["fixed"]), ("adaptive", t["adaptive"])]
        rows += [(b["name"], b) for b in t.get("baselines", []) if b["name"] in shown] + [(v["name"], v) for v in t.get("virtual", [])]
        per_technique.append(rows)
    bars = max(len(rows) for rows in per_technique)
    fig, ax = plt.subplots(figsize=(max(7.5, 1.6 + 0.62 * bars * len(techniques)), 5.2))
    width = 0.8 / bars
    seen = set()
    for i, (t, rows) in enumerate(zip(techniques, per_technique)):
        for j, (name, row) in enumerate(rows):
            ms = row["frame_ms"]
            x = i + (j - (len(rows) - 1) / 2) * width
            tag(list(ax.bar(x, ms["median"], width * 0.92, color=colour(name), label=name if name not in seen else None)), name)
            seen.add(name)
            ax.errorbar(x, ms["median"], yerr=[[ms["median"] - ms["p10"]], [ms["p90"] - ms["median"]]], color="black", capsize=2, lw=0.8)
            err = rmse(row)
            if err is not None:
                ax.annotate(f"{err:.3f}", (x, ms["p90"]), textcoords="offset points", xytext=(0, 2), ha="center", va="bottom",
                            fontsize=6, rotation=90)
        top = max(row["frame_ms"]["p90"] for _, row in rows)
        subjects = equal_error_subjects(t)
        if subjects:
            lines = [f"{name}: {ratio_text(time, 'speedup')}, {ratio_text(memory, 'memory')}"
                     for name, _, _, time, memory in subjects]
            lines.insert(0, "at equal error against the engine front:")
        else:
            lines = [f"no equal-error reading: {t.get('equal_error', {}).get('unavailable', 'no engine front')}"]
        fixed_err, adaptive_err = rmse(t["fixed"]), rmse(t["adaptive"])
        errors = f" (RMSE {fixed_err:.3f} vs {adaptive_err:.3f})" if fixed_err is not None and adaptive_err is not None else ""
        lines.append(f"fixed {t['fixed']['resolution_texels']}$^2$ / adaptive: {t['speedup_median']:.2f}x{errors}; "
                     f"adaptive {t['adaptive']['cascades_most_frames']}$^2$ most frames")
        ax.annotate("\n".join(lines), (i, top), textcoords="offset points", xytext=(0, 30), ha="center", va="bottom", fontsize=7)
    ax.set_xticks(range(len(techniques)), [t["technique"] for t in techniques])
    ax.set_ylabel(f"frame time, ms ({report.get('frame_time_method', '')}; median, p10-p90)")
    ax.set_title(f"{run_line(report)}: frame time per configuration; above each bar its visibility RMSE against the reference",
                 fontsize=9)
    ax.set_ylim(0, ax.get_ylim()[1] * 1.7)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0)
    fig.tight_layout()
    return fig


def consecutive_pairs(report):
    """The path frames t whose frame t - 1 was visited just before: where flicker is measured, one
    value per pair, in order. A short path's stations are separate runs of such frames."""
    frames = report.get("path_frame_index", [])
    return [frames[j] for j in range(1, len(frames)) if frames[j] == frames[j - 1] + 1]


def station_positions(frames):
    """x of each path frame: consecutive frames one apart, a station's first frame two after the
    last one's (a short path's stations, 120 frames apart, would otherwise squeeze each to a dot)."""
    xs = []
    for i, f in enumerate(frames):
        xs.append(0 if i == 0 else xs[-1] + (1 if f == frames[i - 1] + 1 else 2))
    return xs


def station_series(frames, values):
    """(x, y) over station_positions(frames), NaN between stations so that no line joins two."""
    xs, px, py = station_positions(frames), [], []
    for i, (x, v) in enumerate(zip(xs, values)):
        if i > 0 and frames[i] != frames[i - 1] + 1:
            px.append(float("nan"))
            py.append(float("nan"))
        px.append(x)
        py.append(v)
    return px, py


def station_ticks(ax, frames):
    """Ticks at station_positions(frames), labelled with the path frame (at most ~16 of them)."""
    xs = station_positions(frames)
    step = max(1, math.ceil(len(xs) / 16))
    ax.set_xticks(xs[::step], [str(f) for f in frames[::step]], fontsize=7)


def flicker_shown(t):
    """The configurations flicker.png follows along the path: the rule with and without hysteresis
    (does the hysteresis hold the map still?), the fixed map, the engine baseline, and the cached
    virtual map (the strongest reading at equal error)."""
    return ["adaptive", "adaptive, no hysteresis", fixed_name(t), t.get("engine_baseline", ""), "virtual rule, cached"]


def plot_flicker(report, techniques):
    """flicker.png: mean |visibility change| at reprojected pixels from frame t - 1 to t. Left, its
    mean over the path for every configuration; right, along the path for flicker_shown(), one line
    per run of consecutive frames (a short path's stations are not joined). The world-fixed map is
    left out: on the outdoor town it lies above the cascades, so it bounds nothing there."""
    with_flicker = [t for t in techniques if any(f["mean_abs_per_frame"] for f in t.get("flicker", []))]
    if not with_flicker:
        return None
    pairs = consecutive_pairs(report)
    fig, axes = plt.subplots(len(with_flicker), 2, figsize=(12, 3.9 * len(with_flicker)), squeeze=False,
                             gridspec_kw={"width_ratios": [1, 1.5]})
    for (bar_ax, ax), t in zip(axes, with_flicker):
        rows = [f for f in t["flicker"] if f["mean_abs_per_frame"] and not f["configuration"].startswith("floor")]
        names = [f["configuration"] for f in rows]
        y = list(range(len(rows)))[::-1]
        for bar, n in zip(bar_ax.barh(y, [f["mean_abs_mean"] for f in rows], color=[colour(n) for n in names]), names):
            tag(bar, n)
        for yy, f in zip(y, rows):
            bar_ax.annotate(f" {f['resolution_changes']}", (f["mean_abs_mean"], yy), va="center", fontsize=6)
        bar_ax.set_yticks(y, names, fontsize=7)
        bar_ax.set_xlabel("mean |V(t) - V(t-1)| over the path, reprojected\n(beside each bar: resolution changes)", fontsize=8)
        bar_ax.set_title(f"{t['technique']}: every configuration", fontsize=9)
        bar_ax.margins(x=0.15)
        shown = flicker_shown(t)
        for f in sorted((f for f in rows if f["configuration"] in shown), key=lambda f: shown.index(f["configuration"])):
            ys = f["mean_abs_per_frame"]
            px, py = station_series(pairs if len(pairs) == len(ys) else list(range(1, len(ys) + 1)), ys)
            name = f["configuration"]
            c, marker = style(name)
            # The first of flicker_shown() on top: the rule is not hidden under the lines it is compared with.
            tag(ax.plot(px, py, "--" if "no hysteresis" in name else "-", marker=marker, color=c, ms=5, lw=1.4, alpha=0.9,
                        zorder=3 + len(shown) - shown.index(name), label=f"{name} ({f['resolution_changes']} res. changes)"), name)
        ax.set_title(f"{t['technique']}: along the path, the rule with and without hysteresis against "
                     f"{fixed_name(t)}, {t.get('engine_baseline', '')} and the cached virtual map", fontsize=8)
        station_ticks(ax, pairs if pairs else list(range(1, len(rows[0]["mean_abs_per_frame"]) + 1)))
        ax.set_xlabel("path frame t (pair t - 1, t); a gap between stations" if len(pairs) else "consecutive frame pair", fontsize=8)
        ax.set_ylabel("mean |V(t) - V(t-1)|, reprojected", fontsize=8)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.suptitle(f"{run_line(report)}: flicker, the visibility's change from frame to frame where the surface stays in view",
                 fontsize=9)
    fig.tight_layout()
    return fig


def plot_error(report, techniques):
    """error.png: RMSE of the visibility against the technique's reference against median frame
    time, one point per configuration (lower left is better)."""
    with_error = [t for t in techniques if any(rmse(row) is not None for _, row in configurations(t))]
    if not with_error:
        return None
    fig, axes = plt.subplots(1, len(with_error), figsize=(6.4 * len(with_error), 4.4), squeeze=False)
    for ax, t in zip(axes[0], with_error):
        for name, row in configurations(t):
            err = row.get("reference_error")
            if not err:
                continue
            ms = row["frame_ms"]
            per_frame = err.get("rmse_per_frame", [err["rmse_mean"]])
            c, marker = style(name)
            # Vertical bar: the smallest and largest RMSE over the reference frames.
            lines = ax.errorbar(ms["median"], err["rmse_mean"], xerr=[[ms["median"] - ms["p10"]], [ms["p90"] - ms["median"]]],
                                yerr=[[err["rmse_mean"] - min(per_frame)], [max(per_frame) - err["rmse_mean"]]], fmt=marker,
                                color=c, ms=9 if name == "adaptive" else 6, capsize=2, lw=0.8,
                                label=f"{name}: {row['texels_rendered']['median'] / 1e6:.1f} Mtexels drawn")
            tag(lines[0], name)
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1, 2, 5)))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel(f"frame time, ms ({report.get('frame_time_method', '')}; median, p10-p90)", fontsize=8)
        ax.set_ylabel("visibility RMSE against the reference\n(mean; bar: min-max over the frames)", fontsize=8)
        reference = textwrap.fill(f"reference: {t.get('reference', {}).get('description', '')}", 80)
        ax.set_title(f"{t['technique']}: error against frame time per configuration\n{reference}", fontsize=7)
        ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.suptitle(f"{run_line(report)}: error against the reference (at {with_error[0].get('reference', {}).get('frames', 0)}"
                 " reference frames) against frame time (lower left is better)", fontsize=9)
    fig.tight_layout()
    return fig


def plot_path(report, techniques):
    """path.png: texels drawn per frame along the path (the adaptive rule with and without
    hysteresis follows the view; the fixed maps and cascades stay put; a virtual map draws its
    marked pages, the cached one only those it did not keep)."""
    frames = report.get("path_frame_index", [])
    with_path = [t for t in techniques if t.get("along_path")]
    if not with_path or len(frames) < 2:
        return None
    fig, axes = plt.subplots(1, len(with_path), figsize=(6.4 * len(with_path), 4.2), squeeze=False)
    for ax, t in zip(axes[0], with_path):
        shown = {"adaptive", "adaptive, no hysteresis", fixed_name(t), "virtual rule", "virtual rule, cached"}
        shown |= {b["name"] for b in shown_baselines(t)}
        rows = [row for row in t["along_path"] if row["configuration"] in shown]
        for k, row in enumerate(rows):
            name = row["configuration"]
            c, marker = style(name)
            # Thinning lines: equal series (4096² and 4 × 2048² both draw 16.8 Mtexels) stay
            # visible one over the other.
            px, py = station_series(frames, [max(v, 1) / 1e6 for v in row["texels"]])
            tag(ax.plot(px, py, "--" if "no hysteresis" in name else "-", marker=marker,
                        color=c, ms=max(7 - k * 0.5, 3), alpha=0.85, lw=max(2.2 - 0.2 * k, 0.6), label=name), name)
        ax.set_yscale("log")
        station_ticks(ax, frames)
        if report.get("path") == "short":
            ax.set_xlabel(f"path frame\n({len(frames)} frames: stations of consecutive frames along the "
                          f"{report.get('path_length', len(frames))}-frame path)", fontsize=8)
        else:
            ax.set_xlabel(f"frame of the {report.get('path_length', len(frames))}-frame {report.get('path', '')} path", fontsize=8)
        ax.set_ylabel("Mtexels drawn per frame (virtual: pages drawn)", fontsize=8)
        ax.set_title(f"{t['technique']}: shadow-map texels drawn along the path", fontsize=9)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.suptitle(f"{run_line(report)}: texels drawn per frame", fontsize=9)
    fig.tight_layout()
    return fig


if __name__ == "__main__":
    main()
