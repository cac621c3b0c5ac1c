#!/usr/bin/env python3
"""The layer rule of docs/architecture.md, read from the sources' includes.

  check_layers.py ROOT            checks the tree at ROOT; exit 1 on a violation
  check_layers.py ROOT --selftest also checks that an upward include and a
                                  circle injected into a copy of the tree fail
  check_layers.py ROOT --graph    prints the folders' include graph (every
                                  arrow from a folder to one it includes)

A file may include only headers of its own layer or of a layer below it, and
modules (a header and the files defining what it declares) form no circle.
Every sb_ function a source file exports is declared in a header (never only in
another .c file, which would hide a call from the includes). Only the history
module speaks SQL: no other file includes <sqlite3.h> (the report asks the
history's queries)."""
import os
import re
import shutil
import sys
import tempfile

# The layers, lowest first: each is one top-level folder, and a file's layer
# is the folder it stands in (at any depth below it).
LAYERS = ["base", "gl", "scenes", "paths", "reference", "techniques", "results", "report", "harness"]
# Top-level folders that hold C sources and are no layer: the tests and the
# build's helpers, which may include any layer.
NOT_LAYERS = {"tests", "scripts", "docs", "out", ".git"}   # and every build folder (build, build-*: .gitignore's)
# Headers generated at build time, and the layer they belong to.
GENERATED = {
    "glad_gl.h": "gl", "khrplatform.h": "gl",
    "shaders.h": "techniques", "technique_list.h": "techniques", "site_assets.h": "report",
    "version.h": "harness",
}
SOURCE_EXT = (".c", ".cc", ".h")
# The one module that may include <sqlite3.h>.
SQL_MODULE = "results/history_store.c"
SQL_INCLUDE = re.compile(r'^\s*#\s*include\s+<sqlite3\.h>', re.M)
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
# An exported definition: at the start of a line, not static, an sb_ name, then
# a parameter list whose line does not end the declaration.
FUNCTION_LINE = re.compile(r'^(?!static\b|typedef\b|return\b)(?:extern "C" )?[A-Za-z_][\w \*]*?\b(sb_\w+)\s*\((.*)$', re.M)


def layer_of(rel):
    top = rel.split("/")[0]
    return LAYERS.index(top) if top in LAYERS else None


def stray_folders(root):
    """Top-level folders holding C sources that are neither a layer nor listed as no layer."""
    out = []
    for top in sorted(os.listdir(root)):
        if top in LAYERS or top in NOT_LAYERS or top.startswith((".", "build")) or not os.path.isdir(os.path.join(root, top)):
            continue
        for dirpath, _, names in os.walk(os.path.join(root, top)):
            if any(n.endswith(SOURCE_EXT) for n in names):
                out.append(top)
                break
    return out


def scan(root):
    files = {}
    for folder in LAYERS:
        base = os.path.join(root, folder)
        for dirpath, _, names in os.walk(base):
            for n in names:
                if n.endswith(SOURCE_EXT):
                    rel = os.path.relpath(os.path.join(dirpath, n), root)
                    files[rel] = open(os.path.join(root, rel), encoding="utf-8", errors="replace").read()
    return files


def folder_edges(root):
    """{(from, to): count}: includes from a layer's files of another layer's headers."""
    files = scan(root)
    headers = {os.path.basename(rel): rel for rel in files if rel.endswith(".h")}
    out = {}
    for rel, text in files.items():
        for m in INCLUDE.finditer(text):
            inc = os.path.basename(m.group(1))
            to = GENERATED.get(inc) or (headers[inc].split("/")[0] if inc in headers else None)
            frm = rel.split("/")[0]
            if to and to != frm:
                out[(frm, to)] = out.get((frm, to), 0) + 1
    return out


