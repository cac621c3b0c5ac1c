#!/usr/bin/env python3
"""Renders exported cameras with an engine's own shadows in headless Chromium.

    render.py CAMERAS.json SCENE.glb OUT [--engine three|babylon|filament] [--map 2048] [--type basic|pcf] [--bias B]
                                         [--cascades 4] [--lambda 0.5]

three: three.js's shadow map over the whole scene (--type, --bias: -0.0005 when not given);
babylon: Babylon.js's cascaded shadow generator (--cascades, --lambda; --bias: its default when not given);
filament: Filament's sun at its C++ defaults (one cascade of 1024, LiSPSM, PCF): its npm build cannot set shadow
options from JavaScript, so --map, --type, --bias, --cascades and --lambda are refused for it.

CAMERAS.json is `shadowbench cameras SCENE PATH --frames N --size WxH`'s
document, SCENE.glb the scene file. OUT gets vis_NNNN.png (white lit, black
shadowed) and mask_NNNN.png (white where three.js drew geometry) for every
frame, the files `shadowbench score SCENE PATH OUT --mask mask_%04d.png`
reads. The page (three-shadows.html) is served on localhost from a scratch
folder; three comes from npm (scripts/setup installs it here). Prints the
renderer and what it drew; exit 2 with one line when something is missing,
1 when the page fails. SB_ENGINE_LOG=1 prints the page's own log too.
"""
import argparse
import base64
import functools
import html
import http.server
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import threading

