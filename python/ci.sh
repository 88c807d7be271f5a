#!/usr/bin/env bash
# Build the robokrige wheel (portable x86-64 build, see python/README.md),
# install it into a fresh venv with pytest, numpy, pandas, scikit-learn and
# mypy, check the types (mypy --strict on the package and the examples; the
# extension's stubs against the built module), and run the Python tests.
# Run from anywhere; the venv lives in a temporary folder. The tests
# compare with the command line at target/release/robokrige when it exists
# (`cargo test --release` builds it), and skip those that need it
# otherwise; a test that needs pandas or scikit-learn fails without it
# (ROBOKRIGE_TEST_REQUIRE_ALL): they are installed here.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(dirname "$here")"
python="${PYTHON:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$python" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    "maturin>=1.9.4,<2" pytest numpy pandas scikit-learn mypy
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
# the package's annotations and the examples (pyproject.toml: [tool.mypy])
(cd "$here" && "$work/venv/bin/mypy" --strict --cache-dir "$work/mypy-cache")
# the stubs of the extension against the module built
"$work/venv/bin/python" -m mypy.stubtest --mypy-config-file "$here/pyproject.toml" robokrige._robokrige
echo "python/ci.sh: mypy --strict and stubtest in $((SECONDS - t0)) s"
t0=$SECONDS
# SCIPY_ARRAY_API: check_estimator's array-API check runs instead of skipping
SCIPY_ARRAY_API=1 ROBOKRIGE_TEST_REQUIRE_ALL=1 "$work/venv/bin/pytest" -q -p no:cacheprovider python/tests
echo "python/ci.sh: pytest in $((SECONDS - t0)) s"
