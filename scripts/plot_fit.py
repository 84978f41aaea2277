#!/usr/bin/python3
"""Figures and a tidy table of a penumbra-fit run (docs/fit.md), as PNG and SVG.

    /usr/bin/python3 scripts/plot_fit.py OUT [--units px|arcmin|deg] [--participants p01,p02]

reads OUT/report.json (and, for the visual angles, each input session's session.json) and writes
into OUT/plots/ (pixels) or OUT/plots/arcmin/, OUT/plots/deg/ (--units), so that figures in
different units sit side by side:
  thresholds.{png,svg}           threshold filter radius vs artifact size per condition: the
                                 per-size thresholds (Wald 95 %), every staircase's threshold, the
                                 fitted r = c a with its 95 % band, the published c = 3.47 and the
                                 reference filter size when the fit was given one; panels share
                                 their axes
  psychometric_<participant>.*   per staircase: binned proportion correct and the fitted curve
                                 against r / a (shared axes); each staircase's threshold with the
                                 slope and lapse of its condition (penumbra-fit holds them: a
                                 staircase's trials sit near its threshold and cannot tell a slope)
  quest_<participant>.*          per condition: the QUEST tracks (trial -> radius shown)
  thresholds.csv                 one row per participant x condition x artifact size (one
                                 staircase): participant, technique, pattern, contrast, artifact_px,
                                 threshold_px, threshold_arcmin, ci_low, ci_high (px, the
                                 staircase's Wald 95 %), trials
  summary.txt                    what the figures leave out: each condition's c, intervals, tests
                                 and flags, staircases flagged, the unit conversion used

--units converts radii and artifact sizes with each participant's display: penumbra-fit writes
their pixels per degree at the screen centre into report.json ("pixels_per_degree", computed by
Display::pixels_per_degree from session.json "display", as penumbra-study display-check does);
arcmin = px / ppd * 60. The fitted psychometric functions come sampled in report.json too
(each staircase's "curve"): this script computes no model, it draws.
"""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter  # noqa: E402

PUBLISHED_C = 3.47
UNIT_LABEL = {"px": "px", "arcmin": "arcmin", "deg": "deg"}
SIZE_COLORS = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown"]


def fail(message):
    sys.exit("plot_fit.py: " + message)


def session_geometry(report):
    """{participant: (pixels per degree, where it came from)}: penumbra-fit writes each participant's
    display conversion into report.json ("pixels_per_degree", from their session.json)."""
    out = {}
    for participant, ppd in report.get("pixels_per_degree", {}).items():
        if not isinstance(ppd, (int, float)) or not ppd > 0:
            fail("report.json: pixels_per_degree.%s: expected a positive number, got %r" % (participant, ppd))
        out[participant] = (float(ppd), "report.json")
    return out


class Units:
    """Radii and sizes in px, arcmin or deg, each participant with the display of its session."""

    def __init__(self, unit, geometry, participants):
        self.unit = unit
        self.geometry = geometry
        if unit != "px":
            missing = [p for p in participants if p not in geometry]
            if missing:
                fail("--units %s: report.json has no display (pixels_per_degree) for participant(s) %s: their "
                     "sessions had no session.json with the display" % (unit, ", ".join(missing)))

    def factor(self, participant):
        if self.unit == "px":
            return 1.0
        ppd = self.geometry[participant][0]
        return 60.0 / ppd if self.unit == "arcmin" else 1.0 / ppd

    def common_factor(self, participants):
        """One factor for figures that pool participants; refused when their displays differ."""
        factors = {p: self.factor(p) for p in participants}
        if len(set(round(f, 12) for f in factors.values())) > 1:
            fail("--units %s: the sessions' displays differ (%s); pooled figures need one geometry: use --units px"
                 % (self.unit, ", ".join("%s %.3f px/deg" % (p, self.geometry[p][0]) for p in sorted(factors))))
        return next(iter(factors.values())) if factors else 1.0

    def label(self):
        return UNIT_LABEL[self.unit]


def number_label(v, _pos=None):
    """Tick label of a log axis: 0.5, 2, 10, 200."""
    return "%g" % float("%.3g" % v)


