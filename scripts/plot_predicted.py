#!/usr/bin/env python3
"""Bar chart of data/calibration/predicted.json: the image observer's c per technique and condition.
   /usr/bin/python3 scripts/plot_predicted.py [PREDICTED.json] [OUT.png]"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

src = sys.argv[1] if len(sys.argv) > 1 else "data/calibration/predicted.json"
out = sys.argv[2] if len(sys.argv) > 2 else "docs/images/predicted-c.png"
entries = json.load(open(src))["entries"]
conditions = ["stair/1", "stair/0.5", "step/1", "step/0.5"]
fig, ax = plt.subplots(figsize=(8, 4))
width = 0.8 / len(conditions)
for k, condition in enumerate(conditions):
    xs, cs, hatches, lo, hi = [], [], [], [], []
    for i, e in enumerate(entries):
        per = {c["condition"]: c for c in e["per_condition"]}
        if condition not in per or per[condition]["c"] is None:
            continue
        xs.append(i + (k - 1.5) * width)
        c = per[condition]["c"]
        cs.append(c)
        # The condition's 95 % interval over the stimuli, where the entry has one (none: no bar).
        ci = per[condition].get("ci95") or [math.nan, math.nan]
        lo.append(c - ci[0])
        hi.append(ci[1] - c)
        hatches.append("//" if any(p.get("at_most") for p in per[condition]["per_artifact"]) else "")
    bars = ax.bar(xs, cs, width, label=condition, yerr=[lo, hi], error_kw={"elinewidth": 0.8, "capsize": 1.5})
    for b, h in zip(bars, hatches):
        b.set_hatch(h)
ax.axhline(3.47, color="black", lw=0.8, ls="--", label="published c (PCF, people)")
ax.set_xticks(range(len(entries)))
ax.set_xticklabels([(e["technique"] + (" " + e["kernel"] if e["kernel"] else "")) for e in entries])
ax.set_ylabel("c = r / a (texels)")
ax.set_title("Image observer's predicted c (a model, not human data)\nbars: 95 % over the stimuli; hatched: an upper bound", fontsize=10)
ax.legend(fontsize=8, ncol=5, loc="upper center", bbox_to_anchor=(0.5, -0.1))
fig.tight_layout()
fig.savefig(out, dpi=90)
print("wrote " + out)
