"""Shared fixtures: the repository root (tests run from anywhere) and the `appell` command
the Python results are compared with (APPELL_BIN, else the release build beside the sources,
which the README's test command builds first)."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def cli():
    """Run the command line; return (exit code, stdout, stderr)."""
    binary = os.environ.get("APPELL_BIN") or str(ROOT / "target" / "release" / "appell")
    if not os.path.exists(binary):
        raise RuntimeError(
            f"no appell binary at {binary}: run `cargo build --release` (or set APPELL_BIN)"
        )

    def run(*args):
        p = subprocess.run([binary, *map(str, args)], cwd=ROOT, capture_output=True, text=True)
        return p.returncode, p.stdout, p.stderr

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """The command's JSON output (it must succeed)."""

    def run(*args):
        code, out, err = cli(*args, "--json")
        assert code == 0, err
        return json.loads(out)

    return run


@pytest.fixture(autouse=True)
def _in_root(monkeypatch):
    # Paths in the tests are the repository's, as the CLI's JSON records them.
    monkeypatch.chdir(ROOT)
