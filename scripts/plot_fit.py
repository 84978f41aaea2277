#!/usr/bin/python3
"""Plots of a penumbra-fit run (docs/fit.md), as PNG and SVG.

    /usr/bin/python3 scripts/plot_fit.py OUT [--participants p01,p02]

reads OUT/report.json and writes into OUT/plots/:
  thresholds.{png,svg}           threshold filter radius vs artifact size per condition: the
                                 per-size thresholds (Wald 95 %), every staircase's threshold, the
                                 fitted r = c a with its 95 % band, the published c = 3.47 and the
                                 reference filter size when the fit was given one
  psychometric_<participant>.*   per staircase: binned proportion correct and the fitted curve
  quest_<participant>.*          per staircase: the QUEST track (trial -> radius shown)
"""
import argparse
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PUBLISHED_C = 3.47


def core(family, x, alpha, beta):
    """F(x) of quest/psychometric.h."""
    if family == "weibull":
        return 1.0 - math.exp(-((x / alpha) ** beta))
    if family == "log-weibull":
        return 1.0 - math.exp(-(10.0 ** (beta * (x - alpha))))
    if family == "normal":
        return 0.5 * math.erfc(-beta * (x - alpha) / math.sqrt(2.0))
    if family == "logistic":
        return 1.0 / (1.0 + math.exp(-beta * (x - alpha)))
    raise ValueError("unknown family " + family)


def psi(family, u, alpha, beta, gamma, lam):
    """Probability correct at intensity u = log10(a / r)."""
    x = 10.0 ** u if family == "weibull" else u
    return gamma + (1.0 - gamma - lam) * core(family, x, alpha, beta)


def save(fig, out_dir, name):
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(out_dir, name + "." + ext), dpi=110)
    plt.close(fig)


def grid(n):
    cols = min(n, 2)
    rows = (n + cols - 1) // cols
    return rows, cols


