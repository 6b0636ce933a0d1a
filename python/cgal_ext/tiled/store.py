"""Where the tiled runs read and write points: binary PLY, binary PCD and LAS files at their record layout, and
Zarr groups, row ranges at a time.

A source never loads its file whole: `read(a, b)` reads the records of one row range, with one read of the file
into a fresh array (a memory map of the file, faulted in 4 KiB at a time, cost more than the copy; and its pages
count in the worker's resident memory, which Dask's memory limit watches). Sources and sinks are small picklable
descriptions (a path and a layout); each Dask worker opens the file itself.
"""
import os
import re
import uuid
from pathlib import Path

import numpy as np

PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
PLY_NAMES = {"u1": "uchar", "f8": "double", "f4": "float", "i4": "int", "u4": "uint"}
MAX_HEADER = 1 << 20


class TiledError(ValueError):
    """A tiled run cannot go on: bad input, a tile that cannot be read, a cluster that does not answer."""


def open_source(path):
    """A `PlySource` or `ZarrSource` for `path`, checked: coordinates present, sizes consistent."""
    path = Path(path)
    if not path.exists():
        raise TiledError(f"{path}: no such file or directory")
    if path.is_dir():
        return ZarrSource(path)
    if path.suffix.lower() in (".pcd", ".las", ".laz"):
        return RecordSource(path)
    if path.suffix.lower() != ".ply":
        raise TiledError(f"{path}: the tiled runs read binary PLY, binary PCD and LAS (by row ranges) or a Zarr "
                         f"group, not '{path.suffix}' files; rewrite it as PLY (cgal_ext.read_points, then "
                         "cgal_ext.write_ply)")
    return PlySource(path)


def _parse_ply_header(path):
    """(byte order, vertex count, structured dtype, data offset) of a binary PLY whose first element is `vertex`."""
    with open(path, "rb") as f:
        head = f.read(MAX_HEADER)
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        raise TiledError(f"{path}: not a PLY file (no 'ply' magic or no end_header in its first MiB)")
    newline = head.find(b"\n", end)
    if newline < 0:
        raise TiledError(f"{path}: the PLY header does not end with a line break")
    offset = newline + 1
    lines = [line.strip() for line in head[:end].decode("ascii", "replace").splitlines()]
    order, elements = None, []
    for line in lines[1:]:
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            formats = {"binary_little_endian": "<", "binary_big_endian": ">"}
            if len(words) < 2 or words[1] not in formats:
                raise TiledError(f"{path}: format '{' '.join(words[1:])}' cannot be read by row ranges; the "
                                 "tiled runs read binary PLY (write it with cgal_ext.write_ply)")
            order = formats[words[1]]
        elif words[0] == "element" and len(words) == 3 and re.fullmatch(r"\d+", words[2]):
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            if len(words) != 3 or words[1] == "list":
                raise TiledError(f"{path}: property '{' '.join(words[1:])}' of element '{elements[-1][0]}' is "
                                 "not a scalar; the tiled runs read point sets (vertex elements of scalars)")
            if words[1] not in PLY_TYPES:
                raise TiledError(f"{path}: unknown PLY type '{words[1]}'")
            elements[-1][2].append((words[2], order + PLY_TYPES[words[1]] if order else PLY_TYPES[words[1]]))
        else:
            raise TiledError(f"{path}: malformed PLY header line '{line}'")
    if order is None:
        raise TiledError(f"{path}: the PLY header names no format")
    if not elements or elements[0][0] != "vertex":
        raise TiledError(f"{path}: the first PLY element must be 'vertex'")
    name, count, properties = elements[0]
    names = [p[0] for p in properties]
    if len(set(names)) != len(names):
        raise TiledError(f"{path}: a vertex property appears twice")
    dtype = np.dtype([(p, order + t[-2:]) for p, t in properties])
    return count, dtype, offset


class Source:
    """What the passes ask of an input: `path`, `count`, `dtype`, the fields of the coordinates and of the normals
    (None when there are none), optionally a `scale` and a `shift` of the coordinates, and `read(begin, end)`: the
    records of rows [begin, end), a structured array with those fields. `carried_columns`: the columns the tiles read
    as normals (a source may carry more after them)."""
    scale = shift = None
    carried_columns = 3

    @staticmethod
    def _columns(records, names):
        columns = np.empty((len(records), len(names)))
        for axis, name in enumerate(names):
            columns[:, axis] = records[name]
        return columns

    def points_of(self, records):
        """The points of `records`, float64 (n, 3)."""
        points = self._columns(records, self.coordinate_names)
        return points if self.scale is None else points * self.scale + self.shift

    def normals_of(self, records):
        """The normals of `records`, float64 (n, 3); None when the scan has none."""
        return self._columns(records, self.normal_names) if self.has_normals else None

    def coordinates(self, begin, end):
        """The points of rows [begin, end), float64 (n, 3)."""
        return self.points_of(self.read(begin, end))

    def points_and_normals(self, begin, end):
        """coordinates(begin, end) and normals(begin, end) from one read."""
        records = self.read(begin, end)
        return self.points_of(records), self.normals_of(records)


