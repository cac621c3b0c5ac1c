#!/usr/bin/env python3
"""The results history on replayed nights, and its report in a real browser.

One night is rendered on llvmpipe (plane-box, three shadowed runs, with --images); every other night is that
set replayed: its timing columns (every column whose unit is ms, in summary.csv and the per-frame CSVs)
scaled by a known factor, its date set, its manifest dropped (read as a set from before manifests). The
statistics are pure functions of numbers, so their verdicts here are exact; what a busy machine does to a
live render cannot reach them (they were tested on live slowdowns before: beside busy loops, and CI
machines whose unchanged nights moved by 39 % and 45 % failed them).

- History A: ten nights whose timings wander by a seeded 0.9-1.1x, then four more at 1.3x that (a 1.3x
  step). History B: fourteen nights of the wander alone. `history regressions` (its default noise floor)
  names night 11 for each run's final_ms and gpu_ms on A, finds no change in any error or draw-call
  metric and nothing on B. The wander alone at 10+4 nights is where the detector's power for a 1.3x step
  begins (over 5+3 nights it is not found: said in docs/history.md).
- `history check` by B's band: the night replayed at 1.0x is within it for every figure, at 3x beyond it
  for every run's final_ms.
- history D is A with night 11 on another driver (its meta says so), annotated and accepted; a note by a commit
  the history's first night already ran is not put with --restart (scripts/bench's notes), and is where a
  night before ran without it.
- adding a set twice changes nothing; a history of an older schema is migrated (version 1; version 3 as 26f3f92
  wrote it, to the same regressions and report data: history_v3.sql); a newer one and broken
  input are refused in one line.
- the report of A is opened in headless Chromium: every page kind loads with no script error, draws its
  charts, the night's table holds every run, the regressions list holds night 11, the images of the
  rendered night load. A screenshot of each page kind is kept in OUT/report-shots/.

usage: run_history.py SHADOWBENCH SOURCE_ROOT BUILD_ROOT
"""
import csv
import hashlib
import io
import os
import random
import re
import shutil
import sqlite3
import subprocess
import sys
import time

BIN, SRC, BUILD = sys.argv[1:4]
WORK = os.path.join(BUILD, "test-history")
SHOTS = os.path.join(BUILD, "report-shots")
failures = []
BEFORE, AFTER, STEP = 10, 4, 1.3   # A: ten nights, then four at 1.3x
WANDER = random.Random(54)          # the nights' own wander, seeded: 0.9-1.1x


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def sb(*args, ok=(0,)):
    p = subprocess.run([BIN] + list(args), capture_output=True, text=True)
    if p.returncode not in ok:
        print(p.stdout, p.stderr)
        raise SystemExit("FAIL: shadowbench %s exited %d" % (" ".join(args), p.returncode))
    return p


def render(name, images=False):
    """The one rendered night: three shadowed runs on plane-box, into WORK/name/<stamp>."""
    args = ["run", "plane-box", "plane-box", "sm", "sm:filter=pcf3", "pssm", "--frames", "24", "--size", "480x270",
            "--error-every", "12", "--quiet", "--out", os.path.join(WORK, name)]
    if images:
        args += ["--images", "12"]
    return sb(*args).stdout.strip()


_timing = None


def timing_column(name):
    """Whether a CSV column is a timing: a column of unit ms, or one of its statistics (final_ms_median)."""
    global _timing
    if _timing is None:
        cols = csv.DictReader(io.StringIO(sb("columns").stdout))
        _timing = {c["name"] for c in cols if c["unit"] == "ms"}
    base, _, stat = name.rpartition("_")
    return name in _timing or (stat in ("mean", "median", "p95", "p99", "std", "ci95", "min", "max") and base in _timing)


