#!/usr/bin/env python3
"""The results history on real nights, and its report in a real browser.

Eleven small nights are rendered on llvmpipe. History A is nights 1-5 at the
default thread count, then nights 6-8 with LP_NUM_THREADS=1 on one core that a
three busy loops share: a real, steady slowdown (about 9x) with no hook in the code,
well above the nights' own noise on a shared 2-core machine (which moved a
camera pass by 10-30 % from night to night, more than a 2x step over three
nights can show at the detector's false-alarm rate). History B is the same nights 1-5, then
three more at the default count (rendered interleaved with A's, so the
machine's drift hits both alike). Then:

- `history regressions --noise-floor 30` on A names night 6 for the series whose camera pass
  slowed (final_ms) and finds no change in any error or draw-call metric; it
  exits 1 (a regression in the newest three nights). On B it finds nothing and
  exits 0.
- adding a set twice changes nothing; a history of an older schema is
  migrated; a newer one and broken input are refused in one line.
- the report of A is opened in headless Chromium: every page kind loads with
  no script error, draws its charts, the night's table holds every run, the
  regressions list holds night 6, the images of the night made with --images
  load. A screenshot of each page kind is kept in OUT/report-shots/.

usage: run_history.py SHADOWBENCH SOURCE_ROOT BUILD_ROOT
"""
import csv
import io
import os
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


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def sb(*args, env=None, ok=(0,), prefix=()):
    e = dict(os.environ)
    e.pop("LP_NUM_THREADS", None)
    e.update(env or {})
    p = subprocess.run(list(prefix) + [BIN] + list(args), capture_output=True, text=True, env=e)
    if p.returncode not in ok:
        print(p.stdout, p.stderr)
        raise SystemExit("FAIL: shadowbench %s exited %d" % (" ".join(args), p.returncode))
    return p


def night(name, slow=False, images=False, hogs=1):
    """One night: three shadowed runs on plane-box (not `none`: a 1-ms frame on a shared CPU moves by
    half between nights for reasons of its own), into WORK/name/<stamp>. A slow night renders with one
    llvmpipe thread on core 0, beside `hogs` busy loops on that core (one: about 4.5x slower than a night
    at the default thread count here, two: about 6x, three: about 9x)."""
    args = ["run", "plane-box", "plane-box", "sm", "sm:filter=pcf3", "pssm", "--frames", "24", "--size", "960x540",
            "--error-every", "12", "--quiet", "--out", os.path.join(WORK, name)]
    if images:
        args += ["--images", "12"]
    if not slow:
        return sb(*args).stdout.strip()
    busy = [subprocess.Popen(["taskset", "-c", "0", sys.executable, "-c", "while True: pass"]) for _ in range(hogs)]
    try:
        return sb(*args, env={"LP_NUM_THREADS": "1"}, prefix=["taskset", "-c", "0"]).stdout.strip()
    finally:
        for hog in busy:
            hog.kill()
            hog.wait()


# What a shared 2-core machine does to unchanged code: a camera pass moved by up to 30 % between
# nights a minute apart here (history B found -29 % and -37 % "changes", +25 % on another day, at the
# llvmpipe default of 5 %), and on a CI machine by 39 % (B's nights 1-6 at 6.3 ms, 7-8 at 3.9 ms: a
# "change" at a floor of 15 %). The test says so, as a user of such a machine would: `regressions` runs
# at a floor of 30 % (a sigma of 0.3 in log). Scaling B's figures in place showed what that floor finds:
# a step over the newest three nights of 3.5x in all three series, 3x in two, 2.5x in none; CI's 39 %
# move, none. A's step is about 9x here (one llvmpipe thread beside three busy loops; on the CI machine one
# busy loop gave 3.3x where it gives 4.5x here).
# `history check` judges a set by B's band, which its nights' own spread already widens; it keeps 15 %.
NOISE_FLOOR = "30"
CHECK_FLOOR = "15"


