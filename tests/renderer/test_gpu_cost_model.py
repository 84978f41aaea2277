#!/usr/bin/python3
"""scripts/gpu_cost_model.py on a small hand-made penumbra-demo report: each term of the model
charges its unit of work at the GPU's published rate, a raster pass costs its slowest unit, the
equal-error ratio reads the front between the same two configurations the job read, with the
job's geometric interpolation; a report without work counts is refused in one line, exit 2.
Run by CTest (GpuCostModel.*)."""
import copy
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "scripts", "gpu_cost_model.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import gpu_cost_model as model  # noqa: E402


def spread(x):
    return {"median": x, "p10": x, "p90": x, "min": x, "max": x}


def config(name, primitives, fragments, depth, compute, taps, pixels, shadow_ms):
    return {"name": name, "shadow_ms": spread(shadow_ms), "texels_allocated": depth,
            "work": {"frames": 3, "primitives": spread(primitives), "fragments": spread(fragments),
                     "depth_texels": spread(depth), "compute_invocations": spread(compute),
                     "reads": {"frames": 1, "pixels_per_frame": pixels, "instructions_per_pixel": taps,
                               "texels_per_pixel": 4 * taps, "bytes_per_pixel": 16 * taps}}}


def report():
    fixed = config("fixed-2048", 1e6, 4.0e6, 4.0e6, 0, 25, 5e5, 100.0)
    small = config("fixed-1024", 1e6, 1.0e6, 1.0e6, 0, 25, 5e5, 60.0)
    adaptive = config("adaptive", 1e6, 2.0e6, 2.0e6, 0, 25, 5e5, 70.0)
    virtual = config("virtual rule", 1.2e6, 1.5e6, 1.0e6, 2e6, 30, 5e5, 50.0)
    reading = {"shadow_cost": {"front": ["fixed-2048", "fixed-1024"], "position": "on_front", "between": ["fixed-2048", "fixed-1024"],
                               "weight": 0.5, "front_ms": 77.0, "ratio": {"median": 1.5, "ci95": [1.2, 1.8], "frames": 3}}}
    virtual["equal_flip"] = copy.deepcopy(reading)
    return {"device": {"renderer": "llvmpipe"},
            "techniques": [{"technique": "pcf", "fixed": fixed, "adaptive": adaptive, "baselines": [small], "virtual": [virtual],
                            "equal_flip": copy.deepcopy(reading)}]}


class GpuCostModel(unittest.TestCase):
    def test_each_term_charges_its_unit_at_the_published_rate(self):
        gpu = model.GPUS["rtx4090"]
        clock = gpu["boost_ghz"] * 1e9
        one_ms_of = {
            "primitives": gpu["gpcs"] * model.TRIANGLES_PER_CLOCK_PER_GPC * clock * 1e-3,
            "fragments": gpu["rops"] * clock * 1e-3,
            "instructions": gpu["tmus"] * clock * 1e-3,
            "compute_invocations": gpu["sms"] * model.LANES_PER_SM * clock * 1e-3,
        }
        zero = {"primitives": 0, "fragments": 0, "depth_texels": 0, "instructions": 0, "compute_invocations": 0}
        for key, amount in one_ms_of.items():
            ms, terms = model.predict_ms(zero | {key: amount}, gpu)
            self.assertAlmostEqual(ms, 1.0, places=9, msg=key)
        # 4 bytes a depth texel at the memory bandwidth
        ms, terms = model.predict_ms(zero | {"depth_texels": gpu["bandwidth_gbs"] * 1e9 * 1e-3 / model.DEPTH_BYTES}, gpu)
        self.assertAlmostEqual(ms, 1.0, places=9)

    def test_a_raster_pass_costs_its_slowest_unit_and_the_rest_adds(self):
        gpu = model.GPUS["rtx4080"]
        clock = gpu["boost_ghz"] * 1e9
        work = {"primitives": gpu["gpcs"] * clock * 2e-3, "fragments": gpu["rops"] * clock * 3e-3, "depth_texels": 0,
                "instructions": gpu["tmus"] * clock * 1e-3, "compute_invocations": 0}
        ms, terms = model.predict_ms(work, gpu)
        self.assertAlmostEqual(terms["geometry"], 2.0)
        self.assertAlmostEqual(terms["raster"], 3.0)
        self.assertAlmostEqual(ms, 3.0 + 1.0)

    def test_the_front_is_read_between_the_jobs_two_configurations(self):
        self.assertAlmostEqual(model.interpolate_cost(4.0, 1.0, 0.5), 2.0)  # geometric, as common/stats/pareto.h
        self.assertEqual(model.interpolate_cost(4.0, 1.0, -1), 4.0)
        self.assertEqual(model.interpolate_cost(4.0, 1.0, 2), 1.0)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "report.json")
            with open(path, "w") as f:
                json.dump(report(), f)
            out = os.path.join(tmp, "model.json")
            printed = subprocess.run([sys.executable, SCRIPT, path, "--json", out], capture_output=True, text=True)
            self.assertEqual(printed.returncode, 0, printed.stderr)
            self.assertTrue(printed.stdout.startswith("A MODEL, not a measurement"))
            with open(out) as f:
                table = json.load(f)
        rows = {r["name"]: r for r in table["techniques"][0]["rows"]}
        for gpu in model.GPUS:
            front = math.sqrt(rows["fixed-2048"]["predicted_shadow_ms"][gpu] * rows["fixed-1024"]["predicted_shadow_ms"][gpu])
            for name in ("virtual rule", "adaptive"):
                self.assertAlmostEqual(rows[name]["equal"]["predicted_ratio"][gpu], front / rows[name]["predicted_shadow_ms"][gpu], msg=name)
                self.assertEqual(rows[name]["equal"]["measured_ratio"], 1.5)

    def test_a_report_without_work_is_refused_in_one_line(self):
        bare = report()
        del bare["techniques"][0]["fixed"]["work"]
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "report.json")
            with open(path, "w") as f:
                json.dump(bare, f)
            for args, needle in (([path], "no work counts"), ([os.path.join(tmp, "missing.json")], "missing.json")):
                r = subprocess.run([sys.executable, SCRIPT] + args, capture_output=True, text=True)
                self.assertEqual(r.returncode, 2)
                self.assertIn(needle, r.stderr)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


if __name__ == "__main__":
    unittest.main()
