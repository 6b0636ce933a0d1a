# The package as users meet it: its stub and docstrings, arrays as users hold them (pickled, float32, lists, masks)
# read in place where they can be, the program's readers and writers, threads, and the whole editing class against
# the calls it stands for.
import os
import pickle
import re
import struct
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import cgal_ext
from conftest import PROGRAM, PROGRAM_ENV, read_ply, run_program, write_ply

HERE = os.path.dirname(os.path.abspath(__file__))


# ---- the stub and the docstrings --------------------------------------------------------------------------------

@pytest.mark.skipif(bool(os.environ.get("CGAL_EXT_SANITIZED")),
                    reason="the Release pass checks the stub; mypy under AddressSanitizer's allocator takes a minute")
def test_the_stub_matches_the_extension(tmp_path):
    """mypy's stubtest: every name of the stub exists in the extension, and every public name there is in it."""
    package_root = os.path.dirname(os.path.dirname(os.path.abspath(cgal_ext.__file__)))
    # The tiled runs use libraries that ship no type information.
    (tmp_path / "mypy.ini").write_text("[mypy]\n[mypy-scipy.*,zarr.*,distributed.*]\nignore_missing_imports = True\n")
    result = subprocess.run([sys.executable, "-m", "mypy.stubtest", "cgal_ext", "--allowlist",
                             os.path.join(HERE, "stubtest_allowlist.txt"), "--mypy-config-file", "mypy.ini"],
                            capture_output=True, text=True, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=package_root))
    assert result.returncode == 0, result.stdout + result.stderr


def public_callables():
    for name in cgal_ext.__all__:
        value = getattr(cgal_ext, name)
        if callable(value) and not isinstance(value, type):
            yield name, value
    for name, value in vars(cgal_ext.Deformation).items():
        if not name.startswith("_") and callable(value):
            yield "Deformation." + name, value
    yield "Deformation", cgal_ext.Deformation


def init_signature():
    """The signature line of Deformation's constructor (written by the binding from its table of keywords)."""
    return cgal_ext.Deformation.__init__.__doc__.splitlines()[0]


def signature_parameters(signature):
    """{name: its default as shown, "" where it has none} of a pybind11 signature line, in order."""
    inside = signature[signature.index("(") + 1:signature.rindex(")")]
    shown = {}
    for part in re.split(r",\s*(?![^\[]*\])", inside):
        part = part.strip()
        if part in ("", "*") or part.startswith("self"):
            continue
        shown[part.split(":")[0].split("=")[0].strip()] = part.split(" = ", 1)[1] if " = " in part else ""
    return shown


def parameters_of(name, function):
    """The parameter names of a function, from pybind11's signature line (or Python's own)."""
    if name == "Deformation":
        return list(signature_parameters(init_signature()))
    if name == "threads":
        import inspect
        return [p for p in inspect.signature(function).parameters]
    return list(signature_parameters(function.__doc__.splitlines()[0]))


@pytest.mark.parametrize("name, function", list(public_callables()), ids=lambda x: x if isinstance(x, str) else "")
def test_every_parameter_is_documented(name, function):
    doc = function.__doc__
    assert doc and len(doc.splitlines()) >= 2, name + " has no docstring"
    for parameter in parameters_of(name, function):
        documented = re.search(r"^\s*(\w+, )*\*{0,2}%s(, \w+)* :" % re.escape(parameter.lstrip("*")), doc, re.MULTILINE)
        assert documented or parameter.startswith("**"), "%s: parameter %s is not documented" % (name, parameter)


def test_the_stub_declares_the_constructors_keywords():
    """The stub's Deformation.__init__ has the keywords of the binding's table, in order, with the same types
    (stubtest cannot check it: a compiled constructor has no signature Python can read)."""
    import ast
    with open(os.path.join(os.path.dirname(cgal_ext.__file__), "_core.pyi")) as stub:
        tree = ast.parse(stub.read())
    init = next(node for cls in tree.body if isinstance(cls, ast.ClassDef) and cls.name == "Deformation"
                for node in cls.body if isinstance(node, ast.FunctionDef) and node.name == "__init__")
    declared = {a.arg: ast.unparse(a.annotation) for a in init.args.args[1:] + init.args.kwonlyargs}
    signature = init_signature()
    shown = dict(re.findall(r"(\w+): ((?:Optional\[)?[\w.]+\]?)", signature[signature.index("points"):]))
    assert list(declared) == list(cgal_ext._core._parameters["Deformation"]) == list(shown)
    assert declared == shown
    assert [a.arg for a in init.args.kwonlyargs] == list(shown)[2:]  # the settings are keyword-only


