#!/usr/bin/env python3
"""The scene reference (docs/reference/scene.md), generated, and its check.

    scene-reference.py BIN_DIR [--check]

Two sources, neither written twice:
- the code's key table: every stage run with --print-scene-keys over examples/*.toml and the
  fixtures of tests/data/scene-keys/ prints each key it reads with the type, range and default
  its getter checks (SceneDocument::keySpecsText);
- the words: each key's comment in examples/annotated.toml (unit, range, what it does, what
  it costs), the file an artist copies a scene from.

Without --check it writes docs/reference/scene.md. With --check it writes nothing and exits 1
with one line per problem when a key that a stage reads has no entry in annotated.toml, an
entry of annotated.toml is read by no stage, or the committed reference differs from what the
code and annotated.toml give now (after adding a key: run this script without --check).
"""
import glob
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ANNOTATED = os.path.join(ROOT, "examples", "annotated.toml")
OUT = os.path.join(ROOT, "docs", "reference", "scene.md")
STAGES = [("ferro-sim", []), ("ferro-surface", ["--scene"]), ("ferro-spikes", ["--scene"]), ("ferro-pov", ["--scene"])]


def normalize(key):
    """magnets[0].keys[1].time -> magnets[].keys[].time"""
    return re.sub(r"\[\d+\]", "[]", key)


def code_keys(bin_dir):
    scenes = sorted(glob.glob(os.path.join(ROOT, "examples", "*.toml")))
    scenes += sorted(glob.glob(os.path.join(ROOT, "tests", "data", "scene-keys", "*.toml")))
    keys = {}   # key -> {"type", "defaults": set, "stages": set}
    for scene in scenes:
        for stage, flag in STAGES:
            exe = os.path.join(bin_dir, stage)
            run = subprocess.run([exe] + flag + [scene, "--print-scene-keys"], capture_output=True, text=True)
            if run.returncode != 0:
                sys.exit(f"scene-reference: {stage} could not list the keys of {os.path.relpath(scene, ROOT)}: "
                         f"{run.stderr.strip()}")
            for line in run.stdout.splitlines():
                key, kind, default = line.split("\t")
                k = keys.setdefault(normalize(key), {"type": "-", "defaults": set(), "stages": set(), "absent": False})
                if kind == "-":
                    k["absent"] = True   # looked up only with has(): optional here, or retired
                else:
                    k["type"] = kind
                    k["defaults"].add(default)
                k["stages"].add(stage)
    # The sections themselves ([[fluid.block]], [[magnets]]) are headings, not keys.
    return {k: v for k, v in keys.items() if v["type"] not in ("table", "array of tables")}


def section_path(header, arrays):
    """'[[magnets.keys]]' -> 'magnets[].keys[]' once [[magnets]] was seen; '[fluid]' -> 'fluid'.
    `arrays` collects the array-of-tables paths seen so far."""
    array = header.startswith("[[")
    parts = header.strip("[]").split(".")
    path = ""
    for i, p in enumerate(parts):
        path = f"{path}.{p}" if path else p
        if path + "[]" in arrays or (array and i == len(parts) - 1):
            path += "[]"
    if array:
        arrays.add(path)
    return path


KEY_LINE = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*)$")
# A key shown in a comment: "# length = 0.02   # bar: ..." or "# box:  min = [x, y, z], max = ...".
# The kind before the colon ("box") prefixes the words of its keys and of the indented ones
# under them.
COMMENTED = re.compile(r"^#\s+(?:([a-z]+):\s+)?([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*)$")


def split_value_comment(rest):
    """'0.5   # words' -> ('0.5', 'words'); '[x, y, z]   words' -> ('[x, y, z]', 'words')."""
    if "#" in rest:
        value, words = rest.split("#", 1)
        return value.strip(), words.strip()
    m = re.match(r"^(.*?)\s{2,}(.*)$", rest)
    return (m.group(1).strip(), m.group(2).strip()) if m else (rest.strip(), "")


