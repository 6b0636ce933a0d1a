"""The studio's web server (aiohttp): one page, its static files and one WebSocket over a Session.

Bound to 127.0.0.1; every request needs the session's token and a Host header naming the loopback address and
the port; every response carries headers that keep it out of frames and other sites' referrers. The WebSocket also
checks Origin and admits one tab at a time. Text frames carry JSON commands; binary frames carry arrays: a
little-endian uint32 header length, the JSON header, zero padding to a multiple of 4 bytes, then the arrays the
header lists (doc/studio.md, "Protocol").
"""
import asyncio
import collections
import functools
import hmac
import json
import pathlib
import secrets
import struct
import traceback

import numpy as np
from aiohttp import WSCloseCode, WSMsgType, web

import cgal_ext

from .session import FIXED, Session, StudioError

STATIC = pathlib.Path(__file__).with_name("static")
THREE = pathlib.Path("/usr/share/javascript/three")  # Debian's libjs-three
MAX_TEXT = 1 << 20           # a JSON command
MAX_BINARY = 64 << 20        # a selection of up to 16M indices
MAX_HEADER = 4096
MAX_QUEUED = 64              # commands read ahead of the one being handled (drags merged into them)


def pack(header, arrays=()):
    """A binary frame: header (a dict; the arrays' names, dtypes, shapes and offsets added) and arrays."""
    arrays = [(name, np.ascontiguousarray(a)) for name, a in arrays]
    listed, offset = [], 0
    for name, a in arrays:
        listed.append({"name": name, "dtype": a.dtype.str, "shape": list(a.shape), "offset": offset})
        offset += (a.nbytes + 3) // 4 * 4
    text = json.dumps(dict(header, arrays=listed)).encode()
    text += b" " * (-len(text) % 4)
    parts = [struct.pack("<I", len(text)), text]
    for _, a in arrays:
        parts += [a.tobytes(), b"\0" * (-a.nbytes % 4)]
    return b"".join(parts)


def unpack(data):
    """The header and the one uint32 array of a binary frame from the page, checked; StudioError otherwise."""
    if len(data) < 4:
        raise StudioError("a binary message shorter than its header length")
    (length,) = struct.unpack_from("<I", data)
    if length > MAX_HEADER or 4 + length > len(data) or length % 4:
        raise StudioError("a binary message with a bad header length (%d)" % length)
    try:
        header = json.loads(data[4:4 + length])
    except (ValueError, UnicodeDecodeError, RecursionError):
        raise StudioError("a binary message whose header is not JSON")
    if not isinstance(header, dict) or not isinstance(header.get("count"), int) or header["count"] < 0:
        raise StudioError("a binary message's header needs a count")
    payload = data[4 + length:]
    if len(payload) != 4 * header["count"]:
        raise StudioError("a binary message of %d bytes for %d indices" % (len(payload), header["count"]))
    return header, np.frombuffer(payload, "<u4")


def parse(message):
    """A command from a WebSocket message, checked as far as its form goes; StudioError otherwise."""
    if message.type == WSMsgType.TEXT:
        if len(message.data) > MAX_TEXT:
            raise StudioError("a command of %d bytes; commands are JSON of at most %d bytes" %
                              (len(message.data), MAX_TEXT))
        try:
            return json.loads(message.data)
        except ValueError:
            raise StudioError("a command that is not JSON")
        except RecursionError:
            raise StudioError("a command nested too deeply to be a command")
    header, indices = unpack(message.data)
    return dict(header, indices=indices)


def is_drag(command):
    return isinstance(command, dict) and command.get("type") == "drag" and type(command.get("group")) is int


class Inbox:
    """The commands read from the tab and not handled yet, in order, each a command or a StudioError to reply. A
    drag replaces a queued drag of the same handle group behind which only drags wait: a flood of drags costs one
    solve per group before the next command, not one per message (the replaced drag gets no frame; the page sends
    one drag at a time and never has one replaced)."""

    def __init__(self):
        self.items = collections.deque()
        self.changed = asyncio.Condition()
        self.closed = False

    def merge(self, command):
        for k in range(len(self.items) - 1, -1, -1):
            queued = self.items[k]
            if not is_drag(queued):
                return False
            if queued["group"] == command["group"]:
                self.items[k] = command
                return True
        return False

    async def put(self, item):
        async with self.changed:
            if not (is_drag(item) and self.merge(item)):
                await self.changed.wait_for(lambda: len(self.items) < MAX_QUEUED)
                self.items.append(item)
            self.changed.notify_all()

    async def get(self):
        """The next item, None once closed and empty."""
        async with self.changed:
            await self.changed.wait_for(lambda: self.items or self.closed)
            item = self.items.popleft() if self.items else None
            self.changed.notify_all()
            return item

    async def close(self):
        async with self.changed:
            self.closed = True
            self.changed.notify_all()