class FileSource(Source):
    """Fixed-size records of a file at `offset`, read a row range at a time."""

    def read(self, begin, end):
        # One read into a fresh array: faulting a mapping of the file in page by page cost more than the copy.
        with open(self.path, "rb") as f:
            records = np.fromfile(f, dtype=self.dtype, count=end - begin,
                                  offset=self.offset + begin * self.dtype.itemsize)
        if len(records) != end - begin:
            raise TiledError(f"{self.path}: rows {begin}..{end - 1} lie past the end of the file")
        return records


class PlySource(FileSource):
    """A binary PLY file's vertices."""

    def __init__(self, path):
        self.path = str(Path(path).resolve())
        self.count, self.dtype, self.offset = _parse_ply_header(self.path)
        missing = [c for c in "xyz" if c not in self.dtype.names]
        if missing:
            raise TiledError(f"{self.path}: the vertices have no {', '.join(missing)} coordinate")
        need = self.offset + self.count * self.dtype.itemsize
        size = os.path.getsize(self.path)
        if size < need:
            raise TiledError(f"{self.path}: truncated: the header announces {self.count} vertices "
                             f"({need} bytes with the header), the file has {size} bytes")
        self.has_normals = all(c in self.dtype.names for c in ("nx", "ny", "nz"))
        self.coordinate_names, self.normal_names = ("x", "y", "z"), ("nx", "ny", "nz") if self.has_normals else None


class RecordSource(FileSource):
    """A binary PCD or LAS file's points, at the offsets the I/O layer's header check gives
    (cgal_ext._core.record_layout): LAS coordinates are the records' integers times the scale plus the shift."""

    def __init__(self, path):
        from .. import _core
        self.path = str(Path(path).resolve())
        try:
            layout = _core.record_layout(self.path)
        except ValueError as error:
            raise TiledError(str(error)) from None
        self.count, self.offset = layout["points"], layout["data_offset"]
        fields = {name: (offset, kind) for name, offset, kind in layout["fields"]}
        used = list(layout["coordinates"]) + list(layout["normals"] or ())
        self.dtype = np.dtype({"names": used, "formats": ["<" + fields[n][1] for n in used],
                               "offsets": [fields[n][0] for n in used], "itemsize": layout["record_bytes"]})
        self.coordinate_names, self.normal_names = layout["coordinates"], layout["normals"]
        self.scale, self.shift = np.array(layout["scale"]), np.array(layout["shift"])
        self.has_normals = self.normal_names is not None

    def read(self, begin, end):
        records = super().read(begin, end)
        # The program leaves out a PCD point whose x, y and z are all NaN; a tiled run cannot drop rows.
        if all(records.dtype[name].kind == "f" for name in self.coordinate_names):
            missing = np.flatnonzero(np.logical_and.reduce([np.isnan(records[name])
                                                            for name in self.coordinate_names]))
            if len(missing):
                raise TiledError(f"{self.path}: point {begin + missing[0]} has no position (x, y and z NaN); the "
                                 "tiled runs need every row to be a point: write the scan without them first "
                                 "(point-detail leaves them out of its PLY outputs)")
        return records


class ZarrSource(Source):
    """A Zarr group with one 1-D array per field (x, y, z; nx, ny, nz when it has normals), as the runs write."""

    def __init__(self, path):
        import zarr
        self.path = str(Path(path).resolve())
        try:
            group = zarr.open_group(self.path, mode="r")
        except Exception as error:  # zarr raises several kinds for a folder that is not a group
            raise TiledError(f"{self.path}: not a Zarr group ({error})") from None
        missing = [c for c in "xyz" if c not in group.array_keys()]
        if missing:
            raise TiledError(f"{self.path}: the Zarr group has no array {', '.join(missing)} (one 1-D array per "
                             "coordinate, named as the PLY properties)")
        self.has_normals = all(c in group.array_keys() for c in ("nx", "ny", "nz"))
        fields = list("xyz") + (["nx", "ny", "nz"] if self.has_normals else [])
        shapes = {f: group[f].shape for f in fields}
        if any(len(s) != 1 for s in shapes.values()) or len(set(shapes.values())) != 1:
            raise TiledError(f"{self.path}: the arrays {', '.join(fields)} must be 1-D of one length, not "
                             + ", ".join(f"{f} {s}" for f, s in shapes.items()))
        for f in fields:
            if group[f].dtype.kind != "f":
                raise TiledError(f"{self.path}: array {f} holds {group[f].dtype}, not floating-point numbers")
        self.count = shapes["x"][0]
        self.dtype = np.dtype([(f, group[f].dtype) for f in fields])
        self.coordinate_names, self.normal_names = ("x", "y", "z"), ("nx", "ny", "nz") if self.has_normals else None

    def read(self, begin, end, names=None):
        """The records of rows [begin, end), with the fields `names` only when given."""
        import zarr
        group = zarr.open_group(self.path, mode="r")
        names = names or self.dtype.names
        records = np.empty(end - begin, dtype=[(name, self.dtype.fields[name][0]) for name in names])
        for name in names:
            records[name] = group[name][begin:end]
        return records

    def coordinates(self, begin, end):
        return self.points_of(self.read(begin, end, self.coordinate_names))


