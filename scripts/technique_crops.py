#!/usr/bin/python3
"""Grid of crops of penumbra-render's lit.png images, each labelled, for the docs.
Usage: technique_crops.py OUT.png COLUMNS X Y W H LABEL=PNG [LABEL=PNG ...]
(the crop is W x H pixels from (X, Y), top-left origin; images fill the grid row by row)."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) < 8:
        sys.exit(__doc__.strip())
    out, columns = sys.argv[1], int(sys.argv[2])
    x, y, w, h = (int(v) for v in sys.argv[3:7])
    panels = []
    for arg in sys.argv[7:]:
        label, sep, path = arg.partition("=")
        if not sep:
            sys.exit(f"{arg}: expected LABEL=PNG")
        img = mpimg.imread(path)
        if img.shape[0] < y + h or img.shape[1] < x + w:
            sys.exit(f"{path}: {img.shape[1]}x{img.shape[0]} is smaller than the crop {w}x{h}+{x}+{y}")
        panels.append((label, img[y:y + h, x:x + w]))
    rows = (len(panels) + columns - 1) // columns
    gap = 4
    dpi = 100
    fig = plt.figure(figsize=((columns * w + (columns - 1) * gap) / dpi, (rows * h + (rows - 1) * gap) / dpi), dpi=dpi)
    fig.patch.set_facecolor("white")
    width, height = columns * w + (columns - 1) * gap, rows * h + (rows - 1) * gap
    for i, (label, img) in enumerate(panels):
        r, c = divmod(i, columns)
        ax = fig.add_axes([c * (w + gap) / width, 1 - (r * (h + gap) + h) / height, w / width, h / height])
        ax.imshow(img, interpolation="nearest")
        ax.set_axis_off()
        ax.text(8, 8, label, fontsize=16, va="top", ha="left", color="black")
    fig.savefig(out, dpi=dpi)


if __name__ == "__main__":
    main()
