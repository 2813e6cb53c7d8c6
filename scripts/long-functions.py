#!/usr/bin/env python3
"""Lists the Rust functions of the libraries' and binaries' sources (crates/*/src) longer than a
limit (default 120 lines, from the `fn` line to its closing brace), longest first.

    scripts/long-functions.py [--limit 120] [DIR]

Reads the text only: braces inside strings, characters and comments are skipped. Exits 1 when
any function is over the limit.
"""
import argparse
import pathlib
import re
import sys

FN = re.compile(r"^\s*(pub(\([^)]*\))?\s+)?(const\s+|async\s+|unsafe\s+)*fn\s+(\w+)")


def strip_line(line, in_block):
    """The line without comments, strings and char literals; whether a block comment is open."""
    out, i = [], 0
    while i < len(line):
        if in_block:
            end = line.find("*/", i)
            if end < 0:
                return "".join(out), True
            i, in_block = end + 2, False
        elif line.startswith("//", i):
            break
        elif line.startswith("/*", i):
            in_block, i = True, i + 2
        elif line[i] == '"':
            i += 1
            while i < len(line) and line[i] != '"':
                i += 2 if line[i] == "\\" else 1
            i += 1
        elif line[i] == "'" and re.match(r"'(\\.|[^\\'])'", line[i:]):
            i += len(re.match(r"'(\\.|[^\\'])'", line[i:]).group(0))
        else:
            out.append(line[i])
            i += 1
    return "".join(out), in_block


def functions(path):
    lines = path.read_text(encoding="utf-8").splitlines()
    stack, in_block, depth, found = [], False, 0, []
    for number, raw in enumerate(lines, 1):
        code, in_block = strip_line(raw, in_block)
        match = FN.match(code)
        if match:
            stack.append((match.group(4), number, depth))
        for ch in code:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
                if stack and depth == stack[-1][2]:
                    name, start, _ = stack.pop()
                    found.append((number - start + 1, name, start))
        # A declaration without a body (a trait's) ends with ';' at its own depth.
        if stack and code.rstrip().endswith(";") and depth == stack[-1][2]:
            stack.pop()
    return found


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--limit", type=int, default=120)
    parser.add_argument("root", nargs="?", default=".")
    args = parser.parse_args()
    root = pathlib.Path(args.root)
    long = []
    for path in sorted(root.glob("crates/*/src/**/*.rs")):
        for length, name, start in functions(path):
            if length > args.limit:
                long.append((length, f"{path.relative_to(root)}:{start}", name))
    for length, place, name in sorted(long, reverse=True):
        print(f"{length:5}  {name}  {place}")
    print(f"{len(long)} functions over {args.limit} lines")
    sys.exit(1 if long else 0)


if __name__ == "__main__":
    main()