def readable_log_axis(axis):
    """Log axis labelled at 1, 2 and 5 of every decade (plain numbers, no 10^k)."""
    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(number_label))
    axis.set_minor_locator(LogLocator(base=10, subs=(3.0, 4.0, 6.0, 7.0, 8.0, 9.0)))
    axis.set_minor_formatter(NullFormatter())


def save(fig, out_dir, name):
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(out_dir, name + "." + ext), dpi=130, bbox_inches="tight")
    plt.close(fig)


def grid(n):
    cols = min(n, 2)
    rows = (n + cols - 1) // cols
    return rows, cols


def condition_summary(cond):
    lines = ["%s: c = %.3f, 95 %% profile [%.3f, %.3f]" % (cond["condition"], cond["c"], cond["ci95_profile"]["lo"],
                                                           cond["ci95_profile"]["hi"])]
    p = cond.get("power_law")
    if p and p.get("exponent") is not None and p.get("exponent_se") is not None:
        lines.append("  power law r = k a^p: p = %.2f +- %.2f" % (p["exponent"], p["exponent_se"]))
    if cond.get("linearity") and cond["linearity"].get("p_value") is not None:
        lines.append("  linearity LR test p = %.3g" % cond["linearity"]["p_value"])
    beyond = ["%g" % size["artifact_px"] for size in cond["sizes"]
              if size.get("reference_filter_radius_px") is None and "reference_note" in size]
    if beyond:
        lines.append("  no reference r within the showable radii at a = " + ", ".join(beyond) + " px")
    lines.append("  flags: " + (", ".join(cond["flags"]) if cond["flags"] else "none"))
    return lines


def ordered_conditions(report):
    """Conditions by contrast (high first), then pattern: panels in the same place in every figure."""
    return sorted(report["conditions"], key=lambda c: (-c.get("contrast", 0), c.get("pattern", ""), c["condition"]))


def plot_thresholds(report, units, out_dir):
    conditions = ordered_conditions(report)
    participants = sorted({s["participant"] for s in report["staircases"]})
    k = units.common_factor(participants)
    unit = units.label()
    rows, cols = grid(len(conditions))
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 4.0 * rows), squeeze=False, sharex=True, sharey=True)
    a_max = max(max(cond["artifact_px"]) for cond in conditions) * 1.12 * k
    tops = []
    for ax, cond in zip(axes.flat, conditions):
        sizes = cond["artifact_px"]
        line_a = [0.0, a_max]
        c = cond["c"]
        ci = cond["ci95_profile"]
        ax.fill_between(line_a, [ci["lo"] * a for a in line_a], [ci["hi"] * a for a in line_a],
                        color="tab:blue", alpha=0.18, lw=0, label="95 % interval of c (profile)")
        ax.plot(line_a, [c * a for a in line_a], color="tab:blue", lw=1.8, label="fitted r = c a")
        ax.plot(line_a, [PUBLISHED_C * a for a in line_a], color="0.35", ls="--", lw=1.2,
                label="published r = %.2f a" % PUBLISHED_C)
        stairs = [s for s in report["staircases"] if s["condition"] == cond["condition"]]
        for s in stairs:
            jitter = ((participants.index(s["participant"]) % 7) - 3) * 0.05 * min(sizes)
            if s["r_threshold_px"] is not None:
                ax.plot((s["artifact_px"] + jitter) * k, s["r_threshold_px"] * k, "o", ms=3.5, color="0.55",
                        alpha=0.8, mec="none", label="staircase thresholds")
                tops.append(s["r_threshold_px"] * k)
        for size in cond["sizes"]:
            if size.get("r_threshold_px") is not None:
                lo, hi = size["r_threshold_wald_px"]
                r = size["r_threshold_px"]
                err = [[r - lo if lo is not None else 0], [hi - r if hi is not None else 0]]
                ax.errorbar(size["artifact_px"] * k, r * k, yerr=[[e * k for e in err[0]], [e * k for e in err[1]]],
                            fmt="s", color="k", ms=5, capsize=3, label="per-size threshold (Wald 95 %)")
                tops.append((hi if hi is not None else r) * k)
            ref = size.get("reference_filter_radius_px")
            if ref is not None:
                ax.plot(size["artifact_px"] * k, ref * k, "x", color="tab:red", ms=9, mew=2,
                        label="reference filter size")
                tops.append(ref * k)
        tops += [c * a_max, PUBLISHED_C * a_max]
        ax.set_title("%s: c = %.2f [%.2f, %.2f]\n%d trials, %d participant%s"
                     % (cond["condition"], c, ci["lo"], ci["hi"], cond["trials"], cond["participants"],
                        "" if cond["participants"] == 1 else "s"), fontsize=10)
        ax.grid(alpha=0.3)
        ax.set_xticks([a * k for a in sizes])
        ax.xaxis.set_major_formatter(FuncFormatter(number_label))
    for ax in list(axes.flat)[len(conditions):]:
        ax.axis("off")
    axes[0][0].set_xlim(0, a_max)
    axes[0][0].set_ylim(0, 1.05 * max(tops))
    for ax in axes[-1]:
        ax.set_xlabel("artifact size a (%s)" % unit)
        ax.xaxis.set_tick_params(labelbottom=True)
    for row in axes:
        row[0].set_ylabel("threshold filter radius r (%s)" % unit)
    # One legend for every panel, below them (never over the data).
    handles = {}
    for ax in axes.flat:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    fig.legend(list(handles.values()), list(handles.keys()), loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=3, fontsize=8, frameon=False)
    fig.tight_layout()
    save(fig, out_dir, "thresholds")


