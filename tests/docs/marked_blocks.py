"""What the two doc tests share: the fenced blocks a marker comment stands right before, the docs
they read, and the closing line CTest and CI read."""
import os
import re
import sys


def docs(source):
    """README.md and the guides (docs/*.md; the results pages are history and are not read)."""
    return ["README.md"] + [os.path.join("docs", f) for f in sorted(os.listdir(os.path.join(source, "docs"))) if f.endswith(".md")]


def marked_blocks(path, marker, fence):
    """(marker match, index of the block's first line, index of its closing fence) for every block of
    `fence` (e.g. "```sh") right after a line matching the regular expression `marker`."""
    lines = open(path, encoding="utf-8").read().split("\n")
    found = []
    for i, line in enumerate(lines):
        m = re.fullmatch(marker, line.strip())
        if not m:
            continue
        if i + 1 >= len(lines) or lines[i + 1].strip() != fence:
            sys.exit(f"{path}:{i + 1}: the marker must stand right before a {fence} block")
        end = next((j for j in range(i + 2, len(lines)) if lines[j].strip() == "```"), None)
        if end is None:
            sys.exit(f"{path}:{i + 2}: the block never closes")
        found.append((m, i + 2, end))
    return found


def finish(passed, failures):
    """Prints every failure and the closing 'N passed, N failed' line, and exits 1 on a failure."""
    for f in failures:
        print("FAILED " + f)
    print(f"{passed} passed, {len(failures)} failed")
    sys.exit(1 if failures else 0)