def test_defaults_are_the_libraries():
    """The defaults help() shows come from the C++ settings: the program's own defaults give the same numbers."""
    signature = init_signature()
    assert "k: int = 10" in signature and "rotations: str = 'propagate'" in signature
    settings = cgal_ext.Deformation(np.random.default_rng(0).normal(size=(50, 3)), np.tile([0, 0, 1.0], (50, 1))).settings
    for key, value in re.findall(r"(\w+): \w+(?:\[\w+\])? = ('[^']*'|[^,)]+)", signature[signature.index("*"):]):
        shown = value.strip("'")
        if key == "strength":  # the older spelling of strength_distance: read, never written back
            assert shown == "None" and "strength" not in settings
            continue
        actual = settings[key]
        assert str(actual) == shown or (shown == "None" and actual is None) or float(shown) == actual, key


def test_the_exported_parameters_are_the_signatures():
    """What the tiled runs read (_core._parameters): every library function's parameters in order, with the
    defaults its help() shows, and no default where it shows none."""
    import inspect
    exported = cgal_ext._core._parameters
    assert {"compute_geometric_details", "enhance_geometric_details", "estimate_mean_curvature",
            "estimate_oriented_normals"} <= set(exported)
    for name, parameters in exported.items():
        shown = signature_parameters(init_signature() if name == "Deformation" else
                                     getattr(cgal_ext, name).__doc__.splitlines()[0])
        assert list(parameters) == list(shown), name
        for parameter, default in parameters.items():
            if default is inspect.Parameter.empty:
                assert shown[parameter] == "", (name, parameter)
            else:
                assert shown[parameter] == repr(default), (name, parameter, default)


# ---- arrays as users have them ------------------------------------------------------------------------------------

def test_pickled_float32_and_list_inputs_give_the_float64_results(sphere):
    points, normals = sphere
    reference = cgal_ext.compute_geometric_details(points, normals)
    # An array that went through pickle (multiprocessing, joblib, Dask) has an equal dtype, not the same object.
    pickled_points, pickled_normals = pickle.loads(pickle.dumps((points, normals)))
    assert np.array_equal(cgal_ext.compute_geometric_details(pickled_points, pickled_normals).details, reference.details)
    listed = cgal_ext.compute_geometric_details(points.tolist(), normals.tolist())
    assert np.max(np.abs(listed.details - reference.details)) <= 1e-12
    # float32: the float64 call on the same converted values, exactly.
    p32, n32 = points.astype(np.float32), normals.astype(np.float32)
    assert np.array_equal(cgal_ext.compute_geometric_details(p32, n32).details,
                          cgal_ext.compute_geometric_details(p32.astype(np.float64), n32.astype(np.float64)).details)
    # Big-endian float64 (a file read with numpy) is converted too.
    assert np.array_equal(cgal_ext.compute_geometric_details(points.astype(">f8"), normals).details, reference.details)


def test_results_are_named_and_unpack(sphere):
    points, normals = sphere
    result = cgal_ext.compute_geometric_details(points, normals)
    details, magnitude = result
    assert isinstance(result, cgal_ext.Details) and result.details is details and result.magnitude is magnitude
    assert "Details(details=" in repr(result)


def test_boolean_masks_are_index_arrays(sphere):
    points, normals = sphere
    mask = points[:, 2] > 0.5
    by_index = cgal_ext.scale_geometric_details(points, normals, roi=np.flatnonzero(mask), s=2.0)
    assert np.array_equal(cgal_ext.scale_geometric_details(points, normals, roi=mask, s=2.0), by_index)
    assert np.array_equal(cgal_ext.scale_geometric_details(points, normals, roi=list(np.flatnonzero(mask)), s=2.0), by_index)
    anchors = np.zeros(len(points), bool)
    anchors[np.flatnonzero(mask)[:20]] = True
    assert np.array_equal(cgal_ext.enhance_geometric_details(points, normals, s=2.0, roi=mask, anchors=anchors),
                          cgal_ext.enhance_geometric_details(points, normals, s=2.0, roi=np.flatnonzero(mask),
                                                             anchors=np.flatnonzero(anchors)))


