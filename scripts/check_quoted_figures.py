#!/usr/bin/env python3
"""Checks that every measured figure README.md and the manual quote is the value of a named result.

A quoted figure is a number with a decimal point, or of three digits or more, between the markers

    <!-- figures from benchmark/ -->  ...  <!-- end of figures from benchmark/ -->
    <!-- figures from benchmark/: bench_upsampling bench_editing/arap -->  ...  (from these results only)

in README.md or doc/*.md. doc/figure_sources.csv names the source of each, in the order they appear: a key of
benchmark/results.csv (source/section/row/column, section left out when empty; several keys, separated by spaces,
when results that held the same value could each be the one quoted: then all must match) and the factor between the
result and the quote (1000 for seconds quoted in milliseconds, 100 for a fraction quoted in per cent); a number
of a block that is no measurement has the key "(setting)" (an input size, a setting, a budget, a year) or
"(derived)" (computed by the text from results, as nonzeros per row from nonzeros and rows). The check
fails when a block's figures differ from the list (one was added, removed or changed by hand), when the value at
a key, scaled and rounded to the digits quoted, differs from the quote (a result was measured again and the text
was not updated), or when benchmark/results.csv is not the merge of the stages' CSV files. Exempt: a ratio the
text derives from figures ("1.4 times", "2x"), a size ("416k", "1.66M"), code and links.

Usage: scripts/check_quoted_figures.py [--bind | --update] [REPOSITORY]
  --bind    names a source for each figure the list lacks (and drops the entries of figures no longer quoted;
            the others keep theirs):
            the key whose value matches, preferring the result row that holds most of the line's other figures;
            prints the figures it could not place or placed by a guess, for a person to check
  --update  rewrites every bound figure from the current results (after a benchmark run), keeping its digits
"""
import csv
import difflib
import glob
import importlib.util
import os
import re
import sys

NUMBER = re.compile(r"(?<![\w.])\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?")
# Figures chained to the next one ("3.6-3.9 s", "1.1 / 2.0 ms", "1.1 and 1.2 times") share its unit.
CHAIN = r"(?:\*\*)?(?:\s*(?:-|–|/|,|and|to|→)\s*(?:\*\*)?[\d,.]+(?:e[-+]?\d+)?(?:\*\*)?(?:\s*h)?)*"
EXEMPT = re.compile(CHAIN + r"(?:\s*(?:times\b|x\b|×)|[kM]\b)")  # a ratio ("2.5 times", "3x") or a size ("416k", "1.66M")
BLOCK = re.compile(r"(<!-- figures from benchmark/(?:: ([^>]*?))? -->)(.*?)(<!-- end of figures from benchmark/ -->)", re.S)
CODE_OR_LINK = re.compile(r"`[^`]*`|\]\([^)]*\)")
SCALES = [1, 1000, 100, 1 / 1024]  # as quoted, in ms, in per cent, in GiB of MiB
SOURCES = "doc/figure_sources.csv"


def figures(line):
    """(start, end, text) of each quoted figure of a line, code and links left out."""
    masked = CODE_OR_LINK.sub(lambda m: " " * len(m.group(0)), line)
    found = []
    for match in NUMBER.finditer(masked):
        token = match.group(0).rstrip(",")
        value = token.replace(",", "")
        if EXEMPT.match(masked, match.start() + len(token)) or not ("." in value or len(value) >= 3):
            continue
        found.append((match.start(), match.start() + len(token), token))
    return found


def pages(root):
    return ["README.md"] + sorted(os.path.relpath(p, root) for p in glob.glob(os.path.join(root, "doc", "*.md")))


UNIT = re.compile(CHAIN + r"\s*(ms|s|%|MiB|GiB|B|h)(?![\w])")


def unit_after(line, end, header=""):
    """The unit a figure is quoted in: the one after it or after the figures chained to it ("0.1 / 0.2 s",
    "3.6-3.9 s"), else the one that ends its table column's header ("preprocess s")."""
    match = UNIT.match(line, end)
    if match:
        return match.group(1)
    match = re.search(r"\b(ms|s|MiB|GiB|B|h)\)?$|(%)", header.strip())
    return (match.group(1) or match.group(2)) if match else ""


