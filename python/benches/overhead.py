"""Python against Rust: the same fit, timed two ways.

Against the Rust API, in-process times:

    cargo build --release --manifest-path python/benches/rust_timing/Cargo.toml \
        --target-dir python/target            # with the wheel's RUSTFLAGS
    python python/benches/overhead.py --rust python/target/release/robokrige-rust-timing \
        [--train datasets/comau_lhs.csv] [--poses datasets/comau_verify.csv] [--rounds 7]

Each round runs, alternately, one fresh Rust process (`ErrorModelParams`
→ `check` → `fit`, then `predict_dataset` with standard deviations) and one
fresh Python process (`ErrorModel().fit(q, dirs, errors, covariates)`, then
`predict(q, dirs, return_std=True)`), the data already in memory on both
sides; each reports its own wall times.

Against the command line, the same job end to end (read the campaign CSV,
fit with the defaults, write the model file):

    RUSTFLAGS="-C target-cpu=x86-64" cargo build --release --bin robokrige \
        --target-dir /tmp/cli-baseline        # the wheel's build, for a like-for-like CLI
    python python/benches/overhead.py --cli /tmp/cli-baseline/release/robokrige [--rounds 3]

Each round runs, alternately, `robokrige fit CAMPAIGN -o model.json` (the
process's wall time, measured by this script) and a fresh Python process
timing `rk.ErrorModel().fit(CAMPAIGN).save(model.json)` (the call's wall
time: the interpreter's start and imports are not the fit's).

Either way both sides must fit the same model (the FNV-1a digest of the
model file is compared). Prints the medians and the Python/Rust ratio.
"""

import argparse
import json
import statistics
import subprocess
import sys
import time


def fnv(text: str) -> str:
    h = 0xCBF29CE484222325
    for b in text.encode():
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def child(train: str, poses: str) -> None:
    import numpy as np

    import robokrige as rk

    def arrays(path):
        t = rk.read_campaign(path, as_frame=False)
        n = sum(1 for k in t if k.startswith("q") and k[1:].isdigit())
        q = np.column_stack([t[f"q{j}"] for j in range(1, n + 1)])
        d = np.column_stack([t[f"dir{j}"] for j in range(1, n + 1)])
        e = np.column_stack([t[a] for a in ("ex", "ey", "ez")]) if "ex" in t else None
        skip = {"id", "ex", "ey", "ez", "x", "y", "z"}
        cov = {
            k: v
            for k, v in t.items()
            if k not in skip and not (k[:1] == "q" and k[1:].isdigit()) and not k.startswith("dir")
            and isinstance(v, np.ndarray)
        }
        return q, d, e, cov

    q, d, e, cov = arrays(train)
    qv, dv, _, _ = arrays(poses)
    t0 = time.perf_counter()
    m = rk.ErrorModel().fit(q, d, e, cov)
    fit = time.perf_counter() - t0
    t1 = time.perf_counter()
    mean, std = m.predict(qv, dv, return_std=True)
    predict = time.perf_counter() - t1
    print(json.dumps({"fit": fit, "predict": predict, "rows": len(q), "poses": len(qv),
                      "model_fnv": fnv(m.to_json()), "mean0": float(mean[0, 0]),
                      "build": rk.build_target_cpu()}))


def child_file(train: str, out: str) -> None:
    import robokrige as rk

    t0 = time.perf_counter()
    rk.ErrorModel().fit(train).save(out)
    seconds = time.perf_counter() - t0
    with open(out) as f:
        digest = fnv(f.read())
    print(json.dumps({"fit": seconds, "model_fnv": digest, "build": rk.build_target_cpu()}))


def against_cli(cli: str, train: str, rounds: int) -> None:
    import tempfile

    runs: dict = {"cli": [], "python": []}
    with tempfile.TemporaryDirectory() as tmp:
        out = f"{tmp}/model.json"
        for r in range(rounds):
            t0 = time.perf_counter()
            subprocess.run([cli, "fit", train, "-o", out], capture_output=True, text=True, check=True)
            wall = time.perf_counter() - t0
            with open(out) as f:
                runs["cli"].append({"fit": wall, "model_fnv": fnv(f.read())})
            done = subprocess.run([sys.executable, __file__, "--child-file", "--train", train, "--out", out],
                                  capture_output=True, text=True, check=True)
            runs["python"].append(json.loads(done.stdout.strip().splitlines()[-1]))
            print(f"round {r + 1}: robokrige fit {runs['cli'][-1]['fit']:.3f} s, "
                  f"ErrorModel().fit {runs['python'][-1]['fit']:.3f} s", file=sys.stderr)
    digests = {x["model_fnv"] for v in runs.values() for x in v}
    if len(digests) != 1:
        sys.exit(f"the two sides fitted different models: {digests}")
    med = {k: statistics.median(x["fit"] for x in v) for k, v in runs.items()}
    print(json.dumps({
        "train": train, "rounds": rounds, "wheel_build": runs["python"][0]["build"],
        "seconds": {k: [x["fit"] for x in v] for k, v in runs.items()},
        "median_seconds": med, "ratio_python_cli": med["python"] / med["cli"], "same_model": True,
    }, indent=1))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rust", help="the robokrige-rust-timing binary")
    ap.add_argument("--cli", help="a robokrige command line (built as the wheel is)")
    ap.add_argument("--out", help=argparse.SUPPRESS)
    ap.add_argument("--child-file", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--train", default="datasets/comau_lhs.csv")
    ap.add_argument("--poses", default="datasets/comau_verify.csv")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.train, a.poses)
        return
    if a.child_file:
        child_file(a.train, a.out)
        return
    if a.cli:
        against_cli(a.cli, a.train, a.rounds)
        return
    if not a.rust:
        ap.error("give --rust or --cli")
    runs = {"rust": [], "python": []}
    for r in range(a.rounds):
        out = subprocess.run([a.rust, a.train, a.poses, "1"], capture_output=True, text=True, check=True)
        runs["rust"].append(json.loads(out.stdout.strip().splitlines()[-1]))
        out = subprocess.run([sys.executable, __file__, "--child", "--train", a.train, "--poses", a.poses],
                             capture_output=True, text=True, check=True)
        runs["python"].append(json.loads(out.stdout.strip().splitlines()[-1]))
        print(f"round {r + 1}: rust fit {runs['rust'][-1]['fit']:.3f} s, python fit {runs['python'][-1]['fit']:.3f} s",
              file=sys.stderr)
    digests = {x["model_fnv"] for v in runs.values() for x in v}
    if len(digests) != 1:
        sys.exit(f"the two sides fitted different models: {digests}")
    med = {k: {f: statistics.median(x[f] for x in v) for f in ("fit", "predict")} for k, v in runs.items()}
    tot = {k: med[k]["fit"] + med[k]["predict"] for k in med}
    print(json.dumps({
        "rows": runs["rust"][0]["rows"], "poses": runs["rust"][0]["poses"], "rounds": a.rounds,
        "wheel_build": runs["python"][0]["build"], "median_seconds": med,
        "ratio_fit": med["python"]["fit"] / med["rust"]["fit"],
        "ratio_predict": med["python"]["predict"] / med["rust"]["predict"],
        "ratio_fit_plus_predict": tot["python"] / tot["rust"],
        "same_model": True,
    }, indent=1))


if __name__ == "__main__":
    main()