def test_float64_input_is_read_in_place_and_others_are_copied_once(sphere):
    """The memory the library reads through the points' and normals' maps is the caller's own buffers; a float32
    input is read from one converted copy, so its span lies outside them (a copy of a float64 input would too)."""
    points, normals = sphere
    points = np.asfortranarray(points)  # any layout: still in place

    def span_read(*args):
        cgal_ext._core._trace_reads(True)
        try:
            cgal_ext.compute_geometric_details(*args)
            return cgal_ext._core._read_span()
        finally:
            cgal_ext._core._trace_reads(False)

    def buffer(a):
        lo = a.ctypes.data
        return lo, lo + a.nbytes

    lo, hi = span_read(points, normals)
    assert (lo, hi) == (min(buffer(points)[0], buffer(normals)[0]), max(buffer(points)[1], buffer(normals)[1]))
    p32 = points.astype(np.float32)
    lo32, hi32 = span_read(p32, normals)
    assert not (buffer(p32)[0] <= lo32 < buffer(p32)[1])
    # scale and enhance move a copy of the points, the result they return: that is what they read.
    cgal_ext._core._trace_reads(True)
    try:
        moved = cgal_ext.scale_geometric_details(points, normals, roi=points[:, 2] > 0.5, s=2.0)
        lo, hi = cgal_ext._core._read_span()
    finally:
        cgal_ext._core._trace_reads(False)
    assert buffer(moved)[0] <= lo and hi <= max(buffer(moved)[1], buffer(normals)[1])


def misaligned(array):
    """A copy of an 8-byte-element array in a buffer 4 bytes past an 8-byte boundary, as np.frombuffer at an odd
    offset gives."""
    raw = bytearray(4 + array.nbytes)
    view = np.frombuffer(raw, dtype=array.dtype, offset=4, count=array.size).reshape(array.shape)
    view[...] = array
    assert not view.flags.aligned
    return view


def test_a_float64_array_that_is_not_aligned_is_read_through_a_copy_and_refused_as_an_output(sphere):
    points, normals = sphere
    expected = cgal_ext.compute_geometric_details(points, normals)
    got = cgal_ext.compute_geometric_details(misaligned(points), misaligned(normals))
    assert np.array_equal(got.details, expected.details)
    roi = misaligned(np.flatnonzero(points[:, 2] > 0.5).astype(np.int64))
    assert np.array_equal(cgal_ext.scale_geometric_details(points, normals, roi=roi, s=2.0),
                          cgal_ext.scale_geometric_details(points, normals, roi=points[:, 2] > 0.5, s=2.0))
    radius = misaligned(np.zeros(len(points)))
    with pytest.raises(ValueError, match="neighbor_radius is not aligned"):
        cgal_ext.compute_geometric_details(points, normals, neighbor_radius=radius)
    edit = cgal_ext.Deformation(points, normals)
    edit.insert_roi(points[:, 2] > 0.5)
    edit.create_handle_group(points[:, 2] > 0.9)
    edit.deform()
    with pytest.raises(ValueError, match="points_out is not aligned"):
        edit.diffuse(misaligned(points), np.empty_like(normals))


def test_the_gil_is_released_during_a_call(sphere):
    """The other thread counts at least 10 times what it counts in one switch interval: a call holding the GIL
    would let it run about one switch interval, or none."""
    points, normals = sphere
    many = np.vstack([points * (1 + 0.1 * i) for i in range(30)])  # 180k points: about a second
    many_normals = np.vstack([normals] * 30)
    count, running = [0], [True]

    def spin():
        while running[0]:
            count[0] += 1

    thread = threading.Thread(target=spin)
    thread.start()
    try:
        time.sleep(0.2)  # the other thread alone (this one sleeps, without the GIL)
        before = count[0]
        time.sleep(0.5)
        per_interval = (count[0] - before) * sys.getswitchinterval() / 0.5
        before = count[0]
        cgal_ext.compute_geometric_details(many, many_normals, k=10)
        during = count[0] - before
    finally:
        running[0] = False
        thread.join()
    assert during >= 10 * per_interval, (during, per_interval)


