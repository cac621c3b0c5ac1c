#!/usr/bin/env python3
"""`shadowbench bisect` on a real chain of commits of this repository.

A scratch clone of the source gets eight commits on top of its HEAD (GOOD):

  1 docs: a blank line                  4 sm: broken (does not compile)
  2 none: a trailing space              5 sm: mended
  3 shadow maps: 512 texels by default  6 lamp: a note
    (wronger: pssm's err_rate on        7 shadow maps: pcss by default
    plane-box rises from 0)               (slower: a blocker search and its
                                          filter, about 2.3x the final pass;
                                          pcf5's +30 % was within a noisy
                                          machine's reach of the 512-texel
                                          map's -24 %: CI named no commit)
                                        8 docs: another blank line (BAD)

Commit 4 is the first middle the bisection tries. Then:

- err_rate of pssm on plane-box: bisect names commit 3, skips commit 4 by
  name, measures at most ceil(log2 8) + 2 = 5 commits against GOOD, exits 0;
- final_ms of sm on plane-box (paired, interleaved runs): names commit 7 and
  prints each step's paired difference with its CI; commit 3 (a smaller map,
  a faster final pass) is judged good;
- GOOD against itself, and GOOD against commit 2 (nothing that renders
  changed), exit 1 saying they do not differ;
- an unknown commit, a missing run, and --out in the run exit 2 in one line.

Every bisect here builds with --build-type debug (half a release build's time; final_ms is llvmpipe's, which
the harness's build type does not move enough to hide a 2.3x step): the binaries land in bin/SHA.debug/.

usage: run_bisect.py SHADOWBENCH SOURCE_ROOT BUILD_ROOT
"""
import math
import os
import re
import shutil
import subprocess
import sys
import time

BIN, SRC, BUILD = sys.argv[1:4]
WORK = os.path.join(BUILD, "test-bisect")
REPO = os.path.join(WORK, "repo")
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def git(*args):
    return subprocess.run(["git", "-C", REPO] + list(args), check=True, capture_output=True, text=True).stdout.strip()


def bisect(*args):
    t0 = time.monotonic()
    p = subprocess.run([BIN, "bisect"] + list(args), cwd=REPO, capture_output=True, text=True)
    print("$ shadowbench bisect %s  (exit %d, %.1f s)" % (" ".join(args), p.returncode, time.monotonic() - t0))
    print(p.stdout + p.stderr, flush=True)
    return p


def edit(path, fn):
    full = os.path.join(REPO, path)
    with open(full) as f:
        text = f.read()
    new = fn(text)
    assert new != text, path
    with open(full, "w") as f:
        f.write(new)


def commit(msg):
    git("commit", "-qam", msg)
    return git("rev-parse", "HEAD")


if subprocess.run(["git", "-C", SRC, "rev-parse", "HEAD"], capture_output=True).returncode != 0:
    print("skip: the source is not a git checkout")
    sys.exit(77)
shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
subprocess.run(["git", "clone", "--quiet", SRC, REPO], check=True)
git("config", "user.email", "bisect@test")
git("config", "user.name", "bisect test")
good = git("rev-parse", "HEAD")
c = [good]
edit("README.md", lambda t: t + "\n")
c.append(commit("docs: a blank line"))
edit("techniques/none.c", lambda t: t.replace("\n", " \n", 1))
c.append(commit("none: a trailing space"))
edit("techniques/cascade.h", lambda t: t.replace("SB_PARAM_I(sb_csm_desc, res, 2048,", "SB_PARAM_I(sb_csm_desc, res, 512,"))
c.append(commit("shadow maps: 512 texels by default"))
edit("techniques/sm.c", lambda t: t + "#error deliberately broken\n")
c.append(commit("sm: broken"))
edit("techniques/sm.c", lambda t: t.replace("#error deliberately broken\n", ""))
c.append(commit("sm: mended"))
edit("techniques/lamp.c", lambda t: t + "/* a note */\n")
c.append(commit("lamp: a note"))
edit("techniques/cascade.h", lambda t: t.replace("SB_PARAM_E(sb_csm_desc, filter, hw,", "SB_PARAM_E(sb_csm_desc, filter, pcss,"))
c.append(commit("shadow maps: pcss by default"))
edit("README.md", lambda t: t + "\n")
c.append(commit("docs: another blank line"))
n = len(c) - 1
bound = math.ceil(math.log2(n)) + 2


