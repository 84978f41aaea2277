#!/usr/bin/python3
"""The commands the README and docs/ show run as written in a fresh clone.

Every ```sh block right after the line `<!-- doc-commands: run -->` is run by bash (set -euo
pipefail), the blocks of one file in their order and in one folder that starts empty but for what
a fresh clone has (the tracked data/, scripts/ and docs/, and the build as build/; the build's tools
are on PATH for the guides that write them as installed). A command that
is too long for the suite is shortened by one of SHORTER's exact replacements; each must match in
a block exactly once, so a doc that changes under it fails here instead of being skipped silently.

Usage: doc_commands_test.py SOURCE_DIR BUILD_DIR
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

from marked_blocks import docs, finish, marked_blocks

MARKER = "<!-- doc-commands: run -->"

# (file, text as the doc writes it, text run here): fewer participants, smaller images, fewer seeds.
SHORTER = [
    ("README.md", "$(seq -w 1 10)", "$(seq -w 1 3)"),
    ("docs/fit.md", "$(seq -w 1 10)", "$(seq -w 1 3)"),
    ("docs/fit.md", "--artifact-px 5,10,20 -o out/reference.json", "--artifact-px 5,10,20 --seeds 1 -o out/reference.json"),
    ("README.md", "--resolution 1024 -o out/pcss", "--resolution 1024 --width 96 --height 64 --frames 1 --warmup 0 -o out/pcss"),
    ("README.md", "--pcf.radius 3 -o out/grid", "--pcf.radius 3 --width 96 --height 64 --frames 1 --warmup 0 -o out/grid"),
    ("README.md", "--resolution 512,1024,2048,4096 -o out/sweep", "--resolution 64,128 --width 96 --height 64 --frames 1 --warmup 0 -o out/sweep"),
    ("README.md", "--map.cascades 4 -o out/street", "--map.cascades 4 --width 96 --height 64 --frames 1 --warmup 0 -o out/street"),
]


def blocks(path):
    """The marked ```sh blocks of a markdown file, as (first line number, text)."""
    lines = open(path, encoding="utf-8").read().split("\n")
    return [(start + 1, "\n".join(lines[start:end])) for _, start, end in marked_blocks(path, re.escape(MARKER), "```sh")]


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: doc_commands_test.py SOURCE_DIR BUILD_DIR")
    source, build = (os.path.abspath(p) for p in sys.argv[1:])
    marked = {doc: blocks(os.path.join(source, doc)) for doc in docs(source)}
    marked = {doc: b for doc, b in marked.items() if b}
    # The guides write commands as installed (penumbra-study); the build's tools stand in for them.
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join(os.path.join(build, d) for d in ("study", "analysis", "renderer")) + os.pathsep + env.get("PATH", "")
    failures = []
    passed = 0
    for doc, text, _ in SHORTER:
        n = sum(block.count(text) for _, block in marked.get(doc, []))
        if n != 1:
            failures.append(f"{doc}: the shortened command text {text!r} appears {n} times in its marked blocks (expected once)")
    if not marked:
        failures.append(f"no block is marked with {MARKER}")
    for doc, doc_blocks in marked.items():
        with tempfile.TemporaryDirectory(prefix="penumbra-doc-commands-") as clone:
            for folder in ("data", "scripts", "docs"):
                shutil.copytree(os.path.join(source, folder), os.path.join(clone, folder))
            os.symlink(build, os.path.join(clone, "build"))
            for line, block in doc_blocks:
                run = block
                for d, text, shorter in SHORTER:
                    if d == doc:
                        run = run.replace(text, shorter)
                print(f"--- {doc}:{line}\n{run}", flush=True)
                r = subprocess.run(["bash", "-c", "set -euo pipefail\n" + run], cwd=clone, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, timeout=900, env=env)
                tail = "\n".join(r.stdout.strip().split("\n")[-15:])
                print(tail, flush=True)
                if r.returncode != 0:
                    failures.append(f"{doc}:{line}: exit {r.returncode} in a fresh folder:\n{tail}")
                else:
                    passed += 1
    finish(passed, failures)


if __name__ == "__main__":
    main()
