#!/bin/sh
# Makes (once) the Python environment of the package `linkspace` (python/linkspace): a venv with
# maturin, numpy, pytest, mypy, matplotlib, nbclient and ipykernel from pinned PyPI releases
# (scripts/python-requirements.txt), and the package built from this checkout into it.
# Nothing else is needed on the machine but CPython >= 3.10, cargo and PyPI.
#
# Usage: scripts/python_env.sh [VENV]      (default: target/py-venv)
# Prints the venv's python on the last line. Idempotent: stamps record the hash of the
# requirements (and this script) and of the package's inputs (its crate, the library's sources,
# Cargo.toml and Cargo.lock), so a second call with nothing changed returns at once, and a
# change to the sources rebuilds only the package. Concurrent callers wait on a lock.
#
# The wheel builds in the workspace's target directory (CARGO_TARGET_DIR when set, else
# target/), on the dependencies the root build compiled there.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VENV=${1:-$ROOT/target/py-venv}
mkdir -p "$(dirname "$VENV")"
VENV=$(cd "$(dirname "$VENV")" && pwd)/$(basename "$VENV")
PY=${LINKSPACE_PYTHON:-python3}

exec 9>"$VENV.lock"
flock 9

hash_of() { cat "$@" | sha256sum | cut -d' ' -f1; }
REQ_HASH=$(hash_of "$ROOT/scripts/python-requirements.txt" "$ROOT/scripts/python_env.sh")
PKG_HASH=$(cd "$ROOT" && { find python/linkspace src -type f ! -path '*/__pycache__/*' ! -path 'python/linkspace/tests/*' ! -name '*.pyc'; echo Cargo.toml; echo Cargo.lock; } | LC_ALL=C sort | xargs cat | sha256sum | cut -d' ' -f1)

if [ "$(cat "$VENV/.linkspace-req" 2>/dev/null)" != "$REQ_HASH" ]; then
  if ! "$PY" -c 'import sys; sys.exit(sys.version_info < (3, 10))'; then
    echo "python_env.sh: the package needs CPython >= 3.10; set LINKSPACE_PYTHON" >&2
    exit 1
  fi
  rm -rf "$VENV"
  "$PY" -m venv "$VENV"
  "$VENV/bin/pip" install -q --disable-pip-version-check -r "$ROOT/scripts/python-requirements.txt" >&2
  echo "$REQ_HASH" > "$VENV/.linkspace-req"
  rm -f "$VENV/.linkspace-pkg"
fi

if [ "$(cat "$VENV/.linkspace-pkg" 2>/dev/null)" != "$PKG_HASH" ]; then
  # The backend is in the venv already (on PATH for pip): no isolated build environment to
  # download.
  if ! PATH="$VENV/bin:$PATH" "$VENV/bin/pip" install --disable-pip-version-check --no-build-isolation --no-deps --force-reinstall "$ROOT/python/linkspace" > "$VENV.build.log" 2>&1; then
    echo "python_env.sh: building python/linkspace failed; the end of $VENV.build.log:" >&2
    tail -30 "$VENV.build.log" >&2
    exit 1
  fi
  "$VENV/bin/python" -c "import linkspace" >&2
  echo "$PKG_HASH" > "$VENV/.linkspace-pkg"
fi
echo "$VENV/bin/python"