def binned(track, bins=6):
    """(mean ratio r/a, proportion correct, n) over equal-count bins of intensity."""
    points = sorted((t[1], t[3]) for t in track)
    out = []
    per = max(1, int(math.ceil(len(points) / bins)))
    for i in range(0, len(points), per):
        chunk = points[i:i + per]
        u = sum(p[0] for p in chunk) / len(chunk)
        out.append((10.0 ** -u, sum(p[1] for p in chunk) / len(chunk), len(chunk)))
    return out


def staircase_grid(report, participant):
    stairs = [s for s in report["staircases"] if s["participant"] == participant]
    # The report's condition order for every participant (not each one's run order), so figures compare.
    order = [c["condition"] for c in ordered_conditions(report)]
    conditions = sorted({s["condition"] for s in stairs}, key=lambda c: order.index(c) if c in order else len(order))
    sizes = sorted({s["artifact_px"] for s in stairs})
    return stairs, conditions, sizes


def plot_psychometric(report, participant, units, out_dir):
    stairs, conditions, sizes = staircase_grid(report, participant)
    k = units.factor(participant)
    fig, axes = plt.subplots(len(conditions), len(sizes), figsize=(3.0 * len(sizes), 2.4 * len(conditions)),
                             squeeze=False, sharex=True, sharey=True)
    ratios = [10.0 ** -t[1] for s in stairs for t in s["track"]]
    lo_ratio, hi_ratio = min(ratios) / 1.4, max(ratios) * 1.4
    for s in stairs:
        ax = axes[conditions.index(s["condition"])][sizes.index(s["artifact_px"])]
        f = s["fit"]
        ax.plot(s["curve"]["r_over_a"], s["curve"]["p_correct"], color="tab:blue", label="fitted psychometric function")
        for ratio, p, n in binned(s["track"]):
            ax.plot(ratio, p, "o", color="k", ms=3 + 1.0 * n, alpha=0.55, mec="none",
                    label="proportion correct (bins of equal count; size: trials)")
        if s["c"] is not None:
            ax.axvline(s["c"], color="tab:blue", ls=":", lw=1, label="threshold c = r / a")
        ax.axhline(f["guess"], color="0.7", lw=0.8, label="guess rate")
        title = "%s, a = %s %s: c = %.2f" % (s["condition"], number_label(s["artifact_px"] * k), units.label(), s["c"])
        if not s["converged"]:
            title += "*"
        ax.set_title(title, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes.flat:
        ax.set_xscale("log")
        readable_log_axis(ax.xaxis)
        ax.grid(alpha=0.25, which="major")
    axes[0][0].set_xlim(lo_ratio, hi_ratio)
    axes[0][0].set_ylim(0.35, 1.03)
    for ax in axes[-1]:
        ax.set_xlabel("filter radius / artifact size (r / a)", fontsize=8)
    for row in axes:
        row[0].set_ylabel("proportion correct", fontsize=8)
    handles = {}
    for ax in axes.flat:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    fig.legend(list(handles.values()), list(handles.keys()), loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=2, fontsize=7, frameon=False)
    fig.suptitle("participant %s: psychometric fits (%s)%s" % (
        participant, stairs[0]["fit"]["family"], "; * not converged" if not all(s["converged"] for s in stairs) else ""),
        fontsize=10)
    fig.tight_layout()
    save(fig, out_dir, "psychometric_" + participant)


def plot_quest(report, participant, units, out_dir):
    stairs, conditions, sizes = staircase_grid(report, participant)
    k = units.factor(participant)
    fig, axes = plt.subplots(len(conditions), 1, figsize=(7.0, 2.2 * len(conditions)), squeeze=False, sharex=True,
                             sharey=True)
    longest = max(len(s["track"]) for s in stairs)
    for s in sorted(stairs, key=lambda s: s["artifact_px"]):
        ax = axes[conditions.index(s["condition"])][0]
        color = SIZE_COLORS[sizes.index(s["artifact_px"]) % len(SIZE_COLORS)]
        n = list(range(1, len(s["track"]) + 1))
        radii = [t[2] * k for t in s["track"]]
        ax.plot(n, radii, "-", color=color, lw=1, label="a = %s %s" % (number_label(s["artifact_px"] * k), units.label()))
        ax.plot([i for i, t in zip(n, s["track"]) if t[3]], [t[2] * k for t in s["track"] if t[3]], "o", ms=3.5,
                color=color, label="correct")
        ax.plot([i for i, t in zip(n, s["track"]) if not t[3]], [t[2] * k for t in s["track"] if not t[3]], "o",
                ms=3.5, color=color, mfc="white", label="wrong")
        if s["r_threshold_px"] is not None:
            ax.axhline(s["r_threshold_px"] * k, color=color, ls=":", lw=1, label="fitted threshold")
        ax.set_title(s["condition"], fontsize=9, loc="left")
    for ax in axes.flat:
        ax.set_yscale("log")
        readable_log_axis(ax.yaxis)
        ax.set_ylabel("radius shown (%s)" % units.label(), fontsize=8)
        ax.grid(alpha=0.25, which="major")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True, steps=[1, 2, 5, 10]))
        ax.tick_params(labelsize=7)
    axes[0][0].set_xlim(0.5, longest + 0.5)
    axes[-1][0].set_xlabel("trial of the staircase", fontsize=8)
    # The legend beside the panels: one entry per size, then what the marks mean (in grey).
    size_handles = []
    for ax in axes.flat:
        for h, label in zip(*ax.get_legend_handles_labels()):
            if label.startswith("a = ") and label not in [x[1] for x in size_handles]:
                size_handles.append((h, label))
    marks = [(Line2D([], [], marker="o", ls="", color="0.3", ms=4), "correct"),
             (Line2D([], [], marker="o", ls="", color="0.3", mfc="white", ms=4), "wrong"),
             (Line2D([], [], ls=":", color="0.3"), "fitted threshold")]
    entries = size_handles + marks
    fig.legend([e[0] for e in entries], [e[1] for e in entries], loc="upper left", bbox_to_anchor=(1.0, 0.95),
               fontsize=8, frameon=False)
    fig.suptitle("participant %s: QUEST tracks" % participant, fontsize=10)
    fig.tight_layout()
    save(fig, out_dir, "quest_" + participant)