def test_threads_are_limited_and_restored(sphere):
    points, normals = sphere
    reference = cgal_ext.compute_geometric_details(points, normals).details
    assert cgal_ext.get_num_threads() >= 1
    every_core = cgal_ext.get_num_threads()
    with cgal_ext.threads(1):
        assert cgal_ext.get_num_threads() == 1
        assert np.array_equal(cgal_ext.compute_geometric_details(points, normals).details, reference)
        with cgal_ext.threads(None):
            assert cgal_ext.get_num_threads() == every_core
        assert cgal_ext.get_num_threads() == 1
    assert cgal_ext.get_num_threads() == every_core
    with pytest.raises(ValueError, match="at least 1"):
        cgal_ext.set_num_threads(0)


# ---- files and pictures -------------------------------------------------------------------------------------------

def test_write_and_read_round_trip_every_property_bit_for_bit(sphere, tmp_path):
    points, normals = sphere
    rng = np.random.default_rng(3)
    colors = rng.integers(0, 256, size=(len(points), 3), dtype=np.uint8)
    curvature, label = rng.normal(size=len(points)), rng.integers(0, 1000, size=len(points))
    cgal_ext.write_ply(tmp_path / "a.ply", points, normals, colors, mean_curvature=curvature, label=label)
    read = cgal_ext.read_points(tmp_path / "a.ply")
    assert isinstance(read, cgal_ext.PointSet)
    assert np.array_equal(read.points, points) and np.array_equal(read.normals, normals)
    assert list(read.properties) == ["mean_curvature", "label", "colors"]
    assert np.array_equal(read.properties["mean_curvature"], curvature)
    assert np.array_equal(read.properties["label"], label.astype(np.float64))
    assert read.properties["colors"].dtype == np.uint8 and np.array_equal(read.properties["colors"], colors)
    # Written again from what was read: the same bytes.
    properties = dict(read.properties)
    cgal_ext.write_ply(tmp_path / "b.ply", read.points, read.normals, properties.pop("colors"), **properties)
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    # The program reads what write_ply wrote as it reads its own files.
    run_program("curvature", "-i", tmp_path / "a.ply", "-o", tmp_path / "h.ply")
    assert len(read_ply(tmp_path / "h.ply")) == len(points)


def test_every_format_the_program_reads(sphere, tmp_path):
    points, normals = sphere
    rows = "".join("%.17g %.17g %.17g %.17g %.17g %.17g\n" % tuple(r) for r in np.hstack([points, normals]))
    (tmp_path / "a.pwn").write_text(rows)
    (tmp_path / "a.xyz").write_text(rows)
    (tmp_path / "a.off").write_text("NOFF\n%d 0 0\n" % len(points) + rows)
    for name in ("a.pwn", "a.xyz", "a.off"):
        read = cgal_ext.read_points(tmp_path / name)
        assert np.array_equal(read.points, points) and np.array_equal(read.normals, normals), name
    (tmp_path / "bare.xyz").write_text("".join("%.17g %.17g %.17g\n" % tuple(r) for r in points))
    assert cgal_ext.read_points(str(tmp_path / "bare.xyz")).normals is None


BAD_FILES = {
    "empty.xyz": b"",
    "nan.xyz": b"0 0 0\n1 0 0\nnan 1 0\n0 1 1\n",
    "inf.xyz": b"0 0 0\n1 0 0\ninf 1 0\n0 1 1\n",
    "nan.pwn": b"0 0 0 0 0 1\n1 0 0 0 0 1\nnan 1 0 0 0 1\n",
    "points.txt": b"0 0 0\n1 0 0\n",
    "counts.off": b"OFF\n500 0 0\n" + b"0 0 1\n" * 300,
    "garbage.off": b"OFF\nthree 0 0\n",
    "huge.off": b"OFF\n100000000000 0 0\n" + b"0 0 1\n" * 10,
    "not_ply.ply": b"plx\nformat ascii 1.0\n",
    "quadruple.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty quadruple x\nend_header\n" + b"\x7f" * 100,
    "no_x.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty double y\nproperty double z\n"
                b"end_header\n" + bytes(160),
    "cut.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty double x\nproperty double y\n"
               b"property double z\nend_header\n" + bytes(5000),
    "cut_big_endian.ply": b"ply\nformat binary_big_endian 1.0\nelement vertex 100\nproperty double x\n"
                          b"property double y\nproperty double z\nend_header\n" + bytes(1200),
    "cut_ascii.ply": b"ply\nformat ascii 1.0\nelement vertex 400\nproperty double x\nproperty double y\n"
                     b"property double z\nend_header\n" + b"0 0 1\n" * 300,
    "bad_token.ply": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                     b"property double z\nend_header\n0 0 1\n1.0e+x 0 0\n0 1 0\n",
    "huge.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 100000000000\nproperty double x\n"
                b"property double y\nproperty double z\nend_header\n" + bytes(240),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES) + ["directory.ply"])
