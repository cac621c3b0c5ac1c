#!/usr/bin/env python3
"""Runs the README's five-minute tour from the README text itself.

  run_tour.py SOURCE_ROOT BUILD_DIR

The fenced sh block between <!-- tour: begin --> and <!-- tour: end --> is run
by bash (set -euo pipefail) in a scratch folder that looks like the
repository root after scripts/test (build/, docs/, scripts/ linked), so the
tour's outputs land in that folder's out/, not in the checkout. Each step
must succeed and print what the README says it prints."""
import glob
import os
import re
import subprocess
import sys
import tempfile


def main():
    root, build = sys.argv[1], sys.argv[2]
    text = open(os.path.join(root, "README.md"), encoding="utf-8").read()
    m = re.search(r"<!-- tour: begin -->\s*```sh\n(.*?)```\s*<!-- tour: end -->", text, re.S)
    if not m:
        print("README.md has no tour block (<!-- tour: begin --> ```sh ... ``` <!-- tour: end -->)")
        print("0 passed, 1 failed")
        return 1
    script = m.group(1)
    with tempfile.TemporaryDirectory(prefix="sb-tour-") as work:
        os.symlink(os.path.abspath(build), os.path.join(work, "build"))
        for d in ("docs", "scripts"):
            os.symlink(os.path.join(os.path.abspath(root), d), os.path.join(work, d))
        p = subprocess.run(["bash", "-c", "set -euo pipefail\n" + script], cwd=work, capture_output=True, text=True,
                           timeout=600)
        out = p.stdout + p.stderr
        print(out)
        checks = [
            ("every step exits 0", p.returncode == 0),
            ("step 1 lists the run's files", "summary.csv" in out),
            ("step 2 pairs pssm with sdsm", "1 pair(s) technique=sdsm against technique=pssm" in out),
            ("step 2 shows both runs' time and error", "pssm gpu_ms" in out and "sdsm err_rate" in out),
            ("step 3 recommends a setting", "recommended: sm" in out),
            ("step 4 finds nothing wronger", "0 regression(s)" in out),
        ]
        sums = glob.glob(os.path.join(work, "out", "2*", "summary.csv"))
        rows = [l for l in open(sums[0]).read().splitlines()[1:] if l.strip()] if len(sums) == 1 else []
        checks.append(("step 1's summary holds its two runs, both ok", len(rows) == 2 and all(",ok," in r for r in rows)))
        failed = 0
        for name, ok in checks:
            print(("ok   " if ok else "FAIL ") + name)
            failed += not ok
        print(f"{len(checks) - failed} passed, {failed} failed")
        return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
