#!/usr/bin/env python3
"""The include graph of the project's own headers, as issue 94 measures it.

Prints (1) circular includes between the top-level folders (a folder that includes from one that includes from it),
(2) header cycles (a header that includes itself through others), (3) includes back up: a source file that includes
a header which itself includes the file's own header (a helper reaching up to what is built on it), and one stage's
helper including another stage's header (stages/*/NAME_stage.h from anything but that stage and the registry).
Exits 1 when any is found.  Usage: python3 scripts/include_graph.py [ROOT]
"""
import os
import re
import sys

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
FOLDERS = ["base", "formats", "nerf", "mesh", "splat", "viewer", "pipeline", "stages", "cli", "examples", "bench",
           "tests"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def sources():
    for folder in FOLDERS:
        for directory, _, names in os.walk(os.path.join(ROOT, folder)):
            for name in names:
                if name.endswith((".h", ".cc")):
                    path = os.path.relpath(os.path.join(directory, name), ROOT)
                    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
                        yield path, [i for i in INCLUDE.findall(f.read()) if os.path.exists(os.path.join(ROOT, i))]


def closure(graph, start):
    seen, todo = set(), [start]
    while todo:
        for nxt in graph.get(todo.pop(), []):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


def main():
    graph = dict(sources())
    problems = []
    top = lambda path: path.split("/")[0]
    uses = {}
    for path, includes in graph.items():
        for inc in includes:
            if top(inc) != top(path):
                uses.setdefault(top(path), set()).add(top(inc))
    for a in sorted(uses):
        for b in sorted(uses[a]):
            if a < b and a in uses.get(b, set()):
                problems.append(f"folders {a}/ and {b}/ include from each other")
    for path in sorted(graph):
        if path.endswith(".h") and path in closure(graph, path):
            problems.append(f"header cycle through {path}")
    for path in sorted(graph):
        own = path[:-3] + ".h" if path.endswith(".cc") else None
        for inc in graph[path]:
            if own and inc != own and own in graph and own in closure(graph, inc):
                problems.append(f"{path} includes {inc}, which includes {own}: back up")
            stage = re.match(r"stages/\w+/(\w+)_stage\.h$", inc)
            if stage and not path.startswith(inc[:-2]) and path != "stages/stages.cc" and top(path) == "stages":
                problems.append(f"{path} includes another stage's header {inc}")
    files = len(graph)
    edges = sum(len(v) for v in graph.values())
    print(f"{files} files, {edges} includes of the project's own headers")
    for problem in problems:
        print(problem)
    print(f"{len(problems)} circular or back-up includes")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
