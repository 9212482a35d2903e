#!/usr/bin/env python3
"""Compares two `gaitkeeper bench --json` reports: every value but the timings must be identical
(exit 1 and the first differences otherwise). Usage: compare_bench_reports.py BEFORE.json AFTER.json"""
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
diffs = []
def walk(x, y, p):
    if p.rsplit("/", 1)[-1] in ("timing_ms", "us_per_agent"): return  # wall-clock, differs run to run
    if isinstance(x, dict) and isinstance(y, dict):
        for k in sorted(set(x) | set(y)):
            walk(x.get(k, "<missing>"), y.get(k, "<missing>"), p + "/" + k)
    elif x != y:
        diffs.append((p, x, y))
walk(a, b, "")
for d in diffs[:20]: print("DIFF", *d)
print(f"{len(diffs)} differing values outside timings")
sys.exit(1 if diffs else 0)
