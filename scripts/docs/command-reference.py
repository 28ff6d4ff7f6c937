#!/usr/bin/env python3
"""Keeps docs/reference/commands.md equal to the tools' own --help.

    command-reference.py BIN_DIR [--check]

The page is prose written by hand around blocks that are not: each

    <!-- help: ferro-sim -->
    ...
    <!-- /help -->

holds the text that `ferro-sim --help` prints (a stage from BIN_DIR) or `scripts/NAME --help`
(a script), fenced. Without --check the blocks are rewritten in place. With --check nothing is
written and the exit status is 1, with one line per problem, when a block differs from what
its tool prints now, or when a stage in BIN_DIR or a script that answers --help has no block
(after adding a flag or a tool: run this script without --check and describe it in the prose).
"""
import glob
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PAGE = os.path.join(ROOT, "docs", "reference", "commands.md")
BLOCK = re.compile(r"(<!-- help: (\S+) -->\n)(.*?)(<!-- /help -->)", re.S)


def help_text(bin_dir, name):
    if name.startswith("ferro-"):
        exe = os.path.join(bin_dir, name)
    else:
        exe = os.path.join(ROOT, name)
    if not os.path.exists(exe):
        return None
    # argv[0] is the bare name, so that "Usage:" does not show where the tool was built.
    run = subprocess.run([name, "--help"], executable=exe, capture_output=True, text=True, cwd=ROOT)
    if run.returncode != 0:
        sys.exit(f"command-reference: `{name} --help` failed (exit {run.returncode}): {run.stderr.strip()}")
    return run.stdout.rstrip("\n")


def tools(bin_dir):
    """Every tool the page must describe: the stages and the user-facing scripts."""
    stages = sorted(os.path.basename(p) for p in glob.glob(os.path.join(bin_dir, "ferro-*")))
    scripts = ["scripts/shot.sh", "scripts/farm.sh", "scripts/slurm/submit.sh", "scripts/demo.sh",
               "scripts/install-deps.sh", "scripts/bench.sh", "scripts/gallery.sh"]
    return stages + [s for s in scripts if os.path.exists(os.path.join(ROOT, s))]


def main():
    if len(sys.argv) < 2 or sys.argv[1].startswith("-"):
        sys.exit("usage: command-reference.py BIN_DIR [--check]")
    bin_dir, check = sys.argv[1], "--check" in sys.argv[2:]
    page = open(PAGE).read()
    problems = []
    seen = set()

    def fill(m):
        name = m.group(2)
        seen.add(name)
        text = help_text(bin_dir, name)
        if text is None:
            problems.append(f"{name}: has a block in docs/reference/commands.md but no such tool")
            return m.group(0)
        fresh = "```text\n" + text + "\n```\n"
        if m.group(3) != fresh:
            problems.append(f"{name}: its block in docs/reference/commands.md is not what `{name} --help` prints now")
        return m.group(1) + fresh + m.group(4)

    updated = BLOCK.sub(fill, page)
    for name in tools(bin_dir):
        if name not in seen:
            problems.append(f"{name}: no `<!-- help: {name} -->` block in docs/reference/commands.md")
    if check:
        for p in problems:
            print(p)
        sys.exit(1 if problems else 0)
    with open(PAGE, "w") as f:
        f.write(updated)
    missing = [p for p in problems if "no `<!--" in p or "no such tool" in p]
    for p in missing:
        print(p, file=sys.stderr)
    sys.exit(1 if missing else 0)


if __name__ == "__main__":
    main()
