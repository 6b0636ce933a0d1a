# The studio's server against what a hostile or confused client sends: requests without the token, another
# origin or host, a second tab, paths out of its folder, and malformed, unknown, out-of-order or oversized
# messages, each refused with an error while the session and the folder stay as they were; a flood of drags; then
# a soak of 2,000 drags. Last, the session's files in-process: saves that fail half-way, links swapped while it
# reads.
import asyncio
import base64
import errno
import http.client
import json
import os
import pathlib
import re
import socket
import struct
import threading
import time

import numpy as np
import pytest
from aiohttp import ClientOSError, ClientSession, WSCloseCode, WSMsgType, WSServerHandshakeError

import cgal_ext
from cgal_ext.studio.session import Session, StudioError
from conftest import bumpy_sphere
from studio_support import Server

IDENTITY = np.eye(4).reshape(-1).tolist()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    folder = tmp_path_factory.mktemp("studio_protocol")
    points, normals = bumpy_sphere(6000)
    cgal_ext.write_ply(folder / "sphere.ply", points, normals)
    (folder / "inner").mkdir()
    (folder / "d.ply").mkdir()
    os.symlink("/etc/hostname", folder / "outside.ply")
    for name, edit in MALFORMED_EDITS.items():
        (folder / name).write_text(edit if isinstance(edit, str) else json.dumps(edit))
    studio = Server(folder / "sphere.ply")
    yield studio
    status, err = studio.stop()
    assert status == 0 and "stopped" in err and "Traceback" not in err  # Ctrl-C stops it cleanly


def frame(header, indices=()):
    text = json.dumps(dict({"count": len(indices)}, **header)).encode()
    text += b" " * (-len(text) % 4)
    return struct.pack("<I", len(text)) + text + np.asarray(indices, "<u4").tobytes()


def decoded(data):
    """A binary frame from the server as the page reads it: its header, each array under its name."""
    (length,) = struct.unpack_from("<I", data)
    header = json.loads(data[4:4 + length])
    for a in header["arrays"]:
        count = int(np.prod(a["shape"]))
        header[a["name"]] = np.frombuffer(data, a["dtype"], count, 4 + length + a["offset"]).reshape(a["shape"])
    return header


class Client:
    """One tab's WebSocket, as the page opens it."""

    def __init__(self, server, http, ws):
        self.server, self.http, self.ws = server, http, ws

    @classmethod
    async def open(cls, server, origin=None, token=None, compress=0):
        http = ClientSession()
        try:
            ws = await http.ws_connect("ws://127.0.0.1:%d/ws?token=%s" % (server.port, token or server.token),
                                       headers={"Origin": origin or server.base}, max_msg_size=0, compress=compress)
        except BaseException:
            await http.close()
            raise
        return cls(server, http, ws)

    async def close(self):
        await self.ws.close()
        await self.http.close()

    async def receive(self):
        message = await asyncio.wait_for(self.ws.receive(), 60)
        if message.type == WSMsgType.TEXT:
            return json.loads(message.data)
        if message.type == WSMsgType.BINARY:
            return decoded(message.data)
        if message.type == WSMsgType.CLOSE:  # the code the server sent (close_code is our reply's)
            return {"type": "closed", "code": message.data}
        return {"type": "closed", "code": self.ws.close_code}

    async def until(self, *types):
        """Messages until one of `types` (progress skipped); errors are returned too."""
        while True:
            m = await self.receive()
            if m["type"] in types or m["type"] in ("error", "closed", "refused"):
                return m

    async def command(self, command, *replies):
        if isinstance(command, bytes):
            await self.ws.send_bytes(command)
        elif isinstance(command, str):
            await self.ws.send_str(command)
        else:
            await self.ws.send_str(json.dumps(command))
        return await self.until(*(replies or ("state",)))

    async def ready(self):
        """Waits for the scan: the first state once the studio's scan is open (its load's state, when the tab
        opening is what opens it), so that the next reply is the next command's."""
        while (await self.until("state"))["scan"] is None:
            pass
        return self

    async def snapshot(self):
        """The session's state, its selection and the folder's files (hidden ones too) with their sizes and times."""
        state = await self.command({"type": "state"})
        labels = await self.command({"type": "labels"}, "labels")
        state.pop("files")
        return state, labels["labels"].tobytes(), listing(folder_of(self.server))


def folder_of(server):
    return pathlib.Path(server_scan(server)).parent


def listing(folder):
    files = {}
    for path in sorted(pathlib.Path(folder).rglob("*")):
        entry = path.lstat()
        files[str(path.relative_to(folder))] = (entry.st_size, entry.st_mtime_ns, entry.st_ino)
    return files


def run(coroutine):
    return asyncio.run(coroutine)


def test_every_request_needs_the_token_and_the_origin(server):
    import urllib.error
    import urllib.request

    for path in ("/", "/static/studio.js", "/three/build/three.min.js", "/ws"):
        for query in ("", "?token=wrong", "?token="):
            with pytest.raises(urllib.error.HTTPError) as error:
                urllib.request.urlopen(server.base + path + query)
            assert error.value.code == 403
    assert urllib.request.urlopen(server.url).status == 200
    # Traversal in a static path is not served, with or without the token.
    with pytest.raises(urllib.error.HTTPError) as error:
        urllib.request.urlopen(server.base + "/three/../../../../etc/passwd?token=" + server.token)
    assert error.value.code in (403, 404)

    async def wrong_origin():
        for origin in ("http://evil.example", "http://127.0.0.1:1", "null"):
            with pytest.raises(WSServerHandshakeError) as error:
                await Client.open(server, origin=origin)
            assert error.value.status == 403
        with pytest.raises(WSServerHandshakeError):
            await Client.open(server, token="wrong")
    run(wrong_origin())


