#!/usr/bin/env python3
"""A cost model: the work penumbra-demo counted, turned into a predicted time on a named GPU.

Reads the main job's report.json (penumbra-demo; each configuration's `work`: what its shadow gave
the GPU to do per frame, counted by the driver, and what the shading's shadow lookups read per
pixel, counted by the shader) and prints, per technique and configuration, the measured shadow
cost (frame minus the unshadowed floor, on the machine that ran the job) beside the shadow cost
this model predicts on each GPU of the table below, and both read as ratios: against the fixed
map, and for the rule's configurations against the engine front at equal error, interpolated
between the same two front configurations the job's own reading used.

THIS IS A MODEL, NOT A MEASUREMENT. It charges each unit of work at a GPU's published peak rate:

  geometry   primitives / (GPCs x clock)             one triangle per clock per raster engine
  raster     fragments / (ROPs x clock)              every shadow pass's fragments at the pixel fill rate
  depth out  depth texels x 4 B / memory bandwidth   the maps' raster written once (32-bit depth)
  lookups    texture instructions / (TMUs x clock)   the shading's shadow reads, one per TMU per clock
  compute    invocations / (SMs x 128 x clock)       one operation per invocation: a floor, not a cost

and adds them as `max(geometry, raster, depth out) + lookups + compute` (a raster pass waits on
its slowest unit; the lookups run in the shading, the compute passes on their own). What it leaves
out is said in docs/gpu.md: caches (a lookup's bytes are not charged to memory), clears (GPUs
clear depth through compression metadata), the shaders' arithmetic, state changes and draw calls,
the CPU, a depth-only pass's faster Z rate, and the fact that peak rates are rarely reached.
Its use is a ratio between two configurations of the same frame, not an absolute time.

Usage: gpu_cost_model.py REPORT.json [--gpu NAME ...] [--json OUT]
Exit: 0 printed; 2 a missing or unreadable report, or one without work counts (one line).
"""

import argparse
import json
import math
import sys

# Published units and clocks. Each entry names its source; the triangle rate is an assumption
# (see TRIANGLES_PER_CLOCK_PER_GPC).
GPUS = {
    "rtx4090": {
        "name": "NVIDIA GeForce RTX 4090",
        "gpcs": 11, "sms": 128, "rops": 176, "tmus": 512, "boost_ghz": 2.52, "bandwidth_gbs": 1008.0,
        "source": "NVIDIA Ada GPU Architecture whitepaper v2.01 (2023), appendix table for the GeForce RTX 4090: "
                  "11 GPCs, 128 SMs, 176 ROPs, 512 texture units, 2520 MHz boost clock, 1008 GB/s",
    },
    "rtx4080": {
        "name": "NVIDIA GeForce RTX 4080 (16 GB)",
        "gpcs": 7, "sms": 76, "rops": 112, "tmus": 304, "boost_ghz": 2.505, "bandwidth_gbs": 716.8,
        "source": "NVIDIA Ada GPU Architecture whitepaper v2.01 (2023), appendix table for the GeForce RTX 4080: "
                  "7 GPCs, 76 SMs, 112 ROPs, 304 texture units, 2505 MHz boost clock, 716.8 GB/s",
    },
}
# One triangle per clock per raster engine (one raster engine per GPC) is the rate NVIDIA's Fermi
# (GF100) whitepaper (2010) gives for its raster engines; later whitepapers state no triangle rate,
# so this is an assumption carried forward, not a published Ada number.
TRIANGLES_PER_CLOCK_PER_GPC = 1.0
LANES_PER_SM = 128  # FP32 lanes per Ada SM (the whitepaper's SM diagram)
DEPTH_BYTES = 4     # the maps and the virtual pool are 32-bit float depth


def fail(message):
    print(f"gpu_cost_model: {message}", file=sys.stderr)
    sys.exit(2)


