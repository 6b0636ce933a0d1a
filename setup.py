# The Python package cgal_ext built by the project's CMake build (python/CMakeLists.txt, target cgal_ext_python),
# for pip and python3 -m build (pyproject.toml; doc/python.md, "Install"):
#   python3 -m venv --system-site-packages .venv && .venv/bin/pip install --no-build-isolation .
#   python3 -m build --no-isolation --wheel
# CGAL_EXT_CMAKE_BUILD_DIR=<a configured build tree> reuses that tree: only `cmake --build DIR --target
# cgal_ext_python`, no reconfiguration (the tests build their wheel from the main tree that way). Without it, the
# package gets its own Release tree, build/python-package, configured with only what the module needs
# (extra configure arguments: CMAKE_ARGS).
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
PACKAGE = "cgal_ext"
# setuptools' own scratch folders (build/, *.egg-info) go under the ignored build/, beside the CMake trees.
SETUPTOOLS_BUILD = ROOT / "build" / "setuptools"
OWN_TREE = ROOT / "build" / "python-package"
LEAN_OPTIONS = ["-DCGAL_EXT_BUILD_PROGRAM=OFF", "-DCGAL_EXT_BUILD_EXAMPLES=OFF", "-DCGAL_EXT_BUILD_TESTS=OFF",
                "-DCGAL_EXT_BUILD_BENCHMARKS=OFF", "-DCGAL_EXT_BUILD_PYTHON=ON"]


def cmake_project_version():
    """x.y.z of `project(CGAL_ext VERSION x.y.z ...)` in the top-level CMakeLists.txt."""
    text = (ROOT / "CMakeLists.txt").read_text()
    match = re.search(r"project\s*\(\s*CGAL_ext\b[^)]*?\bVERSION\s+([0-9][0-9A-Za-z.]*)", text)
    if not match:
        sys.exit("setup.py: no `project(CGAL_ext VERSION ...)` in " + str(ROOT / "CMakeLists.txt"))
    return match.group(1)


def run(command, **kwargs):
    print("setup.py: " + " ".join(shlex.quote(str(c)) for c in command), flush=True)
    subprocess.run([str(c) for c in command], check=True, **kwargs)


class CMakeBuild(build_ext):
    """Builds the CMake target cgal_ext_python and copies the package it lays out (<tree>/python/cgal_ext: the
    extension _core, the pure-Python files, the stub, py.typed, _version.py) into the wheel's tree."""

    def run(self):
        if self.inplace:
            sys.exit("setup.py: editable installs are not supported; import the build tree's package instead "
                     "(PYTHONPATH=<build>/python, doc/python.md)")
        package = self.cmake_package()
        destination = Path(self.build_lib) / PACKAGE
        if destination.exists():
            shutil.rmtree(destination)
        destination.mkdir(parents=True)
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        extensions = []
        for source in sorted(package.iterdir()):
            name = source.name
            if source.is_dir() and name != "__pycache__":
                shutil.copytree(source, destination / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
                continue  # a subpackage: the studio, the tiled runs
            if source.is_dir() or name.endswith((".in", ".pyc")):
                continue  # __pycache__, CMake's _version.py.in
            if name.endswith(".so"):
                if not name.endswith(suffix):
                    continue  # not for this interpreter (checked below)
                extensions.append(name)
            shutil.copy2(source, destination / name)
        if extensions != ["_core" + suffix]:
            sys.exit("setup.py: %s has no _core%s for %s (found %s): the tree was configured for another "
                     "interpreter; reconfigure it with -DPYTHON_EXECUTABLE=%s" %
                     (package, suffix, sys.executable, [p.name for p in package.glob("*.so")], sys.executable))

    def cmake_package(self):
        tree = os.environ.get("CGAL_EXT_CMAKE_BUILD_DIR")
        if tree:
            tree = Path(tree).resolve()
            if not (tree / "CMakeCache.txt").is_file():
                sys.exit("setup.py: CGAL_EXT_CMAKE_BUILD_DIR=%s is not a configured CMake build tree "
                         "(no CMakeCache.txt)" % tree)
            run(["cmake", "--build", tree, "--target", "cgal_ext_python"])
        else:
            tree = OWN_TREE
            # pybind11 keeps the interpreter it first found in the cache: a tree of another Python ABI starts over.
            cache = tree / "CMakeCache.txt"
            found = re.search(r"^PYTHON_MODULE_EXTENSION:INTERNAL=(.*)$", cache.read_text(), re.M) \
                if cache.is_file() else None
            if found and found.group(1) != sysconfig.get_config_var("EXT_SUFFIX"):
                print("setup.py: %s was configured for another Python (%s): removing it" % (tree, found.group(1)))
                shutil.rmtree(tree)
            configure = ["cmake", "-S", ROOT, "-B", tree, "-DCMAKE_BUILD_TYPE=Release",
                         "-DPYTHON_EXECUTABLE=" + sys.executable] + LEAN_OPTIONS
            if not (tree / "CMakeCache.txt").is_file() and shutil.which("ninja"):
                configure += ["-G", "Ninja"]  # the generator of an existing tree cannot change
            run(configure + shlex.split(os.environ.get("CMAKE_ARGS", "")))
            run(["cmake", "--build", tree, "--target", "cgal_ext_python", "-j", str(os.cpu_count() or 1)])
        package = tree / "python" / PACKAGE
        if not (package / "__init__.py").is_file():
            sys.exit("setup.py: the target cgal_ext_python left no package in %s (is Debian's pybind11-dev "
                     "installed? CMake skips the module without it)" % package)
        return package


SETUPTOOLS_BUILD.mkdir(parents=True, exist_ok=True)
setup(
    version=cmake_project_version(),
    # The package is the CMake build's (CMakeBuild): setuptools copies no source itself. The extension is a
    # placeholder that makes the wheel a platform wheel and runs CMakeBuild.
    packages=[],
    ext_modules=[Extension(PACKAGE + "._core", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(SETUPTOOLS_BUILD)},
             "egg_info": {"egg_base": str(SETUPTOOLS_BUILD)}},
)