def test_a_bad_file_is_a_value_error_with_the_programs_message(name, tmp_path):
    path = tmp_path / name
    if name == "directory.ply":
        path.mkdir()
    else:
        path.write_bytes(BAD_FILES[name])
    with pytest.raises(ValueError) as raised:
        cgal_ext.read_points(path)
    result = subprocess.run([PROGRAM, "-q", "details", "-i", str(path), "-o", str(tmp_path / "out.ply")],
                            capture_output=True, text=True, env=PROGRAM_ENV)
    assert result.returncode == 1 and not (tmp_path / "out.ply").exists()
    message = result.stderr.strip().splitlines()[-1]
    assert message.startswith("point-detail: error: ")
    expected = message[len("point-detail: error: "):]
    if "of memory" in expected:  # each caller asks for the memory it needs per point
        expected = expected[:expected.index(" points, which need")]
    assert str(raised.value).startswith(expected)


def test_read_points_of_a_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        cgal_ext.read_points(tmp_path / "nothing.ply")


def test_write_ply_writes_whole_or_nothing_and_spares_its_input(sphere, tmp_path):
    points, normals = sphere
    source = tmp_path / "in.ply"
    cgal_ext.write_ply(source, points, normals)
    before = source.read_bytes()
    with pytest.raises(ValueError, match="is the input file"):
        cgal_ext.write_ply(source, points * 2, normals, input_path=source)
    with pytest.raises(ValueError, match="is the input file"):  # through a link too
        os.symlink(source, tmp_path / "link.ply")
        cgal_ext.write_ply(tmp_path / "link.ply", points * 2, normals, input_path=source)
    assert source.read_bytes() == before
    with pytest.raises(ValueError, match="outside 0..255"):
        cgal_ext.write_ply(tmp_path / "c.ply", points, colors=np.full((len(points), 3), 300))
    with pytest.raises(ValueError, match="one value per point"):
        cgal_ext.write_ply(tmp_path / "c.ply", points, curvature=np.zeros(3))
    with pytest.raises(ValueError, match="written from points"):
        cgal_ext.write_ply(tmp_path / "c.ply", points, nx=np.zeros(len(points)))
    with pytest.raises(ValueError, match="does not exist"):
        cgal_ext.write_ply(tmp_path / "no" / "c.ply", points)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.ply", "link.ply"]  # no partial or temporary file


def test_diverging_colors_are_the_programs(sphere, tmp_path):
    points, normals = sphere
    write_ply(tmp_path / "s.ply", points, normals)
    run_program("curvature", "-i", tmp_path / "s.ply", "-o", tmp_path / "h.ply", "--fitting", "closed-form")
    out = read_ply(tmp_path / "h.ply")
    colors = cgal_ext.diverging_colors(np.asarray(out["mean_curvature"]))
    assert colors.dtype == np.uint8 and colors.shape == (len(points), 3)
    assert np.array_equal(colors, np.column_stack([out["red"], out["green"], out["blue"]]))


