#!/usr/bin/env python3
"""Makes tests/history/history_v3.sql and history_v3.expected: a history as shadowbench wrote it at schema
version 3 (series kept as one '|'-joined text) and what that shadowbench said of it (its regressions, as CSV and as text, and its report's data). Run once, with the binary
of a commit from before schema 4 (it was made with 26f3f92's); the history test migrates the file with today's
shadowbench and holds its answers to the expected ones.

The nights: one set of six runs on plane-box and movers whose series cover every part a key had (sized light,
indirect submission, clips held still) replayed as nine nights: six at a 0.98-1.02x wander, three more at 1.3x
that; an accepted note on pssm's step and a plain note on night 2. Per-frame CSVs and all but a few metrics are
dropped to keep the file small (the answers compared are over those metrics).

usage: make_v3_fixture.py OLD_SHADOWBENCH OUT_DIR"""
import csv
import hashlib
import os
import random
import re
import shutil
import sqlite3
import subprocess
import sys

BIN, OUT = sys.argv[1:3]
WORK = os.path.join(OUT, "work")
HERE = os.path.dirname(os.path.abspath(__file__))
METRICS = ["final_ms", "gpu_ms", "err_rate", "draw_calls"]
KEEP = {m + s for m in METRICS for s in ("", "_mean", "_median", "_ci95", "_p95")}
RECENT = 3


def sb(*args, ok=(0,)):
    p = subprocess.run([BIN] + list(args), capture_output=True, text=True)
    if p.returncode not in ok:
        raise SystemExit("shadowbench %s exited %d: %s" % (" ".join(args), p.returncode, p.stderr))
    return p


def last_dir(p):
    return p.stdout.strip().splitlines()[-1]


