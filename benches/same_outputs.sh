#!/usr/bin/env bash
# Do two builds give the same results? Runs the same commands (fit with
# several options and methods, predict, cv, compensate with and without
# the simulator's truth, diagnose, holdout) with each binary on the shipped
# data and compares every output: model files and CSVs byte for byte, JSON
# up to wall times ("*seconds" keys) and 1e-11 relative, and the printed
# logs up to times.
#
#   benches/same_outputs.sh OLD/robokrige NEW/robokrige
#
# Prints "RESULT SAME" or the differences. Takes about 20 s.
set -uo pipefail
[ $# -eq 2 ] || { echo "usage: $0 OLD_BINARY NEW_BINARY" >&2; exit 2; }
here="$(cd "$(dirname "$0")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
run() {
    local bin out D
    bin="$(realpath "$1")" out="$2" D="$here/datasets"
    mkdir -p "$out" && cd "$out" || exit 1
    r() { echo "+ $*" >> log.txt; "$bin" "$@" >> log.txt 2>&1; echo "rc=$?" >> log.txt; }
    head -301 "$D/comau_lhs.csv" > lhs300.csv
    r fit lhs300.csv -o m_default.json
    r fit lhs300.csv --method js-hj -o m_js.json
    r fit lhs300.csv --method ejs-gps -o m_gps.json
    r fit lhs300.csv --space ejs --corr auto -o m_auto.json
    r fit lhs300.csv --space js --corr matern52 --no-nugget -o m_m52.json
    r fit lhs300.csv --robot comau-nj220 --kinematic -o m_kin.json
    r fit lhs300.csv --robot comau-nj220 -o m_cal.json
    r fit lhs300.csv --robot comau-nj220 --no-calibrate --trend linear -o m_lin.json
    r predict m_default.json "$D/comau_verify.csv" -o p_default.csv
    r predict m_cal.json "$D/comau_verify.csv" -o p_cal.csv
    r predict m_auto.json "$D/comau_verify.csv" -o p_auto.csv
    r cv lhs300.csv --folds 5 --json cv.json
    r compensate --model m_cal.json --robot comau-nj220 "$D/comau_circle.csv" -o comp.csv \
        --iterative --truth "$D/comau_circle.truth.json" --json comp.json
    r compensate --model m_default.json --robot comau-nj220 "$D/comau_circle.csv" -o comp1.csv
    r diagnose "$D/comau_tracker_step.csv" --json diag.json --model-out m_diag.json
    r holdout lhs300.csv --robot comau-nj220 --cv 3 --json holdout.json
    sed -i -E 's/[0-9.]+ s\b/T s/g; s/in [0-9.]+s/in Ts/g' log.txt
}
(run "$1" "$work/a")
(run "$2" "$work/b")
python3 - "$work/a" "$work/b" <<'PY'
import json, os, sys
a, b = sys.argv[1], sys.argv[2]
bad = 0
def strip(o):
    if isinstance(o, dict):
        return {k: strip(v) for k, v in o.items() if not (k.endswith("seconds") or k == "elapsed")}
    if isinstance(o, list):
        return [strip(v) for v in o]
    return o
def close(x, y, path):
    global bad
    if isinstance(x, dict) and isinstance(y, dict):
        if set(x) != set(y):
            print(path, "keys differ", set(x) ^ set(y)); bad += 1; return
        for k in x:
            close(x[k], y[k], path + "/" + k)
    elif isinstance(x, list) and isinstance(y, list):
        if len(x) != len(y):
            print(path, "lengths", len(x), len(y)); bad += 1; return
        for i, (u, v) in enumerate(zip(x, y)):
            close(u, v, f"{path}[{i}]")
    elif isinstance(x, float) or isinstance(y, float):
        num = all(isinstance(v, (int, float)) for v in (x, y))
        if not (x == y or (num and abs(x - y) <= 1e-11 * max(1, abs(x), abs(y)))):
            print(path, x, y); bad += 1
    elif x != y:
        print(path, repr(x)[:80], repr(y)[:80]); bad += 1
for f in sorted(set(os.listdir(a)) | set(os.listdir(b))):
    pa, pb = os.path.join(a, f), os.path.join(b, f)
    if not (os.path.exists(pa) and os.path.exists(pb)):
        print("only in one:", f); bad += 1; continue
    A, B = open(pa).read(), open(pb).read()
    if A == B:
        continue
    if f.endswith(".json"):
        close(strip(json.loads(A)), strip(json.loads(B)), f)
    else:
        print("differs:", f); bad += 1
print("RESULT", "SAME" if bad == 0 else f"{bad} differences")
PY