def get(server, path, host="127.0.0.1:%(port)d"):
    """Status, headers and body of GET `path` with the given Host header (None: none)."""
    connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=60)
    try:
        connection.putrequest("GET", path, skip_host=True)
        if host is not None:
            connection.putheader("Host", host % {"port": server.port})
        connection.endheaders()
        response = connection.getresponse()
        return response.status, response.headers, response.read()
    finally:
        connection.close()


def test_only_the_loopback_host_and_the_exact_token_are_answered(server):
    token = "?token=" + server.token
    for host in ("127.0.0.1:%(port)d", "localhost:%(port)d", "LocalHost:%(port)d", "[::1]:%(port)d"):
        assert get(server, "/" + token, host)[0] == 200, host
    # DNS rebinding: another name that resolves to 127.0.0.1 reaches the server with its own Host.
    for host in ("evil.example:%(port)d", "127.0.0.1", "127.0.0.1:1", "localhost.evil.example:%(port)d", "", None):
        status, _, body = get(server, "/" + token, host)
        assert status == 421 and b"127.0.0.1:%d" % server.port in body, (host, status)
    # A token outside ASCII or not UTF-8 is a wrong token, not a server error.
    for query in ("?token=%C3%A9", "?token=%FF", "?token=" + server.token + "%C3%A9"):
        status, _, body = get(server, "/" + query)
        assert status == 403 and b"Traceback" not in body, (query, status, body)

    async def handshakes():
        with pytest.raises(WSServerHandshakeError) as error:
            await Client.open(server, token="%C3%A9")
        assert error.value.status == 403
        http = ClientSession()
        try:
            with pytest.raises(WSServerHandshakeError) as error:
                await http.ws_connect("ws://127.0.0.1:%d/ws?token=%s" % (server.port, server.token),
                                      headers={"Origin": server.base, "Host": "evil.example:%d" % server.port})
            assert error.value.status == 421
        finally:
            await http.close()
    run(handshakes())


def test_every_response_carries_the_security_headers(server):
    token = "?token=" + server.token
    seen = set()
    for path, host in [("/" + token, None), ("/static/studio.js" + token, None),
                       ("/three/build/three.min.js" + token, None), ("/static/missing.js" + token, None),
                       ("/" + token + "x", None), ("/ws" + token, None), ("/" + token, "evil.example:%(port)d")]:
        status, headers, _ = get(server, path, *(() if host is None else (host,)))
        seen.add(status)
        csp = headers.get("Content-Security-Policy", "")
        assert "frame-ancestors 'none'" in csp and "default-src 'self'" in csp, (path, status, csp)
        assert headers.get("Referrer-Policy") == "no-referrer", (path, status)
        assert headers.get("X-Content-Type-Options") == "nosniff", (path, status)
    assert {200, 403, 404, 421} <= seen, seen


def test_a_second_tab_is_refused(server):
    async def scenario():
        first = await Client.open(server)
        assert (await first.until("state"))["type"] == "state"
        second = await Client.open(server)
        refused = await second.receive()
        assert refused["type"] == "refused" and "another tab" in refused["message"]
        assert (await second.receive())["type"] == "closed"
        assert (await first.command({"type": "state"}))["type"] == "state"  # the first tab is unaffected
        await second.close()
        await first.close()
    run(scenario())


def test_the_frames_go_uncompressed_when_the_browser_offers_deflate(server):
    """Browsers offer permessage-deflate; deflating float arrays in the server's loop costs more than it saves."""
    async def scenario():
        client = await Client.open(server, compress=15)  # the offer Chromium makes
        assert client.ws.compress == 0  # declined
        assert (await client.until("state"))["type"] == "state"
        await client.close()
    run(scenario())


# Edit JSONs that Load selection refuses as not the studio's.
MALFORMED_EDITS = {
    "filter_list.json": {"roi": [], "handles": [], "filter": []},
    "handles_numbers.json": {"roi": [], "handles": [5]},
    "handles_object.json": {"roi": [], "handles": {"select": []}},
    "select_string.json": {"roi": [], "handles": [{"select": "indices:a.txt"}]},
    "roi_string.json": {"roi": "indices:a.txt", "handles": []},
    "roi_numbers.json": {"roi": [1, 2], "handles": []},
    "no_roi.json": {"handles": []},
    "top_list.json": [],
    "nested.json": "[" * 100000,
}

