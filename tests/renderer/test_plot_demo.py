#!/usr/bin/python3
"""scripts/plot_demo.py on a penumbra-demo report (data/demo-report.json: the demo scene, 3 orbit
frames at 192x108, PCF and PCSS, the default engine family, the virtual maps; trimmed of the
settings and pass times the figures do not read): one colour per configuration in every figure,
the virtual maps on front.png and on its perceptual twin front-flip.png (FLIP mean as the error),
demo.png led by the equal-error ratios, labelled axes, a readable
flicker.png. Run by CTest (PlotDemo.*); needs python3-matplotlib (scripts/setup.sh)."""
import copy
import json
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import matplotlib  # noqa: E402
import plot_demo  # noqa: E402

FIXTURE = os.path.join(HERE, "data", "demo-report.json")


def drawn_colour(artist):
    """The colour an artist was drawn in, as #rrggbb."""
    if isinstance(artist, matplotlib.patches.Patch):
        return matplotlib.colors.to_hex(artist.get_facecolor())
    return matplotlib.colors.to_hex(artist.get_color())


def tagged(fig):
    """[(configuration, colour)] of every artist drawn for a configuration."""
    return [(a.configuration, drawn_colour(a)) for a in fig.findobj(lambda a: hasattr(a, "configuration"))]


