"""The studio's state: one scan, its selection, its edit and the edit's history, over the cgal_ext library.

Every public method either completes or raises StudioError before changing anything, so a refused message
leaves the session as it was (doc/studio.md, "Bad messages"). The web server (server.py) only parses messages
and calls these methods; nothing here knows about HTTP.
"""
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

# A point's label: fixed, in the region, or a handle of group g (FIRST_HANDLE + g). The page gets these codes and
# the group limit in the geometry's header instead of spelling them itself.
FIXED, ROI, FIRST_HANDLE = 0, 1, 2
LABEL_CODES = {"fixed": FIXED, "roi": ROI, "first_handle": FIRST_HANDLE}
MAX_GROUPS = 8  # the page's shader holds this many handle transforms
COLOURINGS = ("relief", "magnitude", "curvature", "clusters")
ORDERS = ("linear", "quadric", "cubic")
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


_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])
_EYE3 = np.eye(3)


class Session:
    """A scan opened in the studio, inside the folder `root` that bounds every file it reads or writes."""

    def __init__(self, root):
        self.root = pathlib.Path(root).resolve()
        if not self.root.is_dir():
            raise StudioError("%s is not a folder" % root)
        # The folder held open: files are reached from it one name at a time, following no link (_open).
        self._root_fd = os.open(self.root, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        self.scan = None  # path relative to root
        self._scan_file = None  # the scan as read: its resolved path and (st_dev, st_ino)
        self._written = {}  # file name -> (st_dev, st_ino) of each file this session saved
        self.points = self.normals = None
        self.settings = {"order": "cubic", "rotations": "propagate", "strength_distance": "euclidean"}
        self.deformation = None
        self.base_changed = False  # details applied: the edit's input is no longer the scan file
        # One Deformation per scan and settings, whose selection-independent part (the mean shift) is computed in
        # the background from the moment the scan is open, while its user paints.
        self._editor = None  # a future of the Deformation
        self._worker = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="studio-analysis")

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
                if f.lower().endswith((".ply", ".off", ".xyz", ".pwn")):
                    found.append(str(pathlib.Path(dirpath, f).relative_to(self.root)))
                    if len(found) >= 1000:
                        return found
        return found

    def load(self, name, progress=None):
        """Reads a scan (normals estimated when it has none, as the program does) and starts a new edit."""
        cloud, status, resolved = self._read_points(name)
        points = cloud.points
        if len(points) < 20:
            raise StudioError("%s has %d points; editing needs at least 20" % (name, len(points)))
        normals = cloud.normals
        if normals is None or not np.all(np.isfinite(normals)) or np.any(np.all(normals == 0, axis=1)):
            if normals is not None:
                raise StudioError("%s has missing or zero normals; give all or none" % name)
            normals = cgal_ext.estimate_oriented_normals(points, k=min(18, len(points)), progress=progress)
        self.scan, self.points, self.normals = name, points, normals
        self._scan_file = (resolved, (status.st_dev, status.st_ino))
        self.base_changed = False
        self._new_edit()
        self._start_editor()

    def _new_edit(self):
        n = len(self.points)
        self.labels = np.zeros(n, np.int8)
        self.groups = 0
        self.transforms = []  # per group, the 4x4 of the drag under way or of the shown state
        self.history = [[]]   # committed transform lists; history[self.step] is shown
        self.step = 0
        self.shown_points, self.shown_normals = self.points.copy(), self.normals.copy()
        self._drop_deformation()

    def _drop_deformation(self):
        self.deformation = None
        self.renderer = None

    def _start_editor(self):
        """A new Deformation for the scan and the settings, its points analysed in the background."""
        points, normals, settings = self.points, self.normals, dict(self.settings)

        def make():
            editor = cgal_ext.Deformation(points, normals, order=settings["order"], rotations=settings["rotations"],
                                          strength_distance=settings["strength_distance"])
            editor.analyse_points()
            return editor
        self._editor = self._worker.submit(make)  # one worker: made after any editor before it

    def _require_scan(self):
        if self.points is None:
            raise StudioError("open a scan first")

    # ---- selection --------------------------------------------------------------------------------------------

    def _require_undeformed(self, what):
        if any(not np.array_equal(t, _identity()) for t in self.transforms) or self.step != 0:
            raise StudioError("%s changes the edit's selection or settings: undo the drags first (or start a new "
                              "edit)" % what)

    def new_group(self):
        self._require_scan()
        self._require_undeformed("a new handle group")
        if self.groups >= MAX_GROUPS:
            raise StudioError("at most %d handle groups" % MAX_GROUPS)
        self.groups += 1
        self.transforms.append(_identity())
        self.history = [[_identity() for _ in range(self.groups)]]
        self._drop_deformation()
        return self.groups - 1

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
        if target == "handle" and not (isinstance(group, int) and 0 <= group < self.groups):
            raise StudioError("there is no handle group %r (%d groups)" % (group, self.groups))
        labels = self.labels.copy()
        if target == "roi":
            labels[indices] = ROI if mode == "add" else FIXED  # erasing the region erases its handles too
        else:
            handle = FIRST_HANDLE + group
            if mode == "add":
                labels[indices] = handle  # a handle point is in the region; it leaves any other group
            else:
                labels[indices[labels[indices] == handle]] = ROI
        self.labels = labels
        self._drop_deformation()

    def invert(self):
        """Swaps the region and the fixed part (handle points stay handles)."""
        self._require_scan()
        self._require_undeformed("inverting")
        labels = self.labels.copy()
        labels[self.labels == FIXED] = ROI
        labels[self.labels == ROI] = FIXED
        self.labels = labels
        self._drop_deformation()

    def clear(self):
        self._require_scan()
        self._require_undeformed("clearing")
        self._new_edit()

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
            self._start_editor()

    def set_settings(self, **settings):
        self._require_scan()
        self._require_undeformed("changing the settings")
        self._use_settings(self._checked_settings(settings))

    # ---- editing ----------------------------------------------------------------------------------------------

    def preprocess(self, progress=None):
        """Builds the deformation of the current selection; returns what the page's shader needs."""
        self._require_scan()
        if not np.any(self.labels != FIXED):
            raise StudioError("paint a region of interest first")
        if self.groups == 0 or not all(np.any(self.labels == FIRST_HANDLE + g) for g in range(self.groups)):
            raise StudioError("every handle group needs points: paint a handle")
        if self.deformation is not None:
            return self.renderer
        try:
            deformation = self._editor.result()
        except ValueError as error:
            raise StudioError(str(error))
        deformation.reset()
        deformation.clear_selection()
        deformation.insert_roi(self.labels != FIXED)
        for g in range(self.groups):
            deformation.create_handle_group(self.labels == FIRST_HANDLE + g)
        try:
            if not deformation.preprocess(progress=progress):
                raise StudioError("preprocessing was cancelled")
        except ValueError as error:
            raise StudioError(str(error))
        setup = deformation.renderer_setup()
        region_samples = np.unique(deformation.sample_point_of(self.labels != FIXED))
        carried = np.isin(setup["stencil_samples"], region_samples).any(axis=1) | (setup["exact_handle"] != 0)
        setup["movable"] = np.flatnonzero(carried).astype(np.uint32)
        setup["handle_group"] = np.where(self.labels >= FIRST_HANDLE, self.labels - FIRST_HANDLE, -1).astype(np.int8)
        self.deformation, self.renderer = deformation, setup
        return setup

    def _transform(self, matrix, group):
        if not (isinstance(group, int) and 0 <= group < self.groups):
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

    def drag(self, group, matrix):
        """One frame of a drag: the handle group's transform (from the rest pose); returns the frame's motions. A
        transform whose solve fails is refused and the edit stays on the transforms before it."""
        if self.deformation is None:
            raise StudioError("a drag needs the edit preprocessed: paint a region and a handle, then edit")
        T = self._transform(matrix, group)
        d = self.deformation
        try:
            d.set_handle_transform(group, transform=T)
            d.deform()
            frame = d.renderer_frame()
            if not np.isfinite(frame).all():
                raise ValueError("the sample points' motions are not finite")
        except (ValueError, RuntimeError) as error:
            self._restore_deformation()
            raise StudioError("the drag was refused, the handle stays where it was: %s" % error)
        self.transforms[group] = T
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

    def release(self):
        """The end of a drag: the full diffusion and restore_details become the shown state (a step of history)."""
        if self.deformation is None:
            raise StudioError("release without a drag")
        self._show(self.transforms)
        del self.history[self.step + 1:]
        self.history.append([t.copy() for t in self.transforms])
        self.step += 1

    def _show(self, transforms):
        """Shows the edit under `transforms`, or raises StudioError with the session unchanged."""
        d = self.deformation
        try:
            for g, T in enumerate(transforms):
                d.set_handle_transform(g, transform=T)
            if all(np.array_equal(T, _identity()) for T in transforms):
                d.reset()
                points, normals = self.points.copy(), self.normals.copy()
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

    def undo(self):
        if self.step == 0:
            raise StudioError("nothing to undo")
        self._show(self.history[self.step - 1])
        self.step -= 1

    def redo(self):
        if self.step + 1 >= len(self.history):
            raise StudioError("nothing to redo")
        self._show(self.history[self.step + 1])
        self.step += 1

    # ---- details ----------------------------------------------------------------------------------------------

    def details(self, mode, s, apply=False):
        """Scales or enhances the details of the painted region (its points: region and handles) by `s`, as
        point-detail scale / enhance do; with `apply`, the result becomes the scan the edit starts from."""
        self._require_scan()
        self._require_undeformed("changing the details")
        if mode not in ("scale", "enhance"):
            raise StudioError("details: mode must be scale or enhance")
        if not isinstance(s, (int, float)) or isinstance(s, bool) or not math.isfinite(s) or not 0 <= s <= 3:
            raise StudioError("details: s must be a number from 0 to 3")
        roi = self.labels != FIXED
        if not roi.any():
            raise StudioError("paint the region whose details change first")
        function = cgal_ext.scale_geometric_details if mode == "scale" else cgal_ext.enhance_geometric_details
        try:
            result = function(self.points, self.normals, roi=roi, s=float(s))
        except (ValueError, RuntimeError) as error:
            raise StudioError(str(error))
        if apply:
            self.points = result
            self.base_changed = True
            self.shown_points = result.copy()
            self._drop_deformation()
            self._start_editor()
        return result

    # ---- saving -----------------------------------------------------------------------------------------------

    def edit_json(self, name):
        """The edit as the program's edit JSON, its selections in index files beside it."""
        handles = []
        for g in range(self.groups):
            T = self.transforms[g]
            handles.append({"select": ["indices:%s.handle%d.txt" % (name, g)],
                            "matrix": T[:3, :3].tolist(), "translation": T[:3, 3].tolist()})
        return {"roi": ["indices:%s.roi.txt" % name], "handles": handles,
                "filter": {"order": self.settings["order"]}, "rotations": self.settings["rotations"],
                "strength_distance": self.settings["strength_distance"]}

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

    def _outputs(self, name):
        """The files a save as `name` writes, in the order they are put in place: (file name, writer of a path)."""
        outputs = []

        def text(content):
            return lambda path: pathlib.Path(path).write_text(content)
        if self.groups and (self.labels != FIXED).any():
            outputs.append((name + ".roi.txt", text("".join("%d\n" % i for i in np.flatnonzero(self.labels != FIXED)))))
            for g in range(self.groups):
                outputs.append(("%s.handle%d.txt" % (name, g), text(
                    "".join("%d\n" % i for i in np.flatnonzero(self.labels == FIRST_HANDLE + g)))))
            outputs.append((name + ".json", text(json.dumps(self.edit_json(name), indent=2) + "\n")))
        if self.base_changed:  # the scaled input the edit starts from
            outputs.append((name + ".base.ply", lambda path: cgal_ext.write_ply(path, self.points, self.normals)))
        moved = np.linalg.norm(self.shown_points - self.points, axis=1)
        sample = (self.deformation.sample_point_of(np.ones(len(self.points), bool)).astype(float)
                  if self.deformation is not None else np.zeros(len(self.points)))
        status = np.minimum(self.labels, 2).astype(float)
        outputs.append((name + ".ply", lambda path: cgal_ext.write_ply(
            path, self.shown_points, self.shown_normals, colors=cgal_ext.sequential_colors(moved),
            displacement=moved, status=status, ssp_index=sample)))
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

    def save(self, name, overwrite=False):
        """Writes NAME.ply (the shown state with the program's fields) and NAME.json (+ index files) such that
        `point-detail edit -i SCAN --edit NAME.json` reproduces NAME.ply: all of them or, on any failure, none
        (the files they replace restored). Never the scan itself; a file this session did not write only with
        `overwrite` (StudioError with details `replace` otherwise, for the page to ask)."""
        self._require_scan()
        self._check_save_name(name)
        if not isinstance(overwrite, bool):
            raise StudioError("save: overwrite is true or false")
        outputs = self._outputs(name)
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
        fd, path = tempfile.mkstemp(prefix="." + file_name + ".", suffix=suffix, dir=self.root)
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
        """Loads a selection (and settings) from an edit JSON the studio saved: indices files beside it."""
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
        self.labels, self.groups = labels, len(handle_files)
        self.transforms = [_identity() for _ in range(self.groups)]
        self.history, self.step = [[_identity() for _ in range(self.groups)]], 0
        self._drop_deformation()
        self._use_settings(settings)

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
        return {"scan": self.scan, "points": None if self.points is None else len(self.points),
                "groups": self.groups if self.points is not None else 0, "settings": self.settings,
                "step": getattr(self, "step", 0), "steps": len(getattr(self, "history", [[]])) - 1,
                "preprocessed": self.deformation is not None, "base_changed": self.base_changed,
                "region": int(np.count_nonzero(self.labels != FIXED)) if self.points is not None else 0,
                "transforms": [t.reshape(-1).tolist() for t in getattr(self, "transforms", [])]}
