"""A pyqtgraph 3D view in its own native window, embedded in a widget layout.

A ``QOpenGLWidget`` (pyqtgraph's ``GLViewWidget``) renders into a framebuffer object that the
top-level window then composes: once one is in a window, Qt draws the *whole* window through
OpenGL, so every plot repaint uploads the window's pixels as a texture.  On software OpenGL
(Mesa llvmpipe, the usual headless and remote-desktop case) that cost a third of the operator
window's frame rate (issue 15: 19.7 fps with the 3D view against 31 fps without).  pyqtgraph
issues #2656 and #2063 describe it; the fix they give is the one used here: the view is a
``QOpenGLWindow`` (pyqtgraph's ``GLViewMixin`` supplies the camera, items and mouse handling,
pyqtgraph PR #2659) inside ``QWidget.createWindowContainer``, so the rest of the window stays on
the raster path and only the view's own pixels go through OpenGL.  ``scripts/fps.py`` measures it.

Two consequences, handled here: ``QWidget.grab()`` of the window does not contain a native child's
pixels (:func:`grab_window` paints each view's framebuffer into the grab), and a ``QWindow`` has no
tooltip (it goes on the container).
"""

from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtGui import QImage, QOpenGLWindow, QPainter, QPixmap
from PyQt5.QtWidgets import QSizePolicy, QWidget
from pyqtgraph.opengl.GLViewWidget import GLViewMixin


class GLViewWindow(GLViewMixin, QOpenGLWindow):
    """pyqtgraph's 3D view as a native OpenGL window (see the module doc).

    It draws into a framebuffer object that is blitted to the window (``PartialUpdateBlit``): the
    picture stays readable after the swap, where the default mode's back buffer is undefined on
    most drivers (Qt's ``QOpenGLWindow::grabFramebuffer`` note)."""

    def __init__(self) -> None:
        super().__init__(QOpenGLWindow.PartialUpdateBlit)
        self.container: QWidget | None = None

    def render_image(self, timeout: float = 3.0) -> QImage:
        """The view drawn now, as an image (a view not yet on screen gets ``timeout`` s to appear)."""
        import time

        from PyQt5.QtCore import QCoreApplication

        end = time.monotonic() + timeout
        while not self.isValid() and time.monotonic() < end:  # no GL context before the first expose
            QCoreApplication.processEvents()
            time.sleep(0.01)
        if not self.isValid():
            return QImage()
        self.makeCurrent()  # binds the window's framebuffer object
        self.paintGL()
        return self.grabFramebuffer()


def gl_view(parent: QWidget | None = None, tooltip: str = "", min_height: int = 0) -> tuple[GLViewWindow, QWidget]:
    """A :class:`GLViewWindow` and the widget that holds it in a layout (tooltip and size go on that one)."""
    view = GLViewWindow()
    box = QWidget.createWindowContainer(view, parent)
    box.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
    box.setFocusPolicy(Qt.ClickFocus)
    box.setProperty("bosun_gl_view", True)
    if tooltip:
        box.setToolTip(tooltip)
    if min_height:
        box.setMinimumHeight(min_height)
    view.container = box
    return view, box


def grab_window(widget: QWidget) -> QPixmap:
    """``widget.grab()`` with every visible embedded GL view's picture painted where it is shown."""
    pix = widget.grab()
    painter = QPainter(pix)
    try:
        for box in widget.findChildren(QWidget):
            if not box.property("bosun_gl_view") or not box.isVisible() or not box.isVisibleTo(widget):
                continue
            window = _contained(box)
            if window is None:
                continue
            img = window.render_image()
            if img.isNull():
                continue
            seen = box.visibleRegion().boundingRect()  # a view in a scroll area is shown in part
            if seen.isEmpty():
                continue
            img = img.scaled(box.size(), Qt.IgnoreAspectRatio, Qt.SmoothTransformation)
            painter.drawImage(box.mapTo(widget, seen.topLeft()), img, seen)
    finally:
        painter.end()
    return pix


def _contained(box: QWidget) -> GLViewWindow | None:
    """The GL window a container holds (``createWindowContainer`` keeps it as a child QWindow)."""
    for w in _windows():
        if isinstance(w, GLViewWindow) and w.container is box:
            return w
    return None


def _windows():
    from PyQt5.QtGui import QGuiApplication

    return QGuiApplication.allWindows()
