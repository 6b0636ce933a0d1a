"""The point formats of the I/O layer (io/pcd_format.h, io/pts_format.h, io/las_format.h) as cgal_ext.read_points and
the program read them: PCD and PTS files of Open3D's own writers, LAS files of every point format written here from
the ASPRS specification, PTX and PTS files written by hand, and the refusals of broken files, each checked against
its message."""
import os
import struct
import subprocess

import numpy as np
import pytest

import cgal_ext
from conftest import DATA, PROGRAM, PROGRAM_ENV, bumpy_sphere, read_ply, xyz


def read(path):
    return cgal_ext.read_points(str(path))


def assert_refused(path, *fragments):
    """read_points refuses `path` with a ValueError (the program's Cli_error) whose message names the problem."""
    with pytest.raises(ValueError) as error:
        read(path)
    message = str(error.value)
    for fragment in fragments:
        assert fragment in message, message
    assert str(path) in message, message


def text(path, lines):
    path.write_text("".join(line + "\n" for line in lines))
    return path


def numbers(values):
    """Values as a text line that reads back exactly (17 significant digits)."""
    return " ".join("%.17g" % v for v in values)


@pytest.fixture(scope="module")
def o3d():
    return pytest.importorskip("open3d")


# ----------------------------------------------------------------------------------------------------------------
# PCD


def pcd_header(fields, width, height=1, points=None, data="binary"):
    """A PCD v0.7 header as PCL and Open3D write it; fields are (name, size, type, count)."""
    lines = ["# .PCD v0.7 - Point Cloud Data file format", "VERSION 0.7",
             "FIELDS " + " ".join(f[0] for f in fields),
             "SIZE " + " ".join(str(f[1]) for f in fields),
             "TYPE " + " ".join(f[2] for f in fields),
             "COUNT " + " ".join(str(f[3]) for f in fields),
             "WIDTH %d" % width, "HEIGHT %d" % height, "VIEWPOINT 0 0 0 1 0 0 0",
             "POINTS %d" % (width * height if points is None else points), "DATA " + data]
    return ("\n".join(lines) + "\n").encode("ascii")


# Few distinct colours, so that Open3D's compressed writer finds repeats (LZF back references), and components
# whose c * 255 is not whole (rounding).
PALETTE = np.array([[0.1, 0.5, 0.9], [1.0, 0.0, 0.25], [0.33, 0.66, 0.99], [0.0, 0.0, 0.0]])


def open3d_cloud(o3d, n=300, seed=3):
    """A legacy Open3D cloud with points, normals and colours, and those three arrays."""
    points, normals = bumpy_sphere(n, seed)
    points = points * 10 + [100.0, -20.0, 3.0]
    colors = PALETTE[np.arange(n) % len(PALETTE)]
    cloud = o3d.geometry.PointCloud()
    cloud.points = o3d.utility.Vector3dVector(points)
    cloud.normals = o3d.utility.Vector3dVector(normals)
    cloud.colors = o3d.utility.Vector3dVector(colors)
    return cloud, points, normals


def compressed_sizes(data):
    """(compressed, uncompressed) bytes of a binary_compressed PCD, and where the compressed data start."""
    start = data.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n")
    return struct.unpack_from("<II", data, start) + (start + 8,)


PCD_OPTIONS = {"ascii": {"write_ascii": True}, "binary": {}, "binary_compressed": {"compressed": True}}


def assert_float32_equal(got, expected):
    """PCD stores float32: what is read is the written array rounded to float32."""
    assert got.shape == np.shape(expected)
    np.testing.assert_array_equal(got.astype(np.float32), np.asarray(expected).astype(np.float32))


@pytest.mark.parametrize("data", list(PCD_OPTIONS))
def test_open3d_pcd(o3d, tmp_path, data):
    cloud, points, normals = open3d_cloud(o3d)
    path = tmp_path / "cloud.pcd"
    assert o3d.io.write_point_cloud(str(path), cloud, **PCD_OPTIONS[data])
    raw = path.read_bytes()
    assert b"\nDATA %s\n" % data.encode() in raw
    if data == "binary_compressed":
        compressed, uncompressed, _ = compressed_sizes(raw)
        assert compressed < uncompressed  # real compression: the reader's back references are exercised
    got = read(path)
    back = o3d.io.read_point_cloud(str(path))
    if data == "ascii":
        # Open3D's ascii writes the doubles with 10 significant digits (%.10g), not the float32 of its binary files.
        np.testing.assert_array_equal(got.points, np.asarray(back.points))
        np.testing.assert_array_equal(got.normals, np.asarray(back.normals))
        np.testing.assert_allclose(got.points, points, rtol=1e-9, atol=0)
        np.testing.assert_allclose(got.normals, normals, rtol=0, atol=1e-9)
    else:
        assert_float32_equal(got.points, points)
        assert_float32_equal(got.normals, normals)
        np.testing.assert_array_equal(got.points, np.asarray(back.points))
        np.testing.assert_array_equal(got.normals, np.asarray(back.normals))
    # Open3D packs colours into rgb; what it reads back from its own file is what the file holds.
    assert sorted(got.properties) == ["colors"]
    assert got.properties["colors"].dtype == np.uint8
    np.testing.assert_array_equal(got.properties["colors"], np.round(np.asarray(back.colors) * 255).astype(np.uint8))


