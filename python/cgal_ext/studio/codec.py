"""The studio's wire format: JSON commands in text frames, arrays in binary frames.

A binary frame is a little-endian uint32 header length, the JSON header (padded with spaces to a multiple of 4
bytes), then the arrays the header lists, each at its offset and padded with zeros to 4 bytes (doc/studio.md,
"Protocol"). The page sends one kind of binary frame, a selection: a header with a count, then that many uint32
indices.
"""
import json
import struct

import numpy as np
from aiohttp import WSMsgType

from .session import StudioError

MAX_TEXT = 1 << 20           # a JSON command
MAX_BINARY = 64 << 20        # a selection of up to 16M indices
MAX_HEADER = 4096


def pack(header, arrays=()):
    """A binary frame: header (a dict; the arrays' names, dtypes, shapes and offsets added) and arrays, each given
    as (name, array) or (name, array, dtype on the wire). Each array is copied once, converted on the way, into
    the frame: a 1M-point geometry is some 40 MB."""
    arrays = [(name, a, np.dtype(wire[0] if wire else a.dtype))
              for name, a, *wire in ((entry[0], np.asarray(entry[1]), *entry[2:]) for entry in arrays)]
    listed, offset = [], 0
    for name, a, dtype in arrays:
        listed.append({"name": name, "dtype": dtype.str, "shape": list(a.shape), "offset": offset})
        offset += (a.size * dtype.itemsize + 3) // 4 * 4
    text = json.dumps(dict(header, arrays=listed)).encode()
    text += b" " * (-len(text) % 4)
    frame = bytearray(4 + len(text) + offset)  # zeros: the padding
    struct.pack_into("<I", frame, 0, len(text))
    frame[4:4 + len(text)] = text
    for (_, a, dtype), entry in zip(arrays, listed):
        np.frombuffer(frame, dtype, a.size, 4 + len(text) + entry["offset"]).reshape(a.shape)[...] = a
    return frame


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
