#!/usr/bin/env python3
"""Plant effects of our own into the real UR10 campaigns (README, "Planted
into the real rows"). Writes c_bump.csv, c_temp.csv, c_lag.csv and
b_temp.csv into OUT (default: out/plant). Every effect is added to ex, ey,
ez along (1, -1, 1)/sqrt(3):
- c_bump: 0.12 mm on rows m/3 .. 2m/3 - 1 of series C (924-1847);
- c_temp / b_temp: 0.1 mm times (temp_c - min) / (max - min);
- c_lag: 0.005 mm per degree of q2's last move (q2(k) - q2(k-1)).
Then: cargo run --release -- diagnose OUT/c_bump.csv (and so on).
"""
import csv, math, os, sys

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "ipa-ur10")
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join("out", "plant")
S = (1 / math.sqrt(3), -1 / math.sqrt(3), 1 / math.sqrt(3))


def load(name):
    with open(os.path.join(DATA, name)) as f:
        return list(csv.DictReader(f))


def plant(rows, size, name):
    out = []
    for i, r in enumerate(rows):
        r = dict(r)
        s = size(i)
        for k, u in zip(("ex", "ey", "ez"), S):
            r[k] = "%.6f" % (float(r[k]) + s * u)
        out.append(r)
    with open(os.path.join(OUT, name), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(out)


def temp_drift(rows):
    t = [float(r["temp_c"]) for r in rows]
    lo, hi = min(t), max(t)
    return lambda i: 0.1 * (t[i] - lo) / (hi - lo)


os.makedirs(OUT, exist_ok=True)
c = load("series_c_random_poses.csv")
b = load("series_b_joint_configurations.csv")
m = len(c)
plant(c, lambda i: 0.12 if m // 3 <= i < 2 * m // 3 else 0.0, "c_bump.csv")
plant(c, temp_drift(c), "c_temp.csv")
plant(b, temp_drift(b), "b_temp.csv")
plant(c, lambda i: 0.0 if i == 0 else 0.005 * (float(c[i]["q2"]) - float(c[i - 1]["q2"])), "c_lag.csv")
print("wrote", OUT)