class PlotDemo(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with open(FIXTURE) as f:
            cls.report = json.load(f)
        cls.figures = plot_demo.figures(cls.report)

    def names(self):
        out = []
        for t in self.report["techniques"]:
            out += [f["configuration"] for f in t["flicker"]]
        return sorted(set(out))

    def test_every_figure_is_drawn_front_first(self):
        self.assertEqual(list(self.figures), ["front", "front-flip", "demo", "error", "flicker", "path"])

    def test_one_colour_per_configuration_in_every_figure(self):
        seen = {}
        for stem, fig in self.figures.items():
            pairs = tagged(fig)
            self.assertTrue(pairs, stem)
            for name, c in pairs:
                self.assertEqual(c, plot_demo.colour(name), f"{stem}: {name}")
                seen.setdefault(name, set()).add(stem)
        # Every configuration the run measured is drawn somewhere, the flicker-only ones included.
        for name in self.names():
            if not name.startswith("floor"):
                self.assertIn(name, seen)
        self.assertEqual(set(seen["adaptive"]), set(self.figures))

    def test_configurations_get_distinct_colours(self):
        sweep = [f"fixed-{r}" for r in (1024, 2048, 4096, 8192)]
        sweep += [f"{k}x{r}-cascades" for k in (2, 3, 4) for r in (1024, 2048, 4096)]
        names = set(self.names()) | set(sweep)
        colours = {plot_demo.colour(n) for n in names}
        self.assertEqual(len(colours), len(names))
        self.assertEqual(len({plot_demo.style(n) for n in names}), len(names))

    def test_front_shows_every_virtual_map_at_equal_error(self):
        drawn = {name for name, _ in tagged(self.figures["front"])}
        virtual = [v for t in self.report["techniques"] for v in t.get("virtual", [])]
        self.assertEqual(len({v["name"] for v in virtual}), 3)
        for v in virtual:
            self.assertIn(v["name"], drawn)
        labels = [text.get_text() for ax in self.figures["front"].axes for text in ax.get_legend().get_texts()]
        for t in self.report["techniques"]:
            for v in t["virtual"]:
                ratio = v["equal_error"]["time"]["ratio"]["median"]
                self.assertTrue(any(label.startswith(v["name"] + ":") and f"{ratio:.2f}x" in label for label in labels), v["name"])

    def test_front_flip_reads_every_configuration_at_its_flip(self):
        fig = self.figures["front-flip"]
        drawn = {name for name, _ in tagged(fig)}
        labels = [text.get_text() for ax in fig.axes for text in ax.get_legend().get_texts()]
        for t, axes in zip(self.report["techniques"], (fig.axes[0:2], fig.axes[2:4])):
            self.assertIn("FLIP", axes[0].get_xlabel())
            # Each configuration sits at its FLIP mean, not at its RMSE.
            stars = [line for line in axes[0].get_lines() if getattr(line, "configuration", "") == "adaptive" and line.get_marker() == "*"]
            self.assertEqual(len(stars), 1)
            self.assertAlmostEqual(stars[0].get_xdata()[0], t["adaptive"]["flip"]["mean"])
            self.assertNotAlmostEqual(stars[0].get_xdata()[0], t["adaptive"]["reference_error"]["rmse_mean"])
            for v in t["virtual"]:
                self.assertIn(v["name"], drawn)
                ratio = v["equal_flip"]["time"]["ratio"]["median"]
                self.assertTrue(any(label.startswith(v["name"] + ":") and f"{ratio:.2f}x" in label for label in labels), v["name"])

    def test_demo_leads_with_the_equal_error_ratio(self):
        notes = [a.get_text() for a in self.figures["demo"].axes[0].texts if "\n" in a.get_text()]
        self.assertEqual(len(notes), len(self.report["techniques"]))
        for note, t in zip(notes, self.report["techniques"]):
            lines = note.split("\n")
            self.assertTrue(lines[0].startswith("at equal error"), note)
            self.assertIn(f"{t['equal_error']['time']['ratio']['median']:.2f}x", lines[1])
            # The fixed map's ratio comes last, with both errors beside it.
            self.assertIn(f"{t['speedup_median']:.2f}x (RMSE", lines[-1])

    def test_without_a_reference_demo_says_why(self):
        report = copy.deepcopy(self.report)
        for t in report["techniques"]:
            t["equal_error"] = {"unavailable": "no reference (--no-reference): no error to compare at"}
            t.pop("equal_flip")
            for _, row in plot_demo.configurations(t):
                row["reference_error"] = None
            for v in t["virtual"]:
                v["equal_error"] = {"why_not": "no reference"}
        figures = plot_demo.figures(report)
        self.assertNotIn("front", figures)
        self.assertNotIn("front-flip", figures)
        self.assertNotIn("error", figures)
        note = figures["demo"].axes[0].texts[-1].get_text()
        self.assertTrue(note.startswith("no equal-error reading: no reference"), note)

    def test_every_panel_is_labelled(self):
        for stem, fig in self.figures.items():
            self.assertTrue(fig._suptitle is not None or stem == "demo", stem)
            for ax in fig.axes:
                self.assertTrue(ax.get_title(), stem)
                self.assertTrue(ax.get_xlabel() or stem == "demo", stem)  # demo's x axis: the techniques
                self.assertTrue(ax.get_ylabel() or ax.get_yticklabels(), stem)

    def test_flicker_follows_few_configurations_along_the_path(self):
        for t, ax in zip(self.report["techniques"], self.figures["flicker"].axes[1::2]):
            drawn = {line.configuration for line in ax.get_lines() if hasattr(line, "configuration")}
            self.assertLessEqual(len(drawn), 5)
            self.assertIn("adaptive", drawn)
            self.assertIn("virtual rule, cached", drawn)

    def test_short_path_stations_keep_their_frames_apart_and_unjoined(self):
        frames = [0, 1, 2, 357, 358, 359]
        self.assertEqual(plot_demo.station_positions(frames), [0, 1, 2, 4, 5, 6])
        xs, ys = plot_demo.station_series(frames, [1, 2, 3, 4, 5, 6])
        self.assertEqual(len(xs), 7)
        self.assertNotEqual(ys[3], ys[3])  # NaN: no line from frame 2 to frame 357
        self.assertEqual(xs[4:], [4, 5, 6])

    def test_writes_png_and_svg(self):
        with tempfile.TemporaryDirectory() as out:
            sys.argv = ["plot_demo.py", FIXTURE, out]
            plot_demo.main()
            for stem in self.figures:
                for ext in ("png", "svg"):
                    self.assertGreater(os.path.getsize(os.path.join(out, f"{stem}.{ext}")), 1000, f"{stem}.{ext}")


if __name__ == "__main__":
    unittest.main()