BAD_BEFORE_EDITING = [
    ("{", "not JSON"),
    ("[1, 2]", "JSON object with a type"),
    ({"x": 1}, "JSON object with a type"),
    ({"type": 5}, "JSON object with a type"),
    ({"type": "explode"}, "unknown command"),
    ({"type": "__init__"}, "unknown command"),
    ({"type": "drag", "group": 0, "matrix": IDENTITY}, "needs the edit preprocessed"),
    ({"type": "release"}, "release without a drag"),
    ({"type": "undo"}, "nothing to undo"),
    ({"type": "redo"}, "nothing to redo"),
    ({"type": "preprocess"}, "paint a region of interest first"),
    (b"\x01\x00", "shorter than its header"),
    (struct.pack("<I", 400) + b"{}  ", "bad header length"),
    (struct.pack("<I", 4) + b"nope", "not JSON"),
    (frame({"type": "select", "target": "roi", "mode": "add"}, [1, 2, 3])[:-4], "bytes for 3 indices"),
    (frame({"type": "select", "target": "roi", "mode": "add"}, [1, 2, 10 ** 7]), "out of range"),
    (frame({"type": "select", "target": "lung", "mode": "add"}, [1]), "target must be roi or handle"),
    (frame({"type": "select", "target": "handle", "mode": "add", "group": 3}, [1]), "no handle group 3"),
    ({"type": "load", "path": "../sphere.ply"}, "without '..'"),
    ({"type": "load", "path": "/etc/passwd"}, "inside the studio's folder"),
    ({"type": "load", "path": "outside.ply"}, "leads out of the studio's folder"),
    ({"type": "load", "path": "missing.ply"}, "no such file"),
    ({"type": "load", "path": "inner"}, "no such file"),
    ({"type": "load", "path": 7}, "non-empty string"),
    ({"type": "save", "name": "../escape"}, "without folders"),
    ({"type": "save", "name": "sphere"}, "never overwritten"),
    ({"type": "settings", "order": "septic"}, "order must be one of"),
    ({"type": "settings", "colour": "red"}, "unknown setting"),
    ({"type": "details", "mode": "scale", "s": 5}, "from 0 to 3"),
    ('{"type": "details", "mode": "scale", "s": NaN}', "from 0 to 3"),
    ({"type": "details", "mode": "melt", "s": 1}, "scale or enhance"),
    ({"type": "colors", "by": "mood"}, "colour by"),
    ({"type": "colors", "by": "clusters"}, "once the edit is preprocessed"),
    ({"type": "load_edit", "path": "sphere.ply"}, "not an edit the studio saved"),
    *[({"type": "load_edit", "path": name}, "not an edit the studio saved") for name in MALFORMED_EDITS],
    ({"type": "save", "name": " edited"}, "spaces at its start or end"),
    ({"type": "save", "name": "edited "}, "spaces at its start or end"),
    ({"type": "save", "name": "edi\nted"}, "control characters"),
    ({"type": "save", "name": "edi\u202eted"}, "control characters"),
    ({"type": "save", "name": "e" * 201}, "at most 200 bytes"),
    ({"type": "save", "name": "edited", "overwrite": "yes"}, "overwrite is true or false"),
    ({"type": "save", "name": "d"}, "d.ply exists and is not a file"),
    (json.dumps({"type": "state", "pad": "x" * (2 << 20)}), "at most"),
    ("[" * 100000, "nested too deeply"),  # a RecursionError in the parser: refused, the socket stays open
    (struct.pack("<I", 4000) + b"[" * 4000, "not JSON"),
    # The commands of many edits and of the selection over the neighbour graph.
    ({"type": "commit"}, "needs a released drag"),
    ({"type": "fill"}, "needs a released drag"),
    ({"type": "grow", "target": "lung"}, "target must be roi or handle"),
    ({"type": "grow", "target": "handle", "group": 0}, "no handle group 0"),
    ({"type": "grow", "target": ["roi"]}, "target must be roi or handle"),
    ({"type": "shrink", "target": "handle", "group": -1}, "no handle group -1"),
    ({"type": "shrink", "target": "handle", "group": True}, "no handle group True"),
    ({"type": "shrink", "target": None}, "target must be roi or handle"),
    ({"type": "select_connected", "target": "roi", "mode": "add", "seed": 10 ** 7}, "seed is a point index"),
    ({"type": "select_connected", "target": "roi", "mode": "add", "seed": -1}, "seed is a point index"),
    ({"type": "select_connected", "target": "roi", "mode": "add", "seed": "3"}, "seed is a point index"),
    ({"type": "select_connected", "target": "roi", "mode": "add", "seed": 1.5}, "seed is a point index"),
    ({"type": "select_connected", "target": "roi", "mode": "add"}, "seed is a point index"),
    ({"type": "select_connected", "target": "roi", "mode": "paint", "seed": 1}, "mode must be add or erase"),
    ({"type": "select_connected", "target": "handle", "mode": "add", "group": 2, "seed": 1}, "no handle group 2"),
    ({"type": "grow_region_around", "group": 0}, "no handle group 0"),
    ({"type": "grow_region_around"}, "no handle group None"),
    ({"type": "preprocess", "force": "yes"}, "force is true or false"),
    ({"type": "preprocess", "force": True}, "paint a region of interest first"),
    ({"type": "details", "mode": "scale", "s": 1, "apply": "yes"}, "apply is true or false"),
]


def test_bad_messages_are_refused_and_change_nothing(server):
    async def scenario():
        client = await Client.open(server)
        await client.until("state")
        before = await client.snapshot()
        for message, expected in BAD_BEFORE_EDITING:
            reply = await client.command(message)
            assert reply["type"] == "error" and expected in reply["message"], (message if len(str(message)) < 200
                                                                               else str(message)[:200], reply)
            assert await client.snapshot() == before, message
        await client.close()
    run(scenario())


