#!/usr/bin/env python3
"""Renders exported cameras with three.js's shadow map in headless Chromium.

    render.py CAMERAS.json SCENE.glb OUT [--map 2048] [--type basic|pcf] [--bias -0.0005]

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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cameras")
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--map", type=int, default=2048)
    ap.add_argument("--type", choices=["basic", "pcf"], default="basic")
    ap.add_argument("--bias", type=float, default=-0.0005)
    ap.add_argument("--chromium", default=shutil.which("chromium") or "chromium")
    a = ap.parse_args()
    three = os.path.join(HERE, "node_modules", "three", "build", "three.module.js")
    for path, what in [(a.cameras, "cameras"), (a.scene, "scene"), (three, "three (scripts/setup installs it)")]:
        if not os.path.exists(path):
            _bad("%s: no such file (%s)" % (path, what))
    root = tempfile.mkdtemp(prefix="sbthree")
    try:
        shutil.copy(os.path.join(HERE, "three-shadows.html"), root)
        os.symlink(os.path.join(HERE, "node_modules"), os.path.join(root, "node_modules"))
        shutil.copy(a.cameras, os.path.join(root, "cameras.json"))
        shutil.copy(a.scene, os.path.join(root, "scene.glb"))
        handler = functools.partial(Quiet, directory=root)
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = "http://127.0.0.1:%d/three-shadows.html?cameras=cameras.json&scene=scene.glb&map=%d&type=%s&bias=%g" % (
            server.server_address[1], a.map, a.type, a.bias)
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
    print("%s: %d frame(s) into %s (map %d, %s, bias %g)" % (doc["renderer"], len(doc["frames"]), a.out, a.map,
                                                             a.type, a.bias))


def _bad(line):
    print("render.py: " + line, file=sys.stderr)
    sys.exit(2)


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


if __name__ == "__main__":
    main()