def merged_set():
    """One set of the three commands' runs (the summary's columns united; the first set's meta)."""
    common = ["--frames", "3", "--warmup", "0", "--size", "160x90", "--quiet"]
    bench = os.path.join(WORK, "fx.bench")
    with open(bench, "w") as f:
        f.write("scene plane-box plane-box\npath plane-box plane-box\n"
                "defaults --frames 3 --warmup 0 --size 160x90 --error-every 2\n"
                "sm:res=512 pssm:res=512\nsm:res=256 --sun-size 0.53\n")
    sets = [last_dir(sb("batch", bench, "--quiet", "--out", os.path.join(WORK, "a"))),
            last_dir(sb("run", "plane-box", "plane-box", "sm:res=256", "--submit", "indirect", *common,
                        "--out", os.path.join(WORK, "b"))),
            last_dir(sb("run", "movers", "movers", "sm:res=256", "none", "--anim", "none", *common,
                        "--out", os.path.join(WORK, "c")))]
    dst = os.path.join(WORK, "set")
    shutil.copytree(sets[0], dst)
    header, rows = [], []
    for s in sets:
        with open(os.path.join(s, "summary.csv"), newline="") as fh:
            r = list(csv.DictReader(fh))
        for h in csv.DictReader(open(os.path.join(s, "summary.csv"))).fieldnames:
            if h not in header:
                header.append(h)
        rows += r
        for f in os.listdir(s):
            if f.endswith(".csv") and f != "summary.csv":
                shutil.copy(os.path.join(s, f), os.path.join(dst, f))
    for i, r in enumerate(rows):
        r["run_index"] = str(i)
    with open(os.path.join(dst, "summary.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, header, restval="", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    meta = open(os.path.join(dst, "meta")).read()
    open(os.path.join(dst, "meta"), "w").write(re.sub(r"(?m)^runs: .*\n", "", meta))
    os.unlink(os.path.join(dst, "manifest"))
    return dst


def timing(name, ms):
    base, _, stat = name.rpartition("_")
    return name in ms or (stat in ("mean", "median", "p95", "p99", "std", "ci95", "min", "max") and base in ms)


def replay(src, name, factor, day, ms):
    dst = os.path.join(WORK, name)
    shutil.copytree(src, dst)
    for f in os.listdir(dst):
        if not f.endswith(".csv"):
            continue
        path = os.path.join(dst, f)
        rows = list(csv.reader(open(path, newline="")))
        scaled = [i for i, h in enumerate(rows[0]) if timing(h, ms)]
        verdict = [i for i, h in enumerate(rows[0]) if h in ("stable", "unstable_reason")] if f == "summary.csv" else []
        for r in rows[1:]:
            for i in scaled:
                if i < len(r) and r[i] not in ("", "nan"):
                    r[i] = repr(float(r[i]) * factor)
            for i in verdict:
                r[i] = "yes" if rows[0][i] == "stable" else ""
        csv.writer(open(path, "w", newline=""), lineterminator="\n").writerows(rows)
    meta = open(os.path.join(dst, "meta")).read()
    open(os.path.join(dst, "meta"), "w").write(re.sub(r"(?m)^date: .*$", "date: 2026-01-%02dT03:00:00Z" % day, meta))
    return dst


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    src = merged_set()
    ms = {c["name"] for c in csv.DictReader(sb("columns").stdout.splitlines()) if c["unit"] == "ms"}
    wander = random.Random(67)
    nights = [replay(src, "n%d" % (i + 1), wander.uniform(0.98, 1.02) * (1.3 if i >= 6 else 1), i + 1, ms)
              for i in range(9)]
    hist = os.path.join(WORK, "v3.sqlite")
    sb("history", "add", *nights, "--history", hist)
    sb("history", "annotate", "7", "pssm slower on purpose", "--series", "pssm", "--accept", "--history", hist)
    sb("history", "annotate", "2", "a note on night 2", "--history", hist)
    db = sqlite3.connect(hist)
    assert db.execute("PRAGMA user_version").fetchone()[0] == 3
    db.execute("DELETE FROM frames")
    db.execute("DELETE FROM metrics WHERE name NOT IN (%s)" % ",".join("?" * len(KEEP)), sorted(KEEP))
    db.commit()
    db.execute("VACUUM")
    with open(os.path.join(HERE, "history_v3.sql"), "w") as f:
        f.write("-- A history as shadowbench 26f3f92 wrote it at schema version 3 (tests/history/make_v3_fixture.py).\n")
        for line in db.iterdump():
            f.write(line + "\n")
        f.write("PRAGMA user_version = 3;\n")
    db.close()
    # what that shadowbench said of it
    reg = sb("history", "regressions", "--history", hist, "--format", "csv", "--recent", str(RECENT), "--metric",
             ",".join(METRICS), ok=(0, 1))
    text = sb("history", "regressions", "--history", hist, "--recent", str(RECENT), "--metric", ",".join(METRICS),
              ok=(0, 1))
    with open(os.path.join(HERE, "history_v3.expected"), "w") as f:
        f.write("# history regressions --format csv --recent %d --metric %s: exit %d\n" % (RECENT, ",".join(METRICS),
                                                                                         reg.returncode))
        f.write(reg.stdout)
        f.write("# the same as text\n")
        f.write(text.stdout)
        f.write("# the report's data files: sha256 of each, its \"source\" emptied\n")
        site = os.path.join(WORK, "site")
        sb("report", "--history", hist, "--out", site)
        for name, digest in report_digests(site):
            f.write("%s %s\n" % (digest, name))
    print(reg.stdout)
    print(text.stdout, text.stderr)


def report_digests(site):
    """(file, sha256) of each of the report's data files, the history's path (\"source\") left out."""
    out = []
    for name in sorted(os.listdir(os.path.join(site, "data"))):
        text = open(os.path.join(site, "data", name)).read()
        text = re.sub(r'"source":"[^"]*"', '"source":""', text)
        out.append((name, hashlib.sha256(text.encode()).hexdigest()))
    return out


if __name__ == "__main__":
    main()
