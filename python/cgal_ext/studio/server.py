"""The studio's web server (aiohttp): one page, its static files and one WebSocket over a Session.

Bound to 127.0.0.1; every request needs the session's token and a Host header naming the loopback address and
the port; every response carries headers that keep it out of frames and other sites' referrers. The WebSocket also
checks Origin and admits one tab at a time. Text frames carry JSON commands; binary frames carry arrays: a
little-endian uint32 header length, the JSON header, zero padding to a multiple of 4 bytes, then the arrays the
header lists (doc/studio.md, "Protocol").
"""
import asyncio
import collections
import concurrent.futures
import functools
import hmac
import pathlib
import secrets
import traceback

import numpy as np
from aiohttp import WSCloseCode, WSMsgType, web

from .codec import MAX_BINARY, MAX_HEADER, MAX_TEXT, pack, parse
from .session import FIXED, LABEL_CODES, MAX_GROUPS, Session, StudioError

STATIC = pathlib.Path(__file__).with_name("static")
THREE = pathlib.Path("/usr/share/javascript/three")  # Debian's libjs-three
MAX_QUEUED = 64              # commands read ahead of the one being handled (drags merged into them)


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

    def __init__(self, root, scan=None, token=None, **level):
        self.session = Session(root, **level)
        self.initial_scan = scan
        self.token = token or secrets.token_urlsafe(24)
        self.socket = None
        self.port = None
        self.lock = asyncio.Lock()
        # One thread for the session's calls (they run one at a time under the lock anyway): the history's arrays
        # are then allocated and freed in one malloc arena, not spread over one per thread.
        self.executor = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="studio-session")
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

    def cookie_name(self):
        # Per port: cookies ignore the port, and two studios on one machine must not overwrite each other's.
        return "cgal_ext_studio_%d" % self.port

    def cookie_authorised(self, request):
        """The page's own static files only: ES modules import each other by plain URLs, which cannot carry the
        token; the page's response set it as an HttpOnly, SameSite=Strict cookie. The page and the WebSocket
        still need the token in the URL."""
        if not request.path.startswith(("/static/", "/three/")):
            return False
        given = request.cookies.get(self.cookie_name(), "").encode("utf-8", "surrogatepass")
        return hmac.compare_digest(given, self.token.encode())

    @web.middleware
    async def require_token(self, request, handler):
        if not self.host_allowed(request):
            return web.Response(status=421, text="421: this studio answers only at 127.0.0.1:%d\n" % self.port)
        if not (self.authorised(request) or self.cookie_authorised(request)):
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
        response = web.Response(text=page, content_type="text/html", headers={"Cache-Control": "no-store"})
        response.set_cookie(self.cookie_name(), self.token, path="/", httponly=True, samesite="Strict")
        return response

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
        # No permessage-deflate, which browsers offer and aiohttp accepts by default: the frames are float arrays
        # that deflate by a few percent, and aiohttp deflates in the event loop, which then stalls on every
        # geometry and drag frame (doc/studio.md, "How a drag reaches the screen").
        ws = web.WebSocketResponse(max_msg_size=MAX_BINARY + MAX_HEADER + 4, heartbeat=30, compress=False)
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
        """report(fraction, named stage or None for `stage`), sent to the page at every 2 % and each new stage."""
        loop = asyncio.get_running_loop()
        last = [-1.0, stage]

        def report(fraction, named=None):
            named = named or stage
            if named != last[1] or fraction - last[0] >= 0.02 or fraction >= 1:
                last[:] = fraction, named
                asyncio.run_coroutine_threadsafe(ws.send_json({"type": "progress", "stage": named,
                                                               "fraction": fraction}), loop)
        return report

    async def run(self, function, *args, **kwargs):
        """A library call in a worker thread (the library releases the GIL), so that progress reaches the page."""
        return await asyncio.get_running_loop().run_in_executor(self.executor,
                                                                functools.partial(function, *args, **kwargs))

    async def handle(self, ws, command):
        if not isinstance(command, dict) or not isinstance(command.get("type"), str):
            await self.error(ws, "a command is a JSON object with a type")
            return
        kind = command["type"]
        handler = COMMANDS.get(kind)
        if handler is None:
            await self.error(ws, "unknown command %r" % kind[:40])
            return
        async with self.lock:
            try:
                await handler(self, ws, command)
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
        arrays = [("positions", s.shown_points, "<f4"), ("normals", s.shown_normals, "<f4"), ("labels", s.labels)]
        if s.shown_points is not s.points and not np.array_equal(s.shown_points, s.points):
            arrays += [("rest", s.points, "<f4"), ("rest_normals", s.normals, "<f4")]
        spacing, exact = s.drawn_spacing()
        if spacing is not None:
            arrays.append(("spacing", spacing))
        if not exact:  # computed in the background: sent when done
            asyncio.ensure_future(self.send_spacing_when_done(ws, *s.base_spacing()))
        inserted = s.inserted()
        if inserted is not None:
            arrays.append(("inserted", inserted))
        await ws.send_bytes(pack({"type": "geometry", "scan": s.scan, "label_codes": LABEL_CODES,
                                  "max_groups": MAX_GROUPS}, arrays))

    async def send_spacing_when_done(self, ws, points, future):
        """The local spacing of the base `points` once computed, unless the base changed meanwhile (its next
        geometry carries its own)."""
        try:
            await asyncio.wrap_future(future)
        except ValueError:
            return  # the points the library refuses are refused by name where they are needed (fill, selections)
        async with self.lock:
            if self.session.points is not points or ws.closed:
                return
            spacing, _ = self.session.drawn_spacing()
            try:
                await ws.send_bytes(pack({"type": "spacing"}, [("spacing", spacing)]))
            except ConnectionResetError:
                pass

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
        force = command.get("force", False)
        if not isinstance(force, bool):
            raise StudioError("preprocess: force is true or false")
        if not force and self.session.deformation is None:
            warnings = await self.run(self.session.warnings)
            if warnings:  # nothing prepared: the page asks, then sends grow_region_around or force
                await ws.send_json({"type": "warning", "warnings": warnings})
                await self.send_state(ws)
                return
        setup = await self.run(self.session.preprocess, progress=self.progress_reporter(ws, "preprocess"))
        movable = setup["movable"]
        await ws.send_bytes(pack({"type": "renderer", "sample_points": int(setup["sample_points"]),
                                  "collar_handles": len(setup["collar_handles"])},
                                 [("movable", movable),
                                  # uint16 where the sample points allow it: half the bytes on the wire
                                  ("stencil_samples", setup["stencil_samples"][movable],
                                   "<u2" if setup["sample_points"] <= 65536 else "<f4"),
                                  ("stencil_weights", setup["stencil_weights"][movable]),
                                  ("handle_group", setup["handle_group"][movable]),
                                  ("collar_points", setup["collar_points"], "<u4"),
                                  ("collar_slots", setup["collar_slots"], "<f4"),
                                  ("collar_weights", setup["collar_weights"])]))
        await self.send_state(ws)

    async def on_drag(self, ws, command):
        frame = self.session.drag(command.get("group"), command.get("matrix"), command.get("also"))
        await ws.send_bytes(pack({"type": "frame", "seq": command.get("seq")}, [("frame", frame)]))

    async def send_shown(self, ws):
        s = self.session
        movable = s.renderer["movable"]  # release, undo and redo need the edit prepared
        await ws.send_bytes(pack({"type": "shown"}, [("indices", movable, "<u4"),
                                                     ("positions", s.shown_points[movable], "<f4"),
                                                     ("normals", s.shown_normals[movable], "<f4")]))
        await self.send_state(ws)

    async def on_release(self, ws, command):
        await self.run(self.session.release)
        await self.send_shown(ws)
        warnings = self.session.swing_warnings()
        if warnings:
            await ws.send_json({"type": "warning", "warnings": warnings})

    async def send_step(self, ws, whole):
        """After undo or redo: the whole geometry when the base, the selection or the preparation changed, else
        the prepared edit's moved points."""
        if whole:
            await self.send_geometry(ws)
            await self.send_state(ws)
        else:
            await self.send_shown(ws)

    async def on_undo(self, ws, command):
        await self.send_step(ws, await self.run(self.session.undo))

    async def on_redo(self, ws, command):
        await self.send_step(ws, await self.run(self.session.redo))

    async def on_commit(self, ws, command):
        await self.run(self.session.commit)
        await self.send_geometry(ws)
        await self.send_state(ws)

    async def on_fill(self, ws, command):
        await self.run(self.session.fill, progress=self.progress_reporter(ws, "fill"))
        await self.send_geometry(ws)
        await self.send_state(ws)

    async def on_grow(self, ws, command):
        await self.run(self.session.grow, command.get("target"), command.get("group", 0))
        await self.send_labels(ws)

    async def on_shrink(self, ws, command):
        await self.run(self.session.shrink, command.get("target"), command.get("group", 0))
        await self.send_labels(ws)

    async def on_select_connected(self, ws, command):
        await self.run(self.session.select_connected, command.get("target"), command.get("mode"),
                       command.get("group", 0), command.get("seed"))
        await self.send_labels(ws)

    async def on_grow_region_around(self, ws, command):
        await self.run(self.session.grow_region_around, command.get("group"))
        await self.send_labels(ws)

    async def on_details(self, ws, command):
        s = self.session
        applied = command.get("apply", False)
        result = await self.run(s.details, command.get("mode"), command.get("s"), applied)
        region = np.flatnonzero(s.labels != FIXED)
        await ws.send_bytes(pack({"type": "details", "applied": applied},
                                 [("indices", region, "<u4"), ("positions", result[region], "<f4")]))
        if applied:
            await self.send_geometry(ws)
        await self.send_state(ws)

    async def on_colors(self, ws, command):
        by = command.get("by")
        colors = await self.run(self.session.colors, by)
        await ws.send_bytes(pack({"type": "colors", "by": by}, [("colors", colors)]))

    async def on_save(self, ws, command):
        written = await self.run(self.session.save, command.get("name"), command.get("overwrite", False),
                                 progress=self.progress_reporter(ws, "save"))
        await ws.send_json({"type": "saved", "files": written})
        await self.send_state(ws)

    async def on_load_edit(self, ws, command):
        self.session.load_edit(command.get("path"))
        await self.send_labels(ws)


# The commands a tab may send, by their "type": the only way from a message to code (doc/studio.md, "Protocol",
# lists the same names; a test compares them).
COMMANDS = {
    "state": Studio.on_state,
    "load": Studio.on_load,
    "labels": Studio.on_labels,
    "select": Studio.on_select,
    "new_group": Studio.on_new_group,
    "invert": Studio.on_invert,
    "clear": Studio.on_clear,
    "settings": Studio.on_settings,
    "preprocess": Studio.on_preprocess,
    "drag": Studio.on_drag,
    "release": Studio.on_release,
    "undo": Studio.on_undo,
    "redo": Studio.on_redo,
    "details": Studio.on_details,
    "colors": Studio.on_colors,
    "save": Studio.on_save,
    "load_edit": Studio.on_load_edit,
    "commit": Studio.on_commit,
    "fill": Studio.on_fill,
    "grow": Studio.on_grow,
    "shrink": Studio.on_shrink,
    "select_connected": Studio.on_select_connected,
    "grow_region_around": Studio.on_grow_region_around,
}


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