def technique(out_dir):
    """The technique of the calibration entry penumbra-fit wrote beside report.json."""
    try:
        with open(os.path.join(out_dir, "calibration.json")) as f:
            return json.load(f)["entries"][0]["technique"]
    except (OSError, ValueError, KeyError, IndexError, TypeError):
        return ""


def write_table(report, units, fit_dir, out_dir):
    """thresholds.csv: one row per staircase (participant x condition x artifact size)."""
    conditions = {c["condition"]: c for c in report["conditions"]}
    tech = technique(fit_dir)

    def fmt(v):
        return "" if v is None else "%.6g" % v

    rows = []
    for s in report["staircases"]:
        cond = conditions.get(s["condition"], {})
        r = s["r_threshold_px"]
        lo, hi = (s.get("c_wald") or [None, None])[:2]
        ppd = units.geometry.get(s["participant"], (None, None))[0]
        rows.append([s["participant"], tech, cond.get("pattern", ""), fmt(cond.get("contrast")), fmt(s["artifact_px"]),
                     fmt(r), fmt(r * 60.0 / ppd if r is not None and ppd else None),
                     fmt(lo * s["artifact_px"] if lo is not None else None),
                     fmt(hi * s["artifact_px"] if hi is not None else None), str(len(s["track"]))])
    rows.sort(key=lambda row: (row[0], row[2], -float(row[3] or 0), float(row[4])))
    path = os.path.join(out_dir, "thresholds.csv")
    with open(path + ".tmp", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["participant", "technique", "pattern", "contrast", "artifact_px", "threshold_px", "threshold_arcmin",
                    "ci_low", "ci_high", "trials"])
        w.writerows(rows)
    os.replace(path + ".tmp", path)
    return len(rows)


