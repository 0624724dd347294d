"""What several test files share: the checkout's root, the command line run in-process or as a
child process, a child Python with this checkout on its path, and which tests count as slow.

`pytest -m "not slow"` is the quick suite (about 1.5 minutes of CPU on the 2-core machine); CI and
`scripts/test.sh` run everything. A test is marked slow where it is written when it took more than
about 5 s in `pytest --durations` on the shared machine (with others' jobs running); the browser
tests, which start Chromium, are slow as a group (marked here, so their files need not say it).
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("browser") is not None:
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return ROOT


@pytest.fixture
def cli(capsys):
    """Run `theoria ARGS...` in this process: (exit code, stdout, stderr)."""
    from theoria.app.cli import main

    def run(*argv):
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return code, out, err

    return run


def child_env() -> dict:
    """The environment of a child Python that imports this checkout."""
    return dict(os.environ, PYTHONPATH=str(ROOT))


@pytest.fixture
def cli_process():
    """Run `python -m theoria.app.cli ARGS...` as a child process from the checkout's root:
    (exit code, stdout, stderr). The timeout only guards CI against a hang; it is no speed
    requirement."""

    def run(*argv, timeout=3600):
        p = subprocess.run([sys.executable, "-m", "theoria.app.cli", *map(str, argv)], capture_output=True,
                           text=True, timeout=timeout, cwd=ROOT, env=child_env())
        return p.returncode, p.stdout, p.stderr

    return run


@pytest.fixture
def python_child():
    """Start `python -c CODE` from the checkout's root (a subprocess.Popen; keyword arguments
    go to Popen), for tests that signal or watch a running command."""

    def start(code: str, **popen_kw):
        return subprocess.Popen([sys.executable, "-c", code], env=child_env(), cwd=ROOT, **popen_kw)

    return start