def annotated_entries():
    """(section order, {key: description}) from annotated.toml's comments."""
    sections, entries, section, current, arrays, kind = [], {}, "", None, set(), None
    with open(ANNOTATED) as f:
        for raw in f:
            line = raw.rstrip("\n")
            stripped = line.strip()
            if stripped.startswith("["):
                section = section_path(stripped.split("#")[0].strip(), arrays)
                if section not in sections:
                    sections.append(section)
                current = None
                continue
            if not stripped:
                current = None
                continue
            m = KEY_LINE.match(line)
            # A key shown in a comment: "# key = ..." starts an entry; an indented one
            # ("#       closed_top = ...") only right under another entry, since the prose
            # between sections holds formulas ("#     z = C0 [...]").
            c = COMMENTED.match(line) if not m else None
            if c and not re.match(r"^# \S", line) and current is None:
                c = None
            # A continuation: a comment indented under the entry above it.
            if not c and current and stripped.startswith("#") and (line[0].isspace() or re.match(r"^#\s{4,}", line)):
                entries[current].append(stripped.lstrip("#").strip())
                continue
            if m or c:
                name = m.group(1) if m else c.group(2)
                value, words = split_value_comment(m.group(2) if m else c.group(3))
                if c and c.group(1):
                    kind = c.group(1)
                elif m or re.match(r"^# \S", line):
                    kind = None
                if kind and not words.startswith(kind + ":"):
                    words = f"{kind}: {words}"
                # "min = [x, y, z], max = [x, y, z]   corners": both keys share the words.
                names = [name] + re.findall(r",\s*([A-Za-z_]+)\s*=", value)
                for n in names:
                    key = f"{section}.{n}" if section else n
                    # A key written again without words (the second of two [[...keys]]
                    # tables) keeps the words of its first, documented occurrence.
                    if words or key not in entries:
                        entries[key] = [words]
                current = f"{section}.{names[-1]}" if section else names[-1]
                if len(names) > 1:
                    for n in names[:-1]:
                        entries[f"{section}.{n}"] = entries[current]
                continue
            current = None
    return sections, {k: " ".join(w for w in v if w) for k, v in entries.items()}


def render(sections, words, keys):
    out = ["# Scene reference",
           "",
           "Every key of a scene file, by section. Generated by `scripts/docs/scene-reference.py` from the",
           "stages' own parsers (`--print-scene-keys`: the type, range and default each getter checks) and",
           "the comments of [examples/annotated.toml](../../examples/annotated.toml) (what the key does,",
           "its unit, the further limits its stage checks and what it costs); a test fails when the two",
           "disagree. Do not edit by hand: edit annotated.toml or the parser and run the script.",
           "",
           "Units are SI. \"required\" keys have no default. A default marked *per scene* follows other",
           "keys (the description says which). Any key can be set from the command line without editing",
           "the file: `--set section.key=value` (the value is TOML; `fluid.block.0.count` picks an element",
           "of an array of tables).",
           ""]
    order = sections + sorted({k.rsplit(".", 1)[0] for k in keys} - set(sections))
    out.append("Sections: " + ", ".join(f"[`{s}`](#{anchor(s)})" for s in order) + ".")
    out.append("")
    for s in order:
        members = [k for k in words if k.rsplit(".", 1)[0] == s] + \
                  sorted(k for k in keys if k.rsplit(".", 1)[0] == s and k not in words)
        members = [k for k in dict.fromkeys(members) if k in keys]
        if not members:
            continue
        out.append(f"## {s}")
        out.append("")
        for k in members:
            spec = keys[k]
            defaults = spec["defaults"]
            if not defaults:
                default = "none (retired: setting it is an error)"
            elif len(defaults) > 1:
                default = "*per scene*"
            elif defaults == {"required"}:
                # Required where its kind or its partner needs it, absent elsewhere.
                default = "none (optional)" if spec["absent"] else "required"
            else:
                default = f"`{next(iter(defaults))}`"
            stages = ", ".join(st for st, _ in STAGES if st in spec["stages"])
            kind = spec["type"] if spec["type"] != "-" else "see below"
            out.append(f"**`{k}`** · {kind} · default {default} · read by {stages}  ")
            out.append(words.get(k, "") or "(no words in annotated.toml)")
            out.append("")
    return "\n".join(out)


def anchor(section):
    return re.sub(r"[^a-z0-9 -]", "", section.lower()).replace(" ", "-")


def main():
    if len(sys.argv) < 2 or sys.argv[1].startswith("-"):
        sys.exit("usage: scene-reference.py BIN_DIR [--check]")
    check = "--check" in sys.argv[2:]
    keys = code_keys(sys.argv[1])
    sections, words = annotated_entries()
    problems = []
    for k in sorted(keys):
        if k not in words:
            problems.append(f"{k}: read by {', '.join(sorted(keys[k]['stages']))} but not documented in examples/annotated.toml")
    for k in sorted(words):
        if k not in keys:
            problems.append(f"{k}: documented in examples/annotated.toml but read by no stage (examples/*.toml, tests/data/scene-keys/*.toml)")
    text = render(sections, words, keys) + "\n"
    if check:
        try:
            committed = open(OUT).read()
        except OSError:
            committed = ""
        if committed != text:
            problems.append("docs/reference/scene.md is not what the parsers and annotated.toml give now: run scripts/docs/scene-reference.py build/bin")
        for p in problems:
            print(p)
        sys.exit(1 if problems else 0)
    for p in problems:
        print(p, file=sys.stderr)
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w") as f:
        f.write(text)
    print(f"wrote {os.path.relpath(OUT, ROOT)}: {len(keys)} keys", file=sys.stderr)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
