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


def share_gl_contexts() -> None:
    """Let every OpenGL view's context share objects (shaders, buffers) with the others.

    pyqtgraph compiles a shader once and reuses its program id in every view; without sharing, the
    second 3D view (crane head, lab, analysis, each a native GL window) fails with GL_INVALID_OPERATION
    on ``glUseProgram``.  Qt needs this before the application object exists."""
    from PyQt5.QtCore import QCoreApplication, Qt

    if QCoreApplication.instance() is None:
        QCoreApplication.setAttribute(Qt.AA_ShareOpenGLContexts)
