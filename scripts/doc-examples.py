#!/usr/bin/env python3
"""Runs every `specula analyze` example command in README.md and docs/ with two builds of
specula and compares their JSON documents: the figures a user gets from the docs' commands
before and after a change.

    python3 scripts/doc-examples.py OLD_SPECULA NEW_SPECULA [--allow=PATH=OLD->NEW ...]
        [--ignore=PATH ...]

Commands are taken from fenced code blocks (lines joined at a trailing backslash) and inline
code; those with placeholders (SCENE, NAME, [..], |, ...) are skipped. Each is run from the
repository's root with `--json` added (and `--report` sent to a scratch folder). A difference
is listed by its JSON path; `--allow` names a path whose old value is expected to become the
new one (a change made on purpose); `--ignore` a path that is no figure (a wall-clock time).
Exit status 1 if any command's documents differ
otherwise, or a command fails in one build and not the other.
"""

import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def doc_files():
    yield os.path.join(ROOT, "README.md")
    for folder, _, files in os.walk(os.path.join(ROOT, "docs")):
        for name in sorted(files):
            if name.endswith(".md") and name != "cli.md":
                yield os.path.join(folder, name)


def commands(text):
    found = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        joined = re.sub(r"\\\n\s*", " ", block)
        found += [line.strip() for line in joined.splitlines()]
    found += re.findall(r"`(specula analyze [^`]*)`", text)
    wanted = []
    for c in found:
        c = re.sub(r"^\$\s*", "", c)
        c = re.sub(r"^cargo run --release -- ", "specula ", c)
        if not c.startswith("specula analyze "):
            continue
        c = c.split(" #")[0].strip()
        # A report folder's placeholder is the scratch folder's; a surface's runs each.
        c = c.replace("--report DIR", "--report scratch")
        variants = [c.replace("--surface S", f"--surface {s}") for s in ("exact", "mesh")]
        for c in dict.fromkeys(variants):
            words = shlex.split(c)
            if len(words) < 4 or "--help" in words:
                continue
            if any(re.search(r"[\[\]|<>]|\.\.\.|^[A-Z_]{2,}$", w) for w in words):
                continue
            wanted.append(words)
    return wanted


def run(binary, words, scratch, tag):
    words = list(words[1:])
    if "--report" in words:
        i = words.index("--report")
        words[i + 1] = os.path.join(scratch, f"report-{tag}")
    if "--json" in words:
        i = words.index("--json")
        del words[i : i + 2]
    out = os.path.join(scratch, f"{tag}.json")
    done = subprocess.run([binary, *words, "--json", out], cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        return None, (done.stderr.strip().splitlines() or ["?"])[-1]
    with open(out) as f:
        return json.load(f), None


def differences(a, b, path=""):
    if type(a) != type(b):
        return [(path, a, b)]
    if isinstance(a, dict):
        out = []
        for k in list(a) + [k for k in b if k not in a]:
            out += differences(a.get(k), b.get(k), f"{path}/{k}")
        return out
    if isinstance(a, list):
        if len(a) != len(b):
            return [(path, f"{len(a)} items", f"{len(b)} items")]
        out = []
        for i, (x, y) in enumerate(zip(a, b)):
            out += differences(x, y, f"{path}[{i}]")
        return out
    return [] if a == b else [(path, a, b)]


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    old, new = args[0], args[1]
    allowed, ignored = set(), set()
    for spec in args[2:]:
        if spec.startswith("--ignore="):
            ignored.add(spec[len("--ignore="):])
        if spec.startswith("--allow="):
            path, change = spec[len("--allow="):].split("=", 1)
            before, after = change.split("->", 1)
            allowed.add((path, before, after))
    seen, failed = set(), False
    with tempfile.TemporaryDirectory() as scratch:
        for path in doc_files():
            for words in commands(open(path).read()):
                key = " ".join(words)
                if key in seen:
                    continue
                seen.add(key)
                where = os.path.relpath(path, ROOT)
                a, a_err = run(old, words, scratch, "old")
                b, b_err = run(new, words, scratch, "new")
                if a is None or b is None:
                    same_failure = a is None and b is None
                    failed |= not same_failure
                    print(f"{'FAILS IN BOTH' if same_failure else 'FAILS'}  {where}: {key}\n    before: {a_err or 'ok'}\n    after:  {b_err or 'ok'}")
                    continue
                diffs = [
                    d for d in differences(a, b)
                    if (d[0], str(d[1]), str(d[2])) not in allowed and d[0] not in ignored
                ]
                on_purpose = len(differences(a, b)) - len(diffs)
                note = f" ({on_purpose} change(s) on purpose)" if on_purpose else ""
                if diffs:
                    failed = True
                    print(f"DIFFERS  {where}: {key}")
                    for d in diffs[:5]:
                        print(f"    {d[0]}: {d[1]} -> {d[2]}")
                else:
                    print(f"same     {where}: {key}{note}")
    print(f"{len(seen)} example commands")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
