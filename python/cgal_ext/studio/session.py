"""The studio's state: one scan, its selection, its edit and the edit's history, over the cgal_ext library.

Every public method either completes or raises StudioError before changing anything, so a refused message
leaves the session as it was (doc/studio.md, "Bad messages"). The web server (server.py) only parses messages
and calls these methods; nothing here knows about HTTP.
"""
import collections
import concurrent.futures
import json
import math
import os
import pathlib
import stat
import tempfile
import unicodedata

import numpy as np

import cgal_ext

from . import level_of_detail
from .selection import Graph

# A point's label: fixed, in the region, or a handle of group g (FIRST_HANDLE + g). The page gets these codes and
# the group limit in the geometry's header instead of spelling them itself.
FIXED, ROI, FIRST_HANDLE = 0, 1, 2
LABEL_CODES = {"fixed": FIXED, "roi": ROI, "first_handle": FIRST_HANDLE}
MAX_GROUPS = 8  # the page's shader holds this many handle transforms
# Undo goes back at most this many steps, and drops the oldest ones whose arrays (shown states, bases) take more.
HISTORY_STEPS = 100
HISTORY_BYTES = 1 << 30
COLOURINGS = ("relief", "magnitude", "curvature", "clusters")
ORDERS = ("linear", "quadric", "cubic")
SWING_RATIO = 2.0  # above it, a release warns that the region swung past its handles (as point-detail edit does)
ROTATIONS = ("propagate", "arap")  # as the edit JSON and the Python package spell them
STRENGTHS = ("euclidean", "geodesic")


class StudioError(Exception):
    """A request the session refuses; its message is shown in the page, `details` go with it in the reply (the
    files a save would replace, for the page's question)."""

    def __init__(self, message, **details):
        super().__init__(message)
        self.details = details


def _identity():
    return np.eye(4)


def _text_writer(content):
    return lambda path: pathlib.Path(path).write_text(content)


def _index_files(files):
    """(file name, writer) of each (file name, indices): one index per line, the program's format."""
    return [(file_name, _text_writer("".join("%d\n" % i for i in indices))) for file_name, indices in files]


def _pass_progress(progress, prefix):
    """A tiled run's progress(pass, done, tasks) as the session's progress(fraction, stage)."""
    def report(what, done, total):
        if progress:
            progress(done / max(total, 1), prefix + what)
    return report


_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])
_EYE3 = np.eye(3)


