"""scripts/check_quoted_figures.py fails on what it is there to catch: a quoted figure changed by hand, a result
measured again while the text kept the old figure, and a results.csv older than the stages' CSV files."""
import csv
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCRIPT = os.path.join(ROOT, "scripts", "check_quoted_figures.py")


def run(root, *args):
    return subprocess.run([sys.executable, SCRIPT, *args, str(root)], capture_output=True, text=True)


@pytest.fixture
def copy(tmp_path):
    """README.md, doc/*.md, doc/figure_sources.csv and benchmark/ (CSV files and make_results.py) of the repository."""
    shutil.copy(os.path.join(ROOT, "README.md"), tmp_path)
    shutil.copytree(os.path.join(ROOT, "doc"), tmp_path / "doc", ignore=shutil.ignore_patterns("images", "api", "edits"))
    (tmp_path / "benchmark").mkdir()
    for name in os.listdir(os.path.join(ROOT, "benchmark")):
        if name.endswith(".csv") or name == "make_results.py":
            shutil.copy(os.path.join(ROOT, "benchmark", name), tmp_path / "benchmark")
    return tmp_path


def replace_in(path, old, new):
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, 1))


def test_the_repository_passes():
    result = run(ROOT)
    assert result.returncode == 0, result.stderr


def test_figures_changed_by_hand_fail_each(copy):
    # Three "ours" figures of the headline table changed by 13 %, and one figure of the "beside it" column.
    replace_in(copy / "README.md", "0.0282 / 0.0446 / 0.0746 s", "0.0319 / 0.0504 / 0.0843 s")
    replace_in(copy / "README.md", "0.051 / 6.398 s", "0.058 / 6.398 s")
    result = run(copy)
    assert result.returncode == 1
    for figure in ["0.0319", "0.0504", "0.0843", "0.058"]:
        assert f": {figure} (" in result.stderr, (figure, result.stderr)
    assert "6.398" not in result.stderr


def test_a_result_measured_again_fails_the_text_that_quotes_it(copy):
    # The tentacle's linear editing time of Table 1 is measured again; the README still quotes the old figure.
    rows = list(csv.reader(open(copy / "benchmark" / "editing_results.csv")))
    row = next(r for r in rows if r[0] == "table1" and r[2] == "linear" and r[1].startswith("tentacle"))
    row[7] = "0.0301"
    csv.writer(open(copy / "benchmark" / "editing_results.csv", "w", newline="")).writerows(rows)
    stale = run(copy)
    assert stale.returncode == 1 and "not the merge of the stages' CSV files" in stale.stderr
    subprocess.run([sys.executable, str(copy / "benchmark" / "make_results.py"), "--merge", str(copy / "benchmark")], check=True)
    result = run(copy)
    assert result.returncode == 1
    assert "0.0282 (" in result.stderr and "bench_editing/table1/0/editing_ssps_s is 0.0301" in result.stderr
    # --update writes the new figure with the digits quoted, and the check passes again.
    assert run(copy, "--update").returncode == 0
    assert "0.0301 / 0.0446 / 0.0746 s" in (copy / "README.md").read_text()
    assert run(copy).returncode == 0


def test_update_leaves_figures_that_match_as_they_are_written(copy):
    # Nothing measured again: --update rewrites no page, whatever the form of its figures ("1.28e+03", "6.8e-5").
    pages = sorted((copy / "doc").glob("*.md")) + [copy / "README.md"]
    before = [p.read_text() for p in pages]
    assert run(copy, "--update").returncode == 0
    assert [p.name for p, text in zip(pages, before) if p.read_text() != text] == []


def test_a_figure_added_without_a_source_fails(copy):
    replace_in(copy / "README.md", "| 2.04 s |", "| 2.04 s (2.17 s the run before) |")
    result = run(copy)
    assert result.returncode == 1 and "2.17" in result.stderr and "names no source" in result.stderr


def test_bind_keeps_the_sources_already_named(copy):
    before = [r for r in csv.DictReader(open(copy / "doc" / "figure_sources.csv")) if r["page"] == "README.md"]
    replace_in(copy / "README.md", "| 2.04 s |", "| 2.04 s (1.25 s with one thread) |")
    assert run(copy).returncode == 1
    assert run(copy, "--bind").returncode == 0
    assert run(copy).returncode == 0
    after = [r for r in csv.DictReader(open(copy / "doc" / "figure_sources.csv")) if r["page"] == "README.md"]
    added = next(i for i, r in enumerate(after) if r["quoted"] == "1.25" and i > 0 and after[i - 1]["quoted"] == "2.04")
    assert [(r["quoted"], r["key"], r["scale"]) for r in after[:added] + after[added + 1:]] == \
        [(r["quoted"], r["key"], r["scale"]) for r in before]
