#!/usr/bin/env python3
"""Writes the glTF fuzz seeds with 64-bit edge values (tests/fuzz/corpus/gltf/edge-*.gltf).

Every offset, length, count and index field of a one-triangle document (and of
a sparse accessor, a light, a camera and a skin) gets edge values written as
exact JSON text: numbers beyond 2^53 only survive as text, so a fuzzer that
mutates parsed numbers would never reach them. Run it again after changing the
list; the files are committed."""
import base64, os, struct, sys

out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "corpus", "gltf")
buf = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 0, 1) + struct.pack("<3H", 0, 1, 2) + b"\0\0"
uri = "data:application/octet-stream;base64," + base64.b64encode(buf + struct.pack("<H2x3f", 1, 0, 1, 0)).decode()

def doc(f):
    d = dict(buffer_len="60", v0_off="0", v0_len="36", v0_buf="0", v1_off="36", v1_len="6", v2_off="44", v2_len="16",
             a0_view="0", a0_off="0", a0_count="3", a0_ctype="5126", a1_view="1", a1_off="0", a1_count="3",
             sp_count="1", sp_iview="2", sp_ioff="0", sp_vview="2", sp_voff="4", mesh="0", child="1", scene="0",
             scene_node="0", light="0", camera="0", skin_joint="0", material="0")
    d.update(f)
    return ('{"asset":{"version":"2.0"},"extensionsUsed":["KHR_lights_punctual"],"scene":%(scene)s,'
            '"scenes":[{"nodes":[%(scene_node)s]}],'
            '"nodes":[{"mesh":%(mesh)s,"children":[%(child)s],"skin":0},'
            '{"camera":%(camera)s,"extensions":{"KHR_lights_punctual":{"light":%(light)s}},"rotation":[0,0,0,1]}],'
            '"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":%(material)s}]}],'
            '"materials":[{"alphaMode":"MASK","doubleSided":true}],'
            '"cameras":[{"type":"perspective","perspective":{"yfov":1,"znear":0.1,"zfar":100}}],'
            '"skins":[{"joints":[%(skin_joint)s]}],'
            '"extensions":{"KHR_lights_punctual":{"lights":[{"type":"spot","spot":{"outerConeAngle":0.5}}]}},'
            '"buffers":[{"byteLength":%(buffer_len)s,"uri":"' + uri + '"}],'
            '"bufferViews":[{"buffer":%(v0_buf)s,"byteOffset":%(v0_off)s,"byteLength":%(v0_len)s},'
            '{"buffer":0,"byteOffset":%(v1_off)s,"byteLength":%(v1_len)s},'
            '{"buffer":0,"byteOffset":%(v2_off)s,"byteLength":%(v2_len)s}],'
            '"accessors":[{"bufferView":%(a0_view)s,"byteOffset":%(a0_off)s,"componentType":%(a0_ctype)s,'
            '"count":%(a0_count)s,"type":"VEC3","sparse":{"count":%(sp_count)s,'
            '"indices":{"bufferView":%(sp_iview)s,"byteOffset":%(sp_ioff)s,"componentType":5123},'
            '"values":{"bufferView":%(sp_vview)s,"byteOffset":%(sp_voff)s}}},'
            '{"bufferView":%(a1_view)s,"byteOffset":%(a1_off)s,"componentType":5123,"count":%(a1_count)s,'
            '"type":"SCALAR"}]}\n') % d

edges = ["18446744073709551615", "18446744073709551580", "9223372036854775808", "4294967296", "2147483648",
         "9007199254740993", "-1", "-9223372036854775808", "1e300", "18446744073709551616"]
fields = ["buffer_len", "v0_off", "v0_len", "v0_buf", "v1_off", "v1_len", "a0_view", "a0_off", "a0_count",
          "a0_ctype", "a1_view", "a1_off", "a1_count", "sp_count", "sp_iview", "sp_ioff", "sp_voff", "mesh", "child",
          "scene", "scene_node", "light", "camera", "skin_joint", "material"]
os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "edge-valid.gltf"), "w") as f:
    f.write(doc({}))
for i, field in enumerate(fields):
    for k in range(3):  # three edge values a field, rotating through the list
        v = edges[(3 * i + k) % len(edges)]
        with open(os.path.join(out, "edge-%s-%d.gltf" % (field, k)), "w") as f:
            f.write(doc({field: v}))

# One broken rule each (issue 17): the valid document with one piece of text replaced.
valid = doc({})
rules = {
    "uri-dir": ('"uri":"data:', '"uri":".","x":"data:'),
    "uri-up": ('"uri":"data:', '"uri":"../../../../etc/passwd","x":"data:'),
    "uri-dev": ('"uri":"data:', '"uri":"/dev/zero","x":"data:'),
    "uri-scheme": ('"uri":"data:', '"uri":"http://example.com/a.bin","x":"data:'),
    "stride-small": ('"byteLength":36}', '"byteLength":36,"byteStride":4}'),
    "stride-odd": ('"byteLength":36}', '"byteLength":36,"byteStride":14}'),
    "offset-unaligned": ('"bufferView":0,"byteOffset":0', '"bufferView":0,"byteOffset":2'),
    "index-stride": ('"byteOffset":36,"byteLength":6}', '"byteOffset":34,"byteLength":10,"byteStride":4}'),
    "quat-zero": ('"rotation":[0,0,0,1]', '"rotation":[0,0,0,0]'),
    "quat-long": ('"rotation":[0,0,0,1]', '"rotation":[0,0,0,2]'),
    "matrix-w": ('"rotation":[0,0,0,1]', '"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,0]'),
    "scale-zero": ('"rotation":[0,0,0,1]', '"scale":[0,0,0]'),
    "scene-negative": ('"scene":0', '"scene":-1'),
    "cycle": ('"children":[1]', '"children":[1]},{"children":[3]},{"children":[2]'),
    "two-parents": ('"rotation":[0,0,0,1]}', '"rotation":[0,0,0,1],"children":[1]}'),
    "spot-cone": ('"outerConeAngle":0.5', '"outerConeAngle":2'),
    "spot-negative": ('"type":"spot"', '"type":"spot","intensity":-1'),
    "syntax": ('"scenes":[', '"scenes":[[,'),
}
for name, (old, new) in rules.items():
    assert old in valid, name
    with open(os.path.join(out, "rule-%s.gltf" % name), "w") as f:
        f.write(valid.replace(old, new, 1))
# a chain of 300 nodes (deeper than the old recursion limit of 256)
chain = ",".join('{"translation":[0,0.01,0],"children":[%d]}' % (i + 1) for i in range(300)) + ',{"mesh":0}'
with open(os.path.join(out, "rule-chain.gltf"), "w") as f:
    f.write(valid.replace('"nodes":[{"mesh":0,"children":[1],"skin":0},', '"nodes":[' + chain + ',{"skin":0},')
            .replace('"joints":[0]', '"joints":[301]').replace('"children":[1],"skin":0}', '"skin":0}'))