def test_render_png_is_a_picture_of_the_asked_size(sphere):
    points, normals = sphere
    magnitude = cgal_ext.compute_geometric_details(points, normals).magnitude
    png = cgal_ext.render_png(points, normals, values=magnitude, width=320, height=240, view="iso")
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", png[16:24])
    assert (width, height) == (320, 240)
    plain = cgal_ext.render_png(points, width=320, height=240)
    assert plain != png
    named = cgal_ext.render_png(points, normals, values=magnitude, width=320, height=240, view="iso",
                                legend="signed detail magnitude, model units")
    assert named != png
    with pytest.raises(ValueError, match="font has no"):
        cgal_ext.render_png(points, values=magnitude, legend="Δ, model units")
    with pytest.raises(ValueError, match="give values too"):
        cgal_ext.render_png(points, legend="nothing")
    with pytest.raises(ValueError, match="not both"):
        cgal_ext.render_png(points, values=magnitude, colors=np.zeros((len(points), 3), np.uint8))
    with pytest.raises(ValueError):
        cgal_ext.render_png(points, view="sideways")


# ---- the editing class --------------------------------------------------------------------------------------------

def rotation_x(degrees):
    a = np.radians(degrees)
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


@pytest.fixture
def deformation(sphere):
    points, normals = sphere
    d = cgal_ext.Deformation(points, normals)
    d.insert_roi(points[:, 2] > 0.0)
    d.create_handle_group(points[:, 2] > 0.8)
    assert d.preprocess()
    return d


def test_the_editing_class_reads_back_what_it_was_given(sphere):
    points, normals = sphere
    d = cgal_ext.Deformation(points, normals, rotations="arap", k=12, target_count=800, diffusion_turn="frames")
    assert d.settings["rotations"] == "arap" and d.settings["k"] == 12 and d.settings["target_count"] == 800
    assert d.settings["diffusion_turn"] == "frames" and d.settings["max_cluster_size"] is None
    assert len(d) == len(points) and not d.is_preprocessed() and d.number_of_handle_groups() == 0
    assert "not preprocessed" in repr(d)
    d.insert_roi(points[:, 2] > 0.0)
    g = d.create_handle_group()
    d.insert_handle_points(g, np.flatnonzero(points[:, 2] > 0.8))
    fractions = []
    d.deform(progress=fractions.append)  # preprocesses first, and says so
    assert fractions and d.is_preprocessed() and d.number_of_handle_groups() == 1
    assert "%d sample points" % d.number_of_sample_points() in repr(d)
    labels = d.sample_point_of(np.arange(len(points)))
    assert labels.dtype == np.int64 and labels.max() < d.number_of_sample_points()
    assert d.sample_point_of(7) == labels[7]
    assert np.array_equal(d.sample_point_of(points[:, 2] > 0.8), labels[points[:, 2] > 0.8])
    d.clear_selection()
    assert d.number_of_handle_groups() == 0 and not d.is_preprocessed()


def test_transform_forms_are_the_same_motion(sphere, deformation):
    points, normals = sphere
    R, t, c = rotation_x(25), np.array([0.05, -0.02, 0.1]), np.array([0.1, 0.2, 0.9])
    deformation.set_handle_transform(0, R, t)
    deformation.deform()
    by_pair = deformation.diffuse()
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    deformation.set_handle_transform(0, transform=T)
    deformation.deform()
    assert np.array_equal(deformation.diffuse().points, by_pair.points)
    deformation.set_handle_transform(0, R, pivot=c)
    deformation.deform()
    about_pivot = deformation.diffuse().points
    deformation.set_handle_transform(0, R, c - R @ c)
    deformation.deform()
    assert np.max(np.abs(deformation.diffuse().points - about_pivot)) < 1e-14
    handles = points[:, 2] > 0.8
    assert np.max(np.abs(about_pivot[handles] - ((points[handles] - c) @ R.T + c))) < 1e-12


def test_reset_gives_the_input_back_bit_for_bit(sphere, deformation):
    points, normals = sphere
    deformation.set_handle_transform(0, rotation_x(30), [0, 0, 0.2])
    deformation.deform()
    moved = deformation.diffuse()
    deformation.restore_details()
    assert np.max(np.abs(moved.points - points)) > 0.05
    deformation.reset()
    back = deformation.diffuse()
    assert np.array_equal(back.points, points)
    assert np.max(np.abs(back.normals - normals)) < 1e-15  # the normals as the library normalised them


