#!/usr/bin/env python3
"""Where are a model's gross held-out errors? For each row whose
out-of-fold 3D error exceeds 3x the 3D RMS (the `holdout` "gross error"
rule), print its nearest poses in the campaign (largest joint difference,
degrees, angles wrapped), whether they were approached from the same
directions, how far their measured errors are from its own, and their own
out-of-fold errors.

    robokrige cv DATA.csv --robot ur10 --tool=-0.14,0.30,92.82 \\
        --folds 10 --mode closed-form --json cv.json
    python3 benches/gross_rows.py cv.json DATA.csv

A gross row whose nearest pose repeats its joints (within REPEAT_DEG) but
whose measured error differs by more than the gross threshold is counted
as "contradicted by a repeat": the campaign measured the same
configuration twice with errors that no smooth model reconciles, and a
warning built from the poses alone cannot single it out. Standard library
only.
"""
import csv
import json
import math
import sys

REPEAT_DEG = 0.05


def wrapped(a, b):
    return max(min(abs(x - y) % 360, 360 - abs(x - y) % 360) for x, y in zip(a, b))


def main(cv_json, data_csv):
    res = json.load(open(cv_json))["residuals"]
    rows = list(csv.DictReader(open(data_csv)))
    n = sum(1 for k in rows[0] if k.startswith("q") and k[1:].isdigit())
    q = [[float(r[f"q{j}"]) for j in range(1, n + 1)] for r in rows]
    dirs = [[r.get(f"dir{j}") for j in range(1, n + 1)] for r in rows]
    e = [[float(r[k]) for k in ("ex", "ey", "ez")] for r in rows]
    norm = [math.sqrt(sum(x * x for x in r)) for r in res]
    rms = math.sqrt(sum(x * x for x in norm) / len(norm))
    gross = [i for i, v in enumerate(norm) if v > 3 * rms]
    print(f"{len(rows)} rows, out-of-fold 3D RMS {rms:.4f} mm, {len(gross)} gross (> {3 * rms:.4f} mm)")
    repeats = 0
    for i in gross:
        near = sorted((wrapped(q[i], q[k]), k) for k in range(len(q)) if k != i)[:3]
        line = f"row {i}: out-of-fold {norm[i]:.3f} mm"
        for d, k in near:
            de = math.sqrt(sum((a - b) ** 2 for a, b in zip(e[i], e[k])))
            same = "same" if dirs[k] == dirs[i] else "other"
            line += f" | row {k} at {d:.2f} deg, {same} directions, measured {de:.3f} mm apart, out-of-fold {norm[k]:.3f}"
        d0, k0 = near[0]
        de0 = math.sqrt(sum((a - b) ** 2 for a, b in zip(e[i], e[k0])))
        if d0 <= REPEAT_DEG and de0 > 3 * rms:
            repeats += 1
            line += "  [contradicted by a repeat]"
        print(line)
    print(f"{repeats} of {len(gross)} gross rows contradicted by a repeat of their joints")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
