#!/usr/bin/env python3
"""The CI matrix example (scripts/cluster/github-matrix.yml) run locally.

GitHub Actions itself cannot run here, so this runs what the file's steps run:
every `run:` line of the `shard` job once per matrix value, each shard in a
checkout-like folder of its own whose `out` becomes its artifact; then the
`merge` job's `run:` lines in a folder where the artifacts are downloaded
together (as `merge-multiple: true` does), against a baseline written by an
unsharded run. The setup-and-build step is left out (the test's binary is
already built; `scripts/build` is exercised by scripts/test) and the batch is
tests/cluster/cluster.bench instead of the nightly, for time. What cannot run
here: runners, checkout, the artifact service and $GITHUB_STEP_SUMMARY's page
(a file stands in). compare's timing gate (exit 1 slower, 3 unstable) is
noise on a shared CPU and is not held against the file; a usage error is.
  tests/cluster/matrix.py SHADOWBENCH SOURCE_ROOT
"""
import os, re, shutil, subprocess, sys, tempfile

sb, root = os.path.realpath(sys.argv[1]), os.path.realpath(sys.argv[2])
bench = os.path.join(root, "tests/cluster/cluster.bench")
yml = os.path.join(root, "scripts/cluster/github-matrix.yml")


def jobs(text):
    """{job: {"matrix": [values], "steps": [(kind, text)]}} from the example's simple layout."""
    out, job = {}, None
    for line in text.splitlines():
        m = re.match(r"^  (\w+):\s*$", line)
        if m:
            job = out.setdefault(m.group(1), {"matrix": [], "steps": []})
            continue
        if job is None:
            continue
        m = re.match(r"^\s+matrix:\s*\{shard:\s*\[([\d,\s]+)\]\}", line)
        if m:
            job["matrix"] = [int(v) for v in m.group(1).split(",")]
        m = re.match(r"^\s+- run:\s*(.*)$", line)
        if m:
            job["steps"].append(("run", m.group(1)))
        m = re.match(r"^\s+- uses:\s*actions/(upload|download)-artifact", line)
        if m:
            job["steps"].append((m.group(1), ""))
    return out


def workspace(path):
    """A folder that looks like the checkout after the build step."""
    os.makedirs(os.path.join(path, "build-release"))
    os.symlink(sb, os.path.join(path, "build-release", "shadowbench"))
    os.symlink(os.path.join(root, "scripts"), os.path.join(path, "scripts"))


def run(cmd, cwd, env, shard=None):
    if cmd.startswith("scripts/setup") and "scripts/build" in cmd:
        print(f"  (left out: {cmd})")
        return
    if shard is not None:
        cmd = cmd.replace("${{ matrix.shard }}", str(shard))
    if "${{" in cmd:
        sys.exit(f"FAIL: unexpanded expression in: {cmd}")
    cmd = cmd.replace("scripts/nightly.bench", bench)
    print(f"  $ {cmd}", flush=True)
    r = subprocess.run(["bash", "-eo", "pipefail", "-c", cmd], cwd=cwd, env=env)
    if " compare " in cmd and r.returncode in (1, 3):
        # the gate's verdict on timings (1: slower, 3: unstable) is noise on a
        # shared CPU; what must hold here is that the command is right (2: bad usage)
        print(f"  (compare's timing verdict here: exit {r.returncode}; not a failure of the file)")
        return
    if r.returncode != 0:
        sys.exit(f"FAIL: exit {r.returncode}: {cmd}")


def main():
    j = jobs(open(yml).read())
    if set(j) != {"shard", "merge"} or not j["shard"]["matrix"]:
        sys.exit(f"FAIL: {yml}: expected jobs shard (with a shard matrix) and merge, found {sorted(j)}")
    tmp = tempfile.mkdtemp(prefix="sbmatrix.")
    try:
        artifacts = os.path.join(tmp, "artifacts")
        env = dict(os.environ, GITHUB_STEP_SUMMARY=os.path.join(tmp, "step-summary.md"))
        for shard in j["shard"]["matrix"]:
            ws = os.path.join(tmp, f"shard{shard}")
            workspace(ws)
            print(f"shard {shard}:")
            for kind, cmd in j["shard"]["steps"]:
                if kind == "run":
                    run(cmd, ws, env, shard)
                elif kind == "upload":
                    shutil.copytree(os.path.join(ws, "out"), os.path.join(artifacts, f"shard-{shard}"))
        ws = os.path.join(tmp, "merge")
        workspace(ws)
        base = subprocess.run([sb, "batch", bench, "--out", os.path.join(tmp, "base"), "--quiet"],
                              capture_output=True, text=True, check=True).stdout.strip().splitlines()[-1]
        shutil.copytree(base, os.path.join(ws, "baseline"))
        print("merge:")
        for kind, cmd in j["merge"]["steps"]:
            if kind == "run":
                run(cmd, ws, env)
            elif kind == "download":
                for a in sorted(os.listdir(artifacts)):
                    shutil.copytree(os.path.join(artifacts, a), os.path.join(ws, "out"), dirs_exist_ok=True)
        merged = os.path.join(ws, "out", "merged", "summary.csv")
        rows = sum(1 for _ in open(merged)) - 1
        want = sum(1 for _ in open(os.path.join(base, "summary.csv"))) - 1
        if rows != want:
            sys.exit(f"FAIL: the merge has {rows} runs, the unsharded batch {want}")
        page = open(env["GITHUB_STEP_SUMMARY"]).read()
        if "|" not in page:
            sys.exit("FAIL: compare --format markdown wrote no table to $GITHUB_STEP_SUMMARY")
        night = open(os.path.join(ws, "out", "site", "data", "night-1.js")).read()
        if night.count('"ok"') < rows:
            sys.exit("FAIL: the merged night's report does not hold every run")
        print(f"pass: {len(j['shard']['matrix'])} shards merged to {rows} runs, compare's table "
              f"({page.count(chr(10))} lines), a report of the merged night")
    finally:
        if not os.environ.get("SB_KEEP_MATRIX_TMP"):
            shutil.rmtree(tmp, ignore_errors=True)


main()
