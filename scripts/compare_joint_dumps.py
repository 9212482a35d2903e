#!/usr/bin/env python3
"""Compares two `gaitkeeper bench --dump-joints` CSVs value by value (same header and rows; every
number within TOL, default 1e-4 m). Usage: compare_joint_dumps.py BEFORE.csv AFTER.csv [TOL]"""
import csv, sys
a_path, b_path = sys.argv[1], sys.argv[2]
tol = float(sys.argv[3]) if len(sys.argv) > 3 else 1e-4
with open(a_path) as fa, open(b_path) as fb:
    ra, rb = csv.reader(fa), csv.reader(fb)
    ha, hb = next(ra), next(rb)
    if ha != hb:
        sys.exit(f"headers differ: {ha[:5]} vs {hb[:5]}")
    worst, rows, vals = 0.0, 0, 0
    for la, lb in zip(ra, rb, strict=True):
        rows += 1
        for x, y in zip(la, lb, strict=True):
            try:
                fx, fy = float(x), float(y)
            except ValueError:
                if x != y: sys.exit(f"row {rows}: {x!r} != {y!r}")
                continue
            vals += 1
            worst = max(worst, abs(fx - fy))
print(f"{rows} rows, {vals} values, max |diff| = {worst:.3g} ({'OK' if worst <= tol else 'FAIL'} at tol {tol})")
sys.exit(0 if worst <= tol else 1)
