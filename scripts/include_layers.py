#!/usr/bin/env python3
"""Prints which of the package's headers include which, layer by layer, and checks the one rule the layering
keeps today: a header under include/CGAL_ext/internal/ includes only other internal headers and the value
types (exceptions.h, Detail_filter.h and the *_settings.h headers), never an algorithm header.

Layers, bottom up: value types, internal, algorithms (every other public header). The report lists, for each
header, the package headers it includes, and then the edges between algorithm headers (an algorithm that
reaches into another instead of sharing an internal header).

Usage: scripts/include_layers.py [--check] [REPOSITORY]   (--check: exit status 1 and the offending includes
when an internal header includes an algorithm header; no report)
"""
import glob
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*<CGAL_ext/([^>]+)>', re.M)


def layer(header):
    name = os.path.basename(header)
    if header.startswith("internal/"):
        return "internal"
    if name in ("exceptions.h", "Detail_filter.h") or name.endswith("_settings.h"):
        return "value types"
    return "algorithms"


def include_graph(root):
    base = os.path.join(root, "include", "CGAL_ext")
    graph = {}
    for path in sorted(glob.glob(os.path.join(base, "*.h")) + glob.glob(os.path.join(base, "internal", "*.h"))):
        header = os.path.relpath(path, base).replace(os.sep, "/")
        with open(path, encoding="utf-8") as f:
            graph[header] = sorted(set(INCLUDE.findall(f.read())))
    return graph


def main(argv):
    check = "--check" in argv
    args = [a for a in argv if a != "--check"]
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    graph = include_graph(root)
    violations = [(h, d) for h, deps in graph.items() if layer(h) == "internal"
                  for d in deps if layer(d) == "algorithms"]
    if check:
        for h, d in violations:
            print(f"include_layers.py: internal header {h} includes the algorithm header {d}")
        return 1 if violations else 0
    for name in ("value types", "internal", "algorithms"):
        members = [h for h in graph if layer(h) == name]
        print(f"## {name} ({len(members)} headers)\n")
        for h in members:
            print(f"- {h}: {', '.join(graph[h]) or '(none)'}")
        print()
    across = [(h, d) for h, deps in graph.items() if layer(h) == "algorithms" for d in deps if layer(d) == "algorithms"]
    print(f"## algorithm headers including algorithm headers ({len(across)})\n")
    for h, d in across:
        print(f"- {h} -> {d}")
    print(f"\ninternal headers including algorithm headers: {len(violations)}")
    return 1 if violations else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
