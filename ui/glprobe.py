"""Can this process draw OpenGL?  Asked once, in a subprocess, because a failing GL context
can take the whole process down (measured: offscreen Qt has no GL context)."""

from __future__ import annotations

import os
import subprocess
import sys
from functools import lru_cache

_PROBE = """
import sys
from PyQt5.QtGui import QGuiApplication, QOpenGLContext, QOffscreenSurface
app = QGuiApplication(sys.argv[:1])
ctx = QOpenGLContext()
if not ctx.create():
    sys.exit(3)
surf = QOffscreenSurface(); surf.create()
sys.exit(0 if ctx.makeCurrent(surf) else 4)
"""


@lru_cache(maxsize=1)
def gl_available() -> bool:
    """True when a GL context can be created and made current on this display."""
    if os.environ.get("BOSUN_NO_GL") == "1" or os.environ.get("QT_QPA_PLATFORM", "") in ("offscreen", "minimal"):
        return False
    try:
        import OpenGL  # noqa: F401  (pyqtgraph.opengl needs PyOpenGL)
    except ImportError:
        return False
    try:
        res = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, timeout=20)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return res.returncode == 0