def predict_ms(work, gpu):
    """The model's shadow time (ms) of one configuration's median frame on `gpu`, and its terms."""
    clock = gpu["boost_ghz"] * 1e9
    geometry = work["primitives"] / (gpu["gpcs"] * TRIANGLES_PER_CLOCK_PER_GPC * clock)
    raster = work["fragments"] / (gpu["rops"] * clock)
    depth_out = work["depth_texels"] * DEPTH_BYTES / (gpu["bandwidth_gbs"] * 1e9)
    lookups = work["instructions"] / (gpu["tmus"] * clock)
    compute = work["compute_invocations"] / (gpu["sms"] * LANES_PER_SM * clock)
    terms = {"geometry": geometry, "raster": raster, "depth_out": depth_out, "lookups": lookups, "compute": compute}
    return 1e3 * (max(geometry, raster, depth_out) + lookups + compute), {k: 1e3 * v for k, v in terms.items()}


def counts(entry, where):
    """The per-frame counts of a configuration's `work` (medians over the path's frames)."""
    work = entry.get("work")
    if not isinstance(work, dict) or "primitives" not in work:
        fail(f"{where}: no work counts (a report of penumbra-demo from before the work was counted?)")
    reads = work.get("reads")
    per_pixel = reads["instructions_per_pixel"] if reads else 0.0
    pixels = reads["pixels_per_frame"] if reads else 0.0
    return {
        "primitives": work["primitives"]["median"],
        "fragments": work["fragments"]["median"],
        "depth_texels": work["depth_texels"]["median"],
        "compute_invocations": work["compute_invocations"]["median"],
        "instructions": per_pixel * pixels,
        "instructions_per_pixel": per_pixel,
        "bytes_per_pixel": reads["bytes_per_pixel"] if reads else 0.0,
        "resident_bytes": 4.0 * entry.get("texels_allocated", 0.0),
    }


def interpolate_cost(lo, hi, weight):
    """As the job reads its front (common/stats/pareto.h): lo^(1-w) hi^w, lo at w <= 0, hi at w >= 1."""
    if weight <= 0:
        return lo
    if weight >= 1:
        return hi
    if lo <= 0 or hi <= 0:
        return lo + (hi - lo) * weight
    return math.exp((1 - weight) * math.log(lo) + weight * math.log(hi))


def configurations(technique):
    """(name, entry, equal-error readings) of every configuration the report measured."""
    out = []
    fixed = technique.get("fixed")
    if fixed:
        out.append(("fixed", fixed, {}))
    adaptive = technique.get("adaptive")
    if adaptive:
        readings = {k: technique[k] for k in ("equal_flip", "equal_error") if isinstance(technique.get(k), dict)}
        out.append(("rule (" + str(adaptive.get("name", "adaptive")) + ")", adaptive, readings))  # the one map the rule sizes
    for b in technique.get("baselines", []):
        out.append((b["name"], b, {}))
    for v in technique.get("virtual", []):
        readings = {k: v[k] for k in ("equal_flip", "equal_error") if isinstance(v.get(k), dict)}
        out.append((v["name"], v, readings))
    return out


