#!/usr/bin/env python3
"""Prints which of the package's headers include which, layer by layer, and checks the rules the layering
keeps: a header under include/CGAL_ext/internal/ includes only other internal headers and the value types
(exceptions.h, setting_names.h, Detail_filter.h, neighbor_radius_map.h and the *_settings.h headers), never an algorithm header or a
view; a view (a public type an algorithm hands out over its internal parts, as Diffusion_view.h) includes no
algorithm header; an algorithm header includes no other algorithm header (what two algorithms share lives in
internal/); and no public header is longer than its line budget, so that an algorithm stays a thin layer over
its internal parts.

Layers, bottom up: value types, internal, views, algorithms (every other public header). The report lists, for
each header, the package headers it includes, then the edges between algorithm headers and the headers over
budget.

Usage: scripts/include_layers.py [--check] [REPOSITORY]   (--check: exit status 1 and the broken rules, no
report)
"""
import glob
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*<CGAL_ext/([^>]+)>', re.M)

# Lines a public header may have: its declarations, their Doxygen comments and a driver over internal/.
LINE_BUDGET = 450
# Headers allowed more, with the reason. Lower a budget when a header shrinks; raise one only for new public API,
# named here, never for the algorithm's code. None today.
LINE_BUDGET_EXCEPTIONS = {}
# The views: public types an algorithm hands out over its internal parts.
VIEWS = ("Diffusion_view.h",)


def layer(header):
    name = os.path.basename(header)
    if header.startswith("internal/"):
        return "internal"
    if name in VIEWS:
        return "views"
    if name in ("exceptions.h", "setting_names.h", "Detail_filter.h", "neighbor_radius_map.h") or \
            name.endswith("_settings.h"):
        return "value types"
    return "algorithms"


def line_budget(header):
    return LINE_BUDGET_EXCEPTIONS.get(header, LINE_BUDGET)


def include_graph(root):
    base = os.path.join(root, "include", "CGAL_ext")
    graph, lines = {}, {}
    for path in sorted(glob.glob(os.path.join(base, "*.h")) + glob.glob(os.path.join(base, "internal", "*.h"))):
        header = os.path.relpath(path, base).replace(os.sep, "/")
        with open(path, encoding="utf-8") as f:
            text = f.read()
        graph[header] = sorted(set(INCLUDE.findall(text)))
        lines[header] = text.count("\n")
    return graph, lines


def main(argv):
    check = "--check" in argv
    args = [a for a in argv if a != "--check"]
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    graph, lines = include_graph(root)
    violations = [(h, d) for h, deps in graph.items() if layer(h) in ("internal", "views")
                  for d in deps if layer(d) == "algorithms" or (layer(h), layer(d)) == ("internal", "views")]
    across = [(h, d) for h, deps in graph.items() if layer(h) == "algorithms" for d in deps if layer(d) == "algorithms"]
    over = [(h, n) for h, n in lines.items() if not h.startswith("internal/") and n > line_budget(h)]
    broken = len(violations) + len(across) + len(over)
    if check:
        for h, d in violations:
            print(f"include_layers.py: {'internal header' if layer(h) == 'internal' else 'view'} {h} includes the "
                  f"{'algorithm header' if layer(d) == 'algorithms' else 'view'} {d}")
        for h, d in across:
            print(f"include_layers.py: algorithm header {h} includes the algorithm header {d}; share an internal "
                  "header instead")
        for h, n in over:
            print(f"include_layers.py: {h} has {n} lines, over its budget of {line_budget(h)}; move its parts "
                  "into internal/")
        return 1 if broken else 0
    for name in ("value types", "internal", "views", "algorithms"):
        members = [h for h in graph if layer(h) == name]
        print(f"## {name} ({len(members)} headers)\n")
        for h in members:
            print(f"- {h}: {', '.join(graph[h]) or '(none)'}")
        print()
    print(f"## algorithm headers including algorithm headers ({len(across)})\n")
    for h, d in across:
        print(f"- {h} -> {d}")
    print(f"\n## public headers over their line budget ({len(over)})\n")
    for h, n in over:
        print(f"- {h}: {n} lines (budget {line_budget(h)})")
    largest = sorted(((n, h) for h, n in lines.items() if not h.startswith("internal/")), reverse=True)[:5]
    print("\nlargest public headers: " + ", ".join(f"{h} {n}" for n, h in largest))
    print(f"\ninternal headers and views including what they may not: {len(violations)}")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
