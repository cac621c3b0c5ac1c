"""sbscene: what the scripts that write scenes share (add-lamps, place-movers, tile-gltf), so they follow the
tool's own rules in one place:

- bad input is one line on stderr, `SCRIPT: what is wrong`, and exit 2 (never a traceback);
- a .gltf's buffers are read only from inside the scene's folder (the loader's rule; `--allow-external-uris`
  lifts it), a data: URI decoded;
- the output is a .glb that is not the input, is not overwritten without --force, and is written to a
  temporary name in its folder, loaded there by the tool's own loader (`shadowbench info`, the binary
  SHADOWBENCH names, default build/shadowbench), then renamed: nothing is half-written, and nothing the tool
  would refuse is written at all;
- numbers are finite and within the range the tool reads back (the JSON never holds NaN or Infinity).
"""
import base64
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

# what the tool holds (scenes/scene.h's SB_SCENE_MAX_COORD)
MAX_COORD = 1e12


class Bad(Exception):
    """Bad input: its text is the one line said."""


def die(prog, msg):
    print("%s: %s" % (prog, msg), file=sys.stderr)
    sys.exit(2)


def run(prog, main):
    """main() with every bad input one line and exit 2: a Bad said as it is, and what a file that is no glTF
    raises (a missing key, a wrong type, bytes that do not decode) said with what it is."""
    try:
        main()
    except Bad as e:
        die(prog, str(e))
    except (KeyError, IndexError, TypeError, ValueError, struct.error, UnicodeDecodeError, RecursionError) as e:
        die(prog, "the input is not a glTF this script can read (%s: %s)" % (type(e).__name__, e))
    except OSError as e:
        die(prog, "%s: %s" % (e.filename or "", e.strerror or e))
    except KeyboardInterrupt:
        sys.exit(130)


def number(text, what, lo=-MAX_COORD, hi=MAX_COORD, integer=False):
    """text as a finite number in [lo, hi] (an int where integer), else Bad naming what."""
    try:
        v = int(text) if integer else float(text)
    except (TypeError, ValueError):
        raise Bad("%s %s: expected %s" % (what, text, "a whole number" if integer else "a number"))
    if not (isinstance(v, int) or math.isfinite(v)) or not lo <= v <= hi:
        raise Bad("%s %s: expected %s from %g to %g" % (what, text, "a whole number" if integer else "a finite number",
                                                        lo, hi))
    return v


def numbers(text, n, what):
    """'x,y,z' as n finite numbers within MAX_COORD."""
    parts = (text or "").split(",")
    if len(parts) != n:
        raise Bad("%s %s: expected %d numbers separated by commas" % (what, text, n))
    return [number(p, what) for p in parts]


def inside(folder, path):
    """Whether path (links and .. resolved) lies inside folder."""
    folder, path = os.path.realpath(folder), os.path.realpath(path)
    return os.path.commonpath([folder, path]) == folder


def read_gltf(path, allow_external=False, one_buffer=True):
    """(document, BIN bytes or None) of a .glb, or of a .gltf with its buffer read in (a data: URI, or a file
    inside the scene's folder unless allow_external). one_buffer: a .gltf of more buffers is refused."""
    if not os.path.isfile(path):
        raise Bad("%s: %s" % (path, "no such file" if not os.path.exists(path) else "not a file"))
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        if len(data) < 20:
            raise Bad("%s: cut short (%d bytes)" % (path, len(data)))
        version, total = struct.unpack_from("<II", data, 4)
        if version != 2:
            raise Bad("%s: glTF version %d, not 2" % (path, version))
        if total > len(data):
            raise Bad("%s: cut short (%d bytes of %d)" % (path, len(data), total))
        doc, binary, at = None, None, 12
        while at + 8 <= total:
            clen, kind = struct.unpack_from("<II", data, at)
            body = data[at + 8:at + 8 + clen]
            if len(body) < clen:
                raise Bad("%s: a chunk at byte %d runs past the file" % (path, at))
            if kind == 0x4E4F534A:
                doc = parse_json(path, body)
            elif kind == 0x004E4942 and binary is None:
                binary = body
            at += 8 + clen
        if doc is None:
            raise Bad("%s: no JSON chunk" % path)
        return doc, binary
    doc = parse_json(path, data)
    bufs = doc.get("buffers", [])
    if not isinstance(bufs, list):
        raise Bad("%s: /buffers is not an array" % path)
    if one_buffer and len(bufs) > 1:
        raise Bad("%s: %d buffers: only a file of one buffer can become a .glb" % (path, len(bufs)))
    binary = None
    if bufs:
        uri = bufs[0].get("uri", "")
        if not isinstance(uri, str) or not uri:
            raise Bad("%s: /buffers/0: no uri" % path)
        if uri.startswith("data:"):
            try:
                binary = base64.b64decode(uri.split(",", 1)[1], validate=True)
            except (IndexError, ValueError):
                raise Bad("%s: /buffers/0/uri: a data: URI that is not base64" % path)
        else:
            folder = os.path.dirname(os.path.abspath(path))
            src = os.path.join(folder, uri)
            if not allow_external and not inside(folder, src):
                raise Bad("%s: /buffers/0/uri: %s leaves the scene's folder (the loader's rule; "
                          "--allow-external-uris lifts it)" % (path, uri))
            if not os.path.isfile(src):
                raise Bad("%s: /buffers/0/uri: %s: no such file" % (path, src))
            with open(src, "rb") as f:
                binary = f.read()
        bufs[0].pop("uri", None)
    return doc, binary