def test_bad_messages_while_editing_change_nothing(server):
    async def scenario():
        client = await Client.open(server)
        await client.until("state")
        points = cgal_ext.read_points(server_scan(server)).points
        region = np.flatnonzero(points[:, 2] > 0.0)
        await client.command(frame({"type": "select", "target": "roi", "mode": "add"}, region))
        await client.command({"type": "new_group"})
        handle = np.flatnonzero(points[:, 2] > 0.9)
        await client.command(frame({"type": "select", "target": "handle", "mode": "add", "group": 0}, handle))
        assert (await client.command({"type": "preprocess"}))["preprocessed"]
        T = np.eye(4)
        T[:3, 3] = (0.1, 0, 0.2)
        assert (await client.command({"type": "drag", "group": 0, "matrix": T.reshape(-1).tolist()}, "frame"))["type"] == "frame"
        assert (await client.command({"type": "release"}))["step"] == 1
        before = await client.snapshot()
        scale = np.diag([2.0, 2, 2, 1]).reshape(-1).tolist()
        bad = [
            ('{"type": "drag", "group": 0, "matrix": [NaN, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}', "not finite"),
            ({"type": "drag", "group": 0, "matrix": scale}, "not a rigid motion"),
            ({"type": "drag", "group": 0, "matrix": [1, 0, 0]}, "16 numbers"),
            ({"type": "drag", "group": 0, "matrix": "identity"}, "16 numbers"),
            ({"type": "drag", "group": 4, "matrix": IDENTITY}, "no handle group 4"),
            ({"type": "drag", "group": "0", "matrix": IDENTITY}, "no handle group"),
            (frame({"type": "select", "target": "roi", "mode": "add"}, [0]), "undo the drags first"),
            ({"type": "settings", "order": "linear"}, "undo the drags first"),
            ({"type": "new_group"}, "undo the drags first"),
            ({"type": "details", "mode": "scale", "s": 2}, "undo the drags first"),
            ({"type": "redo"}, "nothing to redo"),
            ({"type": "grow", "target": "roi"}, "undo the drags first"),
            ({"type": "shrink", "target": "handle", "group": 0}, "undo the drags first"),
            ({"type": "select_connected", "target": "roi", "mode": "add", "seed": 0}, "undo the drags first"),
            ({"type": "grow_region_around", "group": 0}, "undo the drags first"),
            ({"type": "drag", "group": 0, "matrix": IDENTITY, "also": [{"group": 1, "matrix": IDENTITY}]},
             "no handle group 1"),
            ({"type": "drag", "group": 0, "matrix": IDENTITY, "also": [{"group": 0, "matrix": IDENTITY}]},
             "moved twice"),
            ({"type": "drag", "group": 0, "matrix": IDENTITY, "also": 5}, "also is a list"),
            ({"type": "drag", "group": 0, "matrix": IDENTITY, "also": [{"group": 0, "matrix": IDENTITY, "x": 1}]},
             "also is a list"),
            ({"type": "drag", "group": 0, "matrix": IDENTITY, "also": [{"group": "1", "matrix": IDENTITY}]},
             "no handle group"),
            ({"type": "new_group"}, "undo the drags first"),
        ]
        for message, expected in bad:
            reply = await client.command(message, "frame")
            assert reply["type"] == "error" and expected in reply["message"], (message, reply)
            assert await client.snapshot() == before, message
        # 100 MB of JSON: past the WebSocket's size limit, the connection is closed; the session is kept.
        try:
            await client.ws.send_str(json.dumps({"type": "state", "pad": "x" * (100 << 20)}))
            assert (await client.until("state"))["type"] == "closed"
        except (ClientOSError, ConnectionResetError):
            pass  # the server closed the connection while the message was still being sent
        await client.close()
        client = await Client.open(server)
        await client.until("state")
        assert await client.snapshot() == before
        # Undo returns the input bit for bit, then the session starts over.
        assert (await client.command({"type": "undo"}))["step"] == 0
        await client.command({"type": "clear"})
        await client.close()
    run(scenario())


def server_scan(server):
    return server.process.args[3]


async def prepared_edit(client, points):
    """The upper half as the region, its top as handle group 0, preprocessed."""
    await client.command(frame({"type": "select", "target": "roi", "mode": "add"}, np.flatnonzero(points[:, 2] > 0)))
    await client.command({"type": "new_group"})
    await client.command(frame({"type": "select", "target": "handle", "mode": "add", "group": 0},
                               np.flatnonzero(points[:, 2] > 0.9)))
    assert (await client.command({"type": "preprocess"}))["preprocessed"]


async def save(client, **fields):
    """A save's reply, and the state after it if it saved."""
    reply = await client.command(dict(fields, type="save"), "saved")
    if reply["type"] == "saved":
        assert (await client.until("state"))["type"] == "state"
    return reply


async def start_over(client):
    """Back to the bare scan: every drag undone, the selection cleared."""
    state = await client.command({"type": "release"})
    while state["step"] > 0:
        state = await client.command({"type": "undo"})
    cleared = await client.command({"type": "clear"})
    assert cleared["type"] == "state" and cleared["region"] == 0, cleared


def test_a_save_replaces_a_file_this_session_did_not_write_only_when_told(server):
    folder = folder_of(server)

    async def scenario():
        client = await (await Client.open(server)).ready()
        (folder / "other.ply").write_bytes(b"another program's file\n")
        before = await client.snapshot()
        refused = await save(client, name="other")
        assert refused["type"] == "error" and refused["replace"] == ["other.ply"] and refused["name"] == "other"
        assert "overwrite" in refused["message"]
        assert await client.snapshot() == before
        assert (folder / "other.ply").read_bytes() == b"another program's file\n"
        # Told to: replaced. Saved again by the same session: no question.
        assert (await save(client, name="other", overwrite=True))["files"] == ["other.ply"]
        assert len(cgal_ext.read_points(folder / "other.ply").points) == 6000
        assert (await save(client, name="other"))["type"] == "saved"
        # Replaced by someone else meanwhile (another inode at that name): asked again.
        (folder / "other.tmp").write_bytes(b"changed by hand\n")
        os.replace(folder / "other.tmp", folder / "other.ply")
        assert (await save(client, name="other"))["replace"] == ["other.ply"]
        assert (folder / "other.ply").read_bytes() == b"changed by hand\n"
        await client.close()
    run(scenario())


