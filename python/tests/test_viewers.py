"""The program's PLY files in the viewers people already use: Debian's CloudCompare, whose command line loads only
the standard properties and those named scalar_*, exports every scalar field of a file written with
--cloudcompare-fields, by name and with the file's values (README.md, "Quick start")."""
import glob
import os
import shutil
import subprocess

import numpy as np
import pytest

import cgal_ext
from conftest import PROGRAM_ENV, bumpy_sphere, read_ply, run_program, write_ply, xyz

CLOUDCOMPARE = shutil.which("CloudCompare")


def cloudcompare_columns(ply, folder):
    """The cloud CloudCompare's command line loads from `ply`, saved as ASCII with its header: {column: values}."""
    if CLOUDCOMPARE is None:
        pytest.fail("CloudCompare is not installed (scripts/setup.sh installs Debian's cloudcompare)")
    for old in glob.glob(os.path.join(folder, "*.asc")):
        os.remove(old)
    env = dict(PROGRAM_ENV, QT_QPA_PLATFORM="offscreen")
    result = subprocess.run([CLOUDCOMPARE, "-SILENT", "-O", ply, "-C_EXPORT_FMT", "ASC", "-ADD_HEADER", "-SAVE_CLOUDS"],
                            cwd=folder, env=env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    (saved,) = glob.glob(os.path.join(folder, "*.asc"))
    with open(saved) as f:
        names = f.readline().lstrip("/").split()
    values = np.loadtxt(saved, comments="//", ndmin=2)
    assert values.shape[1] == len(names)
    return dict(zip(names, values.T))


@pytest.mark.parametrize("command", [["details", "--order", "cubic"], ["curvature"], ["simplify"]])
def test_cloudcompare_loads_every_scalar_field(tmp_path, command):
    points, normals = bumpy_sphere(3000, seed=5)
    source, written, plain = tmp_path / "sphere.ply", tmp_path / "fields.ply", tmp_path / "plain.ply"
    write_ply(source, points, normals)
    run_program("--cloudcompare-fields", *command[:1], "-i", source, "-o", written, *command[1:])
    run_program(*command[:1], "-i", source, "-o", plain, *command[1:])
    vertex = read_ply(written)
    scalars = [name for name in vertex.dtype.names if name.startswith("scalar_")]
    assert scalars, vertex.dtype.names
    # The same file but for the names: the prefix is all the option changes.
    assert [n.replace("scalar_", "", 1) for n in vertex.dtype.names] == list(read_ply(plain).dtype.names)
    columns = cloudcompare_columns(str(written), str(tmp_path))
    # CloudCompare keeps coordinates and scalar fields in single precision.
    points_seen = np.column_stack([columns["X"], columns["Y"], columns["Z"]])
    assert np.abs(points_seen - xyz(vertex)).max() <= 1e-6 * np.abs(xyz(vertex)).max()
    for name in scalars:
        shown = name[len("scalar_"):]
        assert shown in columns, (shown, sorted(columns))
        expected = vertex[name]
        assert np.abs(columns[shown] - expected).max() <= 1e-6 * max(np.abs(expected).max(), 1e-30), shown
    # Without the option CloudCompare's command line drops the same fields: why the option exists.
    dropped = cloudcompare_columns(str(plain), str(tmp_path))
    assert not any(name[len("scalar_"):] in dropped for name in scalars), sorted(dropped)
    # The program and the package read such a file's fields under their own names, and write them back once
    # prefixed: the file and its rewrite hold the same fields.
    properties = cgal_ext.read_points(str(written)).properties
    colors = ["colors"] if "red" in vertex.dtype.names else []
    assert sorted(properties) == sorted([name[len("scalar_"):] for name in scalars] + colors)
    if command[0] == "details":
        run_program("render", "-i", written, "-o", tmp_path / "view.png", "--color-by", "detail_normal")
        run_program("--cloudcompare-fields", "details", "-i", written, "-o", tmp_path / "again.ply")
        again = read_ply(tmp_path / "again.ply").dtype.names
        assert sorted(again) == sorted(vertex.dtype.names)