def test_diffusing_into_the_same_arrays_drag_after_drag_is_the_fresh_result(sphere, deformation):
    """Into the arrays it filled whole, a drag rewrites only the points the edit can move: the same bits as a new
    array each time, also after the selection changed and for arrays written by someone else in between."""
    points, normals = sphere
    P, N = np.full_like(points, np.nan), np.full_like(normals, np.nan)
    for degrees in (10, 20, 30):
        deformation.set_handle_transform(0, rotation_x(degrees))
        deformation.deform()
        fresh = deformation.diffuse()
        into = deformation.diffuse(P, N)
        assert into.points is P and into.normals is N
        assert np.array_equal(P, fresh.points) and np.array_equal(N, fresh.normals)
    deformation.diffuse()
    restored = deformation.restore_details().points
    deformation.diffuse(P, N)
    assert deformation.restore_details(P, N).points is P and np.array_equal(P, restored)
    deformation.insert_roi(points[:, 2] > -0.5)  # a wider region: more points can move
    deformation.deform()
    fresh = deformation.diffuse()
    deformation.diffuse(P, N)
    assert np.array_equal(P, fresh.points)
    Q = P.copy()
    deformation.diffuse(Q[:, :], N)  # another array object over other memory: written whole
    assert np.array_equal(Q, fresh.points)


@pytest.mark.parametrize("layout", ["C", "F"])
def test_drags_into_the_same_arrays_equal_fresh_results_in_place_or_copied(sphere, deformation, layout):
    """Drag after drag into the same arrays, with no other call between: C-ordered arrays are written in place
    (Deformation::diffuse_in_input_order), Fortran-ordered ones by the copy; either way the bits of a second
    object's fresh arrays, in both rotation modes, and restore_details() into them afterwards too."""
    points, normals = sphere
    for rotations in ("propagate", "arap"):
        d, twin = (cgal_ext.Deformation(points, normals, rotations=rotations) for _ in range(2))
        for e in (d, twin):
            e.insert_roi(points[:, 2] > 0.0)
            e.create_handle_group(points[:, 2] > 0.8)
        P, N = np.full_like(points, np.nan, order=layout), np.full_like(normals, np.nan, order=layout)
        for degrees in (0, 10, 20, 30):
            for e in (d, twin):
                e.set_handle_transform(0, rotation_x(degrees), [0, 0.1 * degrees / 30, 0])
                e.deform()
            assert d.diffuse(P, N).points is P
            fresh = twin.diffuse()
            assert np.array_equal(P, fresh.points) and np.array_equal(N, fresh.normals), (rotations, degrees)
        restored, fresh = d.restore_details(P, N), twin.restore_details()
        assert restored.points is P
        assert np.array_equal(P, fresh.points) and np.array_equal(N, fresh.normals), rotations


@pytest.mark.parametrize("call, needle", [
    (lambda d: d.set_handle_transform(3, np.eye(3)), "no handle group 3"),
    (lambda d: d.set_handle_transform(-1, np.eye(3)), "no handle group -1"),
    (lambda d: d.set_handle_transform(0, 2 * np.eye(3)), "not a rotation"),
    (lambda d: d.set_handle_transform(0, np.diag([1.0, 1.0, -1.0])), "not a rotation"),
    (lambda d: d.set_handle_transform(0, transform=np.diag([1.0, 1.0, 1.0, 2.0])), "last row"),
    (lambda d: d.set_handle_transform(0, transform=np.diag([2.0, 1.0, 1.0, 1.0])), "not a rotation"),
    (lambda d: d.set_handle_transform(0, transform=np.eye(3)), "(4, 4)"),
    (lambda d: d.set_handle_transform(0, np.eye(3), transform=np.eye(4)), "alone"),
    (lambda d: d.set_handle_transform(0, np.eye(3), [0, np.nan, 0]), "not finite"),
    (lambda d: d.set_handle_transform(0, np.eye(3), pivot=[0, 0]), "3 numbers"),
    (lambda d: d.insert_handle_points(5, [0]), "no handle group 5"),
    (lambda d: d.restore_details(), "diffuse() first"),
    (lambda d: d.diffuse(np.zeros((3, 3)), None), "rows"),
    (lambda d: d.sample_point_of(10 ** 9), "not a point index"),
])
def test_a_bad_call_is_a_value_error_and_changes_nothing(sphere, deformation, call, needle):
    points, normals = sphere
    deformation.set_handle_transform(0, rotation_x(15))
    deformation.deform()
    if needle != "diffuse() first":
        deformation.diffuse()
        deformation.reset()
        deformation.set_handle_transform(0, rotation_x(15))
        deformation.deform()
    before = (deformation.statistics()["roi_samples"], deformation.number_of_handle_groups())
    with pytest.raises(ValueError) as raised:
        call(deformation)
    assert needle in str(raised.value)
    assert (deformation.statistics()["roi_samples"], deformation.number_of_handle_groups()) == before
    # The same drag as an untouched object's.
    fresh = cgal_ext.Deformation(points, normals)
    fresh.insert_roi(points[:, 2] > 0.0)
    fresh.create_handle_group(points[:, 2] > 0.8)
    fresh.set_handle_transform(0, rotation_x(15))
    fresh.deform()
    deformation.deform()
    assert np.array_equal(deformation.diffuse().points, fresh.diffuse().points)