def test_a_drag_whose_solve_fails_leaves_the_edit_as_it_was(server):
    folder = folder_of(server)

    async def scenario():
        client = await (await Client.open(server)).ready()
        await prepared_edit(client, cgal_ext.read_points(server_scan(server)).points)
        T = np.eye(4)
        T[:3, 3] = (0.1, 0, 0.2)
        drag = {"type": "drag", "group": 0, "matrix": T.reshape(-1).tolist()}
        assert (await client.command(drag, "frame"))["type"] == "frame"
        before = await client.snapshot()
        huge = np.eye(4)
        huge[0, 3] = 1e308
        reply = await client.command({"type": "drag", "group": 0, "matrix": huge.reshape(-1).tolist()}, "frame")
        assert reply["type"] == "error", reply
        assert await client.snapshot() == before  # the transform before, not 1e308
        assert "refused" in reply["message"], reply
        # The drag ends (the release solves the transform before) and the edit is saved with that transform.
        assert (await client.command({"type": "release"}))["step"] == 1
        assert (await save(client, name="after_a_failed_drag"))["type"] == "saved"
        saved = json.loads((folder / "after_a_failed_drag.json").read_text())
        assert np.abs(np.array(saved["steps"][-1]["handles"][0]["translation"]) - T[:3, 3]).max() < 1e-12
        assert np.all(np.isfinite(cgal_ext.read_points(folder / "after_a_failed_drag.ply").points))
        await start_over(client)
        await client.close()
    run(scenario())


def test_many_edits_over_the_websocket(server):
    """The warning, the remedy, a mirrored drag, commit, undo and redo of it, a fill and a save, as the page sends
    them; the shapes of the replies."""
    folder = folder_of(server)

    async def scenario():
        client = await (await Client.open(server)).ready()
        points = cgal_ext.read_points(server_scan(server)).points
        n = len(points)
        await client.command(frame({"type": "select", "target": "roi", "mode": "add"}, np.flatnonzero(points[:, 2] > 0)))
        await client.command({"type": "new_group"})
        await client.command({"type": "new_group"})
        await client.command(frame({"type": "select", "target": "handle", "mode": "add", "group": 0},
                                   np.flatnonzero(points[:, 2] > 0.9)))
        await client.command(frame({"type": "select", "target": "handle", "mode": "add", "group": 1},
                                   np.flatnonzero(points[:, 2] < -0.95)))  # an island in the fixed part
        before = await client.snapshot()
        warning = await client.command({"type": "preprocess"}, "warning")
        assert warning["type"] == "warning", warning
        assert [(w["kind"], w.get("group")) for w in warning["warnings"]] == [("island", 1)]
        assert "grow the region around it" in warning["warnings"][0]["message"]
        assert (await client.until("state"))["preprocessed"] is False
        assert await client.snapshot() == before
        labels = await client.command({"type": "grow_region_around", "group": 1}, "labels")
        assert labels["type"] == "labels" and np.count_nonzero(labels["labels"]) > np.count_nonzero(
            np.frombuffer(before[1], np.int8))
        await client.until("state")
        assert (await client.command({"type": "preprocess"}))["preprocessed"]
        # A mirrored drag: group 1 moved with group 0 in one frame; a bad `also` changes nothing.
        up, down = np.eye(4), np.eye(4)
        up[2, 3], down[2, 3] = 0.1, -0.1
        before = await client.snapshot()
        for also, expected in (([{"group": 1, "matrix": np.diag([2.0, 2, 2, 1]).reshape(-1).tolist()}],
                                 "not a rigid motion"),
                                ([{"group": 1, "matrix": [0] * 15}], "16 numbers"),
                                ([{"group": 8, "matrix": IDENTITY}], "no handle group 8")):
            reply = await client.command({"type": "drag", "group": 0, "matrix": up.reshape(-1).tolist(),
                                          "also": also}, "frame")
            assert reply["type"] == "error" and expected in reply["message"], reply
            assert await client.snapshot() == before
        reply = await client.command({"type": "drag", "group": 0, "matrix": up.reshape(-1).tolist(), "seq": 1,
                                      "also": [{"group": 1, "matrix": down.reshape(-1).tolist()}]}, "frame")
        assert reply["type"] == "frame" and reply["seq"] == 1
        shown = await client.command({"type": "release"}, "shown")
        assert shown["type"] == "shown"
        state = await client.until("state")
        assert state["step"] == 1 and state["committable"]
        assert np.allclose(np.array(state["transforms"][1]).reshape(4, 4), down)
        # Commit: the geometry again, no selection, the codes and the spacing with it.
        geometry = await client.command({"type": "commit"}, "geometry")
        assert geometry["type"] == "geometry", geometry
        assert geometry["label_codes"] == {"fixed": 0, "roi": 1, "first_handle": 2} and geometry["max_groups"] == 8
        assert geometry["spacing"].shape == (n,) and np.all(geometry["spacing"] > 0)
        assert not geometry["labels"].any() and "rest" not in geometry and "inserted" not in geometry
        committed = geometry["positions"].copy()
        state = await client.until("state")
        assert state["chain"] == ["edit"] and state["groups"] == 0 and state["history"] == ["open", "drag", "commit"]
        # Undo: the first edit as it was shown, its selection and groups, to prepare again.
        geometry = await client.command({"type": "undo"}, "geometry")
        assert np.array_equal(geometry["positions"], committed) and "rest" in geometry
        state = await client.until("state")
        assert state["chain"] == [] and state["groups"] == 2 and state["preprocessed"] is False
        await client.command({"type": "redo"}, "geometry")
        assert (await client.until("state"))["chain"] == ["edit"]
        # A second edit, then fill: the geometry grows, with `inserted`.
        shown_points = committed.astype(float)
        await client.command(frame({"type": "select", "target": "roi", "mode": "add"},
                                   np.flatnonzero(shown_points[:, 0] > 0.2)))
        await client.command({"type": "new_group"})
        await client.command(frame({"type": "select", "target": "handle", "mode": "add", "group": 0},
                                   np.flatnonzero(shown_points[:, 0] > 0.85)))
        assert (await client.command({"type": "preprocess"}))["preprocessed"]
        stretch = np.eye(4)
        stretch[0, 3] = 0.5
        await client.command({"type": "drag", "group": 0, "matrix": stretch.reshape(-1).tolist()}, "frame")
        await client.command({"type": "release"})
        geometry = await client.command({"type": "fill"}, "geometry")
        assert geometry["type"] == "geometry", geometry
        added = len(geometry["positions"]) - n
        assert added > 0 and geometry["inserted"].sum() == added and not geometry["inserted"][:n].any()
        state = await client.until("state")
        assert state["chain"] == ["edit", "edit", "fill"] and state["points"] == n + added
        saved = await save(client, name="many_edits")
        assert "many_edits.step2.handle0.txt" not in saved["files"] and "many_edits.step1.handle0.txt" in saved["files"]
        assert [step["type"] for step in json.loads((folder / "many_edits.json").read_text())["steps"]] == \
            ["edit", "edit", "fill"]
        # Back to the bare scan for the tests after this one.
        await client.command({"type": "load", "path": "sphere.ply"})
        await client.close()
    run(scenario())