def regressions(hist, *extra):
    p = sb("history", "regressions", "--history", hist, "--format", "csv", "--noise-floor", NOISE_FLOOR, *extra,
           ok=(0, 1))
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
    night("warm-up")   # not kept: the first runs after a build meet a colder machine
    base = [night("n%d" % i) for i in range(1, 6)]
    slow, same = [], []
    for i in range(6, 9):
        slow.append(night("a%d" % i, slow=True, images=(i == 8), hogs=3))
        same.append(night("b%d" % i))
    print("12 nights rendered (one to warm up) in %.0f s" % (time.time() - t0))
    A, B = os.path.join(WORK, "a.sqlite"), os.path.join(WORK, "b.sqlite")
    for d in base + slow:
        sb("history", "add", d, "--history", A)
    sb("history", "add", *(base + same), "--history", B)

    # the same set twice: nothing changes
    db = sqlite3.connect(A)
    before = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    p = sb("history", "add", base[2], "--history", A)
    after = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    check(before == after == 24 and "already in" in p.stderr, "adding a set twice changes nothing (%d runs)" % after)
    nights = [r[0] for r in db.execute("SELECT id FROM nights ORDER BY date, id")]
    db.close()
    sixth = nights[5]

    # the camera pass is the stage LP_NUM_THREADS slows steadily; gpu_ms carries pssm's cascade pass as well,
    # whose time on a shared CPU moves by a third between nights of the same code: its changes are printed,
    # not held to the night
    rc, rows, err = regressions(A, "--metric", "gpu_ms,cascade_ms")
    for r in rows:
        print("  A (not checked): %s %s night %s %s%%" % (r["series"], r["metric"], r["night_after"], r["change_pct"]))
    metrics = "final_ms,err_rate,draw_calls,shadow_draw_calls"
    rc, rows, err = regressions(A, "--metric", metrics)
    print(err.strip())
    for r in rows:
        print("  A: %s %s night %s %s%% %s" % (r["series"], r["metric"], r["night_after"], r["change_pct"], r["verdict"]))
    check(rc == 1, "history A: exit 1 (a regression in the newest nights), got %d" % rc)
    for tech in ("sm:filter=hw", "sm:filter=pcf3", "pssm"):   # as the short names say them
        hit = [r for r in rows if r["metric"] == "final_ms" and r["series"].split()[1] == tech]
        check(len(hit) == 1 and int(hit[0]["night_after"]) == sixth and hit[0]["verdict"].startswith("REGRESSION"),
              "history A: %s final_ms regresses from night 6 (#%d): %s" % (tech, sixth,
              [(h["night_after"], h["change_pct"]) for h in hit]))
    wrong = [r for r in rows if r["metric"] in ("err_rate", "draw_calls", "shadow_draw_calls")]
    check(not wrong, "history A: no change in error or draw-call metrics (%d)" % len(wrong))
    stray = [r for r in rows if int(r["night_after"]) != sixth]
    check(not stray, "history A: every change found starts at night 6 (others: %d)" % len(stray))

    rc, rows, err = regressions(B, "--metric", metrics)
    for r in rows:
        print("  B: %s %s night %s %s%%" % (r["series"], r["metric"], r["night_after"], r["change_pct"]))
    check(rc == 0 and not rows, "history B (no change): no change found, exit 0 (got %d, %d changes)" % (rc, len(rows)))

    # what changed on the machine: history D is A with night 6 run on another driver (its meta says so)
    drv = os.path.join(WORK, "a6-driver")
    shutil.copytree(slow[0], drv)
    meta = open(os.path.join(drv, "meta")).read()
    old_ver = re.search(r"(?m)^gl_version: (.*)$", meta).group(1)
    old_num = re.search(r"[0-9][0-9.]*$", old_ver).group(0)
    new_ver = old_ver[:-len(old_num)] + "23.0.1"
    open(os.path.join(drv, "meta"), "w").write(meta.replace("gl_version: " + old_ver, "gl_version: " + new_ver))
    os.unlink(os.path.join(drv, "manifest"))   # the edited set is read as one from before manifests
    D = os.path.join(WORK, "d.sqlite")
    sb("history", "add", *(base + [drv] + slow[1:]), "--history", D)
    rc, rows, err = regressions(D, "--metric", metrics)
    hit = [r for r in rows if r["metric"] == "final_ms" and int(r["night_after"]) == sixth]
    want = "the driver changed here too: %s → 23.0.1" % old_num
    check(len(hit) == 3 and all(want in r["machine"] for r in hit),
          "history D: each final_ms regression on night 6 says '%s' (%s)" % (want, [r["machine"] for r in hit]))
    p = sb("history", "regressions", "--history", D, "--metric", "final_ms", "--noise-floor", NOISE_FLOOR, ok=(1,))
    check(want in p.stdout, "history D: the text table says it too")
    # annotations: accepting pssm's change leaves sm's; accepting the night leaves none (exit 0)
    p = sb("history", "annotate", str(sixth), "pssm slower on purpose", "--series", "pssm", "--accept", "--history", D)
    rc, rows, err = regressions(D, "--metric", metrics)
    pssm = [r for r in rows if r["series"].split()[1] == "pssm"]
    others = [r for r in rows if r["series"].split()[1] != "pssm"]
    check(rc == 1 and pssm and all(r["verdict"].startswith("accepted") and "on purpose" in r["note"] for r in pssm)
          and others and all(r["verdict"].startswith("REGRESSION") for r in others),
          "history D: pssm's accepted, sm's still regressions, exit 1 (got %d)" % rc)
    sb("history", "annotate", str(sixth), "one llvmpipe thread from here on", "--accept", "--history", D)
    rc, rows, err = regressions(D, "--metric", metrics)
    check(rc == 0 and rows and all(r["verdict"].startswith("accepted") for r in rows) and "accepted" in err,
          "history D: every regression accepted: listed as accepted, exit 0 (got %d: %s)" % (rc, err.strip()))
    commit = re.search(r"(?m)^commit: (.*)$", open(os.path.join(base[0], "meta")).read()).group(1)
    p = sb("history", "annotate", commit[:10], "the first night of this commit", "--history", D)
    check("night %d annotated" % nights[0] in p.stderr, "annotate by commit: its first night (%s)" % p.stderr.strip())
    # the same note again (scripts/bench puts scripts/nightly.notes on every night it runs): kept once
    p = sb("history", "annotate", commit[:10], "the first night of this commit", "--history", D)
    db = sqlite3.connect(D)
    same = db.execute("SELECT count(*) FROM annotations WHERE text = 'the first night of this commit'").fetchone()[0]
    db.close()
    check(same == 1 and "already had this note" in p.stderr, "the same note twice: kept once, said (%d, %s)" %
          (same, p.stderr.strip()))
    p = sb("history", "annotate", "no-such-night", "x", "--history", D, ok=(2,))
    check(len(p.stderr.strip().splitlines()) == 1 and "no-such-night" in p.stderr, "annotate an unknown night: exit 2, one line")
    # a branch against the nights: a slowed set beyond B's band (exit 1), an unchanged one within (exit 0)
    # An unchanged set rendered now: the machine of this minute may be busier than B's nights were (other work on
    # a shared 2-core machine made a set 2x slower here once), so a set beyond the band is rendered again, once,
    # as `--rerun-unstable` does for a disturbed night; unchanged code is within the band on one of the two.
    fresh = night("c9")
    p = sb("history", "check", fresh, "--history", B, "--noise-floor", CHECK_FLOOR, ok=(0, 1))
    print(p.stdout)
    if p.returncode == 1:
        print("the unchanged set was beyond B's band: rendered again once")
        p = sb("history", "check", night("c9b"), "--history", B, "--noise-floor", CHECK_FLOOR, ok=(0, 1))
        print(p.stdout)
    check(p.returncode == 0 and "REGRESSION" not in p.stdout and p.stdout.count("within") >= 12,
          "history check, an unchanged set: every figure within B's band, exit 0 (got %d)" % p.returncode)
    # B's band is median +- 3.9 sigma of its nights' differences: on a CI machine whose nights moved by 45 %
    # (sigma 0.39 in log) it reached 4.9x above the median, so a night 4x slower (slow[2]) fell inside it
    # for two of the three runs. The set checked here is about 10x slower, beyond such a band.
    slower = night("c10", slow=True, hogs=3)
    p = sb("history", "check", slower, "--history", B, "--noise-floor", CHECK_FLOOR, ok=(0, 1))
    print(p.stdout)
    check(p.returncode == 1 and len(re.findall(r"final_ms .* REGRESSION", p.stdout)) == 3,
          "history check, a slowed set: final_ms beyond B's band for all three runs, exit 1 (got %d)" % p.returncode)
    # a note for the report (not accepted): the pssm series' chart draws it
    sb("history", "annotate", str(sixth), "LP_NUM_THREADS=1 from here", "--series", "pssm", "--history", A)

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
    check(v == 3 and kept == 1 and frames == 3, "a version 1 history is migrated to 3, its night kept (v%d, %d, %d frames)"
          % (v, kept, frames))
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
    other = os.path.join(WORK, "other-host")
    shutil.copytree(base[0], other)
    meta = open(os.path.join(other, "meta")).read()
    open(os.path.join(other, "meta"), "w").write(re.sub(r"(?m)^host: .*$", "host: other-machine", meta))
    os.unlink(os.path.join(other, "manifest"))   # edited: read as a set from before manifests
    C = os.path.join(WORK, "c.sqlite")
    sb("history", "add", base[0], other, "--history", C)
    db = sqlite3.connect(C)
    nseries = db.execute("SELECT count(DISTINCT series) FROM runs").fetchone()[0]
    db.close()
    check(nseries == 6, "two machines' nights stay separate series (%d series of 3 runs each)" % nseries)

    part = os.path.join(WORK, "partial")
    shutil.copytree(base[0], part)
    with open(os.path.join(part, "meta"), "a") as f:
        f.write("runs: 9 of 9\n")   # as a batch's meta says: a summary of 3 is a set still running
    os.unlink(os.path.join(part, "manifest"))   # edited: read as a set from before manifests
    p = sb("history", "add", part, "--history", A, ok=(2,))
    check("3 of the 9 runs" in p.stderr and "incomplete" in p.stderr, "an incomplete batch is refused: " + p.stderr.strip())
    p = sb("history", "regressions", "--history", os.path.join(WORK, "none.sqlite"), ok=(2,))
    check("no history here" in p.stderr, "a missing history is said: " + p.stderr.strip())
    p = sb("history", "regressions", "--history", A, "--metric", "gpu_sm", ok=(2,))
    check("unknown metric 'gpu_sm'" in p.stderr, "an unknown metric is said: " + p.stderr.strip())

    # the report in a browser
    site = os.path.join(WORK, "site")
    t1 = time.time()
    sb("report", "--history", A, "--out", site)
    print("report written in %.2f s" % (time.time() - t1))
    shutil.rmtree(SHOTS, ignore_errors=True)
    os.makedirs(SHOTS)
    last = nights[-1]
    db = sqlite3.connect(A)
    run_ids = [r[0] for r in db.execute("SELECT run_id FROM runs WHERE night = ?", (last,))]
    pssm_run = db.execute("SELECT run_id FROM runs WHERE night = ? AND technique = 'pssm'", (last,)).fetchone()[0]
    series = sorted(r[0] for r in db.execute("SELECT DISTINCT series FROM runs"))
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
            check("night.html?n=%d" % sixth in dom and 'class="regression recent"' in dom,
                  "index page: the regressions list links night 6 (#%d) and marks it recent" % sixth)
        if kind == "run":
            check(int(a.get("images-loaded", "0")) >= 5, "run page: the evaluated frames' images loaded (%s)" % a.get("images-loaded"))
        if kind == "series":
            check("night.html?n=%d" % sixth in dom, "series page: its change links night 6")
            check(int(a.get("notes-drawn", "0")) >= 5 and "LP_NUM_THREADS=1 from here" in dom,
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
    # layered against per-cascade: the pairs table shows the parameters that differ, not each run's all
    lay = sb("run", "plane-box", "plane-box", "pssm:layered=off,gs:cascades=2,4", "--frames", "3", "--size", "320x180",
             "--quiet", "--out", os.path.join(WORK, "layered")).stdout.strip()
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