def replay(src, name, factor, day):
    """The set src again as night `day` (a date of its own), every timing scaled by factor; its manifest
    dropped (an edited set reads as one from before manifests)."""
    dst = os.path.join(WORK, name)
    shutil.copytree(src, dst)
    for f in os.listdir(dst):
        if not f.endswith(".csv"):
            continue
        path = os.path.join(dst, f)
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        scaled = [i for i, h in enumerate(rows[0]) if timing_column(h)]
        # the stability verdict is the test's to give: every replayed night stable (the live night's verdict is
        # the machine's mood, and an unstable night weighs a quarter in the detector: seen, a rendered night
        # flagged beside a build, and the 1.3x step not found on A)
        verdict = [i for i, h in enumerate(rows[0]) if h in ("stable", "unstable_reason")] if f == "summary.csv" else []
        for r in rows[1:]:
            for i in scaled:
                if r[i] not in ("", "nan"):
                    r[i] = repr(float(r[i]) * factor)
            for i in verdict:
                r[i] = "yes" if rows[0][i] == "stable" else ""
        with open(path, "w", newline="") as fh:
            csv.writer(fh, lineterminator="\n").writerows(rows)
    meta = open(os.path.join(dst, "meta")).read()
    open(os.path.join(dst, "meta"), "w").write(re.sub(r"(?m)^date: .*$", "date: 2026-01-%02dT03:00:00Z" % day, meta))
    os.unlink(os.path.join(dst, "manifest"))
    return dst


SERIES_COLS = "host, renderer, scene, path, size, technique, params, light, anim, indirect, run_options"


def series_key(r):
    """A series' key text from its columns (SERIES_COLS), as shadowbench joins it (series.h)."""
    host, renderer, scene, path, size, tech, params, light, anim, indirect, run_options = r
    return "|".join([host, renderer, scene, path, size, tech, params]) + ("|" + light if light else "") + \
        ("|anim=" + anim if anim else "") + ("|indirect" if indirect else "") + ("|" + run_options if run_options else "")


def report_digests(site):
    """(file, sha256) of each of the report's data files, the history's path ("source") left out."""
    out = []
    for name in sorted(os.listdir(os.path.join(site, "data"))):
        text = re.sub(r'"source":"[^"]*"', '"source":""', open(os.path.join(site, "data", name)).read())
        out.append((name, hashlib.sha256(text.encode()).hexdigest()))
    return out