class RawSocket:
    """A WebSocket on a plain socket, for writing many commands in one go (aiohttp's client sends each by
    itself, so that how many queue up at the server would depend on the two processes' speeds)."""

    def __init__(self, server):
        self.socket = socket.create_connection(("127.0.0.1", server.port), timeout=120)
        key = base64.b64encode(os.urandom(16)).decode()
        self.socket.sendall(("GET /ws?token=%s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nOrigin: %s\r\nUpgrade: websocket\r\n"
                             "Connection: Upgrade\r\nSec-WebSocket-Key: %s\r\nSec-WebSocket-Version: 13\r\n\r\n" %
                             (server.token, server.port, server.base, key)).encode())
        self.buffer = b""
        while b"\r\n\r\n" not in self.buffer:
            self.buffer += self.socket.recv(65536)
        head, self.buffer = self.buffer.split(b"\r\n\r\n", 1)
        assert head.startswith(b"HTTP/1.1 101"), head

    @staticmethod
    def text_frame(text, opcode=0x81):
        data = text.encode()
        n = len(data)
        length = bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n)
        return bytes([opcode]) + length + b"\0\0\0\0" + data  # masked with a zero key: the data as it is

    def read(self, n):
        while len(self.buffer) < n:
            chunk = self.socket.recv(1 << 20)
            if not chunk:
                raise EOFError("the server closed the connection")
            self.buffer += chunk
        data, self.buffer = self.buffer[:n], self.buffer[n:]
        return data

    def receive(self):
        """The server's next message: a JSON command, or the header of a binary one."""
        first, second = self.read(2)
        n = second & 0x7F
        if n == 126:
            (n,) = struct.unpack(">H", self.read(2))
        elif n == 127:
            (n,) = struct.unpack(">Q", self.read(8))
        data = self.read(n)
        if first & 0x0F == 1:
            return json.loads(data)
        if first & 0x0F == 2:
            (length,) = struct.unpack_from("<I", data)
            return json.loads(data[4:4 + length])
        return {"type": "closed"}

    def close(self):
        self.socket.sendall(bytes([0x88, 0x82]) + b"\0\0\0\0" + struct.pack(">H", 1000))
        while self.receive()["type"] != "closed":
            pass
        self.socket.close()


def test_a_flood_of_drags_cannot_delay_a_command(server):
    drags = 5000

    async def prepare():
        client = await (await Client.open(server)).ready()
        await prepared_edit(client, cgal_ext.read_points(server_scan(server)).points)
        await client.close()
    run(prepare())
    raw = RawSocket(server)
    assert raw.receive()["type"] == "state"
    matrices = []
    for k in range(1, drags + 1):
        T = np.eye(4)
        T[:3, 3] = (1e-4 * k, 0, 0)
        matrices.append(T)
    raw.socket.sendall(b"".join(RawSocket.text_frame(json.dumps({"type": "drag", "group": 0, "seq": k,
                                                                  "matrix": T.reshape(-1).tolist()}))
                                for k, T in enumerate(matrices, 1)) +
                       RawSocket.text_frame(json.dumps({"type": "state"})))
    frames = []
    while (reply := raw.receive())["type"] != "state":
        assert reply["type"] == "frame", reply
        frames.append(reply["seq"])
    raw.close()
    # Without merging, all 5,000 frames come first; merged, one per batch the server read while it solved.
    assert 1 <= len(frames) <= 100 and frames == sorted(frames) and frames[-1] == drags, frames
    assert np.abs(np.array(reply["transforms"][0]).reshape(4, 4) - matrices[-1]).max() < 1e-12

    async def clean_up():
        client = await (await Client.open(server)).ready()
        await start_over(client)
        await client.close()
    run(clean_up())


