#!/usr/bin/env python3
"""Ctrl-C and SIGTERM during a batch: an orderly stop, then a resume.

A small batch (three runs on towers, error evaluated) is stopped by SIGINT at
a random moment, 6 times (the last two by SIGTERM), each time resumed into
the same folder with `batch --resume`. After every stop:
  - the exit status is 130 (SIGINT) or 143 (SIGTERM), or 0 when the signal
    came after the batch's last frame;
  - no temporary file is left and every per-frame CSV named in the summary is
    whole (its header, one row a frame);
  - the summary's rows are the completed runs, `ok`, plus at most one
    `interrupted` run with its reason.
At the end the resumed set's rows equal a batch that was never stopped
(timings aside). A second SIGINT a moment after the first ends the process at
once (within 2 s, by the signal). `run` stops the same way and `run
--resume DIR` completes its folder; so does `tune` with its `--resume DIR`.
`stress` stops between its rows, keeping them, and removes its scenes.
Every long command of the suite's kinds (run, batch, tune, score, info and
run with a scene-cache entry that is a FIFO, history add on a FIFO) exits
within 5 s of a SIGTERM.

usage: interrupt.py SHADOWBENCH BUILD_ROOT
"""
import csv
import glob
import os
import random
import shutil
import signal
import struct
import subprocess
import sys
import time
import zlib

BIN, BUILD = sys.argv[1:3]
WORK = os.path.join(BUILD, "test-interrupt")
failures = []
TRIES = 6   # stops of the batch, the last two by SIGTERM


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def rows(dir_):
    with open(os.path.join(dir_, "summary.csv")) as f:
        return list(csv.DictReader(f))


def whole(dir_):
    """Problems with the folder's files: temporaries left, per-frame files not whole."""
    bad = [os.path.basename(p) for p in glob.glob(os.path.join(dir_, "**", "*.tmp"), recursive=True)]
    for r in rows(dir_) if os.path.exists(os.path.join(dir_, "summary.csv")) else []:
        if r["status"] != "ok":
            continue
        p = os.path.join(dir_, r["run_id"] + ".csv")
        if not os.path.exists(p):
            bad.append(r["run_id"] + ".csv missing")
            continue
        with open(p) as f:
            lines = f.read().splitlines()
        if len(lines) != 1 + int(r["frames"]) * int(r["repeats"] or 1):
            bad.append("%s.csv has %d lines" % (r["run_id"], len(lines)))
    return bad


