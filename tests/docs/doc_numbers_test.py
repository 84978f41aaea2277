#!/usr/bin/python3
"""Numbers the docs quote from a program are the numbers the program prints now.

A ```text block right after `<!-- doc-numbers: NAME -->` in README.md or docs/ (results pages
excepted: they are history) must equal what generator NAME below prints: it runs the commands the
doc names, in a fresh folder, and keeps the lines that do not depend on the machine (counts, fitted
values; no times). A change that moves such a number fails here until the doc is updated:
`doc_numbers_test.py SOURCE_DIR BUILD_DIR --update` rewrites the blocks (then read the prose
around them). Expensive measurements (the main job, the bench) carry their command and commit
instead and are refreshed by the change that moves them.

Usage: doc_numbers_test.py SOURCE_DIR BUILD_DIR [--update] [--only NAME]
"""
import os
import subprocess
import sys
import tempfile

from marked_blocks import docs, finish, marked_blocks

MARKER = r"<!-- doc-numbers: ([a-z0-9-]+) -->"


def run(cmd, cwd, timeout=1200):
    r = subprocess.run(["bash", "-c", "set -euo pipefail\n" + cmd], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, timeout=timeout)
    if r.returncode != 0:
        raise RuntimeError(f"exit {r.returncode}: {cmd}\n" + "\n".join(r.stdout.strip().split("\n")[-10:]))
    return r.stdout


def fit_example(build, work):
    """docs/fit.md's worked example: the quick start's 10 simulated participants, fitted."""
    out = run(f"""mkdir -p out/study
for i in $(seq -w 1 10); do
  {build}/study/penumbra-study run --config data/studies/default.json \\
      --observer psychometric:c=3.0,beta=3.5,lapse=0.02 --headless \\
      --participant p$i --observer-seed $((10#$i)) -o out/study/p$i >/dev/null
done
{build}/analysis/penumbra-fit out/study/p* -o out/fit""", work)
    lines = out.split("\n")
    start = next(i for i, line in enumerate(lines) if line.startswith("condition  trials"))
    end = next(i for i in range(start, len(lines)) if not lines[i].strip())
    keep = lines[start:end]
    keep += [line for line in lines if line.startswith(("conditions differ?", "calibration: c =", "thesis-style estimate"))]
    return "\n".join(line.rstrip() for line in keep)


def pages(build, work):
    """docs/adaptive.md's `penumbra-demo --pages`: pages marked by the rule and the footprint along the
    main job's path, and how many each frame drew (its draw times left out)."""
    out = run(f"mkdir -p out && {build}/renderer/penumbra-demo --pages -o out/pages", work)
    keep = []
    for line in out.split("\n"):
        f = line.split()
        if len(f) >= 10 and f[0] in ("pcf", "pcss") and f[1].isdigit():
            # tech frame rule footprint ratio MB-rule MB-footprint ms-rule ms-footprint drawn/requested
            keep.append(f"{f[0]:<6}{f[1]:>6}{f[2]:>13}{f[3]:>13}{f[4]:>9}{f[5]:>13}{f[6]:>13}{f[9]:>13}")
        elif len(f) > 2 and f[0] in ("pcf", "pcss") and f[1] == "median":
            keep.append(line.rstrip())
    if not keep:
        raise RuntimeError("penumbra-demo --pages printed no page rows:\n" + out[-2000:])
    header = f"{'tech':<6}{'frame':>6}{'pages rule':>13}{'footprint':>13}{'ratio':>9}{'MB rule':>13}{'MB footprint':>13}{'drawn':>13}"
    return "\n".join([header] + keep)


def engine_example(build, work):
    """docs/adaptive.md's engine example (examples/engine_integration) with the shipped calibration."""
    out = run(f"{build}/tests/docs/engine_integration_in_tree data/calibration/default.json", work)
    # The first line (c and its entry) and the frames the doc's prose reads: the first, where one
    # cascade reaches the largest map, where two take over and one returns, and the hysteresis's end.
    shown = {0, 22, 23, 27, 31, 60}
    keep = [line.rstrip() for line in out.strip().split("\n")
            if not line.startswith("frame") or int(line.split()[1]) in shown]
    return "\n".join(keep)


GENERATORS = {"fit-example": fit_example, "pages": pages, "engine-example": engine_example}


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    update = "--update" in sys.argv
    only = sys.argv[sys.argv.index("--only") + 1] if "--only" in sys.argv else None
    if only:
        args.remove(only)
    if len(args) != 2:
        sys.exit("usage: doc_numbers_test.py SOURCE_DIR BUILD_DIR [--update] [--only NAME]")
    source, build = (os.path.abspath(p) for p in args)
    uses = {}
    for doc in docs(source):
        for m, start, end in marked_blocks(os.path.join(source, doc), MARKER, "```text"):
            uses.setdefault(m.group(1), []).append((doc, start, end))
    failures = []
    for name in sorted(set(GENERATORS) - set(uses)):
        failures.append(f"generator {name} quotes into no doc (mark its block with <!-- doc-numbers: {name} -->)")
    for name in sorted(set(uses) - set(GENERATORS)):
        failures.append(f"{uses[name][0][0]}: <!-- doc-numbers: {name} --> names no generator of {os.path.basename(__file__)}")
    passed = 0
    for name in sorted(set(uses) & set(GENERATORS)):
        if only and name != only:
            continue
        print(f"--- {name}: {GENERATORS[name].__doc__.split(chr(10))[0]}", flush=True)
        with tempfile.TemporaryDirectory(prefix="penumbra-doc-numbers-") as work:
            os.symlink(os.path.join(source, "data"), os.path.join(work, "data"))
            try:
                printed = GENERATORS[name](build, work)
            except (RuntimeError, subprocess.TimeoutExpired, StopIteration) as e:
                failures.append(f"{name}: the program failed: {e}")
                continue
        print(printed, flush=True)
        for doc, start, end in uses[name]:
            path = os.path.join(source, doc)
            lines = open(path, encoding="utf-8").read().split("\n")
            quoted = "\n".join(line.rstrip() for line in lines[start:end])
            if quoted == printed:
                passed += 1
                continue
            if update:
                lines[start:end] = printed.split("\n")
                with open(path, "w", encoding="utf-8") as f:
                    f.write("\n".join(lines))
                print(f"updated {doc}:{start + 1} ({name})")
                continue
            diff = [f"  doc:     {a}\n  program: {b}" for a, b in zip(quoted.split("\n"), printed.split("\n")) if a != b]
            if quoted.count("\n") != printed.count("\n"):
                diff.append(f"  the doc quotes {quoted.count(chr(10)) + 1} lines, the program prints {printed.count(chr(10)) + 1}")
            failures.append(f"{doc}:{start + 1}: {name} differs from what the program prints now "
                            f"(rerun with --update, then check the prose around it):\n" + "\n".join(diff[:12]))
    finish(passed, failures)


if __name__ == "__main__":
    main()