def check(root):
    files = scan(root)
    problems = [f"{top}/ holds C sources but is no layer: add it to LAYERS in its place (docs/architecture.md)"
                for top in stray_folders(root)]
    headers = {}
    for rel in files:
        if rel.endswith(".h"):
            headers.setdefault(os.path.basename(rel), []).append(rel)
    for name, where in headers.items():
        if len(where) > 1:
            problems.append(f"header name {name} is used twice ({', '.join(sorted(where))}): includes would be ambiguous")
    layer_index = {name: i for i, name in enumerate(LAYERS)}

    # which header declares each exported function, and which .c defines it
    declared = {}
    for rel, text in files.items():
        if rel.endswith(".h"):
            for m in re.finditer(r'\b(sb_\w+)\s*\(', text):
                declared.setdefault(m.group(1), set()).add(rel)
    module_of = {}
    for rel, text in files.items():
        if rel.endswith(".h"):
            module_of[rel] = {rel}
            continue
        mods = set()
        for m in FUNCTION_LINE.finditer(text):
            name, rest = m.group(1), m.group(2)
            code = re.sub(r'/\*.*?\*/|//.*', '', rest).rstrip()
            if code.endswith(";") and "{" not in code:
                line = text.count("\n", 0, m.start()) + 1
                problems.append(f"{rel}:{line}: declares {name} outside a header (a call the includes do not show)")
                continue
            if name in declared:
                mods |= declared[name]
            else:
                line = text.count("\n", 0, m.start()) + 1
                problems.append(f"{rel}:{line}: {name} is exported but declared in no header")
        own = os.path.splitext(rel)[0] + ".h"
        if own in files:
            mods.add(own)
        module_of[rel] = mods or {rel}

    edges = {}
    for rel, text in files.items():
        src_layer = layer_of(rel)
        for m in INCLUDE.finditer(text):
            inc = os.path.basename(m.group(1))
            line = text.count("\n", 0, m.start()) + 1
            if inc in GENERATED:
                target, tl = None, layer_index[GENERATED[inc]]
            elif inc in headers:
                target = headers[inc][0]
                tl = layer_of(target)
            else:
                problems.append(f"{rel}:{line}: includes \"{m.group(1)}\", which is no project header")
                continue
            if tl > src_layer:
                problems.append(f"{rel}:{line}: {LAYERS[src_layer]} includes {inc} of the {LAYERS[tl]} layer above it")
            if target:
                for mod in module_of[rel]:
                    if mod != target:
                        edges.setdefault(mod, set()).add(target)

    for rel, text in files.items():
        m = SQL_INCLUDE.search(text)
        if m and rel != SQL_MODULE:
            line = text.count("\n", 0, m.start()) + 1
            problems.append(f"{rel}:{line}: includes <sqlite3.h>: only {SQL_MODULE} speaks SQL (add a query there)")

    for cycle in circles(edges):
        problems.append("circle: " + " -> ".join(cycle + [cycle[0]]))
    return problems


def circles(edges):
    """One cycle for each strongly connected component of more than one module (Tarjan)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(path_in(set(comp), edges, min(comp)))

    sys.setrecursionlimit(10000)
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def path_in(comp, edges, start):
    """A cycle through start inside the component (breadth-first back to start)."""
    prev, frontier = {start: None}, [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(edges.get(v, ())):
                if w == start:
                    path = [v]
                    while prev[path[-1]] is not None:
                        path.append(prev[path[-1]])
                    return list(reversed(path))
                if w in comp and w not in prev:
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    return sorted(comp)


def selftest(root):
    """Copies the tree, breaks the rule two ways, and requires each to be caught."""
    cases = [
        ("an upward include", "base/util.c", '#include "scene.h"\n', "base includes scene.h"),
        ("an include of the layer above", "reference/error.c", '#include "render.h"\n',
         "reference includes render.h of the techniques layer above it"),
        ("a folder that is no layer", "extra/thing.c", "int sb_thing(void);\n", "extra/ holds C sources but is no layer"),
        ("a circle in the harness", "harness/session.h", '#include "run.h"\n', ["circle:", "harness/session.h", "harness/run.h"]),
        ("a function declared in no header", "scenes/scene.c",
         "bool sb_hidden_helper(int x) {\n    return x > 0;\n}\n", "sb_hidden_helper is exported but declared in no header"),
        ("a declaration in a .c file", "paths/path.c",
         "bool sb_gltf_secret(int cam); /* gltf_load.cc */\n", "declares sb_gltf_secret outside a header"),
        ("SQL outside the history", "report/site.c", "#include <sqlite3.h>\n", "report/site.c:"),
    ]
    failures = 0
    for what, rel, text, expect in cases:
        tmp = tempfile.mkdtemp(prefix="sb-layers-")
        try:
            for top in LAYERS:
                shutil.copytree(os.path.join(root, top), os.path.join(tmp, top))
            os.makedirs(os.path.dirname(os.path.join(tmp, rel)), exist_ok=True)
            with open(os.path.join(tmp, rel), "a") as f:
                f.write("\n" + text)
            want = expect if isinstance(expect, list) else [expect]
            found = [p for p in check(tmp) if all(w in p for w in want)]
            print(f"selftest: {what} in {rel}: " + (f"caught: {found[0]}" if found else "NOT caught"))
            failures += not found
        finally:
            shutil.rmtree(tmp)
    return failures


def print_graph(root):
    """Each folder and the folders it includes, lowest layer first; an arrow up is marked."""
    edges = folder_edges(root)
    for frm in LAYERS:
        tos = sorted((t for f, t in edges if f == frm), key=LAYERS.index)
        marks = [f"{t} ({edges[(frm, t)]})" + ("  <-- UP" if LAYERS.index(t) > LAYERS.index(frm) else "") for t in tos]
        print(f"{frm:<11} -> " + (", ".join(marks) if marks else "(nothing)"))


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    if "--graph" in sys.argv:
        print_graph(root)
        return
    problems = check(root)
    for p in problems:
        print(p)
    failed = 1 if problems else 0
    print(f"layers: {len(problems)} violation(s) in {root}")
    if "--selftest" in sys.argv:
        failed += selftest(root)
    passed = 1 + (7 if "--selftest" in sys.argv else 0) - failed
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