def stopped(cmd, after, sig=signal.SIGINT, env=None):
    """Runs cmd, sends it sig `after` seconds in, and waits: (exit status, stdout, stderr)."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    time.sleep(after)
    p.send_signal(sig)
    so, se = p.communicate(timeout=120)
    return p.returncode, so, se


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    bench = os.path.join(WORK, "small.bench")
    with open(bench, "w") as f:
        f.write("scene towers towers\npath towers towers\n"
                "defaults --frames 10 --warmup 1 --error-every 5 --size 320x180\n"
                "sm:res=512\npssm:res=512\nsdsm:res=512\n")   # small maps: a stop is a stop at any size
    t0 = time.time()
    clean = subprocess.run([BIN, "batch", bench, "--out", os.path.join(WORK, "clean"), "--quiet"],
                           capture_output=True, text=True, check=True).stdout.strip().splitlines()[-1]
    whole_s = time.time() - t0
    print("the whole batch: %.1f s" % whole_s)
    rng = random.Random(28)
    out = os.path.join(WORK, "stopped")
    dir_ = None
    stops = 0
    for k in range(TRIES):
        sig = signal.SIGTERM if k >= TRIES - 2 else signal.SIGINT
        cmd = [BIN, "batch", bench, "--quiet"] + (["--resume", dir_] if dir_ else ["--out", out])
        got, so, se = stopped(cmd, rng.uniform(0.05, whole_s * 0.5), sig)
        if dir_ is None:
            dir_ = so.strip().splitlines()[-1] if so.strip() else sorted(glob.glob(os.path.join(out, "*", "*")))[-1]
        want = 128 + sig
        st = [r["status"] for r in rows(dir_)] if os.path.exists(os.path.join(dir_, "summary.csv")) else []
        stops += got == want
        check(got in (want, 0), "try %2d: %s -> exit %d (%s), rows %s" % (k + 1, sig.name, got,
                                                                         "stopped" if got == want else "had ended", st))
        check(not whole(dir_), "try %2d: whole files, no temporary left %s" % (k + 1, whole(dir_)))
        check(all(s in ("ok", "interrupted") for s in st) and st.count("interrupted") <= 1,
              "try %2d: completed runs ok, at most one interrupted" % (k + 1))
        if got == want:
            check("--resume" in se, "try %2d: says how to resume" % (k + 1))
    check(stops >= TRIES // 2, "the signal stopped the batch in %d of %d tries (>= %d)" % (stops, TRIES, TRIES // 2))
    p = subprocess.run([BIN, "batch", bench, "--resume", dir_, "--quiet"], capture_output=True, text=True)
    check(p.returncode == 0, "the last resume completes the set (exit %d)" % p.returncode)
    a = {r["run_id"]: r for r in rows(clean)}
    b = {r["run_id"]: r for r in rows(dir_)}
    check(sorted(a) == sorted(b), "the resumed set has the clean set's runs (%d, %d)" % (len(a), len(b)))
    same = ["technique", "params", "status", "frames", "draw_calls_mean", "err_rate_mean", "texel_px_p95_mean"]
    diff = [(i, c) for i in a if i in b for c in same if a[i][c] != b[i][c]]
    check(not diff, "the resumed rows equal the clean rows, timings aside %s" % diff[:4])

    # `run` stops and resumes the same way
    cmd = [BIN, "run", "towers", "towers", "sm:res=512", "pssm:res=512", "sdsm:res=512", "--frames", "10", "--warmup", "1",
           "--error-every", "5",
           "--size", "320x180", "--quiet"]
    rc, so, se = stopped(cmd + ["--out", os.path.join(WORK, "run")], whole_s * 0.5)
    run_dir = so.strip().splitlines()[-1]
    st = [r["status"] for r in rows(run_dir)]
    check(rc == 130 and "--resume" in se and not whole(run_dir),
          "run: SIGINT -> exit %d, rows %s, whole files, says how to resume" % (rc, st))
    p = subprocess.run(cmd + ["--resume", run_dir], capture_output=True, text=True)
    c = {r["technique"]: r for r in rows(run_dir)}
    diff = [(r["technique"], k) for r in rows(clean) for k in same if c.get(r["technique"], {}).get(k) != r[k]]
    check(p.returncode == 0 and len(c) == 3 and not diff,
          "run --resume completes it (exit %d), rows equal the clean batch's, timings aside %s" % (p.returncode, diff[:4]))

    # `tune` stops the same way: the outputs from what was measured, and its own --resume completes the search
    cmd = [BIN, "tune", "towers", "auto", "sm:res=256,512,1024", "pssm:res=512:cascades=2,4", "--frames", "9",
           "--size", "320x180", "--max-err", "0.5", "--seed", "3", "--quiet"]
    t0 = time.time()
    p = subprocess.run(cmd + ["--out", os.path.join(WORK, "tune-whole")], capture_output=True, text=True)
    tune_s = time.time() - t0
    whole_tune = p.stdout.strip().splitlines()[-1]
    check(p.returncode == 0, "tune, never stopped: exit %d in %.1f s" % (p.returncode, tune_s))
    rc, so, se = stopped(cmd + ["--out", os.path.join(WORK, "tune")], tune_s * 0.4)
    tune_dir = so.strip().splitlines()[-1]
    rungs = sorted(glob.glob(os.path.join(tune_dir, "rung-*")))
    st = [r["status"] for d in rungs for r in rows(d)]
    check(rc == 130 and "--resume" in se and os.path.exists(os.path.join(tune_dir, "tune.csv"))
          and not any(whole(d) for d in rungs) and set(st) <= {"ok", "interrupted"},
          "tune: SIGINT -> exit %d, rung rows %s, whole files, tune.csv written, says how to resume" % (rc, st))
    p = subprocess.run(cmd + ["--resume", tune_dir], capture_output=True, text=True)
    a = {r["run_id"]: r["err_rate_mean"] for r in rows(os.path.join(whole_tune, "rung-0"))}
    b = {r["run_id"]: r["err_rate_mean"] for r in rows(os.path.join(tune_dir, "rung-0"))}
    check(p.returncode == 0 and a == b and "interrupted" not in [r["status"] for d in rungs for r in rows(d)],
          "tune --resume completes it (exit %d): rung 0 has the whole search's runs and errors (%d, %d), "
          "none interrupted" % (p.returncode, len(a), len(b)))

    # `stress` stops between its rows: the rows so far, said so, and its temporary scenes removed
    # (in a TMPDIR of its own: a `stress` test running beside this one leaves its scenes in /tmp meanwhile)
    tmp = os.path.join(WORK, "tmp")
    os.makedirs(tmp)
    rc, so, se = stopped([BIN, "stress"], 3, env=dict(os.environ, TMPDIR=tmp))
    left = set(glob.glob(os.path.join(tmp, "*")))
    rows_ = [l for l in so.splitlines() if l.split()[2:3] in (["ok"], ["FAIL"])]
    check(rc == 130 and "interrupted by SIGINT" in so and rows_ and not left,
          "stress: SIGINT -> exit %d, %d row(s) kept, temporary scenes left %s" % (rc, len(rows_), sorted(left)))

    # a second SIGINT: at once. When the first one's orderly stop is over before the second can be sent (it
    # came at a frame's end: seen once, status 130 after 0.01 s), or ends just as it is sent (status 130 at once),
    # there was no second to test: again, later; five tries without one test fail the check (dt stays NaN)
    dt = float("nan")
    for attempt in range(5):
        p = subprocess.Popen([BIN, "batch", bench, "--out", os.path.join(WORK, "twice"), "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(whole_s * (0.3 + 0.1 * attempt))
        p.send_signal(signal.SIGINT)
        time.sleep(0.05)
        if p.poll() is not None:
            p.communicate(timeout=60)
            print("note: the first SIGINT's stop was over in 0.05 s (status %d): again" % p.returncode)
            continue
        t1 = time.time()
        p.send_signal(signal.SIGINT)
        p.communicate(timeout=60)
        dt = time.time() - t1
        if p.returncode == 128 + signal.SIGINT and dt < 0.05:
            # the orderly stop ended between the poll and the second signal (seen once in CI: status 130 at
            # 0.00 s): the second reached a process already exiting; nothing was tested, again
            print("note: the first SIGINT's stop ended as the second was sent (status 130 after %.3f s): again" % dt)
            dt = float("nan")
            continue
        break
    check(p.returncode == -signal.SIGINT and dt < 2,
          "a second SIGINT ends it at once (%.2f s, status %d)" % (dt, p.returncode))
    hears_sigterm(bench)
    if failures:
        print("%d check(s) failed" % len(failures))
        sys.exit(1)


def png(path, w, h, v):
    """A grey PNG of w x h pixels of value v."""
    raw = b"".join(b"\x00" + bytes([v]) * w for _ in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def hears_sigterm(bench):
    """Every wait bounded and every signal heard: each command of the kinds the suite runs, started and sent SIGTERM
    a second in (or ended by itself before), exits within 5 s of it. Before, a scene-cache entry that is a FIFO
    blocked in open() (57ff219: `run` still running 5 s after SIGTERM), printing "stopping after the frame in
    flight" and going on. (score's frames here do not line up, so its runs end by themselves; test_score holds
    `--repeat 2`, which spun for ever, on a renderer's real frames.)"""
    white = os.path.join(WORK, "white")
    os.makedirs(white)
    for f in range(2):
        png(os.path.join(white, "vis_%04d.png" % f), 96, 54, 255)
        png(os.path.join(white, "mask_%04d.png" % f), 96, 54, 255)
    cache = os.path.join(WORK, "fifo-cache")
    env_cache = dict(os.environ, SB_SCENE_CACHE=cache)
    subprocess.run([BIN, "info", "towers"], env=env_cache, capture_output=True, check=True)
    for e in glob.glob(os.path.join(cache, "*.sbscene")):
        os.unlink(e)
        os.mkfifo(e)
    fifo_history = os.path.join(WORK, "fifo.sqlite")
    os.mkfifo(fifo_history)
    small = ["--size", "160x90", "--quiet"]
    cmds = [
        ("run", [BIN, "run", "towers", "towers", "sm", "pssm", "--frames", "400", "--error-every", "100"] + small, None),
        ("run --repeat 3", [BIN, "run", "towers", "towers", "sm", "--frames", "50", "--repeat", "3"] + small, None),
        ("run score:... --repeat 2", [BIN, "run", "plane-box", "plane-box", "score:dir=%s:mask=mask_%%04d.png" % white,
                                      "--frames", "2", "--repeat", "2", "--size", "96x54", "--quiet"], None),
        ("score --repeat 2", [BIN, "score", "plane-box", "plane-box", white, "--mask", "mask_%04d.png", "--frames", "2",
                              "--repeat", "2", "--size", "96x54", "--quiet"], None),
        ("batch", [BIN, "batch", bench, "--quiet"], None),
        ("tune", [BIN, "tune", "towers", "auto", "sm:res=256,512,1024", "--frames", "9", "--max-err", "0.5"] + small, None),
        ("info, its cache entry a FIFO", [BIN, "info", "towers"], env_cache),
        ("run, its cache entry a FIFO", [BIN, "run", "towers", "towers", "sm", "--frames", "200"] + small, env_cache),
        ("history add, the history a FIFO", [BIN, "history", "add", WORK, "--history", fifo_history], None),
    ]
    for k, (name, cmd, env) in enumerate(cmds):
        p = subprocess.Popen(cmd + (["--out", os.path.join(WORK, "term-%d" % k)] if cmd[1] in ("run", "batch", "tune", "score") else []),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        try:
            p.wait(timeout=1)
            how = "ended by itself (status %d)" % p.returncode
            took = 0
        except subprocess.TimeoutExpired:
            t0 = time.time()
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout=5)
                took = time.time() - t0
                how = "stopped %.1f s after SIGTERM (status %d)" % (took, p.returncode)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
                took = float("inf")
                how = "still running 5 s after SIGTERM: killed"
        p.communicate()
        check(took <= 5 and p.returncode in (0, 1, 2, 128 + signal.SIGTERM), "SIGTERM heard: %s: %s" % (name, how))


if __name__ == "__main__":
    main()