@pytest.mark.parametrize("data", list(PCD_OPTIONS))
def test_open3d_tensor_pcd_extra_fields(o3d, tmp_path, data):
    n = 250
    points, normals = bumpy_sphere(n, seed=4)
    rng = np.random.default_rng(4)
    intensity = (rng.random(n) * 1000).astype(np.float32)
    label = rng.integers(-40000, 40000, n).astype(np.int32)  # negative values: the sign of an I 4 field
    cloud = o3d.t.geometry.PointCloud()
    cloud.point.positions = o3d.core.Tensor(points.astype(np.float32))
    cloud.point.normals = o3d.core.Tensor(normals.astype(np.float32))
    cloud.point.colors = o3d.core.Tensor(PALETTE[np.arange(n) % len(PALETTE)].astype(np.float32))
    cloud.point.intensity = o3d.core.Tensor(intensity[:, None])
    cloud.point.label = o3d.core.Tensor(label[:, None])
    path = tmp_path / "tensor.pcd"
    assert o3d.t.io.write_point_cloud(str(path), cloud, **PCD_OPTIONS[data])
    assert b"intensity" in path.read_bytes()[:400]
    got = read(path)
    back = o3d.t.io.read_point_cloud(str(path))
    assert_float32_equal(got.points, points)
    assert_float32_equal(got.normals, normals)
    assert_float32_equal(got.points, back.point.positions.numpy())
    assert sorted(got.properties) == ["colors", "intensity", "label"]
    assert_float32_equal(got.properties["intensity"], intensity)
    np.testing.assert_array_equal(got.properties["label"], label)
    np.testing.assert_array_equal(got.properties["colors"], back.point.colors.numpy())


