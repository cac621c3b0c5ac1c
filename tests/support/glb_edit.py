#!/usr/bin/env python3
"""glb_edit.py IN OUT CODE: a .glb rewritten with CODE run on it, for tests that need one rule of a real file
broken. CODE sees `doc` (the JSON, a dict) and `bin` (the BIN chunk, a bytearray), and `f32(accessor, index,
values)`, which writes floats over an accessor's elements (its view's stride kept)."""
import json
import struct
import sys

src, dst, code = sys.argv[1:4]
data = open(src, "rb").read()
n = struct.unpack("<I", data[12:16])[0]
doc = json.loads(data[20:20 + n])
rest = data[20 + n:]
bin = bytearray(rest[8:8 + struct.unpack("<I", rest[:4])[0]]) if rest else bytearray()


def f32(acc, index, values):
    a = doc["accessors"][acc]
    v = doc["bufferViews"][a["bufferView"]]
    comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[a["type"]]
    stride = v.get("byteStride", 4 * comps)
    struct.pack_into("<%df" % len(values), bin, v.get("byteOffset", 0) + a.get("byteOffset", 0) + index * stride,
                     *values)


exec(code)
js = json.dumps(doc).encode()
js += b" " * (-len(js) % 4)
chunks = struct.pack("<II", len(js), 0x4E4F534A) + js
if bin:
    bin += b"\0" * (-len(bin) % 4)
    chunks += struct.pack("<II", len(bin), 0x004E4942) + bytes(bin)
open(dst, "wb").write(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)