def declared(root):
    """{(page, block): the result sources (source or source/section) its marker names, or None for any}."""
    out = {}
    for page in pages(root):
        with open(os.path.join(root, page)) as f:
            for b, match in enumerate(BLOCK.finditer(f.read())):
                out[(page, b)] = match.group(2).split() if match.group(2) else None
    return out


def from_declared(key, sources):
    return sources is None or any(key == s or key.startswith(s + "/") for s in sources)


def quoted(root):
    """{(page, block): [(line, text, unit)]} of every figure in every marked block, in order."""
    out = {}
    for page in pages(root):
        with open(os.path.join(root, page)) as f:
            for b, match in enumerate(BLOCK.finditer(f.read())):
                found, header = [], []
                lines = match.group(3).splitlines()
                for n, line in enumerate(lines):
                    following = lines[n + 1] if n + 1 < len(lines) and not line.startswith("|") else ""
                    if line.startswith("|") and not header:
                        header = line.strip().strip("|").split("|")
                    elif not line.startswith("|"):
                        header = []
                    for start, end, text in figures(line):
                        cell = line[:start].count("|") - 1
                        column = header[cell] if line.startswith("|") and 0 <= cell < len(header) else ""
                        found.append((line, text, unit_after(line + " " + following.strip(), end, column)))
                out[(page, b)] = found
    return out


def fits_unit(key, scale, unit):
    column = key.rsplit("/", 1)[1]
    if column == "value":  # a row of (measure, value, unit): the unit is the row's own
        return scale == 1
    return {"s": column.endswith("_s") and scale == 1, "ms": column.endswith("_s") and scale == 1000,
            "%": scale in (100, 1) and not column.endswith(("_s", "_mib", "_h", "points", "count", "ssps"))
            and column not in ("iterations", "cg_iterations"), "MiB": "mib" in column and scale == 1, "GiB": ("gib" in column and scale == 1) or
            ("mib" in column and scale == 1 / 1024), "B": "bytes" in column and scale == 1,
            "h": column.endswith("_h") and scale == 1}.get(unit, scale == 1)


def preference(key, scale):
    """Among equally supported sources: a median before its minimum or maximum, plain figures before scaled ones."""
    column = key.rsplit("/", 1)[1]
    return (column.endswith(("_min_s", "_max_s")) or column in ("min_s", "max_s"), scale != 1, key)


def results(root):
    with open(os.path.join(root, "benchmark", "results.csv"), newline="") as f:
        rows = list(csv.reader(f))[1:]
    values = {}
    for source, section, row, column, value in rows:
        try:
            values["/".join(p for p in (source, section, row, column) if p)] = float(value)
        except ValueError:
            pass
    return rows, values