def measured(out):
    m = re.search(r"measured: (\d+) commit", out)
    return int(m.group(1)) if m else 99


# an error: exact
p = bisect(good, c[n], "--metric", "err_rate", "--build-type", "debug", "--", "run", "plane-box", "plane-box", "pssm", "--frames", "5",
           "--size", "320x180")
check(p.returncode == 0, "err_rate: exit 0")
check(("first bad commit: %s shadow maps: 512 texels by default" % c[3]) in p.stdout, "err_rate: commit 3 named")
check(re.search(r"skipped %s sm: broken" % c[4][:12], p.stdout) is not None, "err_rate: commit 4 skipped by name")
check("does not build" in p.stdout, "err_rate: the skip says it does not build")
check(measured(p.stdout) <= bound, "err_rate: %d commits measured, at most %d" % (measured(p.stdout), bound))
m = re.search(r"runs: (\d+) of theirs, (\d+) of GOOD's", p.stdout)
check(m and int(m.group(1)) <= bound and int(m.group(2)) <= bound, "err_rate: renders of each side within the bound")
bins = os.path.join(REPO, ".git", "shadowbench-bisect", "bin")
check(os.path.exists(os.path.join(bins, good + ".debug", "shadowbench")) and not os.path.exists(os.path.join(bins, good)),
      "--build-type debug: GOOD's binary in bin/SHA.debug/, none in bin/SHA/ (%s)" % sorted(os.listdir(bins))[:3])

# a timing: paired, interleaved
p = bisect(good, c[n], "--metric", "final_ms", "--repeat", "3", "--build-type", "debug", "--", "run", "plane-box", "plane-box", "sm",
           "--frames", "10", "--size", "640x360", "--error-every", "0")
check(p.returncode == 0, "final_ms: exit 0")
check(("first bad commit: %s shadow maps: pcss by default" % c[7]) in p.stdout, "final_ms: commit 7 named")
steps = re.findall(r"final_ms [\d.e+-]+ against GOOD [\d.e+-]+: ([+-][\d.e+-]+) ms ± ([\d.e+-]+) \(([+-][\d.]+) %\) "
                   r"over (\d+) pairs(?:  -> (\w+))?", p.stdout)
check(len(steps) >= 3, "final_ms: every step prints the paired difference and its CI (%d)" % len(steps))
verdicts = re.findall(r"step \d+  (\w{12}) .*\n  built[^:]*: .*-> (\w+)", p.stdout)
check((c[3][:12], "good") in verdicts or all(v[0] != c[3][:12] for v in verdicts),
      "final_ms: the smaller map (faster) is not taken for the slowdown")
check(measured(p.stdout) <= bound, "final_ms: %d commits measured, at most %d" % (measured(p.stdout), bound))

# no difference
p = bisect(good, good, "--metric", "err_rate", "--", "run", "plane-box", "plane-box", "pssm", "--frames", "3")
check(p.returncode == 1 and "do not differ" in p.stdout, "GOOD against itself: exit 1, said")
p = bisect(good, c[2], "--metric", "err_rate", "--build-type", "debug", "--", "run", "plane-box", "plane-box", "pssm", "--frames", "5",
           "--size", "320x180")
check(p.returncode == 1 and "do not differ" in p.stdout, "GOOD against a change that renders nothing new: exit 1")

# bad input
for args, what in [(["nosuchcommit", c[n], "--", "run", "plane-box", "plane-box", "sm"], "an unknown commit"),
                   ([good, c[n]], "no run"),
                   ([good, c[n], "--", "run", "plane-box", "plane-box", "sm", "--out", "x"], "--out in the run"),
                   ([c[n], good, "--", "run", "plane-box", "plane-box", "sm"], "GOOD after BAD"),
                   ([good, c[n], "--metric", "nosuch", "--", "run", "plane-box", "plane-box", "sm"], "an unknown metric")]:
    p = bisect(*args)
    lines = p.stderr.strip().splitlines()
    check(p.returncode == 2 and len(lines) == 1 and lines[0].startswith("shadowbench"), "%s: exit 2, one line" % what)

if failures:
    print("%d check(s) failed" % len(failures))
    sys.exit(1)
print("all bisect checks passed")