def shadow_reading(readings):
    """The job's reading of a configuration's shadow cost against the front: FLIP first, else RMSE."""
    for key in ("equal_flip", "equal_error"):
        r = readings.get(key)
        if not r:
            continue
        for name in ("shadow", "shadow_cost"):
            c = r.get(name)
            if isinstance(c, dict) and "between" in c:
                return key, c
    return None, None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report", help="penumbra-demo's report.json")
    parser.add_argument("--gpu", action="append", choices=sorted(GPUS), help="GPUs to predict for (default: all)")
    parser.add_argument("--json", metavar="OUT", help="also write the table as JSON")
    args = parser.parse_args()
    try:
        with open(args.report, encoding="utf-8") as f:
            report = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{args.report}: {e}")
    techniques = report.get("techniques")
    if not isinstance(techniques, list) or not techniques:
        fail(f"{args.report}: no 'techniques' (not a penumbra-demo report)")
    gpus = [GPUS[g] | {"key": g} for g in (args.gpu or sorted(GPUS))]

    print("A MODEL, not a measurement: published peak rates charged per unit of work (scripts/gpu_cost_model.py, docs/gpu.md).")
    print(f"Measured: {report.get('device', {}).get('renderer', 'the machine that ran the job')}, shadow cost = frame - floor.")
    for g in gpus:
        print(f"  {g['key']}: {g['source']}; triangles {TRIANGLES_PER_CLOCK_PER_GPC:g}/clock/GPC (assumed)")
    table = []
    for t in techniques:
        name = t.get("technique", "?")
        rows = []
        for label, entry, readings in configurations(t):
            c = counts(entry, f"{args.report}: {name}, {label}")
            measured = entry.get("shadow_ms", {}).get("median", float("nan"))
            predicted = {g["key"]: predict_ms(c, g) for g in gpus}
            rows.append({"configuration": label, "counts": c, "measured_shadow_ms": measured,
                         "predicted_shadow_ms": {k: v[0] for k, v in predicted.items()},
                         "predicted_terms_ms": {k: v[1] for k, v in predicted.items()}, "readings": readings,
                         "name": entry.get("name", label)})
        by_name = {r["name"]: r for r in rows}
        fixed = rows[0] if rows and rows[0]["configuration"] == "fixed" else None
        print(f"\n{name}: per frame (medians along the path); ratios are the fixed map's cost over the row's")
        header = f"  {'configuration':<30} {'ktri':>7} {'Mfrag':>7} {'Mdepth':>7} {'taps/px':>7} {'B/px':>7} {'MB res':>7} {'meas ms':>8} {'vs fixed':>8}"
        for g in gpus:
            header += f" {g['key'] + ' µs':>12} {'vs fixed':>8}"
        print(header)
        for r in rows:
            c = r["counts"]
            line = (f"  {r['configuration'][:30]:<30} {c['primitives'] / 1e3:7.1f} {c['fragments'] / 1e6:7.2f} {c['depth_texels'] / 1e6:7.2f}"
                    f" {c['instructions_per_pixel']:7.1f} {c['bytes_per_pixel']:7.0f} {c['resident_bytes'] / 1e6:7.1f} {r['measured_shadow_ms']:8.1f}")
            line += f" {fixed['measured_shadow_ms'] / r['measured_shadow_ms']:7.2f}x" if fixed and r["measured_shadow_ms"] > 0 else f" {'':>8}"
            for g in gpus:
                p = r["predicted_shadow_ms"][g["key"]]
                line += f" {1e3 * p:12.1f}"
                line += f" {fixed['predicted_shadow_ms'][g['key']] / p:7.2f}x" if fixed and p > 0 else f" {'':>8}"
            print(line)
        # At equal error: the front interpolated between the same two configurations the job read.
        for r in rows:
            key, reading = shadow_reading(r["readings"])
            if not reading:
                continue
            lo, hi = reading["between"]
            if lo not in by_name or hi not in by_name:
                print(f"  at equal {key}, {r['configuration']}: the front's {lo} or {hi} is not in the report: not modelled")
                continue
            measured_ratio = reading["ratio"]["median"]
            text = f"  at equal {'FLIP' if key == 'equal_flip' else 'RMSE'}, {r['configuration']}: measured {measured_ratio:.2f}x less shadow cost than the front ({reading['position']}, between {lo} and {hi})"
            r["equal"] = {"reading": key, "between": [lo, hi], "weight": reading["weight"], "measured_ratio": measured_ratio,
                          "predicted_ratio": {}}
            for g in gpus:
                front = interpolate_cost(by_name[lo]["predicted_shadow_ms"][g["key"]], by_name[hi]["predicted_shadow_ms"][g["key"]],
                                         reading["weight"])
                ratio = front / r["predicted_shadow_ms"][g["key"]] if r["predicted_shadow_ms"][g["key"]] > 0 else float("nan")
                r["equal"]["predicted_ratio"][g["key"]] = ratio
                text += f"; model {g['key']} {ratio:.2f}x"
            print(text)
        table.append({"technique": name, "rows": [{k: v for k, v in r.items() if k != "readings"} for r in rows]})
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"model": "scripts/gpu_cost_model.py", "gpus": gpus, "triangles_per_clock_per_gpc": TRIANGLES_PER_CLOCK_PER_GPC,
                       "techniques": table}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
