#!/usr/bin/env python3
"""Checks that every measured figure README.md and the manual quote from the benchmark comes from a committed
result file of the harness: each number with a decimal point, or of three digits or more, in README's headline
table ("ours" column) and between the markers

    <!-- figures from benchmark/ -->  ...  <!-- end of figures from benchmark/ -->

in doc/*.md must appear in benchmark/RESULTS.md or one of benchmark/*_results.md, to the digits quoted (0.97
matches 0.970 or 0.9712; thousands separators are ignored). The ends of a range ("0.05-0.17 s") are figures
like any other; a ratio the text derives from figures ("1.4 times", "2x"), a size ("416k", "1.66M"), code and
links are exempt.

Usage: scripts/check_quoted_figures.py [REPOSITORY]   (exit status 1 and the missing figures when one is not found)
"""
import glob
import os
import re
import sys

NUMBER = re.compile(r"(?<![\w.])\d[\d,]*(?:\.\d+)?")
EXEMPT = re.compile(r"\s*(?:times\b|x\b|×)|[kM]\b")  # a ratio ("2.5 times", "3x") or a size ("416k", "1.66M")
BLOCK = re.compile(r"<!-- figures from benchmark/ -->(.*?)<!-- end of figures from benchmark/ -->", re.S)
CODE_OR_LINK = re.compile(r"`[^`]*`|\]\([^)]*\)")


def numbers(text, skip_ratios=False):
    found = set()
    for match in NUMBER.finditer(text):
        if skip_ratios and EXEMPT.match(text, match.end()):
            continue
        token = match.group(0).rstrip(",")
        value = token.replace(",", "")
        if "." in value or len(value) >= 3:
            found.add(value)
    return found


def headline_rows(readme):
    """The rows of the table after "Headlines of the latest run", as lists of cells."""
    lines = readme.splitlines()
    start = next((i for i, line in enumerate(lines) if "Headlines of the latest run" in line), None)
    if start is None:
        sys.exit("check_quoted_figures.py: README.md has no 'Headlines of the latest run' table")
    rows = []
    for line in lines[start + 1:]:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not all(set(c) <= set("-: ") for c in cells):
                rows.append(cells)
        elif rows:
            break
    return rows[1:]  # without the header


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    with open(os.path.join(root, "README.md")) as f:
        rows = headline_rows(f.read())
    results = ""
    for path in [os.path.join(root, "benchmark", "RESULTS.md")] + sorted(glob.glob(os.path.join(root, "benchmark", "*_results.md"))):
        with open(path) as f:
            results += f.read() + "\n"
    # Every result figure rounded to 0-4 decimals: a quote may give fewer digits than the file.
    available = set()
    for value in numbers(results):
        for decimals in range(5):
            available.add(f"{round(float(value), decimals):.{decimals}f}")
    missing = []
    for page in sorted(glob.glob(os.path.join(root, "doc", "*.md"))):
        with open(page) as f:
            blocks = BLOCK.findall(f.read())
        for block in blocks:
            for line in block.splitlines():
                for value in sorted(numbers(CODE_OR_LINK.sub("", line), skip_ratios=True)):
                    if value not in available:
                        missing.append(f"{value} (doc/{os.path.basename(page)}: {line.strip()[:70]})")
    for cells in rows:
        if len(cells) < 2:
            continue
        for value in sorted(numbers(cells[1])):
            if value not in available:
                missing.append(f"{value} ({cells[0]})")
    if missing:
        print("check_quoted_figures.py: README.md or doc/ quotes figures that no committed result file holds:", file=sys.stderr)
        for m in missing:
            print("  " + m, file=sys.stderr)
        sys.exit(1)
    print(f"check_quoted_figures.py: every figure of README.md's {len(rows)} headline rows and of doc/'s marked blocks is in benchmark/")


if __name__ == "__main__":
    main()