def test_started_on_a_link_the_studio_opens_the_file_it_leads_to(tmp_path):
    # cli/tentacle.ply -> ../demo2/edit_cubic.ply, and demo2 holds another tentacle.ply.
    (tmp_path / "cli").mkdir()
    (tmp_path / "demo2").mkdir()
    for name, n in (("edit_cubic.ply", 2500), ("tentacle.ply", 3000)):
        cgal_ext.write_ply(tmp_path / "demo2" / name, *bumpy_sphere(n, seed=n))
    os.symlink("../demo2/edit_cubic.ply", tmp_path / "cli" / "tentacle.ply")
    studio = Server(tmp_path / "cli" / "tentacle.ply")

    async def scenario():
        client = await Client.open(studio)
        geometry = await client.until("geometry")
        assert geometry["scan"] == "edit_cubic.ply" and len(geometry["positions"]) == 2500
        state = await client.command({"type": "state"})
        assert state["scan"] == "edit_cubic.ply" and state["files"] == ["edit_cubic.ply", "tentacle.ply"]
        refused = await save(client, name="edit_cubic")
        assert refused["type"] == "error" and "the scan itself" in refused["message"]
        await client.close()
    try:
        run(scenario())
    finally:
        status, err = studio.stop()
    assert status == 0 and "Traceback" not in err


def test_soak_2000_drags_keep_memory_flat(server):
    async def scenario():
        client = await Client.open(server)
        await client.until("state")
        points = cgal_ext.read_points(server_scan(server)).points
        await client.command(frame({"type": "select", "target": "roi", "mode": "add"}, np.flatnonzero(points[:, 0] > 0)))
        await client.command({"type": "new_group"})
        await client.command(frame({"type": "select", "target": "handle", "mode": "add", "group": 0},
                                   np.flatnonzero(points[:, 0] > 0.9)))
        await client.command({"type": "preprocess"})
        rng = np.random.default_rng(3)
        resident = []
        for drag in range(2000):
            for step in range(3):
                T = np.eye(4)
                T[:3, 3] = rng.normal(scale=0.05, size=3)
                reply = await client.command({"type": "drag", "group": 0, "matrix": T.reshape(-1).tolist()}, "frame")
                assert reply["type"] == "frame"
            assert (await client.command({"type": "release"}, "state"))["type"] == "state"
            if drag in (99, 1999):
                resident.append(server.resident_bytes())
        await client.close()
        assert resident[1] <= 1.05 * resident[0], resident
    run(scenario())


def test_ctrl_c_with_a_tab_open_stops_at_once_and_tells_the_tab(tmp_path):
    # aiohttp waits for open WebSockets for its grace period of a minute: the studio closes the tab's first.
    points, normals = bumpy_sphere(2000)
    cgal_ext.write_ply(tmp_path / "sphere.ply", points, normals)
    studio = Server(tmp_path / "sphere.ply")

    async def scenario():
        client = await Client.open(studio)
        await client.until("geometry")
        start = time.monotonic()
        status, err = await asyncio.get_running_loop().run_in_executor(None, studio.stop)
        assert status == 0 and "stopped" in err and "Traceback" not in err
        assert time.monotonic() - start < 5
        closed = await client.until("closed")
        assert closed["code"] == WSCloseCode.GOING_AWAY
        await client.close()
    run(scenario())


# ---- the session's files, in-process ----------------------------------------------------------------------------

def open_session(folder, name, n=2000, groups=1):
    """A Session on a bumpy sphere written as folder/name, its upper half the region, `groups` handle groups."""
    points, normals = bumpy_sphere(n)
    cgal_ext.write_ply(folder / name, points, normals)
    session = Session(folder)
    session.load(name)
    session.select("roi", "add", np.flatnonzero(points[:, 2] > 0))
    for g in range(groups):
        session.new_group()
        session.select("handle", "add", np.flatnonzero(points[:, 2] > 0.9 - 0.05 * g), g)
    return session


def test_a_save_never_writes_over_the_scan_under_any_name(tmp_path):
    session = open_session(tmp_path, "scan.ply")
    session.details("scale", 2.0, apply=True)  # a chain step: no file but NAME.json, its index files, NAME.ply
    os.link(tmp_path / "scan.ply", tmp_path / "hard.ply")
    os.symlink("scan.ply", tmp_path / "soft.ply")
    scan = (tmp_path / "scan.ply").read_bytes()
    before = listing(tmp_path)
    for name, file in (("scan", "scan.ply"), ("hard", "hard.ply"), ("soft", "soft.ply")):
        with pytest.raises(StudioError, match="%s is the scan itself" % file):
            session.save(name, overwrite=True)
        assert listing(tmp_path) == before and (tmp_path / "scan.ply").read_bytes() == scan
    assert session.save("scaled") == ["scaled.json", "scaled.ply", "scaled.step0.roi.txt", "scaled.step1.handle0.txt",
                                      "scaled.step1.roi.txt"]


def test_a_rename_failing_half_way_through_a_save_restores_every_file(tmp_path, monkeypatch):
    session = open_session(tmp_path, "sphere.ply")
    first = session.save("edit")
    saved = {name: (tmp_path / name).read_bytes() for name in first}
    before = listing(tmp_path)
    # The second save writes other selections and one more file (handle group 1).
    session.select("roi", "add", np.arange(100))
    session.new_group()
    session.select("handle", "add", np.arange(10), 1)
    replace, placed = os.replace, []

    def replace_failing_on_the_second_file(source, target, *args, **kwargs):
        if not os.path.basename(target).startswith("."):  # a file put in place (not one put aside)
            placed.append(os.path.basename(target))
            if len(placed) == 2:
                raise OSError(errno.EIO, "simulated failure", target)
        return replace(source, target, *args, **kwargs)
    monkeypatch.setattr(os, "replace", replace_failing_on_the_second_file)
    with pytest.raises(StudioError, match="save failed, nothing written: .*simulated failure"):
        session.save("edit")
    assert placed[:2] == ["edit.step0.roi.txt", "edit.step0.handle0.txt"]  # the first in place when the second failed
    assert listing(tmp_path) == before
    assert {name: (tmp_path / name).read_bytes() for name in first} == saved
    monkeypatch.undo()
    assert "edit.step0.handle1.txt" in session.save("edit")
    assert (tmp_path / "edit.step0.roi.txt").read_bytes() != saved["edit.step0.roi.txt"]