def plot_thresholds(report, out_dir):
    conditions = report["conditions"]
    rows, cols = grid(len(conditions))
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.2 * rows), squeeze=False)
    for ax, cond in zip(axes.flat, conditions):
        sizes = cond["artifact_px"]
        a_max = max(sizes) * 1.15
        line_a = [0.0, a_max]
        c = cond["c"]
        ci = cond["ci95_profile"]
        ax.fill_between(line_a, [ci["lo"] * a for a in line_a], [ci["hi"] * a for a in line_a],
                        color="tab:blue", alpha=0.18, lw=0, label="95 % interval (profile)")
        ax.plot(line_a, [c * a for a in line_a], color="tab:blue", lw=1.8, label="fit r = %.2f a" % c)
        ax.plot(line_a, [PUBLISHED_C * a for a in line_a], color="0.35", ls="--", lw=1.2,
                label="published r = 3.47 a")
        stairs = [s for s in report["staircases"] if s["condition"] == cond["condition"]]
        people = sorted({s["participant"] for s in stairs})
        labelled = False
        for s in stairs:
            jitter = ((people.index(s["participant"]) % 7) - 3) * 0.06 * min(sizes)
            if s["r_threshold_px"] is not None:
                ax.plot(s["artifact_px"] + jitter, s["r_threshold_px"], "o", ms=3, color="0.6", alpha=0.7,
                        mec="none", label="_staircase" if labelled else "staircase thresholds")
                labelled = True
        for i, size in enumerate(cond["sizes"]):
            if "r_threshold_px" in size and size["r_threshold_px"] is not None:
                lo, hi = size["r_threshold_wald_px"]
                r = size["r_threshold_px"]
                err = [[r - lo if lo is not None else 0], [hi - r if hi is not None else 0]]
                ax.errorbar(size["artifact_px"], r, yerr=err, fmt="s", color="k", ms=5, capsize=3,
                            label="per-size threshold (Wald 95 %)" if i == 0 else "_size")
            ref = size.get("reference_filter_radius_px")
            if ref is not None:
                ax.plot(size["artifact_px"], ref, "x", color="tab:red", ms=9, mew=2,
                        label="reference filter size" if i == 0 else "_ref")
        text = "c = %.3f [%.3f, %.3f]" % (c, ci["lo"], ci["hi"])
        beyond = ["%g" % size["artifact_px"] for size in cond["sizes"]
                  if size.get("reference_filter_radius_px") is None and "reference_note" in size]
        if beyond:
            text += "\nno reference r within the showable radii at a = " + ", ".join(beyond)
        if cond.get("power_law"):
            p = cond["power_law"]
            if p["exponent"] is not None and p["exponent_se"] is not None:
                text += "\nexponent p = %.2f ± %.2f" % (p["exponent"], p["exponent_se"])
        if cond.get("linearity") and cond["linearity"]["p_value"] is not None:
            text += "\nlinearity LR p = %.3g" % cond["linearity"]["p_value"]
        if cond["flags"]:
            text += "\nflags: " + ", ".join(cond["flags"])
        ax.text(0.03, 0.97, text, transform=ax.transAxes, va="top", fontsize=8,
                bbox=dict(fc="white", ec="0.8", alpha=0.9))
        # Head room above the data for the text box; the legend is shared below the panels.
        tops = [c * a_max, PUBLISHED_C * a_max, ci["hi"] * a_max]
        tops += [s["r_threshold_px"] for s in stairs if s["r_threshold_px"] is not None]
        tops += [size.get("reference_filter_radius_px") or 0 for size in cond["sizes"]]
        ax.set_xlim(0, a_max)
        ax.set_ylim(0, 1.4 * max(tops))
        ax.set_title("%s  (%d trials, %d participants)" % (cond["condition"], cond["trials"], cond["participants"]),
                     fontsize=10)
        ax.set_xlabel("artifact size a (px)")
        ax.set_ylabel("threshold filter radius r (px)")
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(conditions):]:
        ax.axis("off")
    handles, labels = {}, []
    for ax in axes.flat:
        for h, label in zip(*ax.get_legend_handles_labels()):
            key = label if not label.startswith("fit r") else "fit"
            if key not in handles:
                handles[key] = h
                labels.append(label if key != "fit" else "fitted r = c a")
    fig.legend(list(handles.values()), labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
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
    conditions = []
    for s in stairs:
        if s["condition"] not in conditions:
            conditions.append(s["condition"])
    sizes = sorted({s["artifact_px"] for s in stairs})
    return stairs, conditions, sizes


def plot_psychometric(report, participant, out_dir):
    stairs, conditions, sizes = staircase_grid(report, participant)
    fig, axes = plt.subplots(len(conditions), len(sizes), figsize=(3.2 * len(sizes), 2.6 * len(conditions)),
                             squeeze=False, sharey=True)
    for s in stairs:
        ax = axes[conditions.index(s["condition"])][sizes.index(s["artifact_px"])]
        f = s["fit"]
        family = f["family"]
        lo = min(t[1] for t in s["track"]) - 0.3
        hi = max(t[1] for t in s["track"]) + 0.3
        us = [lo + (hi - lo) * i / 200.0 for i in range(201)]
        ax.plot([10.0 ** -u for u in us],
                [psi(family, u, s["alpha"], f["beta"], f["guess"], f["lambda"]) for u in us], color="tab:blue")
        for ratio, p, n in binned(s["track"]):
            ax.plot(ratio, p, "o", color="k", ms=3 + 1.2 * n, alpha=0.6, mec="none")
        if s["c"] is not None:
            ax.axvline(s["c"], color="tab:blue", ls=":", lw=1)
        ax.set_xscale("log")
        ax.set_ylim(0.35, 1.03)
        ax.axhline(f["guess"], color="0.7", lw=0.8)
        title = "%s a=%g: c=%.2f" % (s["condition"], s["artifact_px"], s["c"])
        if not s["converged"]:
            title += " (not converged)"
        ax.set_title(title, fontsize=8)
        ax.set_xlabel("filter radius / artifact size", fontsize=8)
        ax.tick_params(labelsize=7)
    for row in axes:
        row[0].set_ylabel("proportion correct", fontsize=8)
    fig.suptitle("participant %s: psychometric fits (%s), binned data" % (participant, stairs[0]["fit"]["family"]),
                 fontsize=10)
    fig.tight_layout()
    save(fig, out_dir, "psychometric_" + participant)


def plot_quest(report, participant, out_dir):
    stairs, conditions, sizes = staircase_grid(report, participant)
    fig, axes = plt.subplots(len(conditions), 1, figsize=(7.5, 2.4 * len(conditions)), squeeze=False)
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]
    for s in stairs:
        ax = axes[conditions.index(s["condition"])][0]
        color = colors[sizes.index(s["artifact_px"]) % len(colors)]
        n = list(range(1, len(s["track"]) + 1))
        radii = [t[2] for t in s["track"]]
        ax.plot(n, radii, "-", color=color, lw=1, label="a = %g px" % s["artifact_px"])
        for i, t in zip(n, s["track"]):
            ax.plot(i, t[2], "o", ms=3.5, color=color, mfc=color if t[3] else "white")
        if s["r_threshold_px"] is not None:
            ax.axhline(s["r_threshold_px"], color=color, ls=":", lw=1)
        ax.set_yscale("log")
        ax.set_title(s["condition"], fontsize=9)
        ax.set_ylabel("radius shown (px)", fontsize=8)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1][0].set_xlabel("trial of the staircase (filled: correct, open: wrong; dotted: fitted threshold)",
                           fontsize=8)
    fig.suptitle("participant %s: QUEST tracks" % participant, fontsize=10)
    fig.tight_layout()
    save(fig, out_dir, "quest_" + participant)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", help="penumbra-fit output directory (holds report.json)")
    parser.add_argument("--participants", default="",
                        help="comma-separated participants for the per-staircase plots (default: all)")
    args = parser.parse_args()
    path = os.path.join(args.out, "report.json")
    try:
        with open(path) as f:
            report = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit("plot_fit.py: %s: %s" % (path, e))
    out_dir = os.path.join(args.out, "plots")
    os.makedirs(out_dir, exist_ok=True)
    plot_thresholds(report, out_dir)
    participants = []
    for s in report["staircases"]:
        if s["participant"] not in participants:
            participants.append(s["participant"])
    if args.participants:
        wanted = args.participants.split(",")
        unknown = [p for p in wanted if p not in participants]
        if unknown:
            sys.exit("plot_fit.py: --participants: not in the report: " + ", ".join(unknown))
        participants = wanted
    for p in participants:
        plot_psychometric(report, p, out_dir)
        plot_quest(report, p, out_dir)
    print("wrote %s/{thresholds, psychometric_*, quest_*}.{png,svg} (%d participants)" % (out_dir, len(participants)))


if __name__ == "__main__":
    main()
