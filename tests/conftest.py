"""Shared fixtures.  Headless defaults are set before anything imports Qt or pygame."""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
# one BLAS thread a test process, as the engines take (app/launch.py): the tests' matrices are small and xdist
# already runs a process a core; a second OpenBLAS thread a process only spins against the others
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# QSettings (the GUI's remembered choices) goes to a throw-away folder, never the user's config
os.environ["XDG_CONFIG_HOME"] = tempfile.mkdtemp(prefix="bosun-test-config-")

import numpy as np
import pytest

try:  # before pytest-qt makes the QApplication: the GL views share shaders (ui/glprobe.py)
    from ui.glprobe import share_gl_contexts

    share_gl_contexts()
except ImportError:  # the core without the GUI extra
    pass

# removed when the test process ends (each xdist worker makes its own: 467 were left in /tmp in a day)
atexit.register(shutil.rmtree, os.environ["XDG_CONFIG_HOME"], ignore_errors=True)

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: every test run draws the same numbers."""
    return np.random.default_rng(20261122)


@pytest.fixture
def shared_data() -> Path:
    """The third-party reference data beside the checkout; skips when absent (a user's clone)."""
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data is not present")
    return SHARED_DATA


@pytest.fixture(scope="module")
def mss_table():
    """The MSS supply vessel's ShipX/VERES RAO table (``../shared/data/supply_mss.mat``: test data only)."""
    from app.marine.vessel import load_rao

    path = SHARED_DATA / "supply_mss.mat"
    if not path.is_file():
        pytest.skip("../shared/data/supply_mss.mat is not present")
    return path, load_rao(path)


@pytest.fixture
def serve():
    """Start engines on 127.0.0.1 (free port) in threads: ``serve(session, token=None, rate=200, publish_rate=None,
    duration=120.0, **server_kw)`` (tests.helpers.start_engine) returns (server, thread); every one is stopped
    and closed after the test, after the fixtures that use this one (a window closes before its engines stop)."""
    from tests.helpers import start_engine, stop_engine

    started = []

    def start(session, token=None, rate=200, **kw):
        started.append(start_engine(session, rate, token=token, **kw))
        return started[-1]

    yield start
    for srv, th in started:
        stop_engine(srv, th)


def pytest_configure(config):
    """Kernel caches made stale by an edit of a kernel file another one imports are cleared once, by the
    controlling process (xdist's workers start after it), before any test loads a kernel."""
    if not hasattr(config, "workerinput"):
        from app.models.kernels import clear_stale

        clear_stale()


def pytest_collection_modifyitems(items):
    """Every test in a tests/test_gui*.py file is marked ``gui`` and ``slow``: each starts engine processes
    and a window (seconds).  The fast lane, ``-m "not slow"``, runs everything else."""
    for item in items:
        if item.path.name.startswith("test_gui"):
            item.add_marker(pytest.mark.gui)
            item.add_marker(pytest.mark.slow)