def merged_results(root):
    """results.csv as benchmark/make_results.py would write it from the stages' CSV files now."""
    spec = importlib.util.spec_from_file_location("make_results", os.path.join(root, "benchmark", "make_results.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.long_rows(os.path.join(root, "benchmark"))


def digits(text):
    """The decimals of a quote ("0.97": 2; "6.8e-5": 1) and its exponent (-5, or 0)."""
    mantissa, _, exponent = text.replace(",", "").partition("e")
    return (len(mantissa.split(".")[1]) if "." in mantissa else 0), int(exponent or 0)


def render(value, scale, like):
    """The value times scale, written as the quote `like` is: its decimals, exponent and thousands separators."""
    decimals, exponent = digits(like)
    value *= float(scale)
    if "e" in like:
        mantissa, _, power = f"{value:.{decimals}e}".partition("e")
        written = like.replace(",", "").partition("e")[2]  # "-5", "3" or "+03": its sign and width kept
        sign = "-" if int(power) < 0 else "+" if written.startswith("+") else ""
        return f"{mantissa}e{sign}{abs(int(power)):0{len(written.lstrip('+-'))}d}"
    return f"{value:,.{decimals}f}" if "," in like else f"{value:.{decimals}f}"


def matches(value, scale, text):
    decimals, exponent = digits(text)
    target = float(text.replace(",", ""))
    return abs(value * float(scale) - target) <= 0.5 * 10 ** (exponent - decimals) * (1 + 1e-9) + 1e-300


def read_sources(root):
    path = os.path.join(root, SOURCES)
    if not os.path.exists(path):
        return {}
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            out.setdefault((r["page"], int(r["block"])), []).append(r)
    return out


def write_sources(root, bound):
    with open(os.path.join(root, SOURCES), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")  # the file's own line ends
        w.writerow(["page", "block", "figure", "quoted", "key", "scale"])
        for (page, block), entries in sorted(bound.items()):
            for i, e in enumerate(entries):
                w.writerow([page, block, i, e["quoted"], e["key"], e["scale"]])


def row_of(key):
    return key.rsplit("/", 1)[0]


CANDIDATES = {}


def candidates_of(text, values):
    """Every (key, scale) whose value matches the quote."""
    if text not in CANDIDATES:
        CANDIDATES[text] = [(k, s) for k, v in values.items() for s in SCALES if matches(v, s, text)]
    return CANDIDATES[text]


def row_labels(root):
    """{result row: its text fields} (model, method, stage ...), to find the row a line of the text names."""
    rows, _ = results(root)
    labels = {}
    for source, section, row, column, value in rows:
        try:
            float(value)
        except ValueError:
            if len(value) >= 3:
                labels.setdefault("/".join(p for p in (source, section, row) if p), []).append(value.lower())
    return labels


def named_by(labels, row, text):
    """How many of a result row's text fields the text names ("camel", "closed_form" as "closed form")."""
    text = text.lower()
    return sum(1 for label in labels.get(row, []) if label in text or label.replace("_", " ") in text)


def bind(root, values):
    """Names a source for each figure without one; returns the figures a person should look at."""
    labels = row_labels(root)
    old = read_sources(root)
    bound, doubtful = {}, []
    sources = declared(root)
    for (page, block), found in quoted(root).items():
        # Figures the list already names keep their source (a person may have chosen it); only the others are bound.
        previous = old.get((page, block), [])
        kept = {}
        matcher = difflib.SequenceMatcher(a=[p["quoted"] for p in previous], b=[t for _, t, _ in found], autojunk=False)
        for tag, i1, i2, j1, j2 in matcher.get_opcodes():
            if tag == "equal":
                kept.update({j1 + k: previous[i1 + k] for k in range(i2 - i1)})
        if len(kept) == len(found):
            bound[(page, block)] = [kept[j] for j in range(len(found))]
            continue
        entries = []
        lines = {}
        for line, text, unit in found:
            lines.setdefault(line, []).append((text, unit))

        def plausible(text, unit, allowed=sources[(page, block)]):
            all_of = [c for c in candidates_of(text, values) if from_declared(c[0], allowed)]
            return [c for c in all_of if fits_unit(c[0], c[1], unit)]

        # The result tables (source and section) that hold most of the block's figures.
        tables = {}
        for text, unit in {(t, u) for _, t, u in found}:
            for table in {row_of(row_of(k)) for k, _ in plausible(text, unit)}:
                tables[table] = tables.get(table, 0) + 1

        for j, (line, text, unit) in enumerate(found):
            if j in kept:
                entries.append(kept[j])
                continue
            candidates = plausible(text, unit)
            # The result row that holds most of this line's figures.
            support = {}
            for other in lines[line]:
                for row in {row_of(k) for k, _ in plausible(*other)}:
                    support[row] = support.get(row, 0) + 1
            def rank(c):
                row = support.get(row_of(c[0]), 0)
                return (-named_by(labels, row_of(c[0]), line), -(row if row > 1 else 0),
                        -tables.get(row_of(row_of(c[0])), 0)) + preference(*c)

            candidates = sorted(candidates, key=rank)
            if not candidates:
                doubtful.append(f"{page} block {block}: {text} has no source ({line.strip()[:80]})")
                entries.append({"quoted": text, "key": "", "scale": "1"})
                continue
            best = candidates[0]
            rivals = [c for c in candidates[1:] if rank(c)[:5] == rank(best)[:5]]
            # Results of the same rank hold the same value: the text does not tell which one it quotes, so all of
            # them stay named, and a later run that changes any of them fails the check (never a silent pass).
            rivals = [c for c in rivals if c[1] == best[1]]
            if rivals:
                doubtful.append(f"{page} block {block}: {text} -> {best[0]} x{best[1]:g} or {len(rivals)} more "
                                f"({line.strip()[:60]})")
            entries.append({"quoted": text, "key": " ".join(k for k, _ in [best] + rivals), "scale": f"{best[1]:g}"})
        bound[(page, block)] = entries
    write_sources(root, bound)
    return doubtful


def update(root, values):
    sources = read_sources(root)
    for page in pages(root):
        path = os.path.join(root, page)
        with open(path) as f:
            text = f.read()

        def rewrite(match, page=page):
            block = sum(1 for _ in BLOCK.finditer(text[:match.start()]))
            entries = iter(sources.get((page, block), []))
            out = []
            for line in match.group(3).split("\n"):
                pieces, at = [], 0
                for start, end, quote in figures(line):
                    e = next(entries, None)
                    keys = e["key"].split() if e else []
                    if e is None or e["quoted"] != quote or not keys or any(k not in values for k in keys):
                        continue
                    fresh = {render(values[k], e["scale"], quote) for k in keys}
                    if len(fresh) > 1:
                        print(f"check_quoted_figures.py: {page}: {quote} names results that now differ "
                              f"({', '.join(sorted(fresh))}): left as it is, for a person to choose", file=sys.stderr)
                        continue
                    e["quoted"] = fresh.pop()
                    pieces += [line[at:start], e["quoted"]]
                    at = end
                out.append("".join(pieces) + line[at:])
            return match.group(1) + "\n".join(out) + match.group(4)

        new = BLOCK.sub(rewrite, text)
        if new != text:
            with open(path, "w") as f:
                f.write(new)
            print(f"check_quoted_figures.py: updated {page}")
    write_sources(root, sources)


def check(root, values):
    problems = []
    merged = merged_results(root)
    rows, _ = results(root)
    if merged != rows:
        problems.append("benchmark/results.csv is not the merge of the stages' CSV files: run "
                        "benchmark/make_results.py --merge benchmark")
    sources = read_sources(root)
    allowed = declared(root)
    count = unmeasured = 0
    quoted_blocks = quoted(root)
    for (page, block), found in quoted_blocks.items():
        entries = sources.get((page, block), [])
        for i, (line, text, _) in enumerate(found):
            count += 1
            e = entries[i] if i < len(entries) else None
            where = f"{page}, figure block {block}: {text} ({line.strip()[:70]})"
            if e is None or e["quoted"] != text:
                problems.append(f"{where}: {SOURCES} names no source for it (--bind names one)")
            elif e["key"] in ("(setting)", "(derived)"):
                unmeasured += 1
            elif not e["key"].split():
                problems.append(f"{where}: {SOURCES} names no source for it")
            else:
                for key in e["key"].split():
                    if not from_declared(key, allowed[(page, block)]):
                        problems.append(f"{where}: its key '{key}' is not from the results the block's marker names")
                    elif key not in values:
                        problems.append(f"{where}: its key '{key}' is not in benchmark/results.csv")
                    elif not matches(values[key], e["scale"], text):
                        problems.append(f"{where}: the result at {key} is {render(values[key], e['scale'], text)}")
        if len(entries) > len(found):
            problems.append(f"{page}, figure block {block}: {SOURCES} lists {len(entries)} figures, the block quotes {len(found)}")
    for (page, block) in sources.keys() - quoted_blocks.keys():
        problems.append(f"{page}: {SOURCES} lists figure block {block}, which the page does not have")
    if problems:
        print("check_quoted_figures.py: figures that do not match their results:", file=sys.stderr)
        for p in problems:
            print("  " + p, file=sys.stderr)
        sys.exit(1)
    print(f"check_quoted_figures.py: each of the {count - unmeasured} figures quoted in README.md and doc/ is the value "
          f"at its key of benchmark/results.csv ({unmeasured} more are settings or derived)")


def main():
    args = sys.argv[1:]
    mode = args.pop(0) if args and args[0].startswith("--") else None
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    _, values = results(root)
    if mode == "--bind":
        for d in bind(root, values):
            print(d)
    elif mode == "--update":
        update(root, values)
    elif mode is None:
        check(root, values)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
