#!/usr/bin/env python3
"""Lengths of the project's functions (test cases and sections included), as issue 94 measures them.

A function is a definition whose header ends a line with "{" (at any indentation, not a namespace, type, control
statement, lambda or initialiser); its length runs from the header's first line to the brace that closes it.
Prints the count, the median and every function over LIMIT lines (default 80); exits 1 when there is one.
Usage: python3 scripts/function_lengths.py [LIMIT]
"""
import os
import re
import statistics
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
FOLDERS = ["base", "formats", "nerf", "mesh", "splat", "viewer", "pipeline", "stages", "cli", "examples", "bench",
           "tests"]
NOT_FUNCTION = re.compile(r"^\s*(namespace|struct|class|enum|union|if|else|for|while|do|switch|try|catch|extern)\b|"
                          r"=\s*[\[{]|\[[^\]]*\]\s*(\([^)]*\))?\s*(mutable\s*)?(->\s*[\w:<>]+\s*)?\{$|^\s*(return|case)\b")


def functions(path):
    lines = open(path, encoding="utf-8").read().split("\n")
    depth_at = []  # the brace depth at the start of each line
    depth = 0
    for line in lines:
        depth_at.append(depth)
        code = re.sub(r'"(\\.|[^"\\])*"|\'(\\.|[^\'\\])*\'|//.*', "", line)
        depth += code.count("{") - code.count("}")
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.rstrip().endswith("{") and ")" in line + (lines[i - 1] if i else "") and not NOT_FUNCTION.search(line):
            start = i
            while start > 0 and lines[start - 1].strip() and not lines[start - 1].rstrip().endswith((";", "}", "{")) \
                    and not lines[start - 1].lstrip().startswith(("//", "#", "template")):
                start -= 1
            end = i + 1
            while end < len(lines) and depth_at[end] > depth_at[i]:
                end += 1
            yield start + 1, end - start + 0, lines[start].strip()[:90]
            i = end if depth_at[i] == 0 or "TEST_CASE" in lines[start] else i + 1
            continue
        i += 1


def main():
    limit = int(sys.argv[1]) if len(sys.argv) > 1 else 80
    lengths, long = [], []
    for folder in FOLDERS:
        for directory, _, names in os.walk(os.path.join(ROOT, folder)):
            for name in sorted(names):
                if name.endswith((".h", ".cc")):
                    path = os.path.join(directory, name)
                    for line, length, header in functions(path):
                        lengths.append(length)
                        if length > limit:
                            long.append(f"{os.path.relpath(path, ROOT)}:{line}: {length} lines: {header}")
    print(f"{len(lengths)} functions, median {statistics.median(lengths):.0f} lines, {len(long)} over {limit}")
    for entry in long:
        print(entry)
    return 1 if long else 0


if __name__ == "__main__":
    sys.exit(main())
