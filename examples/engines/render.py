#!/usr/bin/env python3
"""Renders exported cameras with an engine's own shadows in headless Chromium.

    render.py CAMERAS.json SCENE.glb OUT [--engine three|babylon] [--map 2048] [--type basic|pcf] [--bias B]
                                         [--cascades 4] [--lambda 0.5]

three: three.js's shadow map over the whole scene (--type, --bias: -0.0005 when not given);
babylon: Babylon.js's cascaded shadow generator (--cascades, --lambda; --bias: its default when not given).

CAMERAS.json is `shadowbench cameras SCENE PATH --frames N --size WxH`'s
document, SCENE.glb the scene file. OUT gets vis_NNNN.png (white lit, black
shadowed) and mask_NNNN.png (white where three.js drew geometry) for every
frame, the files `shadowbench score SCENE PATH OUT --mask mask_%04d.png`
reads. The page (three-shadows.html) is served on localhost from a scratch
folder; three comes from npm (scripts/setup installs it here). Prints the
renderer and what it drew; exit 2 with one line when something is missing,
1 when the page fails.
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
import subprocess
import sys
import tempfile
import threading

HERE = os.path.dirname(os.path.abspath(__file__))
# engine: its page, and a file of its npm package that must be there
ENGINES = {"three": ("three-shadows.html", "three/build/three.module.js"),
           "babylon": ("babylon-shadows.html", "babylonjs/babylon.js")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cameras")
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--engine", choices=sorted(ENGINES), default="three")
    ap.add_argument("--map", type=int, default=2048)
    ap.add_argument("--type", choices=["basic", "pcf"], default="basic")
    ap.add_argument("--bias", type=float)
    ap.add_argument("--cascades", type=int, default=4)
    ap.add_argument("--lambda", dest="lam", type=float, default=0.5)
    ap.add_argument("--chromium", default=shutil.which("chromium") or "chromium")
    a = ap.parse_args()
    page, module = ENGINES[a.engine]
    module = os.path.join(HERE, "node_modules", module)
    for path, what in [(a.cameras, "cameras"), (a.scene, "scene"), (module, a.engine + " (scripts/setup installs it)")]:
        if not os.path.exists(path):
            _bad("%s: no such file (%s)" % (path, what))
    if a.bias is None and a.engine == "three":
        a.bias = -0.0005
    root = tempfile.mkdtemp(prefix="sbthree")
    try:
        shutil.copy(os.path.join(HERE, page), root)
        shutil.copy(os.path.join(HERE, "frames.js"), root)
        os.symlink(os.path.join(HERE, "node_modules"), os.path.join(root, "node_modules"))
        shutil.copy(a.cameras, os.path.join(root, "cameras.json"))
        shutil.copy(a.scene, os.path.join(root, "scene.glb"))
        handler = functools.partial(Quiet, directory=root)
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = "http://127.0.0.1:%d/%s?cameras=cameras.json&scene=scene.glb&map=%d&type=%s&cascades=%d&lambda=%g" % (
            server.server_address[1], page, a.map, a.type, a.cascades, a.lam)
        if a.bias is not None:
            url += "&bias=%g" % a.bias
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
    what = doc.get("settings") or "%s, bias %g" % (a.type, a.bias)
    print("%s: %d frame(s) into %s (map %d, %s)" % (doc["renderer"], len(doc["frames"]), a.out, a.map, what))


def _bad(line):
    print("render.py: " + line, file=sys.stderr)
    sys.exit(2)


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


if __name__ == "__main__":
    main()