def nan_pcd(path, points, intensity, nan_at, columns=16):
    """An organised binary PCD as PCL writes a depth camera's (not dense): x y z, 4 padding bytes "_", intensity;
    the records at `nan_at` (indices in the whole grid) have x y z NaN, no measurement."""
    total = len(points) + len(nan_at)
    assert total % columns == 0
    records = np.zeros(total, dtype=[("xyz", "<f4", 3), ("_", "u1", 4), ("intensity", "<f4")])
    measured = np.setdiff1d(np.arange(total), nan_at)
    records["xyz"][measured] = points
    records["xyz"][nan_at] = np.nan
    records["intensity"][measured] = intensity
    records["intensity"][nan_at] = -1
    records["_"] = 0xAB
    fields = [("x", 4, "F", 1), ("y", 4, "F", 1), ("z", 4, "F", 1), ("_", 1, "U", 4), ("intensity", 4, "F", 1)]
    path.write_bytes(pcd_header(fields, columns, total // columns) + records.tobytes())
    return path


def nan_pcd_of_sphere(path):
    points = bumpy_sphere(300, seed=6)[0].astype(np.float32)
    intensity = np.arange(300, dtype=np.float32)
    nan_at = np.arange(3, 320, 16)  # 20 points, one per row of the 16 x 20 grid
    return nan_pcd(path, points, intensity, nan_at), points, intensity


def test_pcd_nan_points_left_out(tmp_path):
    path, points, intensity = nan_pcd_of_sphere(tmp_path / "organised.pcd")
    got = read(path)
    np.testing.assert_array_equal(got.points, points)  # the 300 measured ones, in file order
    assert got.normals is None
    assert sorted(got.properties) == ["intensity"]  # PCL's padding "_" is no field
    np.testing.assert_array_equal(got.properties["intensity"], intensity)


def test_pcd_ascii_pcl_style(tmp_path):
    # PCL's ascii: a packed colour (rgba, U 4) as its 32 bits in decimal, a field of several values, a signed
    # field, and NaN points; only a point with x, y and z all NaN has no position.
    fields = [("x", 4, "F", 1), ("y", 4, "F", 1), ("z", 4, "F", 1), ("rgba", 4, "U", 1), ("label", 2, "I", 1),
              ("hist", 4, "F", 3)]
    lines = ["1.5 2.5 3.5 %d -7 0.1 0.2 0.3" % 0xFF102030,
             "nan nan nan 0 0 0 0 0",
             "nan 4 5 %d 12 1 2 3" % 0x00FFFEFD,
             "",  # blank lines are not points
             "6 7 8 0 -32768 4 5 6"]
    path = tmp_path / "pcl.pcd"
    path.write_bytes(pcd_header(fields, 4, data="ascii") + "\n".join(lines).encode() + b"\n")
    got = read(path)
    np.testing.assert_array_equal(got.points, [[1.5, 2.5, 3.5], [np.nan, 4, 5], [6, 7, 8]])
    np.testing.assert_array_equal(got.properties["colors"], [[0x10, 0x20, 0x30], [0xFF, 0xFE, 0xFD], [0, 0, 0]])
    np.testing.assert_array_equal(got.properties["label"], [-7, 12, -32768])
    assert sorted(got.properties) == ["colors", "hist_0", "hist_1", "hist_2", "label"]
    np.testing.assert_array_equal(np.column_stack([got.properties["hist_%d" % i] for i in range(3)]),
                                  [[0.1, 0.2, 0.3], [1, 2, 3], [4, 5, 6]])


def lzf_compress(data):
    """LZF as liblzf decodes it: a run of one byte as that byte and a back reference at distance 1 (an overlapping
    copy, with the extra length byte past 8 bytes), everything else as literal runs of at most 32 bytes."""
    out, literal, i = bytearray(), bytearray(), 0

    def flush():
        for k in range(0, len(literal), 32):
            out.append(len(literal[k:k + 32]) - 1)
            out.extend(literal[k:k + 32])
        literal.clear()

    while i < len(data):
        run = 1
        while i + run < len(data) and data[i + run] == data[i] and run < 265:
            run += 1
        literal.append(data[i])
        if run >= 4:
            flush()
            code = run - 1 - 2  # copy length - 2
            out.extend([code << 5] if code < 7 else [7 << 5, code - 7])
            out.append(0)  # distance - 1
        i += run if run >= 4 else 1
    flush()
    return bytes(out)


def test_pcd_compressed_field_layout(tmp_path):
    # binary_compressed stores field after field (each point's values of a field together); here with a field of
    # several values, PCL's padding and an 8-bit signed field, through literal runs and overlapping copies.
    n = 100
    rng = np.random.default_rng(12)
    xyz_values = rng.uniform(-1, 1, (3, n)).astype("<f4")
    hist = rng.integers(0, 65536, (n, 2)).astype("<u2")
    label = rng.integers(-128, 128, n).astype("i1")
    rgb = np.full(n, 0x00C08040, "<u4")
    raw = xyz_values.tobytes() + np.zeros((n, 3), "u1").tobytes() + hist.tobytes() + label.tobytes() + rgb.tobytes()
    packed = lzf_compress(raw)
    assert len(packed) < len(raw)
    fields = [("x", 4, "F", 1), ("y", 4, "F", 1), ("z", 4, "F", 1), ("_", 1, "U", 3), ("hist", 2, "U", 2),
              ("label", 1, "I", 1), ("rgb", 4, "U", 1)]
    path = tmp_path / "compressed.pcd"
    path.write_bytes(pcd_header(fields, n, data="binary_compressed") + struct.pack("<II", len(packed), len(raw)) + packed)
    got = read(path)
    np.testing.assert_array_equal(got.points, xyz_values.T)
    assert sorted(got.properties) == ["colors", "hist_0", "hist_1", "label"]
    np.testing.assert_array_equal(got.properties["hist_0"], hist[:, 0])
    np.testing.assert_array_equal(got.properties["hist_1"], hist[:, 1])
    np.testing.assert_array_equal(got.properties["label"], label)
    np.testing.assert_array_equal(got.properties["colors"], np.tile([0xC0, 0x80, 0x40], (n, 1)))


XYZ_FIELDS = [("x", 4, "F", 1), ("y", 4, "F", 1), ("z", 4, "F", 1)]


def xyz_pcd(path, n=20, **header):
    data = np.arange(3 * n, dtype="<f4")
    path.write_bytes(pcd_header(XYZ_FIELDS, n, **header) + data.tobytes())
    return path


def test_pcd_refusals(tmp_path):
    whole = xyz_pcd(tmp_path / "whole.pcd").read_bytes()
    cut = tmp_path / "cut.pcd"
    cut.write_bytes(whole[:-5])
    assert_refused(cut, "truncated pcd file", "announces 20 points, records of 12 bytes", "235 bytes after its header")
    no_z = tmp_path / "no_z.pcd"
    no_z.write_bytes(pcd_header([("x", 4, "F", 1), ("y", 4, "F", 1), ("intensity", 4, "F", 1)], 20) + whole[-240:])
    assert_refused(no_z, "malformed pcd header", "the fields need x, y and z")
    grid = tmp_path / "grid.pcd"
    grid.write_bytes(pcd_header(XYZ_FIELDS, 4, 2, points=7) + np.zeros(24, "<f4").tobytes())
    assert_refused(grid, "POINTS 7 is not WIDTH x HEIGHT (4 x 2)")
    ascii = tmp_path / "ascii.pcd"
    ascii.write_bytes(pcd_header(XYZ_FIELDS, 3, data="ascii") + b"1.0 2.0 3.0\n4.0 5.0\n6.0 7.0 8.0\n")
    assert_refused(ascii, "data line 2 has 2 values, the fields need 3")
    ascii.write_bytes(pcd_header(XYZ_FIELDS, 3, data="ascii") + b"1.0 2.0 3.0\n4.0 5.0 6.0\n")
    assert_refused(ascii, "truncated pcd file (the header announces 3 points, 2 were read)")
    ascii.write_bytes(pcd_header(XYZ_FIELDS, 2, data="ascii") + b"1.0 2.0 3.0\n4.0 five 6.0\n")
    assert_refused(ascii, "data line 2: 'five' is not a number")


def test_compressed_pcd_refusals(o3d, tmp_path):
    cloud = open3d_cloud(o3d)[0]
    good = tmp_path / "good.pcd"
    assert o3d.io.write_point_cloud(str(good), cloud, compressed=True)
    data = good.read_bytes()
    compressed, uncompressed, start = compressed_sizes(data)
    assert uncompressed == 300 * 28
    cut = tmp_path / "cut.pcd"
    cut.write_bytes(data[:start + compressed // 2])
    assert_refused(cut, "truncated pcd file", "%d bytes of compressed data" % compressed)
    # A back reference as the first instruction points before the start of the output.
    backward = bytearray(data)
    backward[start] = 0xE0
    (tmp_path / "backward.pcd").write_bytes(backward)
    assert_refused(tmp_path / "backward.pcd", "corrupted pcd file (its compressed data do not decompress to 8400 bytes)")
    # Fewer compressed bytes announced than the data hold: the stream ends early.
    short = bytearray(data)
    struct.pack_into("<I", short, start - 8, compressed - 20)
    (tmp_path / "short.pcd").write_bytes(short)
    assert_refused(tmp_path / "short.pcd", "corrupted pcd file (its compressed data do not decompress")
    wrong_size = bytearray(data)
    struct.pack_into("<I", wrong_size, start - 4, uncompressed + 4)
    (tmp_path / "size.pcd").write_bytes(wrong_size)
    assert_refused(tmp_path / "size.pcd", "corrupted pcd file (%d compressed bytes said to hold 8404; the header's 300 "
                   "points of 28 bytes need 8400)" % compressed)
    # A small file whose sizes promise more than LZF can expand to is refused before anything is allocated.
    huge = tmp_path / "huge.pcd"
    huge.write_bytes(pcd_header(XYZ_FIELDS, 10_000_000, data="binary_compressed") +
                     struct.pack("<II", 16, 120_000_000) + bytes(16))
    assert_refused(huge, "corrupted pcd file (16 compressed bytes said to hold 120000000")


PCL_SCANS = ["test_pcd", "bun0", "milk", "milk_cartoon_all_small_clorox", "table_scene_lms400",
             "table_scene_mug_stereo_textured"]


@pytest.mark.parametrize("name", PCL_SCANS)
def test_pcl_sample_scans_read_as_open3d_reads_them(o3d, name):
    """PCL's own sample scans (Debian's python3-pcl, fetched by scripts/fetch_data.sh): ASCII and binary_compressed,
    organised 640 x 480 clouds whose missing measurements are NaN, packed rgb and rgba, extra fields. The points
    are Open3D's finite ones in order (float32 exactly; ASCII text read to double, equal once rounded to float32),
    the colours and fields Open3D's."""
    path = os.path.join(DATA, "pcd", name + ".pcd")
    got = read(path)
    theirs = o3d.t.io.read_point_cloud(path).point
    positions = theirs["positions"].numpy()
    finite = ~np.isnan(positions).all(axis=1)
    assert len(got.points) == finite.sum() > 1000
    np.testing.assert_array_equal(got.points.astype(np.float32), positions[finite])
    if "colors" in theirs:
        np.testing.assert_array_equal(got.properties["colors"], theirs["colors"].numpy()[finite][:, :3])
    for field in ("intensity", "distance", "sid"):
        if field in theirs:
            np.testing.assert_array_equal(got.properties[field], theirs[field].numpy()[finite, 0])


def test_record_layout_maps_a_file_larger_than_memory(tmp_path):
    """A sparse 48 GB binary PCD: read_points refuses it for the memory, record_layout (the tiled runs' map) does not."""
    path = tmp_path / "big.pcd"
    n = 4_000_000_000
    header = pcd_header(XYZ_FIELDS, n)
    path.write_bytes(header)
    os.truncate(path, len(header) + 12 * n)
    layout = cgal_ext._core.record_layout(path)
    assert (layout["points"], layout["data_offset"], layout["record_bytes"]) == (n, len(header), 12)
    assert layout["fields"] == [("x", 0, "f4"), ("y", 4, "f4"), ("z", 8, "f4")] and layout["normals"] is None
    assert_refused(path, "announces 4000000000 points, which need about", "of memory")


# ----------------------------------------------------------------------------------------------------------------
# PTS and PTX


@pytest.mark.parametrize("with_colors", [True, False])
def test_open3d_pts(o3d, tmp_path, with_colors):
    cloud, points, _ = open3d_cloud(o3d, n=200)
    if not with_colors:
        cloud.colors = o3d.utility.Vector3dVector(np.zeros((0, 3)))
    path = tmp_path / "cloud.pts"
    assert o3d.io.write_point_cloud(str(path), cloud)
    got = read(path)
    back = o3d.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(got.points, np.asarray(back.points))  # the same decimal text, parsed alike
    np.testing.assert_allclose(got.points, points, rtol=0, atol=1e-9)  # Open3D writes 10 decimals
    assert got.normals is None
    if with_colors:  # Open3D writes x y z intensity r g b, intensity 0
        assert sorted(got.properties) == ["colors", "intensity"]
        np.testing.assert_array_equal(got.properties["colors"], np.round(np.asarray(back.colors) * 255))
        np.testing.assert_array_equal(got.properties["intensity"], np.loadtxt(path, skiprows=1)[:, 3])
    else:
        assert got.properties == {}


def pts_values(n, layout, seed=0):
    """n point lines of a PTS layout (3, 4, 6 or 7 values) as numbers: x y z [intensity] [r g b]."""
    rng = np.random.default_rng(seed)
    columns = [rng.uniform(-500, 500, (n, 3))]
    if layout in (4, 7):
        columns.append(rng.integers(-2048, 2048, (n, 1)))  # Leica's intensity range
    if layout in (6, 7):
        columns.append(rng.integers(0, 256, (n, 3)))
    return np.hstack(columns)


def assert_pts_read(got, values, layout):
    np.testing.assert_array_equal(got.points, values[:, :3])
    expected = {}
    if layout in (4, 7):
        expected["intensity"] = values[:, 3]
    if layout in (6, 7):
        expected["colors"] = values[:, -3:]
    assert sorted(got.properties) == sorted(expected)
    for name, column in expected.items():
        np.testing.assert_array_equal(got.properties[name], column, err_msg=name)


@pytest.mark.parametrize("counted", [True, False], ids=["count_line", "no_count_line"])
@pytest.mark.parametrize("layout", [3, 4, 6, 7])
def test_pts_layouts(tmp_path, layout, counted):
    values = pts_values(50, layout, seed=layout)
    lines = ([str(len(values))] if counted else []) + [numbers(row) for row in values]
    assert_pts_read(read(text(tmp_path / "scan.pts", lines)), values, layout)


def test_pts_two_blocks(tmp_path):
    first, second = pts_values(30, 7, seed=1), pts_values(25, 7, seed=2)
    lines = [str(len(first))] + [numbers(row) for row in first] + [str(len(second))] + [numbers(row) for row in second]
    assert_pts_read(read(text(tmp_path / "two.pts", lines)), np.vstack([first, second]), 7)


def test_pts_refusals(tmp_path):
    values = pts_values(10, 4)
    short = text(tmp_path / "short.pts", ["12"] + [numbers(row) for row in values])
    assert_refused(short, "truncated pts file (a block announces 12 points, 10 follow)")
    lines = ["10"] + [numbers(row) for row in values]
    lines[4] += " 7"  # the 4th point: 5 values in a file of 4
    assert_refused(text(tmp_path / "wide.pts", lines), "wide.pts:5: this line has 5 values, the file's first point 4")
    assert_refused(text(tmp_path / "five.pts", ["1 2 3 4 5"]), "this line has 5 values")
    # A short block before another: the reader names the next block's count line.
    assert_refused(text(tmp_path / "middle.pts", ["3", "1 2 3", "4 5 6", "2", "7 8 9", "10 11 12"]),
                   "middle.pts:4: a block announces 3 points, 2 follow before this count line")


def rotation(angle, axis):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def ptx_transform(angle, axis, translation):
    """The 4 x 4 matrix a PTX file writes for a scan turned by `angle` about `axis` and moved by `translation`:
    p' = [p 1] M (row vectors), so M holds the rotation transposed and, as its last row, the translation."""
    m = np.eye(4)
    m[:3, :3] = rotation(angle, axis).T
    m[3, :3] = translation
    return m


def ptx_scan(local, intensity, transform, columns, colors=None):
    """The lines of one PTX scan: columns, rows, the scanner's position and axes, the transform, then the points
    (x y z intensity [r g b]) in the scanner's frame."""
    lines = [str(columns), str(len(local) // columns), numbers(transform[3, :3])]
    lines += [numbers(transform[i, :3]) for i in range(3)] + [numbers(row) for row in transform]
    for i, p in enumerate(local):
        line = numbers([*p, intensity[i]])
        lines.append(line if colors is None else line + " %d %d %d" % tuple(colors[i]))
    return lines


def scan_points(n, zero_at, seed):
    """Points in a scanner's frame with 0 0 0 (no return) at `zero_at`, their intensities, and the mask of the others."""
    rng = np.random.default_rng(seed)
    local = rng.uniform(-30, 30, (n, 3))
    local[zero_at] = 0
    kept = np.ones(n, bool)
    kept[zero_at] = False
    return local, rng.uniform(0, 1, n), kept


def moved(local, transform):
    return local @ transform[:3, :3] + transform[3, :3]


def test_ptx_two_scans(tmp_path):
    m1 = ptx_transform(0.7, [0.2, 0.3, 1.0], [10.0, -5.0, 2.5])
    m2 = ptx_transform(-2.1, [1.0, -0.4, 0.3], [-40.0, 12.0, 0.75])
    local1, intensity1, kept1 = scan_points(120, [0, 7, 8, 119], seed=1)
    local2, intensity2, kept2 = scan_points(80, [5, 40, 41, 42], seed=2)
    path = text(tmp_path / "two.ptx", ptx_scan(local1, intensity1, m1, 12) + ptx_scan(local2, intensity2, m2, 8))
    got = read(path)
    expected = np.vstack([moved(local1[kept1], m1), moved(local2[kept2], m2)])
    assert got.points.shape == (192, 3)
    np.testing.assert_allclose(got.points, expected, rtol=0, atol=1e-12 * 100)
    assert sorted(got.properties) == ["intensity"]
    np.testing.assert_array_equal(got.properties["intensity"], np.concatenate([intensity1[kept1], intensity2[kept2]]))


def test_ptx_colors(tmp_path):
    m = ptx_transform(1.2, [0, 0, 1], [1.0, 2.0, 3.0])
    local, intensity, kept = scan_points(60, [3, 33], seed=3)
    colors = np.random.default_rng(3).integers(0, 256, (60, 3))
    got = read(text(tmp_path / "color.ptx", ptx_scan(local, intensity, m, 6, colors)))
    np.testing.assert_allclose(got.points, moved(local[kept], m), rtol=0, atol=1e-12 * 100)
    np.testing.assert_array_equal(got.properties["intensity"], intensity[kept])
    np.testing.assert_array_equal(got.properties["colors"], colors[kept])


def test_ptx_refusals(tmp_path):
    m = ptx_transform(0.3, [1, 1, 1], [5.0, 5.0, 5.0])
    local, intensity, _ = scan_points(40, [], seed=4)
    scan = ptx_scan(local, intensity, m, 8)
    cut = text(tmp_path / "cut.ptx", scan + scan[:10 + 15])  # the second scan's header and 15 of its 40 points
    assert_refused(cut, "truncated ptx file (scan 2 announces 40 points, 15 follow)")
    skewed = m.copy()
    skewed[2, 3] = 0.5  # a projective last column
    assert_refused(text(tmp_path / "projective.ptx", ptx_scan(local, intensity, skewed, 8)),
                   "the transform is not an affine map")


# ----------------------------------------------------------------------------------------------------------------
# LAS, written from the ASPRS specification (LAS 1.4 R15: public header block, point data record formats 0 to 10)

LAS_RECORD_BYTES = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67]
LAS_HEADER_BYTES = {0: 227, 1: 227, 2: 227, 3: 235, 4: 375}
SCALE, OFFSET = np.array([0.001, 0.002, 0.0005]), np.array([1000.5, -2000.25, 30.0])


def las_points(fmt, n, seed=0, color_bits=16):
    """Random values of the fields the reader reads, for `n` points of point format `fmt`."""
    rng = np.random.default_rng(seed)
    legacy = fmt <= 5  # formats 0-5: 3-bit return numbers and 5-bit classes; 6-10: 4 bits and a whole byte
    fields = {"ints": rng.integers(-2_000_000, 2_000_000, (n, 3)), "intensity": rng.integers(0, 65536, n),
              "classification": rng.integers(0, 32 if legacy else 256, n),
              "return_number": rng.integers(0, 8 if legacy else 16, n),
              "number_of_returns": rng.integers(0, 8 if legacy else 16, n)}
    if fmt not in (0, 2):
        fields["gps_time"] = rng.uniform(0, 1e6, n)
    if fmt in (2, 3, 5, 7, 8, 10):
        fields["rgb"] = rng.integers(0, 2 ** color_bits, (n, 3))
    if fmt in (8, 10):
        fields["nir"] = rng.integers(0, 65536, n)
    return fields


def las_records(fmt, fields, extra_bytes=0):
    """The point records: the fields at their places in format `fmt`, every other byte (flags, scan angle, user data,
    point source, wave packet, extra bytes) random, so that a wrong place or an unmasked bit shows."""
    n = len(fields["ints"])
    records = np.random.default_rng(99).integers(0, 256, (n, LAS_RECORD_BYTES[fmt] + extra_bytes), dtype=np.uint8)

    def put(at, values, dtype):
        values = np.ascontiguousarray(np.asarray(values).reshape(n, -1), dtype=dtype).view(np.uint8).reshape(n, -1)
        records[:, at:at + values.shape[1]] = values

    put(0, fields["ints"], "<i4")
    put(12, fields["intensity"], "<u2")
    returns, count = fields["return_number"], fields["number_of_returns"]
    if fmt <= 5:
        # Byte 14: return number (bits 0-2), number of returns (3-5), scan direction and edge flags (6-7, random);
        # byte 15: classification (bits 0-4), synthetic, key-point and withheld flags (5-7, random).
        records[:, 14] = (records[:, 14] & 0xC0) | returns | (count << 3)
        # (LAS 1.0 has no flags there: the class is the whole byte.)
        keep = 0 if fields.get("class_is_a_byte") else 0xE0
        records[:, 15] = (records[:, 15] & keep) | fields["classification"]
        gps_at, rgb_at = 20, 20 if fmt == 2 else 28
    else:
        # Byte 14: return number (bits 0-3), number of returns (4-7); 15: flags (random); 16: classification.
        records[:, 14] = returns | (count << 4)
        records[:, 16] = fields["classification"]
        gps_at, rgb_at = 22, 30
    if "gps_time" in fields:
        put(gps_at, fields["gps_time"], "<f8")
    if "rgb" in fields:
        put(rgb_at, fields["rgb"], "<u2")
    if "nir" in fields:
        put(36, fields["nir"], "<u2")
    return records


def las_file(path, fmt, fields, minor=2, extra_bytes=0, vlr=False, legacy_count=None, count=None):
    """A LAS 1.`minor` file: the public header block, an optional VLR, then the point records."""
    records = las_records(fmt, fields, extra_bytes)
    n = len(records) if count is None else count
    header_bytes = LAS_HEADER_BYTES[minor]
    vlr_bytes = b""
    if vlr:
        payload = b"a record the reader steps over"
        vlr_bytes = struct.pack("<H16sHH32s", 0, b"cgal_ext tests", 1234, len(payload), b"test VLR") + payload
    if legacy_count is None:  # LAS 1.4 keeps the 32-bit count 0 for formats 6 to 10
        legacy_count = 0 if minor == 4 and fmt > 5 else n
    h = bytearray(header_bytes)
    h[0:4] = b"LASF"
    h[24:26] = bytes([1, minor])
    h[26:58] = b"cgal_ext tests".ljust(32, b"\0")  # system identifier
    struct.pack_into("<HIIBHI", h, 94, header_bytes, header_bytes + len(vlr_bytes), 1 if vlr else 0, fmt,
                     records.shape[1], legacy_count)
    struct.pack_into("<3d", h, 131, *SCALE)
    struct.pack_into("<3d", h, 155, *OFFSET)
    coordinates = fields["ints"] * SCALE + OFFSET
    high, low = coordinates.max(axis=0), coordinates.min(axis=0)
    struct.pack_into("<6d", h, 179, high[0], low[0], high[1], low[1], high[2], low[2])
    if minor == 4:
        struct.pack_into("<Q", h, 247, n)  # the 64-bit point count
    path.write_bytes(bytes(h) + vlr_bytes + records.tobytes())
    return path


def expected_las_properties(fields):
    expected = {name: fields[name] for name in ("intensity", "classification", "return_number", "number_of_returns",
                                                "gps_time", "nir") if name in fields}
    if "rgb" in fields:
        sixteen_bits = fields["rgb"].max() > 255  # the specification's 16 bits: divided by 256; else kept
        expected["colors"] = fields["rgb"] // 256 if sixteen_bits else fields["rgb"]
    return expected


def assert_las_read(got, fields):
    np.testing.assert_allclose(got.points, fields["ints"] * SCALE + OFFSET, rtol=1e-15, atol=0)
    assert got.normals is None
    expected = expected_las_properties(fields)
    assert sorted(got.properties) == sorted(expected)
    for name, values in expected.items():
        np.testing.assert_array_equal(got.properties[name], values, err_msg=name)


LAS_CASES = [(2, fmt) for fmt in range(6)] + [(4, fmt) for fmt in range(11)] + [(0, 1), (3, 3)]


@pytest.mark.parametrize("minor,fmt", LAS_CASES, ids=["1.%d-format%d" % case for case in LAS_CASES])
def test_las_point_formats(tmp_path, minor, fmt):
    # The 1.4 files also carry a VLR and 3 extra bytes per record, which the reader steps over.
    fields = las_points(fmt, 150, seed=fmt)
    if minor == 0:
        fields["classification"] = np.random.default_rng(5).integers(0, 256, 150)
        fields["class_is_a_byte"] = True
    if "rgb" in fields:
        assert fields["rgb"].max() > 255
    path = las_file(tmp_path / "points.las", fmt, fields, minor, extra_bytes=3 if minor == 4 else 0, vlr=minor == 4)
    assert_las_read(read(path), fields)


@pytest.mark.parametrize("minor,fmt", [(2, 2), (2, 3), (4, 7), (4, 10)])
def test_las_8_bit_colors(tmp_path, minor, fmt):
    fields = las_points(fmt, 100, seed=fmt, color_bits=8)
    got = read(las_file(tmp_path / "points.las", fmt, fields, minor))
    np.testing.assert_array_equal(got.properties["colors"], fields["rgb"])  # 0 to 255: kept as they are
    assert_las_read(got, fields)


def test_las_14_point_count(tmp_path):
    # LAS 1.4 may leave the 32-bit count 0 for any format: the 64-bit count at offset 247 is the count.
    fields = las_points(1, 80, seed=11)
    assert_las_read(read(las_file(tmp_path / "zero.las", 1, fields, minor=4, legacy_count=0)), fields)
    assert_refused(las_file(tmp_path / "disagree.las", 1, fields, minor=4, legacy_count=79),
                   "the header's point counts disagree (79 and 80)")


def test_extension_case(tmp_path):
    # The reader is chosen by the extension, whatever its case.
    fields = las_points(3, 40, seed=13)
    assert_las_read(read(las_file(tmp_path / "SCAN.LAS", 3, fields)), fields)
    values = pts_values(20, 7)
    assert_pts_read(read(text(tmp_path / "scan.Pts", [numbers(row) for row in values])), values, 7)


def test_las_refusals(tmp_path):
    fields = las_points(1, 50, seed=9)
    data = las_file(tmp_path / "good.las", 1, fields).read_bytes()

    def variant(name, content):
        (tmp_path / name).write_bytes(bytes(content))
        return tmp_path / name

    assert_refused(variant("cut.las", data[:-10]),
                   "truncated las file (the header announces 50 points of 28 bytes, the file holds 1390 bytes")
    laz_bit = bytearray(data)
    laz_bit[104] |= 0x80  # LASzip's mark of compressed records
    assert_refused(variant("laz_bit.las", laz_bit), "LAZ (compressed LAS) is not read", "laszip")
    assert_refused(variant("scan.laz", data), "LAZ (compressed LAS) is not read", "decompress it first")
    short = bytearray(data)
    struct.pack_into("<H", short, 105, 27)
    assert_refused(variant("short.las", short), "records of 27 bytes; point format 1 needs at least 28")
    assert_refused(las_file(tmp_path / "format6.las", 6, las_points(6, 10), minor=2),
                   "point format 6 needs LAS 1.4, the file says 1.2")
    assert_refused(las_file(tmp_path / "more.las", 1, fields, minor=4, count=60), "truncated las file")


# ----------------------------------------------------------------------------------------------------------------
# The program


def las_of_sphere(path):
    points = bumpy_sphere(300, seed=7)[0]
    fields = las_points(3, 300, seed=7)
    fields["ints"] = np.round((points * 100 - OFFSET) / SCALE).astype(np.int64)
    return las_file(path, 3, fields)


def ptx_of_sphere(path):
    points = bumpy_sphere(300, seed=8)[0] * 5
    local = np.insert(points, [0, 50, 100, 150, 200, 250, 300, 300], 0, axis=0)  # 8 without return
    m = ptx_transform(0.9, [0.1, 1.0, 0.2], [3.0, 4.0, -1.0])
    return text(path, ptx_scan(local, np.linspace(0, 1, len(local)), m, 44))


@pytest.mark.parametrize("kind,left_out", [("pcd", 20), ("las", 0), ("ptx", 8)])
def test_program_reads_formats(tmp_path, kind, left_out):
    make = {"pcd": lambda p: nan_pcd_of_sphere(p)[0], "las": las_of_sphere, "ptx": ptx_of_sphere}[kind]
    source, out = make(tmp_path / ("input." + kind)), tmp_path / "details.ply"
    result = subprocess.run([PROGRAM, "details", "-i", str(source), "-o", str(out)], capture_output=True, text=True,
                            env=PROGRAM_ENV)
    assert result.returncode == 0, result.stderr
    points = read(source).points
    assert len(points) == 300
    vertex = read_ply(out)
    np.testing.assert_array_equal(xyz(vertex), points)  # every point read, in file order
    note = "note: %d points of %s have no position" % (left_out, source)
    if left_out:
        assert note in result.stderr, result.stderr
    else:
        assert "no position" not in result.stderr, result.stderr
