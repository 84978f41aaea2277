"""summary.txt of scripts/gpu-check.sh (docs/gpu.md), from its work folder. Standard library only.

Usage: gpu_summary.py WORK SOFTWARE RENDERER ELAPSED_S REQUIRE_GPU
  SOFTWARE: 0 GPU renderer, 1 software renderer (llvmpipe, softpipe), 2 no GL context.
  REQUIRE_GPU: 1 when the check ran with --require-gpu (then it stopped at a software renderer).
The first line says which: a software renderer is named there, before any number.
"""
import glob
import json
import os
import re
import sys
import xml.etree.ElementTree as ET


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return ""


def pass_totals(timings):
    """Sum of the per-pass medians, per method: {'gpu_timer': ms, 'wall_finish': ms}."""
    out = {}
    for t in timings or []:
        out[t["method"]] = out.get(t["method"], 0.0) + t["median_ms"]
    return out


def ms(v):
    return "-" if v is None else f"{v:.2f}" if v < 100 else f"{v:.0f}"


def both(totals):
    """'gpu / wall' in ms, or the wall clock alone."""
    g, w = totals.get("gpu_timer"), totals.get("wall_finish")
    return f"{ms(g)} / {ms(w)}" if g is not None else ms(w)


def main():
    work, software, renderer, elapsed, require_gpu = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4]), sys.argv[5] == "1"
    bundle = os.path.dirname(os.path.abspath(__file__))
    lines = []
    steps = [l.split("\t") for l in read(os.path.join(work, "steps.tsv")).splitlines()[1:] if l]
    failed = [s[0] for s in steps if s[1] != "ok"]
    device = (load(os.path.join(work, "probe", "report.json")) or {}).get("device", {})

    if software == 2:
        error = [l for l in read(os.path.join(work, "probe.log")).splitlines() if l.strip()]
        lines.append("NO GL CONTEXT: EGL gave no OpenGL 4.5 context: " + (error[-1] if error else "see check.log"))
    elif software == 1:
        lines.append(f"SOFTWARE RENDERER: EGL picked {renderer}; these are not GPU numbers (no gpu_timer times)")
    else:
        lines.append(f"GPU: {renderer}")
    if software == 2 or (software == 1 and require_gpu):
        verdict = "FAILED: " + ("no GL context" if software == 2 else "--require-gpu and a software renderer") + "; nothing else ran"
    else:
        verdict = "passed" if not failed else "FAILED: " + ", ".join(failed)
    lines.append(f"check: {verdict}; {elapsed} s in all")
    if device:
        lines.append(f"GL: {device.get('vendor')} | {device.get('renderer')} | {device.get('version')} | {device.get('platform')}"
                     f" | GL_MAX_TEXTURE_SIZE {device.get('max_texture_size')}")
    machine = read(os.path.join(work, "machine.txt"))
    m = re.search(r"^name, driver_version.*\n(.+)$", machine, re.M)
    lines.append("nvidia-smi: " + (m.group(1).strip() if m else "not found" if "nvidia-smi: not found" in machine else "no GPU listed"))
    version = dict(l.split(": ", 1) for l in read(os.path.join(bundle, "VERSION")).splitlines() if ": " in l)
    lines.append(f"bundle: commit {version.get('commit', '?')}, payload {version.get('payload', '?')}")
    lines.append("")
    lines.append("steps (limit = the step's cap or what was left of the budget):")
    for name, status, rc, secs, cmd in steps:
        lines.append(f"  {name:<10} {status:<8} {secs:>4} s  {cmd.replace(bundle + '/', '').replace(work + '/', '')}")

    # GL tests: per binary, the XML's counts against the manifest's.
    expected = {}
    for l in read(os.path.join(bundle, "gl-tests.txt")).splitlines():
        if l and not l.startswith("#"):
            f = l.split("\t")
            expected[f[0]] = int(f[1])
    if os.path.isdir(os.path.join(work, "gl-tests")):
        total = passed = 0
        problems = []
        for binary, n in sorted(expected.items()):
            total += n
            xml = os.path.join(work, "gl-tests", binary + ".xml")
            rc = read(os.path.join(work, "gl-tests", binary + ".rc")).strip() or "not run"
            try:
                root = ET.parse(xml).getroot()
            except (OSError, ET.ParseError):
                problems.append(f"{binary}: no results (exit {rc})")
                continue
            cases = root.iter("testcase")
            bad = []
            ran = 0
            for c in cases:
                if c.get("status") == "notrun" or c.get("result") == "skipped":
                    continue
                ran += 1
                if c.find("failure") is not None:
                    bad.append(f"{c.get('classname')}.{c.get('name')}")
            passed += ran - len(bad)
            if bad or ran != n:
                problems.append(f"{binary}: {ran} of {n} ran, {len(bad)} failed {' '.join(bad[:8])}")
        lines.append("")
        lines.append(f"GL tests (ctest -L gl, {len(expected)} binaries): {passed} of {total} passed")
        lines += ["  " + p for p in problems]

    demo = load(os.path.join(work, "demo", "report.json"))
    if demo:
        lines.append("")
        lines.append(f"main job: penumbra-demo --headless, {demo.get('scene')} at {demo['image_px'][0]}x{demo['image_px'][1]},"
                     f" {demo.get('path_frames')} path frames; frame ms = wall clock around glFinish (median [p10, p90])")
        table = [l for l in read(os.path.join(work, "demo.log")).splitlines() if re.match(r"^(tech |pcf |pcss |\w+ +\d)", l)]
        lines += ["  " + l for l in table]
        lines.append("  per-pass sums of medians, ms (" + ("gpu_timer / wall_finish" if software == 0 else "wall_finish") + "):")
        for t in demo.get("techniques", []):
            lines.append(f"    {t['technique']:<6} fixed {both(pass_totals(t['fixed'].get('passes'))):<18}"
                         f" adaptive {both(pass_totals(t['adaptive'].get('passes')))}")
        # The cost model's prediction from the same run's counts, beside these measured shadow costs
        # (gpu-check.sh ran scripts/gpu_cost_model.py on this report).
        model = read(os.path.join(work, "demo", "cost-model.txt"))
        if model:
            lines.append("  the cost model (a model, not a measurement) on this run's counts:")
            lines += ["    " + l for l in model.splitlines()]

    benches = [(name, load(os.path.join(work, name, "report.json"))) for name in ("bench", "bench-wall")]
    benches = [(n, b) for n, b in benches if b]
    if benches:
        lines.append("")
        lines.append("penumbra-bench --quick: median frame ms at each resolution, scene demo (" +
                     " / ".join(f"{b['timing_method']}" for _, b in benches) + ")")
        rows = {}
        resolutions = sorted({r["resolution_texels"] for _, b in benches for r in b["rows"] if not r["adaptive"]})
        for i, (_, b) in enumerate(benches):
            for r in b["rows"]:
                if r["scene"] != "demo" or r["adaptive"]:
                    continue
                rows.setdefault(r["variant"], {}).setdefault(r["resolution_texels"], [None] * len(benches))[i] = r["frame_ms_median"]
        lines.append("  " + f"{'variant':<14}" + "".join(f"{res:>18}" for res in resolutions))
        for variant, by_res in rows.items():
            cells = [" / ".join(ms(v) for v in by_res.get(res, [None] * len(benches))) for res in resolutions]
            lines.append("  " + f"{variant:<14}" + "".join(f"{c:>18}" for c in cells))
        for n, b in benches:
            lines.append(f"  {n}: {len(b['rows'])} rows, {b['timing_method']}, {b.get('elapsed_s', 0):.0f} s;"
                         f" adaptive rows on the front: {b['adaptive_on_front']['pareto']} of {b['adaptive_on_front']['rows']}")

    render = load(os.path.join(work, "render", "report.json"))
    if render:
        lines.append("")
        lines.append(f"penumbra-render --technique all, {render.get('scene')} at {render['image_px'][0]}x{render['image_px'][1]},"
                     f" median of {render.get('frames')} frames: sum of pass medians, ms"
                     f" ({'gpu_timer / wall_finish' if software == 0 else 'wall_finish'})")
        table = {}
        resolutions = []
        for r in render["renders"]:
            if r["resolution_texels"] not in resolutions:
                resolutions.append(r["resolution_texels"])
            table.setdefault(r["technique"], {})[r["resolution_texels"]] = both(pass_totals(r.get("timings")))
        lines.append("  " + f"{'technique':<14}" + "".join(f"{res:>18}" for res in resolutions))
        for tech, by_res in table.items():
            lines.append("  " + f"{tech:<14}" + "".join(f"{by_res.get(res, '-'):>18}" for res in resolutions))

    print("\n".join(lines))


if __name__ == "__main__":
    main()
