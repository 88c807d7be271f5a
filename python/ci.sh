#!/usr/bin/env bash
# Build the robokrige wheel (portable x86-64 build, see python/README.md),
# install it into a fresh venv with pytest, numpy and pandas, and run the
# Python tests. Run from anywhere; the venv lives in a temporary folder.
# The tests compare with the command line at target/release/robokrige when
# it exists (`cargo test --release` builds it), and skip those that need it
# otherwise.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(dirname "$here")"
python="${PYTHON:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$python" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    "maturin>=1.9.4,<2" pytest numpy pandas
# The wheel must run on any x86-64 CPU: baseline x86-64 code, not the
# repository's x86-64-v3 default (.cargo/config.toml); faer picks its SIMD
# kernels at run time. RUSTFLAGS replaces the config's rustflags.
if [ "$(uname -m)" = "x86_64" ]; then
    export RUSTFLAGS="${ROBOKRIGE_WHEEL_RUSTFLAGS:--C target-cpu=x86-64}"
fi
t0=$SECONDS
(cd "$here" && "$work/venv/bin/maturin" build --release --quiet \
    --interpreter "$work/venv/bin/python" --out "$work/wheels")
echo "python/ci.sh: wheel built in $((SECONDS - t0)) s (RUSTFLAGS=${RUSTFLAGS:-})"
"$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$work"/wheels/*.whl
# from the repository root, so that the installed package is imported,
# not the sources in python/robokrige
cd "$repo"
"$work/venv/bin/python" -c "import robokrige as rk; print('robokrige', rk.__version__, 'wheel build:', rk.build_target_cpu())"
t0=$SECONDS
"$work/venv/bin/pytest" -q -p no:cacheprovider python/tests
echo "python/ci.sh: pytest in $((SECONDS - t0)) s"