class Session:
    """A scan opened in the studio, inside the folder `root` that bounds every file it reads or writes. A scan of
    more than `level_of_detail_above` points is opened as its level of detail of about `level_points` points
    (level_of_detail.py)."""

    def __init__(self, root, level_of_detail_above=level_of_detail.LEVEL_OF_DETAIL_ABOVE,
                 level_points=level_of_detail.LEVEL_POINTS):
        self.level_of_detail_above, self.level_points = int(level_of_detail_above), int(level_points)
        self.level = None  # for a level of detail: the scan's path and points, the level's reach
        self.root = pathlib.Path(root).resolve()
        if not self.root.is_dir():
            raise StudioError("%s is not a folder" % root)
        # The folder held open: files are reached from it one name at a time, following no link (_open).
        self._root_fd = os.open(self.root, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        self.scan = None  # path relative to root
        self._scan_file = None  # the scan as read: its resolved path and (st_dev, st_ino)
        self._written = {}  # file name -> (st_dev, st_ino) of each file this session saved
        self.scan_points = self.points = self.normals = None  # the scan as read; the current edit's input
        # The program's defaults: the cubic order keeps sharper details but can swing a region far past its
        # handle (swing_warnings), so it is a choice, not the default.
        self.settings = {"order": "quadric", "rotations": "propagate", "strength_distance": "euclidean"}
        self.deformation = self.renderer = None
        self.chain = ()  # the committed steps: edits, detail scalings, fills (the saved JSON's "steps")
        self.history, self.step = [], 0
        # One Deformation per base and settings, whose selection-independent part (the mean shift) is computed in
        # the background from the moment the base exists, while its user paints (_editor_for).
        self._editors = collections.OrderedDict()
        # Per base, its local spacing and its selection graph, also computed in the background from the moment the
        # base exists, on a thread of their own: a fill, a check before an edit or a grown selection finds them done.
        self._bases = collections.OrderedDict()
        self._worker = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="studio-analysis")
        self._base_worker = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="studio-base")

    # ---- files ------------------------------------------------------------------------------------------------

    def inside(self, name, must_exist=True):
        """The path `name` (relative, inside the root, no link out of it) or StudioError."""
        return self._checked(name, must_exist)[0]

    def _checked(self, name, must_exist=True):
        """inside()'s path and the resolved path it checked."""
        if not isinstance(name, str) or not name or "\0" in name:
            raise StudioError("a file name must be a non-empty string")
        relative = pathlib.PurePosixPath(name)
        if relative.is_absolute() or ".." in relative.parts:
            raise StudioError("%r: give a path inside the studio's folder, without '..'" % name)
        path = self.root / relative
        try:
            resolved = path.resolve()
        except (OSError, RuntimeError):  # a loop of links
            raise StudioError("%r: a link that leads nowhere" % name)
        if resolved != self.root and self.root not in resolved.parents:
            raise StudioError("%r leads out of the studio's folder" % name)
        if must_exist and not resolved.is_file():
            raise StudioError("%r: no such file in the studio's folder" % name)
        return path, resolved

    def _open(self, name):
        """The file `name` opened for reading as inside() checked it: its resolved path walked from the folder's
        descriptor one name at a time, following no link, so that a link swapped in after the check makes the
        open fail instead of reading elsewhere. Returns the descriptor, its stat and the resolved path."""
        resolved = self._checked(name)[1]
        parts = resolved.relative_to(self.root).parts
        if not parts:
            raise StudioError("%r: no such file in the studio's folder" % name)
        folder = self._root_fd
        try:
            for part in parts[:-1]:
                inner = os.open(part, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC, dir_fd=folder)
                if folder != self._root_fd:
                    os.close(folder)
                folder = inner
            # O_NONBLOCK: a FIFO swapped in does not block the open (it is refused below).
            fd = os.open(parts[-1], os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC, dir_fd=folder)
        except OSError as error:
            raise StudioError("%r could not be opened as checked (%s); did it change meanwhile?" %
                              (name, error.strerror))
        finally:
            if folder != self._root_fd:
                os.close(folder)
        status = os.fstat(fd)
        if not stat.S_ISREG(status.st_mode):
            os.close(fd)
            raise StudioError("%r: no such file in the studio's folder" % name)
        return fd, status, resolved

    def _read_bytes(self, name):
        fd, _, _ = self._open(name)
        with os.fdopen(fd, "rb") as file:
            return file.read()

    def _read_text(self, name):
        try:
            return self._read_bytes(name).decode("utf-8")
        except UnicodeDecodeError:
            raise StudioError("%s is not UTF-8 text" % name)

    def _read_points(self, name):
        """cgal_ext.read_points of the file `name` as _open checked it. The library reads by path and tells the
        format by the extension: it is given a link in a private folder to the open descriptor (Linux's
        /proc/self/fd), or a copy of the file where there is none."""
        fd, status, resolved = self._open(name)
        try:
            with tempfile.TemporaryDirectory(prefix="cgal_ext_studio.") as private:
                alias = os.path.join(private, "scan" + resolved.suffix.lower())
                descriptor = "/proc/self/fd/%d" % fd
                if os.path.exists(descriptor):
                    os.symlink(descriptor, alias)
                else:
                    with open(alias, "wb") as copy:
                        while chunk := os.read(fd, 1 << 20):
                            copy.write(chunk)
                try:
                    cloud = cgal_ext.read_points(alias)
                except (OSError, ValueError, RuntimeError) as error:
                    raise StudioError(str(error).replace(alias, name))
        finally:
            os.close(fd)
        return cloud, status, resolved

    def files(self):
        """The scans the page may open: point files under the root, relative paths."""
        found = []
        for dirpath, dirnames, filenames in os.walk(self.root):
            dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
            for f in sorted(filenames):
                if f.lower().endswith((".ply", ".off", ".xyz", ".pwn", ".pcd", ".pts", ".ptx", ".las")):
                    found.append(str(pathlib.Path(dirpath, f).relative_to(self.root)))
                    if len(found) >= 1000:
                        return found
        return found

    def load(self, name, progress=None):
        """Reads a scan (normals estimated when it has none, as the program does), or the level of detail of a
        scan too large to edit whole, and starts a new history. `progress(fraction, stage=None)`."""
        resolved = self._checked(name)[1]
        count = level_of_detail.point_count(resolved)
        if count is not None and count > self.level_of_detail_above:
            points, normals, level, status = self._read_level(name, resolved, count, progress)
        else:
            cloud, status, resolved = self._read_points(name)
            points, normals, level = cloud.points, cloud.normals, None
        if len(points) < 20:
            raise StudioError("%s has %d points; editing needs at least 20" % (name, len(points)))
        if normals is None or not np.all(np.isfinite(normals)) or np.any(np.all(normals == 0, axis=1)):
            if normals is not None:
                raise StudioError("%s has missing or zero normals; give all or none" % name)
            normals = cgal_ext.estimate_oriented_normals(points, k=min(18, len(points)), progress=progress)
        self.level = level
        self.scan, self.scan_points = name, points
        self._scan_file = (resolved, (status.st_dev, status.st_ino))
        self.points, self.normals = points, normals
        self.chain = ()
        self._editors.clear()
        self._bases.clear()
        self._blank_edit()
        self.history, self.step = [self._snapshot("open")], 0
        self._start_editor()

    def _read_level(self, name, resolved, count, progress):
        """The level of detail of the scan `name` (`count` points), read on Dask by path (its workers cannot be
        handed the open file) and cached beside it; with its level description and the scan's stat."""
        from ..tiled import TiledError
        try:
            status = os.stat(resolved)
            points, normals, reach, built = level_of_detail.open_level(resolved, count, self.level_points,
                                                                       _pass_progress(progress, "level of detail: "))
        except (TiledError, OSError) as error:
            raise StudioError("%s: %s" % (name, str(error).replace(str(resolved), name)))
        return points, normals, {"path": resolved, "points": count, "reach": reach, "built": built}, status

    def _blank_edit(self):
        """A new edit of the current base: no selection, no groups, shown as the base."""
        self.labels = np.zeros(len(self.points), np.int8)
        self.groups = 0
        self.transforms = []  # per group, the 4x4 of the drag under way or of the shown state
        self.shown_points, self.shown_normals = self.points, self.normals
        self.ssp_index = None  # the prepared edit's sample point of each point (saved as ssp_index)
        self._drop_deformation()

    def _drop_deformation(self):
        self.deformation = None
        self.renderer = None
        self._stale = False  # the deformation's handle transforms are not the session's (after undo, redo)

    # ---- history ----------------------------------------------------------------------------------------------
    # A step of history is a snapshot of everything an undo restores: the committed chain, the current edit's
    # input (the base), its selection, groups, settings and transforms, and the shown state. The arrays in it are
    # never changed in place, so snapshots share them.

    def _snapshot(self, kind):
        return {"kind": kind, "chain": self.chain, "points": self.points, "normals": self.normals,
                "labels": self.labels, "groups": self.groups, "transforms": tuple(self.transforms),
                "settings": dict(self.settings), "shown_points": self.shown_points,
                "shown_normals": self.shown_normals, "ssp_index": self.ssp_index}

    def _record(self, kind):
        """A new step of history after the current one (the steps that could be redone are dropped; the oldest
        ones too, beyond HISTORY_STEPS steps or HISTORY_BYTES of arrays held only by them)."""
        del self.history[self.step + 1:]
        self.history.append(self._snapshot(kind))
        self.step += 1
        while len(self.history) > 2 and (len(self.history) > HISTORY_STEPS or self._history_bytes() > HISTORY_BYTES):
            del self.history[0]
            self.step -= 1

    def _history_bytes(self):
        """The bytes of the arrays the history holds that the current step does not."""
        current = {id(a) for a in self.history[self.step].values() if isinstance(a, np.ndarray)}
        held = {}
        for snapshot in self.history:
            for a in snapshot.values():
                if isinstance(a, np.ndarray) and id(a) not in current:
                    held[id(a)] = a.nbytes
        return sum(held.values())

    def _amend(self):
        """The current step updated with a selection or settings changed at the start of an edit (painting is not
        a step of history; the steps that could be redone, made on the old selection, are dropped)."""
        del self.history[self.step + 1:]
        self.history[self.step] = dict(self._snapshot(self.history[self.step]["kind"]))

    def _restore(self, snapshot):
        """The session as `snapshot` recorded it; whether the page needs the whole geometry again (another base or
        selection, or the edit no longer prepared) rather than the moved points."""
        same_edit = (snapshot["points"] is self.points and snapshot["labels"] is self.labels and
                     snapshot["settings"] == self.settings and self.deformation is not None)
        self.chain = snapshot["chain"]
        self.points, self.normals = snapshot["points"], snapshot["normals"]
        self.labels, self.groups = snapshot["labels"], snapshot["groups"]
        self.transforms = [T.copy() for T in snapshot["transforms"]]
        self.settings = dict(snapshot["settings"])
        self.shown_points, self.shown_normals = snapshot["shown_points"], snapshot["shown_normals"]
        self.ssp_index = snapshot["ssp_index"]
        if same_edit:
            self._stale = True  # solved again from these transforms at the next drag or release
        else:
            self._drop_deformation()  # prepared again (Edit) before the next drag
        return not same_edit

    def undo(self):
        """One step back: a drag, a commit, a fill or applied details. Returns whether the geometry changed beyond
        the prepared edit's points (see _restore)."""
        self._require_scan()
        if self.step == 0:
            raise StudioError("nothing to undo")
        self.step -= 1
        return self._restore(self.history[self.step])

    def redo(self):
        self._require_scan()
        if self.step + 1 >= len(self.history):
            raise StudioError("nothing to redo")
        self.step += 1
        return self._restore(self.history[self.step])

    def _editor_for(self, points, normals, settings):
        """The Deformation of a base and settings, its points analysed in the background from the moment the base
        exists; the two most recent kept, so that undoing a commit finds its edit's analysis done."""
        key = (id(points), tuple(sorted(settings.items())))
        if key not in self._editors:
            def make():
                editor = cgal_ext.Deformation(points, normals, order=settings["order"],
                                              rotations=settings["rotations"],
                                              strength_distance=settings["strength_distance"])
                editor.analyse_points()
                return editor
            # The points are kept with the future: the key's id stays theirs.
            self._editors[key] = (points, self._worker.submit(make))
            while len(self._editors) > 2:
                self._editors.popitem(last=False)
        self._editors.move_to_end(key)
        return self._editors[key][1]

    def _start_editor(self):
        self._editor_for(self.points, self.normals, dict(self.settings))
        self._base_analysis(self.points)

    def _base_analysis(self, points):
        """The futures of the local spacing and the selection graph of a base; the three most recent kept."""
        key = id(points)
        if key not in self._bases:
            spacing = self._base_worker.submit(cgal_ext.compute_local_spacing, points)
            graph = self._base_worker.submit(Graph, points)
            self._bases[key] = (points, spacing, graph)  # the points kept: the key's id stays theirs
            while len(self._bases) > 3:
                self._bases.popitem(last=False)
        self._bases.move_to_end(key)
        return self._bases[key][1:]

    def _require_scan(self):
        if self.points is None:
            raise StudioError("open a scan first")

    # ---- selection --------------------------------------------------------------------------------------------

    def _at_edit_start(self):
        return self.history[self.step]["kind"] != "drag" and \
            all(np.array_equal(T, _identity()) for T in self.transforms)

    def _require_undeformed(self, what):
        if not self._at_edit_start():
            raise StudioError("%s changes the edit's selection or settings: undo the drags first (or commit the "
                              "edit and start a new one)" % what)

    def _set_selection(self, labels, groups=None):
        """A checked new selection, at the start of the edit."""
        self.labels = labels
        if groups is not None:
            self.groups = groups
            self.transforms = [_identity() for _ in range(groups)]
        self._drop_deformation()
        self.ssp_index = None  # another selection, other sample points
        self._amend()

    def new_group(self):
        self._require_scan()
        self._require_undeformed("a new handle group")
        if self.groups >= MAX_GROUPS:
            raise StudioError("at most %d handle groups" % MAX_GROUPS)
        self._set_selection(self.labels, self.groups + 1)
        return self.groups - 1

    def _check_target(self, target, group, what):
        if target not in ("roi", "handle"):
            raise StudioError("%s: target must be roi or handle" % what)
        if target == "handle" and not (type(group) is int and 0 <= group < self.groups):
            raise StudioError("there is no handle group %r (%d groups)" % (group, self.groups))

    def _painted(self, target, mode, indices, group):
        """The labels with `indices` painted into the region or handle group `group`, or erased from it."""
        labels = self.labels.copy()
        if target == "roi":
            labels[indices] = ROI if mode == "add" else FIXED  # erasing the region erases its handles too
        else:
            handle = FIRST_HANDLE + group
            if mode == "add":
                labels[indices] = handle  # a handle point is in the region; it leaves any other group
            else:
                labels[indices[labels[indices] == handle]] = ROI
        return labels

    def select(self, target, mode, indices, group=0):
        """Paints `indices` into the region (target 'roi') or a handle group ('handle'), or erases them."""
        self._require_scan()
        self._require_undeformed("painting")
        indices = np.asarray(indices)
        if indices.dtype.kind not in "iu" or indices.ndim != 1:
            raise StudioError("a selection is a list of point indices")
        if len(indices) and (indices.min() < 0 or indices.max() >= len(self.points)):
            raise StudioError("a selected index is out of range (%d points)" % len(self.points))
        if target not in ("roi", "handle") or mode not in ("add", "erase"):
            raise StudioError("select: target must be roi or handle, mode add or erase")
        self._check_target(target, group, "select")
        self._set_selection(self._painted(target, mode, indices, group))

    def invert(self):
        """Swaps the region and the fixed part (handle points stay handles)."""
        self._require_scan()
        self._require_undeformed("inverting")
        labels = self.labels.copy()
        labels[self.labels == FIXED] = ROI
        labels[self.labels == ROI] = FIXED
        self._set_selection(labels)

    def clear(self):
        self._require_scan()
        self._require_undeformed("clearing")
        self._set_selection(np.zeros(len(self.points), np.int8), 0)

    def _checked_settings(self, settings):
        new = dict(self.settings)
        for key, value in settings.items():
            allowed = {"order": ORDERS, "rotations": ROTATIONS, "strength_distance": STRENGTHS}.get(key)
            if allowed is None:
                raise StudioError("unknown setting %r (order, rotations, strength_distance)" % key)
            if not isinstance(value, str) or value not in allowed:
                raise StudioError("%s must be one of %s, not %s" % (key, ", ".join(allowed), repr(value)[:40]))
            new[key] = value
        return new

    def _use_settings(self, settings):
        if settings != self.settings:
            self.settings = settings
            self._drop_deformation()
            self.ssp_index = None
            self._start_editor()

    def set_settings(self, **settings):
        self._require_scan()
        self._require_undeformed("changing the settings")
        self._use_settings(self._checked_settings(settings))
        self._amend()

    # ---- editing ----------------------------------------------------------------------------------------------

    def _check_preparable(self):
        self._require_scan()
        if not np.any(self.labels != FIXED):
            raise StudioError("paint a region of interest first")
        if self.groups == 0 or not all(np.any(self.labels == FIRST_HANDLE + g) for g in range(self.groups)):
            raise StudioError("every handle group needs points: paint a handle")

    def preprocess(self, progress=None):
        """Builds the deformation of the current selection; returns what the page's shader needs."""
        self._check_preparable()
        if self.deformation is not None:
            return self.renderer
        try:
            deformation = self._editor_for(self.points, self.normals, self.settings).result()
        except ValueError as error:
            raise StudioError(str(error))
        try:
            deformation.reset()
            deformation.clear_selection()
            deformation.insert_roi(self.labels != FIXED)
            for g in range(self.groups):
                deformation.create_handle_group(self.labels == FIRST_HANDLE + g)
            if not deformation.preprocess(progress=progress):
                raise StudioError("preprocessing was cancelled")
            # An edit restored by undo starts from its transforms (the page draws it from them).
            for g, T in enumerate(self.transforms):
                deformation.set_handle_transform(g, transform=T)
        except ValueError as error:
            raise StudioError(str(error))
        setup = deformation.renderer_setup()
        region_samples = np.unique(deformation.sample_point_of(self.labels != FIXED))
        carried = np.isin(setup["stencil_samples"], region_samples).any(axis=1) | (setup["exact_handle"] != 0)
        setup["movable"] = np.flatnonzero(carried).astype(np.uint32)
        setup["handle_group"] = np.where(self.labels >= FIRST_HANDLE, self.labels - FIRST_HANDLE, -1).astype(np.int8)
        self.deformation, self.renderer, self._stale = deformation, setup, True
        self.ssp_index = deformation.sample_point_of(np.ones(len(self.points), bool)).astype(float)
        self.history[self.step]["ssp_index"] = self.ssp_index  # what a save of this step writes
        return setup

    def _transform(self, matrix, group):
        if not (type(group) is int and 0 <= group < self.groups):
            raise StudioError("there is no handle group %r (%d groups)" % (group, self.groups))
        try:
            T = np.array(matrix, dtype=float).reshape(4, 4)
        except (TypeError, ValueError):
            raise StudioError("a transform is 16 numbers (a 4x4 matrix, row by row)")
        if not np.isfinite(T).all():
            raise StudioError("the transform is not finite")
        # Elementwise checks rather than np.allclose: this runs once per drag frame, and each allclose call costs as
        # much as the rest together.
        R = T[:3, :3]
        if (abs(T[3] - _LAST_ROW) > 1e-8 + 1e-5 * _LAST_ROW).any() or abs(R.T @ R - _EYE3).max() > 1e-5 \
                or np.linalg.det(R) <= 0:
            raise StudioError("the transform is not a rigid motion (rotation and translation)")
        # The nearest rotation: the page's float32 matrix is orthonormal to about 1e-7, the library wants 1e-6.
        u, _, vt = np.linalg.svd(R)
        T[:3, :3] = u @ vt
        T[3] = _LAST_ROW
        return T

    def drag(self, group, matrix, also=None):
        """One frame of a drag: the handle group's transform (from the rest pose), and in `also` other groups'
        transforms set in the same frame ([{"group": h, "matrix": [16]}], mirrored editing); returns the frame's
        motions. A transform whose solve fails is refused and the edit stays on the transforms before it."""
        if self.deformation is None:
            raise StudioError("a drag needs the edit preprocessed: paint a region and a handle, then edit")
        moves = {group: self._transform(matrix, group)}
        if also is not None:
            if not isinstance(also, list) or len(also) > MAX_GROUPS or \
                    not all(isinstance(a, dict) and set(a) <= {"group", "matrix"} for a in also):
                raise StudioError("also is a list of {group, matrix} of other handle groups")
            for a in also:
                h = a.get("group")
                if type(h) is int and h in moves:
                    raise StudioError("also: handle group %d is moved twice in one frame" % h)
                moves[h] = self._transform(a.get("matrix"), h)
        d = self.deformation
        try:
            if self._stale:
                for g, T in enumerate(self.transforms):
                    d.set_handle_transform(g, transform=T)
            for g, T in moves.items():
                d.set_handle_transform(g, transform=T)
            d.deform()
            frame = d.renderer_frame()
            if not np.isfinite(frame).all():
                raise ValueError("the sample points' motions are not finite")
        except (ValueError, RuntimeError) as error:
            self._restore_deformation()
            raise StudioError("the drag was refused, the handle stays where it was: %s" % error)
        for g, T in moves.items():
            self.transforms[g] = T
        self._stale = False
        return frame

    def _restore_deformation(self):
        """The deformation back on the session's transforms after a solve that failed."""
        d = self.deformation
        try:
            for g, T in enumerate(self.transforms):
                d.set_handle_transform(g, transform=T)
            d.deform()
        except (ValueError, RuntimeError):  # what the failed solve left behind: solved again from the rest pose
            d.reset()
            for g, T in enumerate(self.transforms):
                d.set_handle_transform(g, transform=T)
            d.deform()
        self._stale = False

    def _dragged(self):
        """Whether the transforms differ from the shown step's: a drag under way, not released."""
        recorded = self.history[self.step]["transforms"]
        return len(recorded) != len(self.transforms) or \
            any(not np.array_equal(a, b) for a, b in zip(recorded, self.transforms))

    def release(self):
        """The end of a drag: the full diffusion and restore_details become the shown state (a step of history;
        a release with nothing dragged since the last changes nothing)."""
        if self.deformation is None:
            raise StudioError("release without a drag")
        if not self._dragged():
            return
        self._show(self.transforms)
        self._record("drag")

    def swing_warnings(self):
        """After a release: a warning when parts of the region moved more than SWING_RATIO times as far as any
        handle (the solve swings them; point-detail edit warns alike), else none."""
        if self.deformation is None or self.step == 0 or self.history[self.step]["kind"] != "drag":
            return []
        ratio = self.deformation.statistics()["displacement_ratio"]
        if not ratio > SWING_RATIO:
            return []
        return [{"kind": "swing", "message": (
            "parts of the region moved %.1f times as far as any handle: the solve swings them; undo, then choose "
            "the quadric order or as-rigid-as-possible rotations" % ratio)}]

    def _show(self, transforms):
        """Shows the edit under `transforms`, or raises StudioError with the session unchanged."""
        d = self.deformation
        try:
            for g, T in enumerate(transforms):
                d.set_handle_transform(g, transform=T)
            if all(np.array_equal(T, _identity()) for T in transforms):
                d.reset()
                points, normals = self.points, self.normals
            else:
                d.deform()
                normals = d.diffuse().normals
                points = d.restore_details().points
            if not (np.isfinite(points).all() and np.isfinite(normals).all()):
                raise ValueError("the deformed points are not finite")
        except (ValueError, RuntimeError) as error:
            self._restore_deformation()
            raise StudioError("the edit could not be shown: %s" % error)
        self.shown_points, self.shown_normals = points, normals
        self.transforms = [t.copy() for t in transforms]
        self._stale = False

    def _require_released_edit(self, what):
        if self._dragged():
            raise StudioError("%s: release the drag first" % what)
        if self.history[self.step]["kind"] != "drag":
            raise StudioError("%s needs a released drag of the current edit: drag a handle and release it first" % what)

    def _edit_step(self):
        """The current edit as a step of the chain (its shown, released state)."""
        return {"type": "edit", "labels": self.labels, "groups": self.groups,
                "transforms": tuple(T.copy() for T in self.transforms), "settings": dict(self.settings),
                "ssp_index": self.ssp_index}

    def _require_whole(self, what):
        """Refuses what a level of detail cannot carry to its scan: the tiled edit saves one edit."""
        if self.level is not None:
            raise StudioError("%s: this scan is open as its level of detail, whose save carries one edit to its %d "
                              "points; commits, detail scalings and fills stay with scans of at most %d points" %
                              (what, self.level["points"], self.level_of_detail_above))

    def commit(self):
        """The shown state becomes the base of a new edit (no selection, no groups): one step of history."""
        self._require_scan()
        self._require_whole("commit")
        self._require_released_edit("commit")
        chain = self.chain + (self._edit_step(),)
        self._new_base(chain, self.shown_points, self.shown_normals, "commit")

    def _new_base(self, chain, points, normals, kind, labels=None, groups=0):
        """A new edit on `points`, after the chain `chain`: recorded as a step of history of kind `kind`."""
        self.chain = chain
        self.points, self.normals = points, normals
        self._blank_edit()
        if labels is not None:
            self.labels, self.groups = labels, groups
            self.transforms = [_identity() for _ in range(groups)]
        self._start_editor()
        self._record(kind)

    # ---- details ----------------------------------------------------------------------------------------------

    def details(self, mode, s, apply=False):
        """Scales or enhances the details of the painted region (its points: region and handles) by `s`, as
        point-detail scale / enhance do; with `apply`, a step of the chain: the result, its normals refitted where
        points moved, becomes the input of the edit (its selection kept)."""
        self._require_scan()
        if apply is True:
            self._require_whole("applying details")
        self._require_undeformed("changing the details")
        if mode not in ("scale", "enhance"):
            raise StudioError("details: mode must be scale or enhance")
        if not isinstance(s, (int, float)) or isinstance(s, bool) or not math.isfinite(s) or not 0 <= s <= 3:
            raise StudioError("details: s must be a number from 0 to 3")
        if not isinstance(apply, bool):
            raise StudioError("details: apply is true or false")
        roi = self.labels != FIXED
        if not roi.any():
            raise StudioError("paint the region whose details change first")
        function = cgal_ext.scale_geometric_details if mode == "scale" else cgal_ext.enhance_geometric_details
        try:
            result = function(self.points, self.normals, roi=roi, s=float(s))
            normals = self.normals
            if apply:
                moved = np.flatnonzero((result != self.points).any(axis=1))
                if len(moved):
                    normals = cgal_ext.refit_normals(result, self.normals, moved)
        except (ValueError, RuntimeError) as error:
            raise StudioError(str(error))
        if apply:
            step = {"type": mode, "s": float(s), "roi": roi}
            self._new_base(self.chain + (step,), result, normals, mode, self.labels, self.groups)
        return result

    # ---- selection over the neighbour graph -------------------------------------------------------------------

    def graph(self):
        """The selection graph of the current base (computed in the background from the moment it exists)."""
        try:
            return self._base_analysis(self.points)[1].result()
        except ValueError as error:  # points the library refuses to take neighbourhoods of (a pile of duplicates)
            raise StudioError(str(error))

    def grow(self, target, group=0):
        """The region, or handle group `group`, grown by one ring of neighbours. A handle takes in fixed and region
        points, never another group's."""
        self._require_scan()
        self._require_undeformed("growing the selection")
        self._check_target(target, group, "grow")
        labels = self.labels.copy()
        if target == "roi":
            labels[self.graph().ring(self.labels != FIXED) & (self.labels == FIXED)] = ROI
        else:
            handle = FIRST_HANDLE + group
            labels[self.graph().ring(self.labels == handle) & (self.labels < FIRST_HANDLE)] = handle
        self._set_selection(labels)

    def shrink(self, target, group=0):
        """The region, or handle group `group`, less its points that have a neighbour outside it. The region never
        loses handle points; a handle's border points go back to the region."""
        self._require_scan()
        self._require_undeformed("shrinking the selection")
        self._check_target(target, group, "shrink")
        labels = self.labels.copy()
        if target == "roi":
            labels[self.graph().border(self.labels != FIXED) & (self.labels == ROI)] = FIXED
        else:
            labels[self.graph().border(self.labels == FIRST_HANDLE + group)] = ROI
        self._set_selection(labels)

    def select_connected(self, target, mode, group, seed):
        """The connected part of the neighbour graph that holds point `seed`, painted like select()."""
        self._require_scan()
        self._require_undeformed("painting")
        if mode not in ("add", "erase"):
            raise StudioError("select_connected: mode must be add or erase")
        self._check_target(target, group, "select_connected")
        if type(seed) is not int or not 0 <= seed < len(self.points):
            raise StudioError("select_connected: seed is a point index (%d points)" % len(self.points))
        part = np.flatnonzero(self.graph().flood(np.array([seed])) >= 0)
        self._set_selection(self._painted(target, mode, part, group))
        return len(part)

    def grow_region_around(self, group):
        """The remedy for a handle group lying in the fixed part: the region grown from the group through fixed
        points, at least 3 rings and as far as the group's radius beyond it (the largest distance of its points from
        their centroid, measured from the centroid: within twice that)."""
        self._require_scan()
        self._require_undeformed("growing the region")
        self._check_target("handle", group, "grow_region_around")
        handle = np.flatnonzero(self.labels == FIRST_HANDLE + group)
        if not len(handle):
            raise StudioError("handle group %d has no points to grow the region around" % group)
        centre = self.points[handle].mean(axis=0)
        radius = np.linalg.norm(self.points[handle] - centre, axis=1).max()
        near = np.linalg.norm(self.points - centre, axis=1) <= 2 * radius
        graph, fixed = self.graph(), self.labels == FIXED
        ring = graph.flood(handle, allowed=fixed, rings=3)
        grown = ring > 0
        # Beyond the 3 rings, on through fixed points near the handle.
        farther = graph.flood(np.flatnonzero(ring >= 0), allowed=fixed & near)
        grown |= farther > 0
        labels = self.labels.copy()
        labels[grown] = ROI
        self._set_selection(labels)
        return int(grown.sum())

    def warnings(self):
        """What makes the prepared edit tear: a handle group with no movable region point among its neighbours
        (an island in the fixed part, pulled off it by the drag), a region with no fixed point among its
        neighbours (nothing holds it). A list of {kind, group?, message}, empty when the edit makes sense."""
        self._check_preparable()
        graph, found = self.graph(), []
        for g in range(self.groups):
            handle = np.flatnonzero(self.labels == FIRST_HANDLE + g)
            if not np.any(self.labels[graph.of(handle)] == ROI):
                found.append({"kind": "island", "group": g, "message": (
                    "handle group %d touches no movable point of the region: it lies in the fixed part, and a drag "
                    "would pull it off, leaving a trail of loose points; grow the region around it" % g)})
        region = self.labels != FIXED
        if not np.any(self.labels[graph.of(np.flatnonzero(region))] == FIXED):
            found.append({"kind": "no_fixed_part", "message": (
                "the region touches no fixed point: nothing holds it, and it would move as a whole with the "
                "handles")})
        return found

    # ---- filling ----------------------------------------------------------------------------------------------

    def fill(self, progress=None):
        """Commits the current edit and fills what it stretched: the library's up-sampling of the points it moved,
        at the local spacing of its input (point-detail edit --upsample); the new points are appended. One step
        of history, two of the chain (the edit, the fill)."""
        self._require_scan()
        self._require_whole("fill")
        self._require_released_edit("fill")
        moved = np.flatnonzero((self.shown_points != self.points).any(axis=1))
        if not len(moved):
            raise StudioError("fill: the edit moved no point")
        try:
            spacing = self._base_analysis(self.points)[0].result()
            added = cgal_ext.upsample_point_set(self.shown_points, self.shown_normals, roi=moved,
                                                spacing_before=spacing, progress=progress)
        except (ValueError, RuntimeError) as error:
            raise StudioError("fill failed: %s" % error)
        points = np.concatenate([self.shown_points, added.points])
        normals = np.concatenate([self.shown_normals, added.normals])
        chain = self.chain + (self._edit_step(), {"type": "fill", "inserted": len(added.points)})
        self._new_base(chain, points, normals, "fill")
        return len(added.points)

    def drawn_spacing(self):
        """The spacing the page draws each shown point with, and whether it is the base's own: its local spacing
        once computed (the shown points of an edit keep their input's); until then that of the latest base whose
        spacing is known and that has no more points (an edit keeps the points' order, a fill appends), with its
        median for the points it lacks; None before any is known."""
        n = len(self.points)
        for key in reversed(self._bases):
            points, future, _ = self._bases[key]
            if future.done() and not future.exception() and len(points) <= n:
                spacing = future.result().astype(np.float32)
                exact = points is self.points
                if len(spacing) < n:
                    spacing = np.concatenate([spacing, np.full(n - len(spacing), np.median(spacing), np.float32)])
                return spacing, exact
        return None, False

    def base_spacing(self):
        """The future of the current base's local spacing (for the page, once computed)."""
        return self.points, self._base_analysis(self.points)[0]

    def inserted(self):
        """Which points a fill inserted (they follow the scan's), None when none did."""
        n = len(self.scan_points)
        if len(self.shown_points) == n:
            return None
        flags = np.zeros(len(self.shown_points), np.uint8)
        flags[n:] = 1
        return flags

    # ---- saving -----------------------------------------------------------------------------------------------

    def _saved_chain(self):
        """The chain a save writes, from the shown step: the committed steps, then the current edit when it has a
        selection (with the released transforms of the shown step; identity before any drag)."""
        snapshot = self.history[self.step]
        chain = list(snapshot["chain"])
        labels, groups = snapshot["labels"], snapshot["groups"]
        if groups and (labels != FIXED).any():
            chain.append({"type": "edit", "labels": labels, "groups": groups, "transforms": snapshot["transforms"],
                          "settings": snapshot["settings"], "ssp_index": snapshot["ssp_index"]})
        return snapshot, chain

    @staticmethod
    def _step_json(step, prefix, spec="indices"):
        """A step as the program's edit JSON spells it, and its index files: (json, [(file name, indices)]); its
        selections as `spec`:FILE (nearest: for a level of detail, whose indices are the level's)."""
        files = []
        if step["type"] == "fill":
            return {"type": "fill"}, files
        roi = step["labels"] != FIXED if step["type"] == "edit" else step["roi"]
        files.append((prefix + ".roi.txt", np.flatnonzero(roi)))
        if step["type"] != "edit":
            return {"type": step["type"], "s": step["s"], "roi": ["%s:%s.roi.txt" % (spec, prefix)]}, files
        handles = []
        for g in range(step["groups"]):
            T = step["transforms"][g]
            files.append(("%s.handle%d.txt" % (prefix, g), np.flatnonzero(step["labels"] == FIRST_HANDLE + g)))
            handles.append({"select": ["%s:%s.handle%d.txt" % (spec, prefix, g)],
                            "matrix": T[:3, :3].tolist(), "translation": T[:3, 3].tolist()})
        settings = step["settings"]
        return {"type": "edit", "roi": ["%s:%s.roi.txt" % (spec, prefix)], "handles": handles,
                "filter": {"order": settings["order"]}, "rotations": settings["rotations"],
                "strength_distance": settings["strength_distance"]}, files

    def edit_json(self, name):
        """The chain as the program's edit JSON ("steps"), its selections in index files NAME.step<k>.*.txt."""
        return self._edit_files(name)[0]

    def _edit_files(self, name):
        _, chain = self._saved_chain()
        steps, files = [], []
        for k, step in enumerate(chain):
            spelt, indices = self._step_json(step, "%s.step%d" % (name, k))
            steps.append(spelt)
            files += indices
        return {"steps": steps}, files

    @staticmethod
    def _check_save_name(name):
        if not isinstance(name, str) or not name or "/" in name or "\\" in name or name.startswith("."):
            raise StudioError("save: give a file name without folders, e.g. 'edited'")
        if any(unicodedata.category(c) in ("Cc", "Cf", "Cs", "Zl", "Zp") for c in name):
            raise StudioError("save: a file name without control characters")
        if name != name.strip():
            raise StudioError("save: a file name without spaces at its start or end")
        if len(name.encode()) > 200:
            raise StudioError("save: a file name of at most 200 bytes")

    def _outputs(self, name, progress=None):
        """The files a save as `name` writes, in the order they are put in place: (file name, writer of a path)."""
        if self.level is not None:
            return self._level_outputs(name, progress)
        outputs = []
        snapshot, chain = self._saved_chain()
        if chain:
            edit, files = self._edit_files(name)
            outputs += _index_files(files)
            outputs.append((name + ".json", _text_writer(json.dumps(edit, indent=2) + "\n")))
        points, normals = snapshot["shown_points"], snapshot["shown_normals"]
        n, scanned = len(points), len(self.scan_points)
        # The program's fields: distance from the scan (0 for inserted points), the last edit's status and sample
        # points (0 for points inserted after it), which points a fill inserted.
        moved = np.zeros(n)
        moved[:scanned] = np.linalg.norm(points[:scanned] - self.scan_points, axis=1)
        status, sample = np.zeros(n), np.zeros(n)
        edits = [step for step in chain if step["type"] == "edit"]
        if edits:
            last = edits[-1]
            status[:len(last["labels"])] = np.minimum(last["labels"], 2)
            if last["ssp_index"] is not None:
                sample[:len(last["ssp_index"])] = last["ssp_index"]
        fields = dict(displacement=moved, status=status, ssp_index=sample)
        if any(step["type"] == "fill" for step in chain):
            fields["inserted"] = (np.arange(n) >= scanned).astype(float)
        outputs.append((name + ".ply", lambda path: cgal_ext.write_ply(
            path, points, normals, colors=cgal_ext.sequential_colors(moved), **fields)))
        return outputs

    def _level_outputs(self, name, progress):
        """A level of detail's save: the edit's JSON with its selections as nearest: specs of the level's points
        (NAME.sample.ply), and NAME.ply, the tiled edit of the scan run with it (`python3 -m cgal_ext.tiled edit
        SCAN --edit NAME.json --subsample <the level's points>` writes the same)."""
        from .. import tiled
        _, chain = self._saved_chain()
        if not chain:
            raise StudioError("save: paint a region and a handle and drag it; a level of detail saves its edit, "
                              "carried to the scan's %d points" % self.level["points"])
        edit, files = self._step_json(chain[0], name, spec="nearest")
        del edit["type"]
        edit["sample"] = {"points": name + ".sample.ply", "reach": self.level["reach"]}
        level_points = self.scan_points
        outputs = _index_files(files)
        outputs.append((name + ".sample.ply", lambda path: cgal_ext.write_ply(path, level_points)))
        outputs.append((name + ".json", _text_writer(json.dumps(edit, indent=2) + "\n")))
        small = list(outputs)

        def edited(path):
            # The tiled edit reads the edit's files by their names beside its JSON: written once more, in private.
            with tempfile.TemporaryDirectory(dir=self.root, prefix=".%s.edit." % name) as private:
                for file_name, write in small:
                    write(os.path.join(private, file_name))
                tiled.run("edit", str(self.level["path"]), path, edit=os.path.join(private, name + ".json"),
                          subsample=self.level_points, scratch=private,
                          progress=_pass_progress(progress, "save: "))
        outputs.append((name + ".ply", edited))
        return outputs

    def _is_scan(self, path):
        """Whether `path` is the scan's file: the same resolved path, or the same file through another name."""
        resolved, identity = self._scan_file
        if path.resolve() == resolved:
            return True
        try:
            status = os.stat(path)
        except OSError:
            return False
        return (status.st_dev, status.st_ino) == identity

    def save(self, name, overwrite=False, progress=None):
        """Writes NAME.ply (the shown state with the program's fields) and NAME.json (+ index files) such that
        `point-detail edit -i SCAN --edit NAME.json` reproduces NAME.ply: all of them or, on any failure, none
        (the files they replace restored). Never the scan itself; a file this session did not write only with
        `overwrite` (StudioError with details `replace` otherwise, for the page to ask)."""
        self._require_scan()
        self._check_save_name(name)
        if not isinstance(overwrite, bool):
            raise StudioError("save: overwrite is true or false")
        outputs = self._outputs(name, progress)
        targets, replaced = [], []
        for file_name, _ in outputs:
            path = self.inside(file_name, must_exist=False)
            if self._is_scan(path):
                raise StudioError("save: %s is the scan itself; the input is never overwritten" % file_name)
            try:
                entry = os.lstat(path)
            except FileNotFoundError:
                entry = None
            if entry is not None:
                if not path.is_file():
                    raise StudioError("save: %s exists and is not a file" % file_name)
                if self._written.get(file_name) != (entry.st_dev, entry.st_ino):
                    replaced.append(file_name)
            targets.append(path)
        if replaced and not overwrite:
            exist, them = ("exists", "it") if len(replaced) == 1 else ("exist", "them")
            raise StudioError("save: %s already %s and this session did not write %s; saving with overwrite replaces "
                              "%s" % (", ".join(replaced), exist, them, them), name=name, replace=replaced)
        # Every file to a temporary name first; once all are whole, each old file is moved aside and the new one
        # renamed into its place; on a failure the steps done are undone in reverse.
        temporaries, done = [], []  # done: ("aside", path, backup) and ("placed", path), in order
        try:
            for file_name, write in outputs:
                temporaries.append(self._temporary(file_name, ".tmp"))
                write(temporaries[-1])
            for (file_name, _), path, temporary in zip(outputs, targets, list(temporaries)):
                if os.path.lexists(path):
                    backup = self._temporary(file_name, ".old")
                    temporaries.append(backup)  # removed unless it holds a file that could not be put back
                    os.replace(path, backup)
                    done.append(("aside", path, backup))
                os.replace(temporary, path)
                done.append(("placed", path))
        except BaseException as error:
            lost = self._undo_save(done, temporaries)
            if not isinstance(error, (OSError, ValueError, RuntimeError)):
                raise
            if lost:
                raise StudioError("save failed (%s) and could not put back %s" % (error, "; ".join(lost)))
            raise StudioError("save failed, nothing written: %s" % error)
        for step in done:
            if step[0] == "aside":
                self._remove(step[2])
        for (file_name, _), path in zip(outputs, targets):
            entry = os.lstat(path)
            self._written[file_name] = (entry.st_dev, entry.st_ino)
        return sorted(file_name for file_name, _ in outputs)

    def _temporary(self, file_name, suffix):
        # The file's own extension last: the tiled edit writes a PLY only to a name ending in .ply.
        fd, path = tempfile.mkstemp(prefix="." + file_name + ".", suffix=suffix + pathlib.PurePath(file_name).suffix,
                                    dir=self.root)
        os.close(fd)
        return path

    @staticmethod
    def _remove(path):
        """Removes a temporary if it is still there (as best it can: a temporary left is no reason to fail)."""
        try:
            os.unlink(path)
        except OSError:
            pass

    def _undo_save(self, done, temporaries):
        """Undoes the steps of a save in reverse (each file put aside back in its place, each new file removed)
        and removes the temporaries; returns what could not be undone."""
        lost, kept = [], set()
        aside = {step[1] for step in done if step[0] == "aside"}
        for step in reversed(done):
            try:
                if step[0] == "aside":
                    os.replace(step[2], step[1])
                elif step[1] not in aside:  # a new file (one put aside is put back over it by one rename)
                    os.unlink(step[1])
            except OSError as error:
                if step[0] == "aside":
                    kept.add(step[2])
                    lost.append("%s (%s; its previous content is in %s)" % (step[1].name, error.strerror,
                                                                            os.path.basename(step[2])))
                else:
                    lost.append("%s (%s; the new file stays)" % (step[1].name, error.strerror))
        for path in temporaries:
            if path not in kept:
                self._remove(path)
        return lost

    def load_edit(self, name):
        """Loads a selection (and settings) from an edit JSON the studio saved, one edit or a chain of one edit
        step: index files beside it."""
        self._require_scan()
        self._require_undeformed("loading a selection")
        roi_files, handle_files, settings = self._read_edit(name)
        n = len(self.points)

        def indices(specs):
            chosen = []
            for spec in specs:
                if not spec.startswith("indices:"):
                    raise StudioError("%s: the studio loads index-file selections (indices:FILE), not %r" %
                                      (name, spec[:60]))
                file_name = str(pathlib.PurePosixPath(name).parent / spec[len("indices:"):])
                values = []
                for number, line in enumerate(self._read_text(file_name).splitlines(), 1):
                    word = line.split("#")[0]
                    if word.strip():
                        try:
                            values.append(int(word))
                        except ValueError:  # the line's number, not its text: errors never show a file's content
                            raise StudioError("%s, line %d: not a point index" % (file_name, number))
                if values and (min(values) < 0 or max(values) >= n):
                    raise StudioError("%s: an index is out of range (%d points)" % (file_name, n))
                chosen.append(np.array(values, np.int64))
            return np.concatenate(chosen) if chosen else np.zeros(0, np.int64)

        labels = np.zeros(n, np.int8)
        labels[indices(roi_files)] = ROI
        for g, specs in enumerate(handle_files):
            labels[indices(specs)] = FIRST_HANDLE + g
        self._use_settings(settings)
        self._set_selection(labels, len(handle_files))

    def _read_edit(self, name):
        """The selections (roi, per handle group) and settings of an edit JSON the studio saved, checked."""
        def refuse(why):
            return StudioError("%s is not an edit the studio saved: %s" % (name, why))
        try:
            edit = json.loads(self._read_bytes(name))
        except UnicodeDecodeError:
            raise refuse("not UTF-8 text")
        except ValueError as error:
            raise refuse("not JSON (%s)" % error)
        except RecursionError:
            raise refuse("JSON nested too deeply")

        def selections(value, what):
            if not isinstance(value, list) or not all(isinstance(spec, str) for spec in value):
                raise refuse("%s is not a list of selections" % what)
            return value
        if not isinstance(edit, dict):
            raise refuse("not a JSON object")
        if "steps" in edit:
            steps = edit["steps"]
            if not isinstance(steps, list) or not all(isinstance(step, dict) for step in steps):
                raise refuse("steps is not a list of objects")
            if len(steps) != 1 or steps[0].get("type") != "edit":
                raise StudioError("%s holds a chain of %d steps (%s); the studio loads the selection of a single "
                                  "edit step: open the saved PLY to edit its result further" %
                                  (name, len(steps), ", ".join(str(step.get("type"))[:20] for step in steps[:8])))
            edit = steps[0]
        roi = selections(edit.get("roi"), "roi")
        handles = edit.get("handles")
        if not isinstance(handles, list) or not all(isinstance(h, dict) for h in handles):
            raise refuse("handles is not a list of objects")
        if len(handles) > MAX_GROUPS:
            raise StudioError("%s has %d handle groups; the studio holds %d" % (name, len(handles), MAX_GROUPS))
        handle_files = [selections(h.get("select"), "handles[%d].select" % g) for g, h in enumerate(handles)]
        detail_filter = edit.get("filter", {})
        if not isinstance(detail_filter, dict):
            raise refuse("filter is not an object")
        settings = self._checked_settings({"order": detail_filter.get("order", self.settings["order"]),
                                           "rotations": edit.get("rotations", self.settings["rotations"]),
                                           "strength_distance": edit.get("strength_distance",
                                                                         self.settings["strength_distance"])})
        return roi, handle_files, settings

    # ---- what the page shows ----------------------------------------------------------------------------------

    def colors(self, by):
        """Per-point colours (uint8 RGB) of the shown state: its relief, detail magnitude, mean curvature, or the
        sample-point clusters of the prepared edit."""
        self._require_scan()
        if by not in COLOURINGS:
            raise StudioError("colour by relief, magnitude, curvature or clusters, not %r" % (by,))
        if by == "clusters" and self.deformation is None:
            raise StudioError("the sample-point clusters exist once the edit is preprocessed")
        try:
            if by in ("relief", "magnitude"):
                magnitude = cgal_ext.compute_geometric_details(self.shown_points, self.shown_normals,
                                                               order="cubic").magnitude
                return cgal_ext.diverging_colors(magnitude) if by == "relief" else \
                    cgal_ext.sequential_colors(np.abs(magnitude))
            if by == "curvature":
                return cgal_ext.diverging_colors(cgal_ext.estimate_mean_curvature(self.shown_points,
                                                                                  self.shown_normals))
        except (ValueError, RuntimeError) as error:
            raise StudioError(str(error))
        # Each cluster a colour of its own, from a multiplicative hash of its sample point's index, kept mid-bright.
        labels = self.deformation.sample_point_of(np.ones(len(self.points), bool)).astype(np.uint64)
        mixed = (labels * np.uint64(2654435761)) % np.uint64(1 << 24)
        return np.stack([(mixed >> np.uint64(16)) & np.uint64(255), (mixed >> np.uint64(8)) & np.uint64(255),
                         mixed & np.uint64(255)], axis=1).astype(np.uint8) // 2 + 96

    # ---- the state --------------------------------------------------------------------------------------------

    def state(self):
        if self.points is None:
            return {"scan": None, "points": None, "groups": 0, "settings": self.settings, "step": 0, "steps": 0,
                    "preprocessed": False, "base_changed": False, "region": 0, "transforms": [], "chain": [],
                    "history": [], "committable": False, "level_of_detail": None}
        snapshot = self.history[self.step]
        return {"scan": self.scan, "points": len(self.points), "groups": self.groups, "settings": self.settings,
                "step": self.step, "steps": len(self.history) - 1,
                "preprocessed": self.deformation is not None, "base_changed": bool(self.chain),
                "region": int(np.count_nonzero(self.labels != FIXED)),
                "transforms": [t.reshape(-1).tolist() for t in self.transforms],
                "chain": [step["type"] for step in self.chain],
                "history": [s["kind"] for s in self.history],
                "committable": snapshot["kind"] == "drag" and not self._dragged() and self.level is None,
                "level_of_detail": None if self.level is None else {"scan_points": self.level["points"],
                                                                      "cached": not self.level["built"]}}