class Studio:
    """The server's state: the session, the token, the tab that holds the session."""

    def __init__(self, root, scan=None, token=None):
        self.session = Session(root)
        self.initial_scan = scan
        self.token = token or secrets.token_urlsafe(24)
        self.socket = None
        self.port = None
        self.lock = asyncio.Lock()
        self.stopping = False

    # ---- HTTP -------------------------------------------------------------------------------------------------

    def authorised(self, request):
        # Bytes: compare_digest refuses a str with characters outside ASCII (a TypeError, answered 500).
        given = request.query.get("token", "").encode("utf-8", "surrogatepass")
        return hmac.compare_digest(given, self.token.encode())

    def host_allowed(self, request):
        """The Host the page's own address names: another name resolving to 127.0.0.1 (DNS rebinding) is refused."""
        host = request.headers.get("Host", "").lower()
        return host in ("127.0.0.1:%d" % self.port, "localhost:%d" % self.port, "[::1]:%d" % self.port)

    @web.middleware
    async def require_token(self, request, handler):
        if not self.host_allowed(request):
            return web.Response(status=421, text="421: this studio answers only at 127.0.0.1:%d\n" % self.port)
        if not self.authorised(request):
            return web.Response(status=403, text="403: this studio needs its session token (the URL it printed)\n")
        return await handler(request)

    def security_headers(self):
        ws = " ".join("ws://%s:%d" % (host, self.port) for host in ("127.0.0.1", "localhost"))
        return {"Content-Security-Policy": "default-src 'self'; script-src 'self'; connect-src 'self' %s; "
                                           "style-src 'self'; img-src 'self' data: blob:; object-src 'none'; "
                                           "base-uri 'none'; form-action 'none'; frame-ancestors 'none'" % ws,
                "Referrer-Policy": "no-referrer", "X-Content-Type-Options": "nosniff"}

    async def add_security_headers(self, request, response):
        """Every response, the errors and the WebSocket's handshake too (aiohttp's on_response_prepare)."""
        response.headers.update(self.security_headers())

    async def index(self, request):
        page = (STATIC / "index.html").read_text().replace("{{TOKEN}}", self.token)
        return web.Response(text=page, content_type="text/html", headers={"Cache-Control": "no-store"})

    async def static(self, request, folder):
        name = request.match_info["name"]
        path = (folder / name).resolve()
        if folder.resolve() not in path.parents or not path.is_file():
            raise web.HTTPNotFound()
        return web.FileResponse(path, headers={"Cache-Control": "no-store"})

    # ---- WebSocket --------------------------------------------------------------------------------------------

    def origin_allowed(self, request):
        origin = request.headers.get("Origin")
        return origin in ("http://127.0.0.1:%d" % self.port, "http://localhost:%d" % self.port)

    async def websocket(self, request):
        if not self.origin_allowed(request):
            return web.Response(status=403, text="403: WebSocket from another origin\n")
        ws = web.WebSocketResponse(max_msg_size=MAX_BINARY + MAX_HEADER + 4, heartbeat=30)
        await ws.prepare(request)
        if self.socket is not None and not self.socket.closed:
            await ws.send_json({"type": "refused", "message": "this studio session is open in another tab; close "
                                                              "that tab (or use it) to edit here"})
            await ws.close()
            return ws
        self.socket = ws
        try:
            await self.send_state(ws)
            if self.initial_scan and self.session.points is None:
                await self.handle(ws, {"type": "load", "path": self.initial_scan})
            # The messages are read while a command runs, so that queued drags merge (Inbox).
            inbox = Inbox()
            worker = asyncio.create_task(self.work(ws, inbox))
            try:
                async for message in ws:
                    if message.type in (WSMsgType.TEXT, WSMsgType.BINARY):
                        try:
                            await inbox.put(parse(message))
                        except StudioError as error:
                            await inbox.put(error)
            finally:
                await inbox.close()
                try:
                    await worker
                except asyncio.CancelledError:
                    worker.cancel()
                    raise
            if self.stopping:  # serve() ended the loop: tell the tab why (aiohttp would close with 1000)
                await ws.close(code=WSCloseCode.GOING_AWAY, message=b"the studio was stopped")
        finally:
            if self.socket is ws:
                self.socket = None
        return ws

    async def work(self, ws, inbox):
        """Handles the inbox's commands in order until the socket closed and they are done."""
        while (item := await inbox.get()) is not None:
            try:
                if isinstance(item, StudioError):
                    await self.error(ws, str(item))
                else:
                    await self.handle(ws, item)
            except ConnectionResetError:
                pass  # the tab is gone: the commands it sent still run, their replies have no one to reach
            await asyncio.sleep(0)  # the reader's turn: what arrived meanwhile reaches the inbox (and merges)

    async def error(self, ws, text, **details):
        await ws.send_json(dict(details, type="error", message=text))

    async def send_state(self, ws):
        await ws.send_json(dict(self.session.state(), type="state", files=self.session.files()))

    def progress_reporter(self, ws, stage):
        loop = asyncio.get_running_loop()
        last = [-1.0]

        def report(fraction):
            if fraction - last[0] >= 0.02 or fraction >= 1:
                last[0] = fraction
                asyncio.run_coroutine_threadsafe(ws.send_json({"type": "progress", "stage": stage,
                                                               "fraction": fraction}), loop)
        return report

    async def run(self, function, *args, **kwargs):
        """A library call in a worker thread (the library releases the GIL), so that progress reaches the page."""
        return await asyncio.get_running_loop().run_in_executor(None, functools.partial(function, *args, **kwargs))

    async def handle(self, ws, command):
        if not isinstance(command, dict) or not isinstance(command.get("type"), str):
            await self.error(ws, "a command is a JSON object with a type")
            return
        kind = command["type"]
        handler = getattr(self, "on_" + kind, None)
        if handler is None:
            await self.error(ws, "unknown command %r" % kind[:40])
            return
        async with self.lock:
            try:
                await handler(ws, command)
            except StudioError as error:
                await self.error(ws, str(error), **error.details)
            except (TypeError, KeyError, ValueError) as error:
                await self.error(ws, "%s: malformed command (%s)" % (kind, error))
            except ConnectionResetError:
                pass  # the tab closed (or the studio stopped) while the command ran: no one to tell
            except Exception as error:  # a bug: reported to the page and on the console, the server stays up
                traceback.print_exc()
                await self.error(ws, "%s failed: %s: %s" % (kind, type(error).__name__, error))

    # ---- commands ---------------------------------------------------------------------------------------------

    async def send_geometry(self, ws):
        s = self.session
        arrays = [("positions", s.shown_points.astype("<f4")), ("normals", s.shown_normals.astype("<f4")),
                  ("labels", s.labels)]
        if s.shown_points is not s.points and not np.array_equal(s.shown_points, s.points):
            arrays += [("rest", s.points.astype("<f4")), ("rest_normals", s.normals.astype("<f4"))]
        await ws.send_bytes(pack({"type": "geometry", "scan": s.scan}, arrays))

    async def on_load(self, ws, command):
        await self.run(self.session.load, command["path"], progress=self.progress_reporter(ws, "normals"))
        await self.send_geometry(ws)
        await self.send_state(ws)

    async def on_state(self, ws, command):
        await self.send_state(ws)

    async def send_labels(self, ws):
        await ws.send_bytes(pack({"type": "labels"}, [("labels", self.session.labels)]))
        await self.send_state(ws)

    async def on_labels(self, ws, command):
        self.session._require_scan()
        await ws.send_bytes(pack({"type": "labels"}, [("labels", self.session.labels)]))

    async def on_select(self, ws, command):
        self.session.select(command.get("target"), command.get("mode"), command["indices"], command.get("group", 0))
        await self.send_labels(ws)

    async def on_new_group(self, ws, command):
        self.session.new_group()
        await self.send_state(ws)

    async def on_invert(self, ws, command):
        self.session.invert()
        await self.send_labels(ws)

    async def on_clear(self, ws, command):
        self.session.clear()
        await self.send_labels(ws)

    async def on_settings(self, ws, command):
        self.session.set_settings(**{k: v for k, v in command.items() if k != "type"})
        await self.send_state(ws)

    async def on_preprocess(self, ws, command):
        setup = await self.run(self.session.preprocess, progress=self.progress_reporter(ws, "preprocess"))
        movable = setup["movable"]
        await ws.send_bytes(pack({"type": "renderer", "sample_points": int(setup["sample_points"]),
                                  "collar_handles": len(setup["collar_handles"])},
                                 [("movable", movable),
                                  # uint16 where the sample points allow it: half the bytes on the wire
                                  ("stencil_samples", setup["stencil_samples"][movable].astype(
                                      "<u2" if setup["sample_points"] <= 65536 else "<f4")),
                                  ("stencil_weights", setup["stencil_weights"][movable]),
                                  ("handle_group", setup["handle_group"][movable]),
                                  ("collar_points", setup["collar_points"].astype("<u4")),
                                  ("collar_slots", setup["collar_slots"].astype("<f4")),
                                  ("collar_weights", setup["collar_weights"])]))
        await self.send_state(ws)

    async def on_drag(self, ws, command):
        frame = self.session.drag(command.get("group"), command.get("matrix"))
        await ws.send_bytes(pack({"type": "frame", "seq": command.get("seq")}, [("frame", frame)]))

    async def send_shown(self, ws):
        s = self.session
        movable = s.renderer["movable"]  # release, undo and redo need the edit prepared
        await ws.send_bytes(pack({"type": "shown"}, [("indices", movable.astype("<u4")),
                                                     ("positions", s.shown_points[movable].astype("<f4")),
                                                     ("normals", s.shown_normals[movable].astype("<f4"))]))
        await self.send_state(ws)

    async def on_release(self, ws, command):
        await self.run(self.session.release)
        await self.send_shown(ws)

    async def on_undo(self, ws, command):
        await self.run(self.session.undo)
        await self.send_shown(ws)

    async def on_redo(self, ws, command):
        await self.run(self.session.redo)
        await self.send_shown(ws)

    async def on_details(self, ws, command):
        s = self.session
        result = await self.run(s.details, command.get("mode"), command.get("s"), bool(command.get("apply")))
        region = np.flatnonzero(s.labels != FIXED)
        await ws.send_bytes(pack({"type": "details", "applied": bool(command.get("apply"))},
                                 [("indices", region.astype("<u4")), ("positions", result[region].astype("<f4"))]))
        if command.get("apply"):
            await self.send_geometry(ws)
        await self.send_state(ws)

    async def on_colors(self, ws, command):
        s = self.session
        by = command.get("by")
        if s.points is None:
            raise StudioError("open a scan first")
        if by in ("relief", "magnitude"):
            details = await self.run(cgal_ext.compute_geometric_details, s.shown_points, s.shown_normals,
                                     order="cubic")
            magnitude = details.magnitude
            colors = cgal_ext.diverging_colors(magnitude) if by == "relief" else \
                cgal_ext.sequential_colors(np.abs(magnitude))
        elif by == "curvature":
            curvature = await self.run(cgal_ext.estimate_mean_curvature, s.shown_points, s.shown_normals)
            colors = cgal_ext.diverging_colors(curvature)
        elif by == "clusters":
            if s.deformation is None:
                raise StudioError("the sample-point clusters exist once the edit is preprocessed")
            labels = s.deformation.sample_point_of(np.ones(len(s.points), bool)).astype(np.uint64)
            mixed = (labels * np.uint64(2654435761)) % np.uint64(1 << 24)
            colors = np.stack([(mixed >> np.uint64(16)) & np.uint64(255), (mixed >> np.uint64(8)) & np.uint64(255),
                               mixed & np.uint64(255)], axis=1).astype(np.uint8) // 2 + 96
        else:
            raise StudioError("colour by relief, magnitude, curvature or clusters, not %r" % by)
        await ws.send_bytes(pack({"type": "colors", "by": by}, [("colors", colors)]))

    async def on_save(self, ws, command):
        written = await self.run(self.session.save, command.get("name"), command.get("overwrite", False))
        await ws.send_json({"type": "saved", "files": written})
        await self.send_state(ws)

    async def on_load_edit(self, ws, command):
        self.session.load_edit(command.get("path"))
        await self.send_labels(ws)


