#!/usr/bin/env python3
"""Writes docs/benchmarks.md's generated tables, and the README's methods table's two measured
columns, from the JSON runs in docs/figures/runs (written by scripts/figures.sh).

Each table names its command, the machine and the commit (runs/meta.json). Everything in the
tables but the times comes from deterministic runs, so writing them again from a second run
changes only the times.

    python3 scripts/figures.py
"""
import json
import re
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RUNS = ROOT / "docs" / "figures" / "runs"
BENCHMARKS = ROOT / "docs" / "benchmarks.md"
README = ROOT / "README.md"
BEGIN, END = "<!-- figures:begin -->", "<!-- figures:end -->"
TABLE_BEGIN, TABLE_END = "<!-- methods-table:begin -->", "<!-- methods-table:end -->"


def load(name):
    path = RUNS / name
    return json.loads(path.read_text()) if path.exists() else None


def flip(cell):
    if cell is None:
        return "failed"
    if cell["mean_flip"] is None:
        return "—"
    text = f"{cell['mean_flip']:.4f}"
    if cell["delegated"]:
        text += "*"
    return text


def cells(scene, labels):
    by_label = {c["label"]: c for c in scene["methods"]}
    return [by_label.get(label) for label in labels]


def scene_tables(run, meta, what):
    """Accuracy and warm frame time, method × scene, from one `specula compare` run."""
    labels = run["methods"]
    scenes = [s for s in run["scenes"] if not s["error"]]
    size = f"{scenes[0]['width']} × {scenes[0]['height']}" if scenes else "?"
    out = [
        f"### {what}: accuracy",
        "",
        f"Mean FLIP over each scene's mirror and glass pixels against the exact CPU reference, "
        f"{size}, specula's defaults (lower is better; `—`: the method shades none of the "
        f"scene's specular surfaces; `*`: it hands some to another method, whose figure is not "
        f"in this one). Command: `{meta['commands'][run['_name']]}`.",
        "",
        "| scene | pixels | " + " | ".join(f"`{l}`" for l in labels) + " |",
        "|---|---:|" + "---:|" * len(labels),
    ]
    for s in run["scenes"]:
        if s["error"]:
            out.append(f"| {s['source']} | | failed to load or render: {s['error']} |")
            continue
        row = [flip(c) for c in cells(s, labels)]
        out.append(f"| {s['scene']} | {s['mask_pixels']} | " + " | ".join(row) + " |")
    out += [
        "",
        f"### {what}: warm frame time (ms)",
        "",
        f"The median of {scenes[0]['frames'] if scenes else '?'} warm frames after a first "
        f"frame timed apart, on {run['adapter']}; the reference on the CPU (its BVH build not "
        f"included). Same run as above.",
        "",
        "| scene | `reference` | " + " | ".join(f"`{l}`" for l in labels) + " |",
        "|---|---:|" + "---:|" * len(labels),
    ]
    for s in scenes:
        row = [
            "failed" if c is None else f"{c['total_ms']:.1f}" for c in cells(s, labels)
        ]
        out.append(f"| {s['scene']} | {s['reference_ms']:.1f} | " + " | ".join(row) + " |")
    out.append("")
    return out


def embree_table(text, meta):
    """The BVH kernel against Embree, from scripts/bench-bvh.sh's output."""
    embree = re.search(r"embree single-thread primary rays: median ([0-9.]+) Mrays/s", text)
    ratio = re.search(r"single-thread ratio specula / Embree: ([0-9.]+) \(([0-9.]+) /", text)
    mesh = re.search(r"mesh \S+: (\d+) triangles", text)
    if not (embree and ratio):
        sys.exit("figures.py: runs/embree.txt lacks bench-bvh.sh's figures")
    return [
        "### The ray kernel against Intel Embree",
        "",
        f"Primary rays through the Stanford dragon ({mesh.group(1) if mesh else '?'} "
        f"triangles), 1024 × 1024, one thread, both on the same rays in one run. Command: "
        f"`{meta['commands']['embree']}`.",
        "",
        "| | Mrays/s |",
        "|---|---:|",
        f"| specula (`cargo bench -p specula-trace --bench bvh`) | {ratio.group(2)} |",
        f"| Embree (`embreex`, `../shared/bench/embree_rays.py`) | {embree.group(1)} |",
        f"| specula / Embree | {ratio.group(1)} |",
        "",
    ]


