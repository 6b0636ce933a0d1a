# Shared fixtures of the Python module's tests: a generated shape, CGAL's scans, and the point-detail program
# (its binary PLY files read with numpy).
import os
import subprocess

import numpy as np
import pytest

PROGRAM = os.environ.get("POINT_DETAIL", "point-detail")
# The program's environment: without the sanitizer runtime that the sanitized pass preloads into Python (a sanitized
# program carries its own, and refuses a second).
PROGRAM_ENV = {name: value for name, value in os.environ.items() if name != "LD_PRELOAD"}
DATA = os.environ.get("CGAL_EXT_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "data"))

PLY_TYPES = {"double": "<f8", "float64": "<f8", "float": "<f4", "float32": "<f4", "uchar": "u1", "uint8": "u1",
             "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4"}


def read_ply(path):
    """The vertex properties of a binary little-endian PLY file without lists, as a dict of arrays."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    fields, count, in_vertex = [], 0, False
    for line in data[:end].decode("ascii").splitlines():
        words = line.split()
        if words[:1] == ["element"]:
            in_vertex = words[1] == "vertex"
            if in_vertex:
                count = int(words[2])
        elif words[:1] == ["property"] and in_vertex:
            fields.append((words[2], PLY_TYPES[words[1]]))
    return np.frombuffer(data, dtype=np.dtype(fields), count=count, offset=end)


def write_ply(path, points, normals=None):
    """Points (and normals) as a binary little-endian PLY file of doubles."""
    names = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else [])
    header = "ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(points)
    header += "".join("property double %s\n" % n for n in names) + "end_header\n"
    columns = [points] + ([normals] if normals is not None else [])
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(np.hstack(columns), dtype="<f8").tobytes())


def run_program(*args):
    """Runs point-detail quietly; a failure shows its message."""
    result = subprocess.run([PROGRAM, "-q", *map(str, args)], capture_output=True, text=True, env=PROGRAM_ENV)
    assert result.returncode == 0, result.stderr
    return result


def xyz(vertex):
    return np.column_stack([vertex["x"], vertex["y"], vertex["z"]])


def normals_of(vertex):
    return np.column_stack([vertex["nx"], vertex["ny"], vertex["nz"]])


def bumpy_sphere(n=6000, seed=1):
    """Points on a unit sphere with bumps of 2 % of the radius, and their exact normals."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    r = 1.0 + 0.02 * np.sin(8 * d[:, 0]) * np.cos(6 * d[:, 1])
    return d * r[:, None], d.copy()


@pytest.fixture(scope="session")
def sphere():
    return bumpy_sphere()


@pytest.fixture(scope="session")
def armadillo(tmp_path_factory):
    """CGAL's armadillo scan as the program reads it: its vertices and the normals it takes from the faces."""
    mesh = os.path.join(DATA, "meshes", "armadillo.off")
    if not os.path.exists(mesh):
        pytest.skip("no " + mesh + " (scripts/fetch_data.sh)")
    out = tmp_path_factory.mktemp("armadillo") / "details.ply"
    run_program("details", "-i", mesh, "-o", out)
    vertex = read_ply(out)
    return xyz(vertex), normals_of(vertex), vertex