def test_a_refused_or_failed_save_leaves_no_file_behind(tmp_path, monkeypatch):
    session = open_session(tmp_path, "sphere.ply")
    (tmp_path / "d.ply").mkdir()
    os.symlink("/etc/hostname", tmp_path / "e.step0.handle0.txt")
    before = listing(tmp_path)
    with pytest.raises(StudioError, match="d.ply exists and is not a file"):
        session.save("d")
    assert listing(tmp_path) == before  # no d.json nor index files
    with pytest.raises(StudioError, match="leads out of the studio's folder"):
        session.save("e")
    assert listing(tmp_path) == before  # no temporary of e.step0.roi.txt

    def failing_write(path, *args, **kwargs):
        raise RuntimeError("simulated failure")
    monkeypatch.setattr(cgal_ext, "write_ply", failing_write)
    with pytest.raises(StudioError, match="save failed, nothing written: simulated failure"):
        session.save("f")
    assert listing(tmp_path) == before


def test_a_link_swapped_while_the_session_reads_never_reads_outside(tmp_path):
    root, outside = tmp_path / "studio", tmp_path / "outside"
    root.mkdir()
    outside.mkdir()
    cgal_ext.write_ply(root / "inside.ply", *bumpy_sphere(100, seed=1))
    cgal_ext.write_ply(outside / "outside.ply", *bumpy_sphere(150, seed=2))
    (root / "good.txt").write_text("3\n")
    (outside / "secret.txt").write_text("SECRET-LINE\n7\n")
    (outside / "index.txt").write_text("7\n")
    (root / "pick.json").write_text(json.dumps({"roi": ["indices:flip.txt"], "handles": []}))
    links = [(root / "flip.ply", "inside.ply", str(outside / "outside.ply")),
             (root / "flip.txt", "good.txt", str(outside / "secret.txt")),
             (root / "flip.txt", "good.txt", str(outside / "index.txt"))]
    for link, inside, _ in links:
        if not link.is_symlink():
            os.symlink(inside, link)
    stop = threading.Event()

    def swap():
        k = 0
        while not stop.is_set():
            link, inside, away = links[k % 3]
            for target in (away, inside):
                os.symlink(target, root / ".swap")
                os.replace(root / ".swap", link)
            k += 1
    session = Session(root)
    swapper = threading.Thread(target=swap)
    swapper.start()
    loaded = edits = 0
    try:
        for _ in range(200):
            try:
                session.load("flip.ply")
                assert len(session.points) == 100
                loaded += 1
            except StudioError as error:
                assert "SECRET" not in str(error)
            try:
                session.load_edit("pick.json")
                assert np.flatnonzero(session.labels).tolist() == [3]
                edits += 1
            except StudioError as error:
                assert "SECRET" not in str(error), error
    finally:
        stop.set()
        swapper.join()
    assert loaded > 0 and edits > 0  # reads through the link while it pointed inside are served


# ---- the command table against the manual -------------------------------------------------------------------------

def documented_commands():
    """The command names doc/studio.md's "Protocol" section lists: its bullets "- `NAME`" under "Commands"."""
    manual = (pathlib.Path(__file__).parents[2] / "doc" / "studio.md").read_text()
    section = manual.split("\n## Protocol\n", 1)[1].split("\n## ", 1)[0]
    commands = section.split("\nCommands", 1)[1].split("\nMessages", 1)[0]
    return re.findall(r"^- `([a-z_]+)`", commands, re.MULTILINE)


def test_the_command_table_is_the_manuals_list():
    from cgal_ext.studio.server import COMMANDS
    listed = documented_commands()
    assert len(listed) == len(set(listed)), listed
    assert sorted(listed) == sorted(COMMANDS), (sorted(set(listed) ^ set(COMMANDS)))


def test_a_binary_frame_holds_each_array_at_its_offset_converted_and_padded():
    """pack() writes each array once into the frame, converted to its wire dtype, at a 4-byte aligned offset with
    zero padding; read back as the page reads it, every value is there."""
    from cgal_ext.studio.codec import pack
    rng = np.random.default_rng(5)
    arrays = [("positions", rng.normal(size=(7, 3)), "<f4"), ("labels", np.arange(5, dtype=np.uint8)),
              ("indices", np.array([3, 1, 4], np.int64), "<u4"), ("empty", np.zeros((0, 3), np.float32))]
    data = bytes(pack({"type": "geometry", "scan": "s.ply"}, arrays))
    (length,) = struct.unpack_from("<I", data)
    assert length % 4 == 0
    header = decoded(data)
    assert header["type"] == "geometry" and header["scan"] == "s.ply"
    end = 4 + length
    for (name, array, *wire), listed in zip(arrays, header["arrays"]):
        dtype = np.dtype(wire[0] if wire else array.dtype)
        assert listed["name"] == name and listed["dtype"] == dtype.str
        assert np.array_equal(header[name], array.astype(dtype))
        start = 4 + length + listed["offset"]
        assert start % 4 == 0 and start >= end
        assert not any(data[end:start])  # the padding before it is zeros
        end = start + array.size * dtype.itemsize
    assert len(data) == (end + 3) // 4 * 4 and not any(data[end:])