def schema_3():
    """A history as 26f3f92 wrote it (schema 3: a run's series one joined text; tests/history/make_v3_fixture.py)
    is migrated by a write that changes nothing (a note it already has) to typed series columns: each run's
    columns join back to its old text, and its regressions (CSV and text) and its report's data are what 26f3f92
    said of it (history_v3.expected)."""
    old = os.path.join(WORK, "v3.sqlite")
    db = sqlite3.connect(old)
    db.executescript(open(os.path.join(SRC, "tests", "history", "history_v3.sql")).read())
    db.commit()
    before = {r[0]: r[1] for r in db.execute("SELECT id, series FROM runs")}
    db.close()
    p = sb("history", "annotate", "2", "a note on night 2", "--history", old)
    db = sqlite3.connect(old)
    v = db.execute("PRAGMA user_version").fetchone()[0]
    cols = [r[1] for r in db.execute("PRAGMA table_info(runs)")]
    after = {r[0]: series_key(r[1:]) for r in db.execute("SELECT id, %s FROM runs" % SERIES_COLS)}
    notes = db.execute("SELECT count(*) FROM annotations").fetchone()[0]
    db.close()
    check(v == 5 and "series" not in cols and "run_options" in cols and "already had this note" in p.stderr and notes == 2,
          "a version 3 history is migrated to 5: no joined series column, its notes kept (v%d, %d notes)" % (v, notes))
    check(len(before) == 54 and before == after, "each of its %d runs' series columns join back to its old text (%d "
          "differ)" % (len(before), sum(before[k] != after.get(k) for k in before)))
    exp = open(os.path.join(SRC, "tests", "history", "history_v3.expected")).read()
    head, rest = exp.split("\n", 1)
    want_csv, rest = rest.split("# the same as text\n")
    want_text, want_report = rest.split("# the report's data files: sha256 of each, its \"source\" emptied\n")
    metrics = re.search(r"--metric ([^:\s]+)", head).group(1)
    args = ["history", "regressions", "--history", old, "--recent", "3", "--metric", metrics]
    got_csv = sb(*args, "--format", "csv", ok=(0, 1))
    got_text = sb(*args, ok=(0, 1))
    check(got_csv.stdout == want_csv and "exit %d" % got_csv.returncode in head and "note: pssm slower" in want_text,
          "its regressions as CSV are 26f3f92's, the accepted note too (exit %d)" % got_csv.returncode)
    check(got_text.stdout == want_text, "its regressions as text are 26f3f92's")
    site = os.path.join(WORK, "site-v3")
    sb("report", "--history", old, "--out", site)
    got = "".join("%s %s\n" % (d, n) for n, d in report_digests(site))
    check(got == want_report and want_report.count("series-") == 6, "its report's %d data files are 26f3f92's (%d "
          "differ)" % (len(want_report.splitlines()), len(set(got.splitlines()) ^ set(want_report.splitlines())) // 2))
    schema_3_damaged()


def schema_3_damaged():
    """The same history with a scene named "plane|box" (its joined text then splits one field early), one run whose
    summary line is gone and one whose line is garbage, opened by a read verb: migrated in place from each row's
    own summary line (a backup beside it), the named scene kept whole, each unreadable run left out with a line
    that names it (they migrated without a word, shifting the figures; the read verbs refused the file)."""
    old = os.path.join(WORK, "v3-damaged.sqlite")
    db = sqlite3.connect(old)
    db.executescript(open(os.path.join(SRC, "tests", "history", "history_v3.sql")).read())
    ids = [r[0] for r in db.execute("SELECT id FROM runs WHERE scene = 'plane-box' ORDER BY id")]
    named, gone, garbage = ids[0], ids[1], ids[2]
    line = db.execute("SELECT line FROM runs WHERE id = ?", (named,)).fetchone()[0]
    fields = next(csv.reader([line]))
    header = next(csv.reader([db.execute("SELECT n.header FROM runs r JOIN nights n ON n.id = r.night WHERE r.id = ?",
                                         (named,)).fetchone()[0]]))
    fields[header.index("scene")] = "plane|box"
    out = io.StringIO()
    csv.writer(out, lineterminator="").writerow(fields)
    db.execute("UPDATE runs SET scene = 'plane|box', line = ?, series = replace(series, '|plane-box|plane-box|', "
               "'|plane|box|plane-box|') WHERE id = ?", (out.getvalue(), named))
    db.execute("UPDATE runs SET line = NULL WHERE id = ?", (gone,))
    db.execute("UPDATE runs SET line = 'garbage' WHERE id = ?", (garbage,))
    gone_id, garbage_id = [db.execute("SELECT run_id FROM runs WHERE id = ?", (i,)).fetchone()[0] for i in (gone, garbage)]
    total = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    db.commit()
    db.close()
    p = sb("history", "regressions", "--history", old, "--recent", "3", ok=(0, 1))
    backup = old + ".schema-3.bak"
    db = sqlite3.connect(old)
    v = db.execute("PRAGMA user_version").fetchone()[0]
    row = db.execute("SELECT scene, path, technique FROM runs WHERE id = ?", (named,)).fetchone()
    left = db.execute("SELECT count(*) FROM runs WHERE id IN (?, ?)", (gone, garbage)).fetchone()[0]
    now = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    db.close()
    check(v == 5 and os.path.exists(backup) and "migrated to 5" in p.stderr,
          "a version 3 history opened by a read verb is migrated in place, its backup beside it (v%d, %s)" %
          (v, p.stderr.strip().splitlines()[:1]))
    check(row is not None and row[0] == "plane|box" and row[1] == "plane-box" and row[2] == line.split(",")[4],
          "a scene named plane|box migrates as its own row says: scene, path, technique (%s)" % (row,))
    check(left == 0 and now == total - 2 and gone_id in p.stderr and garbage_id in p.stderr and
          p.stderr.count("left out of the migrated history") == 2,
          "the two unreadable runs are left out, each named in a line (%d left of %d; %s)" % (now, total, p.stderr.strip()))
    bk = sqlite3.connect(backup)
    check(bk.execute("PRAGMA user_version").fetchone()[0] == 3 and
          bk.execute("SELECT count(*) FROM runs").fetchone()[0] == total, "the backup is the file as it was")
    bk.close()


def regressions(hist, *extra):
    p = sb("history", "regressions", "--history", hist, "--format", "csv", "--recent", str(AFTER), *extra, ok=(0, 1))
    return p.returncode, list(csv.DictReader(io.StringIO(p.stdout))), p.stderr


def chromium(url, shot=None):
    cmd = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
           "--virtual-time-budget=10000", "--window-size=1300,1100", "--enable-logging=stderr", "--v=0"]
    cmd += ["--screenshot=" + shot] if shot else ["--dump-dom"]
    p = subprocess.run(cmd + [url], capture_output=True, text=True, timeout=120)
    console = [l for l in p.stderr.splitlines() if "CONSOLE" in l and ("ERROR" in l or "Uncaught" in l)]
    return p.stdout, console


def body_attrs(dom):
    m = re.search(r"<body([^>]*)>", dom)
    return dict(re.findall(r'data-([a-z-]+)="([^"]*)"', m.group(1))) if m else {}


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    t0 = time.time()
    rendered = render("rendered", images=True)
    lay = sb("run", "plane-box", "plane-box", "pssm:layered=off,gs:cascades=2,4", "--frames", "3", "--size", "320x180",
             "--quiet", "--out", os.path.join(WORK, "layered")).stdout.strip()
    print("2 sets rendered in %.0f s" % (time.time() - t0))
    wander = [WANDER.uniform(0.9, 1.1) for _ in range(BEFORE + AFTER)]
    n = BEFORE + AFTER
    base = [replay(rendered, "n%d" % (i + 1), wander[i], i + 1) for i in range(BEFORE)]
    slow = [replay(rendered, "a%d" % (i + 1), wander[i] * STEP, i + 1) for i in range(BEFORE, n)]
    same = [replay(rendered, "b%d" % (i + 1), wander[i], i + 1) for i in range(BEFORE, n)]
    A, B = os.path.join(WORK, "a.sqlite"), os.path.join(WORK, "b.sqlite")
    sb("history", "add", *(base + slow), "--history", A)
    sb("history", "add", *(base + same), "--history", B)

    # the same set twice: nothing changes
    db = sqlite3.connect(A)
    before = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    p = sb("history", "add", base[2], "--history", A)
    after = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    check(before == after == 3 * n and "already in" in p.stderr, "adding a set twice changes nothing (%d runs)" % after)
    nights = [r[0] for r in db.execute("SELECT id FROM nights ORDER BY date, id")]
    db.close()
    step = nights[BEFORE]   # the first night at 1.3x

    metrics = "final_ms,gpu_ms,cascade_ms,err_rate,draw_calls,shadow_draw_calls"
    rc, rows, err = regressions(A, "--metric", metrics)
    print(err.strip())
    for r in rows:
        print("  A: %s %s night %s %s%% %s" % (r["series"], r["metric"], r["night_after"], r["change_pct"], r["verdict"]))
    check(rc == 1, "history A: exit 1 (a regression in the newest %d nights), got %d" % (AFTER, rc))
    for tech in ("sm:filter=hw", "sm:filter=pcf3", "pssm"):   # as the short names say them
        for metric in ("final_ms", "gpu_ms"):
            hit = [r for r in rows if r["metric"] == metric and r["series"].split()[1] == tech]
            check(len(hit) == 1 and int(hit[0]["night_after"]) == step and hit[0]["verdict"].startswith("REGRESSION")
                  and abs(float(hit[0]["change_pct"]) - 100 * (STEP - 1)) < 12,
                  "history A: %s %s regresses by about 30 %% from night %d (#%d): %s" % (
                      tech, metric, BEFORE + 1, step, [(h["night_after"], h["change_pct"]) for h in hit]))
    wrong = [r for r in rows if r["metric"] in ("err_rate", "draw_calls", "shadow_draw_calls")]
    check(not wrong, "history A: no change in error or draw-call metrics (%d)" % len(wrong))
    stray = [r for r in rows if int(r["night_after"]) != step]
    check(not stray, "history A: every change found starts at night %d (others: %d)" % (BEFORE + 1, len(stray)))

    rc, rows, err = regressions(B, "--metric", metrics)
    for r in rows:
        print("  B: %s %s night %s %s%%" % (r["series"], r["metric"], r["night_after"], r["change_pct"]))
    check(rc == 0 and not rows, "history B (a 0.9-1.1x wander): no change found, exit 0 (got %d, %d changes)" %
          (rc, len(rows)))

    # what changed on the machine: history D is A with night 11 run on another driver (its meta says so)
    drv = os.path.join(WORK, "a-driver")
    shutil.copytree(slow[0], drv)
    meta = open(os.path.join(drv, "meta")).read()
    old_ver = re.search(r"(?m)^gl_version: (.*)$", meta).group(1)
    old_num = re.search(r"[0-9][0-9.]*$", old_ver).group(0)
    new_ver = old_ver[:-len(old_num)] + "23.0.1"
    open(os.path.join(drv, "meta"), "w").write(meta.replace("gl_version: " + old_ver, "gl_version: " + new_ver))
    D = os.path.join(WORK, "d.sqlite")
    sb("history", "add", *(base + [drv] + slow[1:]), "--history", D)
    rc, rows, err = regressions(D, "--metric", metrics)
    hit = [r for r in rows if r["metric"] == "final_ms" and int(r["night_after"]) == step]
    want = "the driver changed here too: %s → 23.0.1" % old_num
    check(len(hit) == 3 and all(want in r["machine"] for r in hit),
          "history D: each final_ms regression on night %d says '%s' (%s)" % (BEFORE + 1, want,
                                                                          [r["machine"] for r in hit]))
    p = sb("history", "regressions", "--history", D, "--metric", "final_ms", "--recent", str(AFTER), ok=(1,))
    check(want in p.stdout, "history D: the text table says it too")
    # annotations: accepting pssm's change leaves sm's; accepting the night leaves none (exit 0)
    p = sb("history", "annotate", str(step), "pssm slower on purpose", "--series", "pssm", "--accept", "--history", D)
    db = sqlite3.connect(D)
    filed, ran = db.execute("SELECT a.git_commit, n.git_commit FROM annotations a JOIN nights n ON n.id = a.night "
                            "WHERE a.text = 'pssm slower on purpose'").fetchone()
    db.close()
    check(filed == ran and len(ran) >= 7, "a note by night number is filed under that night's commit (%s, ran %s)" %
          (filed, ran))
    rc, rows, err = regressions(D, "--metric", metrics)
    pssm = [r for r in rows if r["series"].split()[1] == "pssm"]
    others = [r for r in rows if r["series"].split()[1] != "pssm"]
    check(rc == 1 and pssm and all(r["verdict"].startswith("accepted") and "on purpose" in r["note"] for r in pssm)
          and others and all(r["verdict"].startswith("REGRESSION") for r in others),
          "history D: pssm's accepted, sm's still regressions, exit 1 (got %d)" % rc)
    sb("history", "annotate", str(step), "slower from here on", "--accept", "--history", D)
    rc, rows, err = regressions(D, "--metric", metrics)
    check(rc == 0 and rows and all(r["verdict"].startswith("accepted") for r in rows) and "accepted" in err,
          "history D: every regression accepted: listed as accepted, exit 0 (got %d: %s)" % (rc, err.strip()))
    commit = re.search(r"(?m)^commit: (.*)$", open(os.path.join(base[0], "meta")).read()).group(1)
    p = sb("history", "annotate", commit[:10], "the first night of this commit", "--history", D)
    check("night %d annotated" % nights[0] in p.stderr, "annotate by commit: its first night (%s)" % p.stderr.strip())
    # the same note again (scripts/bench puts scripts/nightly.notes on every night it runs): kept once
    p = sb("history", "annotate", commit[:10], "the first night of this commit", "--history", D)
    db = sqlite3.connect(D)
    same_note = db.execute("SELECT count(*) FROM annotations WHERE text = 'the first night of this commit'").fetchone()[0]
    db.close()
    check(same_note == 1 and "already had this note" in p.stderr, "the same note twice: kept once, said (%d, %s)" %
          (same_note, p.stderr.strip()))
    # --restart (scripts/bench's notes of the project's own changes): a change the history's first night already
    # ran restarts none of its series (a new user's night 1 showed six such notes): nothing noted, exit 0; where a
    # night before ran without it, noted on the first night that ran it
    p = sb("history", "annotate", commit[:10], "a change older than the history", "--restart", "--history", D)
    db = sqlite3.connect(D)
    older = db.execute("SELECT count(*) FROM annotations WHERE text = 'a change older than the history'").fetchone()[0]
    db.close()
    check(older == 0 and "already ran it" in p.stderr and "nothing noted" in p.stderr,
          "annotate --restart, a commit of the first night: nothing noted (%d, %s)" % (older, p.stderr.strip()))
    R = os.path.join(WORK, "restart.sqlite")
    for k, (name, sha) in enumerate([("r-before", "0" * 40), ("r-after", commit)]):
        night = replay(rendered, name, 1.0 + k / 100, 20 + k)   # another set each (a set is added once)
        meta = open(os.path.join(night, "meta")).read()
        open(os.path.join(night, "meta"), "w").write(re.sub(r"(?m)^commit: .*$", "commit: " + sha, meta))
        sb("history", "add", night, "--history", R)
    p = sb("history", "annotate", commit[:10], "restarts here", "--restart", "--history", R)
    check("night 2 annotated" in p.stderr, "annotate --restart: noted on the night that first ran it (%s)" %
          p.stderr.strip())
    # a note is the user's text: a terminal escape or a newline in it is shown as \xNN, never obeyed, in text and CSV
    E = os.path.join(WORK, "escaped.sqlite")
    shutil.copy(D, E)
    sb("history", "annotate", str(step), "red\x1b[31m here\nsecond line", "--series", "pssm", "--history", E)
    for fmt in ("text", "csv"):
        p = sb("history", "regressions", "--history", E, "--metric", "final_ms", "--recent", str(AFTER), "--format", fmt,
               ok=(0, 1))
        check("\x1b" not in p.stdout and "red\\x1b[31m here\\x0asecond line" in p.stdout,
              "history regressions (%s): a note's escape and newline shown as \\xNN" % fmt)
    p = sb("history", "annotate", "no-such-night", "x", "--history", D, ok=(2,))
    check(len(p.stderr.strip().splitlines()) == 1 and "no-such-night" in p.stderr, "annotate an unknown night: exit 2, one line")
    # a branch against the nights: the rendered night as it was (1.0x) within B's band for every figure (exit 0),
    # and at 3x beyond it for every run's final_ms (exit 1)
    p = sb("history", "check", replay(rendered, "c1", 1.0, 28), "--history", B, ok=(0, 1))
    print(p.stdout)
    check(p.returncode == 0 and "REGRESSION" not in p.stdout and p.stdout.count("within") >= 12,
          "history check, an unchanged set: every figure within B's band, exit 0 (got %d)" % p.returncode)
    p = sb("history", "check", replay(rendered, "c3", 3.0, 28), "--history", B, ok=(0, 1))
    print(p.stdout)
    check(p.returncode == 1 and len(re.findall(r"final_ms .* REGRESSION", p.stdout)) == 3,
          "history check, a set at 3x: final_ms beyond B's band for all three runs, exit 1 (got %d)" % p.returncode)
    # a note for the report (not accepted): the pssm series' chart draws it
    sb("history", "annotate", str(step), "1.3x from here", "--series", "pssm", "--history", A)

    # schema: an older file is migrated forward, a newer one refused
    old = os.path.join(WORK, "v1.sqlite")
    db = sqlite3.connect(old)
    db.executescript(open(os.path.join(SRC, "tests", "history", "schema_v1.sql")).read())
    db.commit()
    db.close()
    sb("history", "add", base[0], "--history", old)
    db = sqlite3.connect(old)
    v = db.execute("PRAGMA user_version").fetchone()[0]
    kept = db.execute("SELECT count(*) FROM nights WHERE set_key = 'v1-night'").fetchone()[0]
    frames = db.execute("SELECT count(*) FROM frames").fetchone()[0]
    db.close()
    check(v == 5 and kept == 1 and frames == 3, "a version 1 history is migrated to 5, its night kept (v%d, %d, %d frames)"
          % (v, kept, frames))
    schema_3()
    newer = os.path.join(WORK, "v99.sqlite")
    db = sqlite3.connect(newer)
    db.execute("PRAGMA user_version = 99")
    db.close()
    p = sb("history", "add", base[0], "--history", newer, ok=(2,))   # an unreadable history: bad input
    check("newer than this shadowbench" in p.stderr and len(p.stderr.strip().splitlines()) == 1,
          "a newer history is refused in one line: " + p.stderr.strip())
    p = sb("history", "add", os.path.join(WORK, "nowhere"), "--history", A, ok=(2,))   # not a results set: bad input
    check("nowhere/summary.csv" in p.stderr, "a folder with no summary is named: " + p.stderr.strip())
    # another machine's night is a series of its own
    other = os.path.join(WORK, "other-host")   # (a replayed set: read as one from before manifests)
    shutil.copytree(base[0], other)
    meta = open(os.path.join(other, "meta")).read()
    open(os.path.join(other, "meta"), "w").write(re.sub(r"(?m)^host: .*$", "host: other-machine", meta))
    C = os.path.join(WORK, "c.sqlite")
    sb("history", "add", base[0], other, "--history", C)
    db = sqlite3.connect(C)
    nseries = db.execute("SELECT count(*) FROM (SELECT DISTINCT %s FROM runs)" % SERIES_COLS).fetchone()[0]
    db.close()
    check(nseries == 6, "two machines' nights stay separate series (%d series of 3 runs each)" % nseries)
    # a night with an identity option of no column of its own (--sun given) is a series of its own too
    sun = os.path.join(WORK, "sun-given")
    shutil.copytree(base[0], sun)
    with open(os.path.join(sun, "summary.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["run_options"] = "--sun 30,45"
    with open(os.path.join(sun, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    D = os.path.join(WORK, "d.sqlite")
    sb("history", "add", base[0], sun, "--history", D)
    db = sqlite3.connect(D)
    keys = sorted(series_key(r) for r in db.execute("SELECT DISTINCT %s FROM runs" % SERIES_COLS))
    db.close()
    check(len(keys) == 6 and sum(k.endswith("|--sun 30,45") for k in keys) == 3,
          "a night with --sun given keeps series of its own (%d series, %d with it)"
          % (len(keys), sum(k.endswith("|--sun 30,45") for k in keys)))

    part = os.path.join(WORK, "partial")
    shutil.copytree(base[0], part)
    with open(os.path.join(part, "meta"), "a") as f:
        f.write("runs: 9 of 9\n")   # as a batch's meta says: a summary of 3 is a set still running
    p = sb("history", "add", part, "--history", A, ok=(2,))
    check("3 of the 9 runs" in p.stderr and "incomplete" in p.stderr, "an incomplete batch is refused: " + p.stderr.strip())
    p = sb("history", "regressions", "--history", os.path.join(WORK, "none.sqlite"), ok=(2,))
    check("no history here" in p.stderr, "a missing history is said: " + p.stderr.strip())
    p = sb("history", "regressions", "--history", A, "--metric", "gpu_sm", ok=(2,))
    check("unknown metric 'gpu_sm'" in p.stderr, "an unknown metric is said: " + p.stderr.strip())

    # the report in a browser
    site = os.path.join(WORK, "site")
    t1 = time.time()
    sb("report", "--history", A, "--out", site, "--recent", str(AFTER))
    print("report written in %.2f s" % (time.time() - t1))
    shutil.rmtree(SHOTS, ignore_errors=True)
    os.makedirs(SHOTS)
    last = nights[-1]
    db = sqlite3.connect(A)
    run_ids = [r[0] for r in db.execute("SELECT run_id FROM runs WHERE night = ?", (last,))]
    pssm_run = db.execute("SELECT run_id FROM runs WHERE night = ? AND technique = 'pssm'", (last,)).fetchone()[0]
    series = sorted(series_key(r) for r in db.execute("SELECT DISTINCT %s FROM runs" % SERIES_COLS))
    db.close()
    pssm_series = [i for i, s in enumerate(series) if "|pssm|" in s][0]   # sorted as the report numbers them
    pages = {
        "index": "index.html",
        "night": "night.html?n=%d" % last,
        "run": "run.html?n=%d&r=%s" % (last, pssm_run),
        "series": "series.html?s=%d" % pssm_series,
    }
    for kind, page in pages.items():
        url = "file://" + os.path.abspath(os.path.join(site, page))
        dom, console = chromium(url)
        a = body_attrs(dom)
        check(a.get("ready") == "yes" and a.get("errors") == "0" and not console,
              "%s page: drawn with no script error (%s %s)" % (kind, a.get("error-text", ""), console[:2]))
        want_charts = {"index": 0, "night": 1, "run": 3, "series": 5}[kind]
        check(int(a.get("charts", "0")) >= want_charts, "%s page: %s chart(s) drawn (>= %d)" % (kind, a.get("charts"), want_charts))
        if kind == "night":
            missing = [r for r in run_ids if r not in dom]
            check(not missing and len(run_ids) == 3, "night page: every run in the table (%d, missing %s)" % (len(run_ids), missing))
        if kind == "index":
            check("night.html?n=%d" % step in dom and 'class="regression recent"' in dom,
                  "index page: the regressions list links night %d (#%d) and marks it recent" % (BEFORE + 1, step))
        if kind == "run":
            check(int(a.get("images-loaded", "0")) >= 5, "run page: the evaluated frames' images loaded (%s)" % a.get("images-loaded"))
        if kind == "series":
            check("night.html?n=%d" % step in dom, "series page: its change links night %d" % (BEFORE + 1))
            check(int(a.get("notes-drawn", "0")) >= 5 and "1.3x from here" in dom,
                  "series page: the annotation drawn on its charts (%s) and listed" % a.get("notes-drawn"))
        if kind == "night":
            check(0 < float(a.get("max-row-lines", "99")) <= 2.05,
                  "night page: no table row taller than two lines (%s)" % a.get("max-row-lines"))
        chromium(url, shot=os.path.join(SHOTS, kind + ".png"))
    # a memory budget on the night's fronts: pssm's four 2048² cascades (64 MiB) are over 20, both sm runs (16) within
    url = "file://" + os.path.abspath(os.path.join(site, pages["night"] + "&budget=20"))
    dom, console = chromium(url)
    fronts = dom[dom.find('id="fronts"'):]
    check("1 run(s) over 20 MiB left out" in fronts and "pssm:" not in fronts and "sm:" in fronts and not console,
          "night page, budget 20 MiB: pssm (64 MiB) left out of the fronts, sm (16) drawn")
    chromium(url, shot=os.path.join(SHOTS, "night-budget.png"))
    # layered against per-cascade (the set rendered at the start): the pairs table shows the parameters that
    # differ, not each run's all
    lsite = os.path.join(WORK, "site-layered")
    sb("report", lay, "--out", lsite)
    url = "file://" + os.path.abspath(os.path.join(lsite, "night.html?n=1"))
    dom, console = chromium(url)
    a = body_attrs(dom)
    pairs = dom[dom.find('id="pairs"'):]
    cells = re.findall(r"<td[^>]*>(.*?)</td>", pairs)
    params = [re.sub(r"<[^>]+>", "", c) for c in cells if "=" in c]
    check(a.get("ready") == "yes" and not console and params and all(len(c) <= len("cascades=2") for c in params)
          and not any("depth=32f" in c for c in cells), "layered pairs: parameter cells only what differs (%s)" % sorted(set(params))[:4])
    check(0 < float(a.get("max-row-lines", "99")) <= 2.05, "layered night: rows of one line (%s)" % a.get("max-row-lines"))
    chromium(url, shot=os.path.join(SHOTS, "night-layered.png"))
    print("screenshots in " + SHOTS)
    if failures:
        print("%d check(s) failed" % len(failures))
        return 1
    print("all checks passed in %.0f s" % (time.time() - t0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
