"""The one wrapper every machine view shares: a drawing (the machine's solids from the engine's description
and its state) shown as OpenGL solids, or, without OpenGL, as 2D projections.

A scene's view is a subclass naming its drawing and filling ``draw_now(*state)``; :func:`make_view` picks
3D or 2D.  The teleop arm (``ui/widgets/view3d.py``), the crane head (``ui/marine_tab.py``) and the
Motion-Lab (``ui/lab/scene.py``) use it.
"""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtWidgets import QVBoxLayout, QWidget

from ui.glprobe import gl_available
from ui.widgets.machines3d import LazyDraw


class DrawnScene(LazyDraw, QWidget):
    """``machines`` (``make_machines(self)``: a :class:`~ui.widgets.machines3d.MachineView3D` or
    ``MachineView2D``) filling the widget, ``draw`` the scene's drawing (``set_description(desc)``, meshes
    from a state).  Drawn only while shown; fitted to the machines once per description."""

    kind = "3d"

    def __init__(self, make_machines: Callable[[QWidget], QWidget], drawing, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        machines = make_machines(self)
        self.machines = machines
        self.draw = drawing
        self._fitted = False
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(machines)

    def set_description(self, desc) -> None:
        """The engine's static data (robot files, ranges, the sea): the drawing's, and a new fit."""
        self.draw.set_description(desc)
        self._fitted = False

    def update_scene(self, *state) -> None:
        """Draw the engine's state (now if shown, else when next shown)."""
        self.submit(*state)

    def fit_once(self, fit: Callable[[], None]) -> None:
        """Run ``fit`` (camera or axes on the machines) the first time after a description."""
        if not self._fitted:
            fit()
            self._fitted = True

    def grab_image(self):
        return self.machines.grab_image()


def make_view(three_d: Callable[[], QWidget], two_d: Callable[[], QWidget], use_gl: bool | None = None) -> QWidget:
    """The 3D view when OpenGL works here (``use_gl`` None: probe it), else the 2D one (never a crash)."""
    if use_gl is None:
        use_gl = gl_available()
    if use_gl:
        try:
            return three_d()
        except Exception:
            pass
    return two_d()
