"""scripts/check_format.sh fails on a changed C++ line that .clang-format would lay out otherwise, and passes
on a formatted change and on unchanged code written before .clang-format, however it is laid out."""
import os
import shutil
import subprocess

import pytest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")

OLD_CODE = "int  old_layout( int a ){return a;}\n"  # before .clang-format: never checked


def git(repo, *args):
    subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True, text=True)


@pytest.fixture
def repo(tmp_path):
    """A repository with the project's script and .clang-format, committed over code of another layout."""
    if shutil.which("clang-format-diff-14") is None:
        pytest.skip("clang-format-14 is not installed (scripts/setup.sh installs it)")
    (tmp_path / "scripts").mkdir()
    shutil.copy(os.path.join(ROOT, "scripts", "check_format.sh"), tmp_path / "scripts")
    (tmp_path / "code.cpp").write_text(OLD_CODE)
    git(tmp_path, "init", "-q")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "add", ".")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "code")
    shutil.copy(os.path.join(ROOT, ".clang-format"), tmp_path / ".clang-format")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "add", ".clang-format")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "layout")
    return tmp_path


def check(repo):
    return subprocess.run(["bash", str(repo / "scripts" / "check_format.sh")], capture_output=True, text=True)


def test_unchanged_code_passes(repo):
    assert check(repo).returncode == 0


def test_a_formatted_change_passes(repo):
    (repo / "code.cpp").write_text(OLD_CODE + "\nint added(int a)\n{\n  if(a > 0) return a;\n  return -a;\n}\n")
    result = check(repo)
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.mark.parametrize("line", ["int added( int a ) { return a; }\n",          # spaces inside parentheses
                                  "int added(int a) { if (a) return a; return 0; }\n",  # if (
                                  "int x = " + " + ".join(["1"] * 60) + ";\n"])    # over 120 columns
def test_a_change_off_the_layout_fails(repo, line):
    (repo / "code.cpp").write_text(OLD_CODE + line)
    result = check(repo)
    assert result.returncode == 1
    assert "not laid out as .clang-format says" in result.stderr


def test_a_committed_change_is_checked_too(repo):
    (repo / "code.cpp").write_text(OLD_CODE + "int added( int a ) { return a; }\n")
    git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-am", "change")
    assert check(repo).returncode == 1