def write_summary(report, units, out_dir):
    lines = ["plot_fit.py: figures in %s; units %s" % (out_dir, units.label())]
    if units.geometry:
        lines.append("display geometry (pixels per degree at the centre, as penumbra-study display-check):")
        for p in sorted(units.geometry):
            lines.append("  %-12s %.4f px/deg  (%s)" % (p, units.geometry[p][0], units.geometry[p][1]))
    else:
        lines.append("report.json holds no display geometry (no session.json with the fit's inputs): threshold_arcmin is empty")
    lines.append("")
    lines.append("conditions (thresholds.png; the titles give c and its profile interval):")
    for cond in ordered_conditions(report):
        lines += condition_summary(cond)
    flagged = [s for s in report["staircases"] if s["flags"] or not s["converged"]]
    lines.append("")
    lines.append("staircases with flags (psychometric_*.png marks the not converged with *): %d of %d"
                 % (len(flagged), len(report["staircases"])))
    for s in flagged:
        lines.append("  %-12s %-10s a%-4g %s" % (s["participant"], s["condition"], s["artifact_px"],
                                                ", ".join(s["flags"]) or "not converged"))
    path = os.path.join(out_dir, "summary.txt")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", help="penumbra-fit output directory (holds report.json)")
    parser.add_argument("--units", choices=["px", "arcmin", "deg"], default="px",
                        help="radii and artifact sizes in pixels (default) or visual angle at the participant's display")
    parser.add_argument("--participants", default="",
                        help="comma-separated participants for the per-staircase plots (default: all)")
    args = parser.parse_args()
    path = os.path.join(args.out, "report.json")
    try:
        with open(path) as f:
            report = json.load(f)
    except (OSError, ValueError) as e:
        fail("%s: %s" % (path, e))
    participants = []
    for s in report["staircases"]:
        if s["participant"] not in participants:
            participants.append(s["participant"])
    units = Units(args.units, session_geometry(report), participants)
    if args.participants:
        wanted = args.participants.split(",")
        unknown = [p for p in wanted if p not in participants]
        if unknown:
            fail("--participants: not in the report: " + ", ".join(unknown))
        participants = wanted
    out_dir = os.path.join(args.out, "plots") if args.units == "px" else os.path.join(args.out, "plots", args.units)
    os.makedirs(out_dir, exist_ok=True)
    plot_thresholds(report, units, out_dir)
    for p in participants:
        plot_psychometric(report, p, units, out_dir)
        plot_quest(report, p, units, out_dir)
    rows = write_table(report, units, args.out, out_dir)
    write_summary(report, units, out_dir)
    print("wrote %s/{thresholds, psychometric_*, quest_*}.{png,svg} (%d participant%s, %s), thresholds.csv (%d rows), "
          "summary.txt" % (out_dir, len(participants), "" if len(participants) == 1 else "s", args.units, rows))


if __name__ == "__main__":
    main()
