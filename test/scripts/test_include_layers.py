"""scripts/include_layers.py --check fails on each rule of the layering: an internal header that includes an
algorithm header, an algorithm header that includes another, and a public header over its line budget."""
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCRIPT = os.path.join(ROOT, "scripts", "include_layers.py")


def check(root):
    return subprocess.run([sys.executable, SCRIPT, "--check", str(root)], capture_output=True, text=True)


@pytest.fixture
def copy(tmp_path):
    """The repository's include/ tree."""
    shutil.copytree(os.path.join(ROOT, "include"), tmp_path / "include")
    return tmp_path


def add_include(path, included):
    text = path.read_text()
    first = text.index("#include")
    path.write_text(text[:first] + f"#include <CGAL_ext/{included}>\n" + text[first:])


def test_the_repository_passes():
    result = check(ROOT)
    assert result.returncode == 0, result.stdout


def test_an_internal_header_including_an_algorithm_fails(copy):
    add_include(copy / "include/CGAL_ext/internal/Laplacian.h", "compute_geometric_details.h")
    result = check(copy)
    assert result.returncode == 1
    assert "internal header internal/Laplacian.h includes the algorithm header compute_geometric_details.h" in result.stdout


def test_an_algorithm_including_another_fails(copy):
    add_include(copy / "include/CGAL_ext/scale_geometric_details.h", "compute_geometric_details.h")
    result = check(copy)
    assert result.returncode == 1
    assert "scale_geometric_details.h includes the algorithm header compute_geometric_details.h" in result.stdout


def test_a_header_over_its_budget_fails(copy):
    header = copy / "include/CGAL_ext/upsample_point_set.h"
    lines = header.read_text().count("\n")
    header.write_text(header.read_text() + "// a line\n" * (451 - lines))
    result = check(copy)
    assert result.returncode == 1
    assert "upsample_point_set.h has 451 lines, over its budget of 450" in result.stdout
    header.write_text(header.read_text().replace("// a line\n", "", 1))
    assert check(copy).returncode == 0, "450 lines are within the budget"


def test_a_view_including_an_algorithm_or_included_by_an_internal_header_fails(copy):
    add_include(copy / "include/CGAL_ext/Diffusion_view.h", "compute_geometric_details.h")
    add_include(copy / "include/CGAL_ext/internal/point_diffusion.h", "Diffusion_view.h")
    result = check(copy)
    assert result.returncode == 1
    assert "view Diffusion_view.h includes the algorithm header compute_geometric_details.h" in result.stdout
    assert "internal header internal/point_diffusion.h includes the view Diffusion_view.h" in result.stdout


def test_the_editing_class_includes_its_view_within_the_rules():
    result = check(ROOT)
    assert result.returncode == 0
    report = subprocess.run([sys.executable, SCRIPT, str(ROOT)], capture_output=True, text=True).stdout
    assert "- Detail_preserving_deformation.h: " in report and "Diffusion_view.h" in report.split("## views")[1]