def _physical_memory():
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def temporary_beside(path):
    """A hidden name beside `path` for writing it whole before renaming."""
    path = Path(path)
    return path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp")


class PlySink:
    """The output PLY, written by row ranges into a file of its final size (binary little endian, as the program
    writes), under a temporary name until `commit`."""
    BLOCK_ROWS = 1 << 14

    def __init__(self, path, count, fields):
        self.path = str(path)
        self.temporary = str(temporary_beside(path))
        self.count = count
        self.dtype = np.dtype([(name, "<" + kind) for name, kind in fields])
        header = ["ply", "format binary_little_endian 1.0", "comment written by cgal_ext.tiled",
                  f"element vertex {count}"]
        header += [f"property {PLY_NAMES[kind]} {name}" for name, kind in fields]
        self.header = ("\n".join(header) + "\nend_header\n").encode("ascii")
        # A write pass far larger than memory whose pages are left for the kernel to write back ran slower on this
        # package's test machine, and one that fits ran faster: only an output over an eighth of the memory is
        # synced range by range (doc/scaling.md, "Costs").
        self.sync = len(self.header) + count * self.dtype.itemsize > _physical_memory() // 8

    def create(self):
        with open(self.temporary, "wb") as f:
            f.write(self.header)
            f.truncate(len(self.header) + self.count * self.dtype.itemsize)

    def write(self, begin, columns):
        rows = len(next(iter(columns.values())))
        # Records interleaved a block of rows at a time, which stays in the processor's cache while each field is
        # filled in.
        block = np.empty(min(rows, self.BLOCK_ROWS), dtype=self.dtype)
        fd = os.open(self.temporary, os.O_WRONLY)
        try:
            for first in range(0, rows, len(block)):
                part = block[:min(len(block), rows - first)]
                for name in self.dtype.names:
                    part[name] = columns[name][first:first + len(part)]
                data = memoryview(part).cast("B")
                offset = len(self.header) + (begin + first) * self.dtype.itemsize
                while data:
                    written = os.pwrite(fd, data, offset)
                    data, offset = data[written:], offset + written
            if self.sync:
                os.fdatasync(fd)
        finally:
            os.close(fd)

    def commit(self):
        os.replace(self.temporary, self.path)

    def discard(self):
        Path(self.temporary).unlink(missing_ok=True)


class ZarrSink:
    """The output Zarr group, one 1-D array per field chunked as the writers' row ranges, under a temporary name
    until `commit`."""

    def __init__(self, path, count, fields, chunk_rows):
        self.path = str(path)
        self.temporary = str(temporary_beside(path))
        self.count, self.fields, self.chunk_rows = count, fields, chunk_rows

    def create(self):
        import zarr
        group = zarr.open_group(self.temporary, mode="w")
        for name, kind in self.fields:
            group.create_dataset(name, shape=(self.count,), chunks=(self.chunk_rows,), dtype=kind)

    def write(self, begin, columns):
        import zarr
        group = zarr.open_group(self.temporary, mode="r+")
        for name, _ in self.fields:
            values = columns[name]
            group[name][begin:begin + len(values)] = values

    def commit(self):
        import shutil
        if Path(self.path).exists():
            if not (Path(self.path) / ".zgroup").exists():
                raise TiledError(f"{self.path}: exists and is not a Zarr group; not replaced")
            shutil.rmtree(self.path)
        os.replace(self.temporary, self.path)

    def discard(self):
        import shutil
        shutil.rmtree(self.temporary, ignore_errors=True)


def checked_output(path, source):
    """`path` as a Path, or a TiledError when it cannot be an output of a run on `source`."""
    path = Path(path)
    if path.suffix.lower() not in (".ply", ".zarr"):
        raise TiledError(f"{path}: the output's name must end in .ply or .zarr")
    if path.resolve() == Path(source.path):
        raise TiledError(f"{path}: is the input; the tiled runs never overwrite their input")
    if not path.parent.is_dir():
        raise TiledError(f"{path.parent}: no such folder for the output")
    return path


def open_sink(path, count, fields, chunk_rows):
    """A PlySink for OUT.ply, otherwise a ZarrSink (`run` has checked the name)."""
    path = Path(path)
    if path.suffix.lower() == ".ply":
        return PlySink(path, count, fields)
    return ZarrSink(path, count, fields, chunk_rows)