def make_app(studio):
    app = web.Application(middlewares=[studio.require_token], client_max_size=MAX_TEXT)
    app.on_response_prepare.append(studio.add_security_headers)
    app.router.add_get("/", studio.index)
    app.router.add_get("/ws", studio.websocket)
    app.router.add_get("/static/{name}", functools.partial(studio.static, folder=STATIC))
    app.router.add_get("/three/{name:.+}", functools.partial(studio.static, folder=THREE))
    return app


async def serve(studio, port=0, ready=None):
    """Serves until cancelled; `ready(url)` is called once it listens."""
    if not (THREE / "build" / "three.min.js").is_file():
        raise SystemExit("studio: three.js is missing (%s); install Debian's libjs-three (scripts/setup.sh)" % THREE)
    runner = web.AppRunner(make_app(studio), handle_signals=False, access_log=None)
    await runner.setup()
    site = web.TCPSite(runner, "127.0.0.1", port)
    await site.start()
    studio.port = site._server.sockets[0].getsockname()[1]
    url = "http://127.0.0.1:%d/?token=%s" % (studio.port, studio.token)
    if ready:
        ready(url)
    try:
        await asyncio.Event().wait()
    finally:
        # An open tab's WebSocket would hold the shutdown for aiohttp's whole grace period: close it first.
        studio.stopping = True
        if studio.socket is not None:
            await studio.socket.close(code=WSCloseCode.GOING_AWAY, message=b"the studio was stopped")
        await runner.cleanup()