def gpu_section():
    gpu = RUNS / "bench-gpu.md"
    if gpu.exists():
        return ["### On a GPU", "", gpu.read_text().strip(), ""]
    return [
        "### On a GPU",
        "",
        "Not measured: no GPU machine has been lent to this project's sessions yet. "
        "`scripts/bench-gpu.sh --out docs/figures/runs` on one writes `bench-gpu.json` and "
        "`bench-gpu.md` there, and this script then shows them here.",
        "",
    ]


def generated(meta, suite, builtins, embree):
    out = [
        f"Machine: {meta['machine']}. Commit: `{meta['commit']}`. Written by "
        f"`scripts/figures.sh` from the JSON runs in `docs/figures/runs`.",
        "",
    ]
    if suite:
        out += scene_tables(suite, meta, "The scene suite")
    if builtins:
        out += scene_tables(builtins, meta, "The built-in scenes")
    if embree:
        out += embree_table(embree, meta)
    out += gpu_section()
    return "\n".join(out)


def replace_between(text, begin, end, body, path):
    if begin not in text or end not in text:
        sys.exit(f"figures.py: {path} lacks its {begin} … {end} markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    return f"{head}{begin}\n{body}\n{end}{tail}"


def summary(values, digits, unit=""):
    if not values:
        return "—"
    values = sorted(values)
    lo, hi, mid = values[0], values[-1], statistics.median(values)
    return f"{lo:.{digits}f}–{hi:.{digits}f}{unit} ({mid:.{digits}f})"


def methods_table(text, suite):
    """The README methods table's two measured columns, from the suite run."""
    scenes = [s for s in suite["scenes"] if not s["error"]]
    head, rest = text.split(TABLE_BEGIN, 1)
    table, tail = rest.split(TABLE_END, 1)
    lines = table.strip("\n").split("\n")
    for k, line in enumerate(lines):
        name = re.match(r"\| \[`([a-z0-9-]+)`\]", line)
        if not name:
            continue
        label = name.group(1)
        if label == "reference":
            accuracy = "0: it is the reference"
            times = [s["reference_ms"] for s in scenes]
        else:
            found = [c for s in scenes for c in s["methods"] if c["label"] == label]
            accuracy = summary([c["mean_flip"] for c in found if c["mean_flip"] is not None], 3)
            shaded = sum(c["mean_flip"] is not None for c in found)
            if shaded < len(scenes):
                accuracy += f" on {shaded} of {len(scenes)}"
            times = [c["total_ms"] for c in found]
        cells_ = line.strip().strip("|").split(" | ")
        cells_[4] = accuracy
        cells_[5] = summary(times, 1, " ms")
        lines[k] = "| " + " | ".join(c.strip() for c in cells_) + " |"
    return f"{head}{TABLE_BEGIN}\n" + "\n".join(lines) + f"\n{TABLE_END}{tail}"


def main():
    meta = load("meta.json")
    if meta is None:
        sys.exit("figures.py: no docs/figures/runs/meta.json: run scripts/figures.sh")
    suite, builtins = load("suite.json"), load("builtins.json")
    for run, name in [(suite, "suite"), (builtins, "builtins")]:
        if run is not None:
            run["_name"] = name
    embree_path = RUNS / "embree.txt"
    embree = embree_path.read_text() if embree_path.exists() else None
    text = BENCHMARKS.read_text()
    BENCHMARKS.write_text(
        replace_between(text, BEGIN, END, generated(meta, suite, builtins, embree), BENCHMARKS)
    )
    if suite:
        README.write_text(methods_table(README.read_text(), suite))
    print(f"figures.py: wrote {BENCHMARKS.relative_to(ROOT)} and {README.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