@pytest.mark.parametrize("make, error, needle", [
    (lambda p, n: cgal_ext.Deformation(p, n, k=-1), ValueError, "k must be a count"),
    (lambda p, n: cgal_ext.Deformation(p, np.where(np.arange(len(n))[:, None] == 5, np.nan, n)), ValueError, "point #5"),
    (lambda p, n: cgal_ext.Deformation(p, n, target_count=0), ValueError, "target_count"),
    (lambda p, n: cgal_ext.Deformation(p, n, rotations="rigid"), ValueError,
     'rotations must be one of "none", "propagate" or "arap"'),
    (lambda p, n: cgal_ext.Deformation(p, n, detail_tolerance=-1.0), ValueError, "detail_tolerance"),
    (lambda p, n: cgal_ext.Deformation(p, n, strength_distance="manhattan"), ValueError,
     "strength_distance must be one of"),
    (lambda p, n: cgal_ext.Deformation(p, n, strength="manhattan"), ValueError, "strength must be one of"),
    (lambda p, n: cgal_ext.Deformation(p, n, strength="geodesic", strength_distance="geodesic"), ValueError, "not both"),
    (lambda p, n: cgal_ext.Deformation(p, n, rotation="arap"), TypeError,
     "takes no keyword argument 'rotation' (did you mean 'rotations'?)"),
    (lambda p, n: cgal_ext.Deformation(p, n, k="ten"), TypeError, "k must be an int, not str"),
    (lambda p, n: cgal_ext.Deformation(p, n, lam="0.5"), TypeError, "lam must be a float, not str"),
    (lambda p, n: cgal_ext.Deformation(p, n, strength=2), TypeError, "strength must be a str, not int"),
    (lambda p, n: cgal_ext.Deformation(p, n, max_cluster_size=0), ValueError, "max_cluster_size must be at least 1"),
    (lambda p, n: cgal_ext.Deformation(p, n, "quadric"), TypeError, "settings by keyword (3 positional arguments"),
    (lambda p, n: cgal_ext.Deformation(normals=n), TypeError, "Deformation() needs the points"),
    (lambda p, n: cgal_ext.Deformation(p, points=p), TypeError, "two values for points"),
    (lambda p, n: cgal_ext.Deformation(p, n, k=True), TypeError, "k must be an int, not bool"),
    (lambda p, n: cgal_ext.Deformation(p, n, k=np.float32(7.9)), TypeError, "k must be an int, not float32"),
    (lambda p, n: cgal_ext.Deformation(p, n, order=b"cubic"), TypeError, "order must be a str, not bytes"),
])
def test_bad_settings_are_refused(sphere, make, error, needle):
    points, normals = sphere
    with pytest.raises(error, match=re.escape(needle)):
        make(points, normals)


def test_settings_are_read_by_keyword_with_numpy_scalars_and_the_older_spelling(sphere):
    points, normals = sphere
    settings = cgal_ext.Deformation(points=points, normals=normals, k=np.int64(7), lam=np.float32(0.5),
                                    strength=None, strength_distance="geodesic").settings
    assert settings["k"] == 7 and settings["lam"] == 0.5 and settings["strength_distance"] == "geodesic"
    assert cgal_ext.Deformation(points, normals, strength="geodesic").settings["strength_distance"] == "geodesic"
