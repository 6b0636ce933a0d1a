# The package installed like any Python package (doc/python.md, "Install"): a wheel built by `python3 -m build`
# from the CMake build tree CGAL_EXT_CMAKE_BUILD_DIR (nothing compiled again), installed by pip into a fresh
# virtual environment and uninstalled; and `cmake --install` of the same tree into a prefix. Each subprocess runs
# outside the repository without PYTHONPATH (ctest points it at the build tree), so that the package imported is
# the installed one.
import os
import re
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD_DIR = os.environ.get("CGAL_EXT_CMAKE_BUILD_DIR")
pytestmark = pytest.mark.skipif(not BUILD_DIR, reason="CGAL_EXT_CMAKE_BUILD_DIR (a configured CMake build tree, "
                                "as ctest's python_install sets it) is not set")


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\s*\(\s*CGAL_ext\b[^)]*?\bVERSION\s+([0-9][0-9A-Za-z.]*)", text).group(1)


def clean_environment():
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "PIP_", "VIRTUAL_ENV"))}
    env.update(PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1", PYTHONDONTWRITEBYTECODE="1")
    return env


def run(command, cwd, env=None, check=True):
    result = subprocess.run([str(c) for c in command], cwd=cwd, env=env or clean_environment(),
                            capture_output=True, text=True)
    if check:
        assert result.returncode == 0, "%s failed:\n%s\n%s" % (" ".join(map(str, command)), result.stdout,
                                                               result.stderr)
    return result


REPORT = """
import importlib.metadata, sys
try:
    import cgal_ext
except ImportError as e:
    print("ImportError", e)
    sys.exit(0)
print(cgal_ext.__version__)
print(cgal_ext.__file__)
print(cgal_ext._core.__file__)
print(importlib.metadata.version("cgal_ext"))
"""


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The wheel `python3 -m build --no-isolation --wheel` makes from the CMake build tree."""
    outdir = tmp_path_factory.mktemp("wheel")
    env = clean_environment()
    env["CGAL_EXT_CMAKE_BUILD_DIR"] = BUILD_DIR
    run([sys.executable, "-m", "build", "--no-isolation", "--wheel", "--outdir", outdir, ROOT], cwd=outdir, env=env)
    wheels = list(outdir.glob("*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


def test_wheel_is_the_whole_package_for_this_platform(wheel):
    version = project_version()
    # A platform wheel (it holds the extension) for this interpreter, named by the CMake project's version.
    assert wheel.name.startswith("cgal_ext-%s-" % version), wheel.name
    assert not wheel.name.endswith("-none-any.whl"), wheel.name
    names = zipfile.ZipFile(wheel).namelist()
    package = {n for n in names if n.startswith("cgal_ext/")}
    extension = "cgal_ext/_core" + sysconfig.get_config_var("EXT_SUFFIX")
    for name in [extension, "cgal_ext/__init__.py", "cgal_ext/_version.py", "cgal_ext/_core.pyi",
                 "cgal_ext/py.typed"]:
        assert name in package, (name, names)
    # Nothing but the package and its metadata: no CMake leftovers, build trees, data or caches.
    dist_info = "cgal_ext-%s.dist-info/" % version
    assert all(n.startswith(dist_info) or n in package for n in names), names
    assert not [n for n in names if n.endswith((".in", ".pyc")) or "__pycache__" in n or "/build/" in n
                or n.startswith(("data/", "build/"))], names


def test_pip_installs_and_uninstalls_the_wheel_in_a_fresh_venv(wheel, tmp_path):
    version = project_version()
    venv = tmp_path / "venv"
    run([sys.executable, "-m", "venv", "--system-site-packages", venv], cwd=tmp_path)
    python = venv / "bin" / "python"
    site = Path(run([python, "-c", "import sysconfig; print(sysconfig.get_path('platlib'))"],
                    cwd=tmp_path).stdout.strip())
    assert site.resolve().is_relative_to(venv.resolve()), site
    # A copy installed system-wide would be seen through --system-site-packages: then only the venv's is checked.
    before = run([python, "-c", REPORT], cwd=tmp_path).stdout.split("\n")
    system_copy = before[0] != "ImportError"

    run([venv / "bin" / "pip", "install", "--no-deps", "--no-index", wheel], cwd=tmp_path)
    lines = run([python, "-c", REPORT], cwd=tmp_path).stdout.split("\n")
    assert lines[0] == version, lines
    for module_file in lines[1:3]:
        assert Path(module_file).resolve().is_relative_to((site / "cgal_ext").resolve()), (module_file, site)
    assert lines[3] == version, lines
    show = run([venv / "bin" / "pip", "show", "cgal_ext"], cwd=tmp_path).stdout
    # The name as the metadata gives it, cgal-ext (setuptools normalises it; pip and importlib take either).
    assert re.search(r"^Name: cgal[-_]ext$", show, re.M) and "Version: %s\n" % version in show, show
    assert "Requires: numpy\n" in show, show
    assert "Location: %s\n" % site in show, show

    run([venv / "bin" / "pip", "uninstall", "-y", "cgal_ext"], cwd=tmp_path)
    assert not (site / "cgal_ext").exists() and not list(site.glob("cgal_ext-*")), list(site.iterdir())
    after = run([python, "-c", REPORT], cwd=tmp_path).stdout.split("\n")
    if system_copy:
        assert after == before, (before, after)
    else:
        assert after[0] == "ImportError", after
    assert run([venv / "bin" / "pip", "show", "cgal_ext"], cwd=tmp_path, check=False).returncode != 0


def test_cmake_install_puts_the_package_into_the_prefix(tmp_path):
    """`cmake --install <build> --prefix P` (no compilation) puts the package where the interpreter looks
    under P."""
    cache = (Path(BUILD_DIR) / "CMakeCache.txt").read_text()
    match = re.search(r"^CGAL_EXT_PYTHON_INSTALL_DIR:PATH=(.*)$", cache, re.M)
    assert match, "no CGAL_EXT_PYTHON_INSTALL_DIR in the build tree's cache"
    if os.path.isabs(match.group(1)):
        pytest.skip("the tree installs the package at the absolute %s, which --prefix does not move"
                    % match.group(1))
    prefix = tmp_path / "prefix"
    run(["cmake", "--install", BUILD_DIR, "--prefix", prefix], cwd=tmp_path)
    package = prefix / match.group(1) / "cgal_ext"
    names = {p.name for p in package.iterdir()}
    for name in ["_core" + sysconfig.get_config_var("EXT_SUFFIX"), "__init__.py", "_version.py", "_core.pyi",
                 "py.typed"]:
        assert name in names, (name, names)
    env = clean_environment()
    env["PYTHONPATH"] = str(package.parent)
    lines = run([sys.executable, "-c", REPORT.replace('print(importlib.metadata.version("cgal_ext"))', "")],
                cwd=tmp_path, env=env).stdout.split("\n")
    assert lines[0] == project_version(), lines
    assert Path(lines[1]).resolve().is_relative_to(package.resolve()), lines
