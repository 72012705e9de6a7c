#!/usr/bin/env bash
# The Python package's tests, as the README says: build the wheel into a fresh virtual
# environment (.venv, with the test extras: pytest, pandas, dask.distributed), run pytest
# against the `appell` binary `cargo test --release` builds, then the notebook-style example.
set -euo pipefail
cd "$(dirname "$0")/../.."
python3 -m venv .venv
.venv/bin/pip install --quiet --upgrade pip
.venv/bin/pip install --quiet './python[test]'
# The binary `cargo test --release` builds (a no-op after it; Cargo.toml asks for the tests' and
# the bindings' features, so the wheel above reused this library too).
cargo test --release --no-run --quiet
# In cargo's target directory: target/, or CARGO_TARGET_DIR when set (pip's build of the wheel
# above used it too).
target_dir=$(cargo metadata --format-version 1 --no-deps |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
APPELL_BIN="${APPELL_BIN:-$target_dir/release/appell}" \
    .venv/bin/python -m pytest -q -p no:cacheprovider python/tests
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
.venv/bin/python docs/examples/notebook.py "$out"
