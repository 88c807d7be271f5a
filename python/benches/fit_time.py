"""Time `ErrorModel().fit` (the command line's defaults) on a campaign.

    python fit_time.py CAMPAIGN.csv [--repeat N]

Prints one JSON line: the build (`build_target_cpu`), rows, the wall time of
each fit, and each axis's ln ψ (to check that builds agree). Used to compare
the portable (baseline x86-64) and x86-64-v3 builds of the wheel, each
installed in its own venv, with alternating runs (python/README.md).
"""

import argparse
import json
import time

import robokrige as rk


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--repeat", type=int, default=1)
    a = ap.parse_args()
    data = rk.as_data(a.csv)
    times, cpu = [], []
    for _ in range(a.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        m = rk.ErrorModel().fit(data)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    print(
        json.dumps(
            {
                "build": rk.build_target_cpu(),
                "rows": len(data),
                "seconds": times,
                "cpu_seconds": cpu,
                "ln_psi": [r["ln_psi"] for r in m.reports_],
                "families": m.families_,
            }
        )
    )


if __name__ == "__main__":
    main()