def parse_json(path, data):
    try:
        doc = json.loads(data.decode("utf-8"), parse_constant=lambda c: _bad_constant(path, c))
    except UnicodeDecodeError:
        raise Bad("%s: not glTF (neither a .glb nor UTF-8 JSON)" % path)
    except ValueError as e:
        raise Bad("%s: not glTF JSON (%s)" % (path, e))
    if not isinstance(doc, dict):
        raise Bad("%s: not glTF JSON (the document is no object)" % path)
    return doc


def _bad_constant(path, c):
    raise Bad("%s: %s in the JSON, which is no number glTF allows" % (path, c))


def check_output(inputs, out, force):
    """OUT: a .glb, none of the inputs, and new unless force."""
    if not out.endswith(".glb"):
        raise Bad("%s: the output is a .glb" % out)
    for src in inputs:
        if os.path.exists(out) and os.path.exists(src) and os.path.samefile(src, out) or \
                os.path.realpath(src) == os.path.realpath(out):
            raise Bad("%s: the output is the input %s: write the scene to another file" % (out, src))
    if os.path.exists(out) and not force:
        raise Bad("%s: exists (--force writes over it)" % out)
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        raise Bad("%s: no such folder" % folder)


def glb_bytes(doc, binary):
    """The document and its BIN chunk as .glb bytes; NaN or Infinity anywhere is refused."""
    try:
        js = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8")
    except ValueError:
        raise Bad("a number that is not finite would be written into the scene's JSON")
    js += b" " * ((4 - len(js) % 4) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary is not None:
        b = bytes(binary) + b"\0" * ((4 - len(binary) % 4) % 4)
        chunks += struct.pack("<II", len(b), 0x004E4942) + b
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


def shadowbench():
    """The binary whose loader the scripts answer to."""
    return os.environ.get("SHADOWBENCH", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build",
                                                      "shadowbench"))


def check_loads(tmp, path):
    """The tool's own loader reads the file at tmp (to be renamed to path), or Bad with its reason. Without a
    built binary, a one-line note says the file is unchecked."""
    tool = shadowbench()
    if not os.access(tool, os.X_OK):
        print("note: %s not loaded by the tool before writing (no binary at %s: scripts/build, or SHADOWBENCH)"
              % (path, tool), file=sys.stderr)
        return
    env = dict(os.environ, SB_SCENE_CACHE="off")
    p = subprocess.run([tool, "info", tmp], capture_output=True, text=True, env=env)
    if p.returncode:
        why = (p.stderr.strip().splitlines() or ["shadowbench info exited %d" % p.returncode])[-1]
        why = why.replace("shadowbench: ", "", 1).replace(tmp, path)
        raise Bad("%s: not written: the tool would refuse it (%s)" % (path, why))


def write_glb(path, doc, binary):
    """The .glb written to a temporary name in its folder, loaded there by the tool, then renamed over path."""
    data = glb_bytes(doc, binary)
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix=".", suffix=".part.glb")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        check_loads(tmp, path)
        umask = os.umask(0)   # mkstemp's file is 0600: the scene gets the mode any new file would (0666 less umask)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
