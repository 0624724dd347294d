#!/usr/bin/env bash
# Installs what the tests need on a fresh machine and runs them: README's test command and CI's.
# - a virtual environment in .venv with theoria and its test extras (pip, from PyPI)
# - Debian's chromium for the browser tests (apt-get, as root), never a downloaded browser
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e '.[test]'
if ! command -v chromium >/dev/null 2>&1 && [ ! -x /usr/bin/chromium ]; then
  if [ "$(id -u)" = 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q
    apt-get install -y -q chromium
  else
    echo "chromium is missing and this is not root: browser tests will be skipped" >&2
  fi
fi
exec .venv/bin/python -m pytest "$@"