HERE = os.path.dirname(os.path.abspath(__file__))
# engine: its page, and a file of its npm package that must be there
ENGINES = {"three": ("three-shadows.html", "three/build/three.module.js"),
           "babylon": ("babylon-shadows.html", "babylonjs/babylon.js"),
           "filament": ("filament-shadows.html", "filament/filament.js")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cameras")
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--engine", choices=sorted(ENGINES), default="three")
    ap.add_argument("--map", type=int)
    ap.add_argument("--type", choices=["basic", "pcf"])
    ap.add_argument("--bias", type=float)
    ap.add_argument("--cascades", type=int)
    ap.add_argument("--lambda", dest="lam", type=float)
    ap.add_argument("--chromium", default=shutil.which("chromium") or "chromium")
    a = ap.parse_args()
    page, module = ENGINES[a.engine]
    module = os.path.join(HERE, "node_modules", module)
    for path, what in [(a.cameras, "cameras"), (a.scene, "scene"), (module, a.engine + " (scripts/setup installs it)")]:
        if not os.path.exists(path):
            _bad("%s: no such file (%s)" % (path, what))
    if a.engine == "filament":
        given = [o for o, v in [("--map", a.map), ("--type", a.type), ("--bias", a.bias), ("--cascades", a.cascades),
                                ("--lambda", a.lam)] if v is not None]
        if given:
            _bad("%s: Filament's npm build cannot set a light's shadow options from JavaScript ('unbound types' "
                 "on LightManager$ShadowOptions): only its defaults can be drawn" % ", ".join(given))
    a.map = 2048 if a.map is None else a.map
    a.type = a.type or "basic"
    a.cascades = 4 if a.cascades is None else a.cascades
    a.lam = 0.5 if a.lam is None else a.lam
    if a.bias is None and a.engine == "three":
        a.bias = -0.0005
    root = tempfile.mkdtemp(prefix="sbthree")
    try:
        shutil.copy(os.path.join(HERE, page), root)
        shutil.copy(os.path.join(HERE, "frames.js"), root)
        os.symlink(os.path.join(HERE, "node_modules"), os.path.join(root, "node_modules"))
        shutil.copy(a.cameras, os.path.join(root, "cameras.json"))
        shutil.copy(a.scene, os.path.join(root, "scene.glb"))
        extra = ""
        if a.engine == "filament":
            for kind in ("lit", "unlit"):
                _white_glb(a.scene, os.path.join(root, "scene-%s.glb" % kind), unlit=kind == "unlit")
            extra = "&lit=scene-lit.glb&unlit=scene-unlit.glb&version=" + _version(module)
        handler = functools.partial(Quiet, directory=root)
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = "http://127.0.0.1:%d/%s?cameras=cameras.json&scene=scene.glb&map=%d&type=%s&cascades=%d&lambda=%g" % (
            server.server_address[1], page, a.map, a.type, a.cascades, a.lam)
        if a.bias is not None:
            url += "&bias=%g" % a.bias
        url += extra
        p = subprocess.run([a.chromium, "--headless", "--no-sandbox", "--use-angle=swiftshader",
                            "--enable-unsafe-swiftshader", "--virtual-time-budget=120000", "--dump-dom", url],
                           capture_output=True, text=True, timeout=300)
        server.shutdown()
    finally:
        shutil.rmtree(root, ignore_errors=True)
    dom = p.stdout
    ready = re.search(r'<body data-ready="(\w+)"', dom)
    log = re.search(r'<pre id="log">(.*?)</pre>', dom, re.S)
    out = re.search(r'<textarea id="out">(.*?)</textarea>', dom, re.S)
    if os.environ.get("SB_ENGINE_LOG") and log:
        print(html.unescape(log.group(1)).strip(), file=sys.stderr)
    if not ready or ready.group(1) != "yes" or not out:
        print("render.py: the page did not finish (%s): %s" % (ready.group(1) if ready else "no page",
              html.unescape(log.group(1)).strip() if log else p.stderr[-2000:]), file=sys.stderr)
        sys.exit(1)
    doc = json.loads(html.unescape(out.group(1)))
    os.makedirs(a.out, exist_ok=True)
    for f in doc["frames"]:
        for kind in ("vis", "mask"):
            data = f[kind].split(",", 1)[1]
            path = os.path.join(a.out, "%s_%04d.png" % (kind, f["frame"]))
            with open(path + ".tmp", "wb") as fh:
                fh.write(base64.b64decode(data))
            os.replace(path + ".tmp", path)
    what = doc.get("settings") or "map %d, %s, bias %g" % (a.map, a.type, a.bias)
    if a.engine == "babylon":
        what = "map %d, %s" % (a.map, what)
    print("%s: %d frame(s) into %s (%s)" % (doc["renderer"], len(doc["frames"]), a.out, what))


def _white_glb(src, dst, unlit):
    """SRC's copy at DST with every primitive one white material (dielectric and fully rough, or unlit), each
    keeping its sidedness, and none of the file's own lights: the engine's page draws its frames from it."""
    with open(src, "rb") as f:
        data = f.read()
    magic, _, total = struct.unpack_from("<III", data, 0)
    jlen, jtype = struct.unpack_from("<II", data, 12)
    if magic != 0x46546C67 or jtype != 0x4E4F534A:
        _bad("%s: not a binary glTF (glb) file" % src)
    doc = json.loads(data[20:20 + jlen])
    sided = [bool(m.get("doubleSided")) for m in doc.get("materials", [])]
    mats = []
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            two = sided[prim["material"]] if "material" in prim and prim["material"] < len(sided) else False
            m = {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 1},
                 "doubleSided": two}
            if unlit:
                m["extensions"] = {"KHR_materials_unlit": {}}
            prim["material"] = len(mats)
            mats.append(m)
    doc["materials"] = mats
    for key in ("textures", "images", "samplers"):
        doc.pop(key, None)
    for node in doc.get("nodes", []):
        node.get("extensions", {}).pop("KHR_lights_punctual", None)
    doc.get("extensions", {}).pop("KHR_lights_punctual", None)
    used = [e for e in doc.get("extensionsUsed", []) if e != "KHR_lights_punctual"]
    if unlit and "KHR_materials_unlit" not in used:
        used.append("KHR_materials_unlit")
    doc["extensionsUsed"] = used
    doc["extensionsRequired"] = [e for e in doc.get("extensionsRequired", []) if e in used]
    if not doc["extensionsRequired"]:
        del doc["extensionsRequired"]
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    rest = data[20 + jlen:total]
    with open(dst, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + len(rest)))
        f.write(struct.pack("<II", len(js), 0x4E4F534A) + js + rest)


def _version(module):
    with open(os.path.join(os.path.dirname(module), "package.json")) as f:
        return json.load(f)["version"]


def _bad(line):
    print("render.py: " + line, file=sys.stderr)
    sys.exit(2)


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


if __name__ == "__main__":
    main()
