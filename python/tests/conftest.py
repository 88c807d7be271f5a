"""Shared fixtures: the shipped campaigns and the command line, if built."""

import importlib
import os
import pathlib
import shutil
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
DATASETS = REPO / "datasets"

#: Set by python/ci.sh, which installs the optional packages: a test that
#: needs one fails instead of skipping, so that CI runs every such test.
REQUIRE_ALL = os.environ.get("ROBOKRIGE_TEST_REQUIRE_ALL") == "1"


def need(module):
    """Import an optional package (pandas, scikit-learn) or skip the test;
    in CI (ROBOKRIGE_TEST_REQUIRE_ALL=1) its absence is a failure."""
    try:
        return importlib.import_module(module)
    except ImportError:
        if REQUIRE_ALL:
            raise
        pytest.skip(f"{module} is not installed")


def cli_path():
    """The `robokrige` binary: $ROBOKRIGE_CLI, else the repository's
    target/release/robokrige (built by `cargo test --release`), else PATH."""
    env = os.environ.get("ROBOKRIGE_CLI")
    if env:
        return env
    for p in (REPO / "target" / "release" / "robokrige",):
        if p.is_file() and os.access(p, os.X_OK):
            return str(p)
    return shutil.which("robokrige")


@pytest.fixture(scope="session")
def datasets():
    return DATASETS


@pytest.fixture(scope="session")
def cli():
    """Run the command line: cli(*args) -> CompletedProcess (text)."""
    path = cli_path()
    if path is None:
        pytest.skip("the robokrige command line is not built (cargo build --release, or set ROBOKRIGE_CLI)")

    def run(*args, check=True):
        return subprocess.run([path, *map(str, args)], capture_output=True, text=True, check=check)

    return run
