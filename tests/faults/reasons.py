#!/usr/bin/env python3
"""No run in the whole test suite ends without a reason.

Every shadowbench the suite starts appends each run that did not end `ok`
(failed, skipped, interrupted) to $SB_AUDIT_OUTCOMES: status, run id,
technique, reason. This test runs last (lowest priority, alone) and reads it:
the suite must have recorded such runs (it provokes dozens), and not one may
have an empty reason. scripts/test starts the file afresh; run alone, with no
file, the test is skipped (exit 77) unless SB_OUTCOMES_REQUIRED is set.

usage: reasons.py
"""
import collections
import os
import sys

path = os.environ.get("SB_AUDIT_OUTCOMES", "")
if not path or not os.path.exists(path):
    print("no outcomes recorded at %r (run the whole suite: scripts/test)" % path)
    sys.exit(1 if os.environ.get("SB_OUTCOMES_REQUIRED") else 77)
rows = [l.rstrip("\n").split("\t") for l in open(path) if l.strip()]
by_status = collections.Counter(r[0] for r in rows)
empty = [r for r in rows if len(r) < 4 or not r[3].strip()]
print("%d runs not ok across the suite: %s" % (len(rows), dict(by_status)))
for r in empty[:10]:
    print("FAIL no reason: %s" % r)
least = 10 if os.environ.get("SB_OUTCOMES_REQUIRED") else 1   # the whole suite provokes dozens
ok = len(rows) >= least and not empty
print("ok   every one has a reason" if ok else "FAIL %d without a reason (of %d)" % (len(empty), len(rows)))
sys.exit(0 if ok else 1)
