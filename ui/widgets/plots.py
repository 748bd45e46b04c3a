"""Live plots fed by engine states: ring buffers with named columns, redrawn by a timer (not per sample).

What every plot of the GUI keeps (tests/test_gui_plots.py checks it for each tab):

* one unit per axis: a second quantity in another unit goes on a right-hand axis of its own
  (:class:`TwinAxis`, a linked ViewBox with its own label and unit), never on the same axis;
* a legend naming every curve (:func:`legend`);
* the data back in view when the plot is shown again after its tab was hidden (:func:`refit`,
  :func:`refit_on_show`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

import numpy as np
import pyqtgraph as pg
from PyQt5 import sip
from PyQt5.QtCore import QEvent, QObject, Qt, QTimer, pyqtSignal
from PyQt5.QtWidgets import QGridLayout, QLabel, QProgressBar, QSizePolicy, QVBoxLayout, QWidget

LEGEND_TEXT = (210, 210, 210)
COLORS = [(230, 90, 70), (80, 180, 90), (80, 140, 230), (220, 180, 60), (170, 100, 210), (70, 200, 200)]
XYZ = ("x", "y", "z")
# units shown as given: an SI prefix in front of them would read wrong ("mdeg", "kms")
NO_PREFIX_UNITS = ("deg", "°", "ms", "mm", "%", "rad", "rad/s", "m²s")


class Ring:
    """Fixed-size ring buffer of rows with named columns.

    ``ring["x"]`` is that column, oldest first; ``ring["x", "y"]`` (or a list of names) the columns
    side by side, shape (n, k); ``view()`` every column.  ``push(row)`` takes a full row in column
    order, ``push(x=…, y=…)`` by name (columns not given are NaN).
    """

    def __init__(self, size: int, columns: Sequence[str]) -> None:
        self.columns = tuple(columns)
        self.index = {c: k for k, c in enumerate(self.columns)}
        if len(self.index) != len(self.columns):
            raise ValueError(f"duplicate column names in {self.columns}")
        self.data = np.full((size, len(self.columns)), np.nan)
        self.n = 0  # rows held
        self.i = 0  # next row written

    @property
    def size(self) -> int:
        return len(self.data)

    @property
    def width(self) -> int:
        return len(self.columns)

    def __len__(self) -> int:
        return self.n

    def push(self, row: Sequence[float] | None = None, **values: float) -> None:
        if row is None:
            unknown = set(values) - set(self.index)
            if unknown:
                raise KeyError(f"no column {sorted(unknown)} in {self.columns}")
            r = np.full(self.width, np.nan)
            for name, v in values.items():
                r[self.index[name]] = v
            row = r
        elif len(row) != self.width:
            raise ValueError(f"a row of {len(row)} values for {self.width} columns")
        self.data[self.i] = row
        self.i = (self.i + 1) % self.size
        self.n = min(self.n + 1, self.size)

    def clear(self) -> None:
        self.data[:] = np.nan
        self.n = self.i = 0

    def _ordered(self, a: np.ndarray) -> np.ndarray:
        if self.n < self.size:
            return a[: self.n]
        return np.concatenate((a[self.i :], a[: self.i]))

    def view(self) -> np.ndarray:
        """Every column, oldest row first."""
        return self._ordered(self.data)

    def __getitem__(self, key: str | Iterable[str]) -> np.ndarray:
        if isinstance(key, str):
            return self._ordered(self.data[:, self.index[key]])
        return self._ordered(self.data[:, [self.index[k] for k in key]])

    def latest(self, key: str) -> float:
        """The newest value of one column (NaN when empty)."""
        if self.n == 0:
            return float("nan")
        return float(self.data[(self.i - 1) % self.size, self.index[key]])


# ---------------------------------------------------------------------------------------------- plot helpers
def axis_label(plot: pg.PlotItem, side: str, text: str, units: str) -> None:
    """One quantity and one unit per axis; units that take no SI prefix are shown as given."""
    ax = plot.getAxis(side)
    if units in NO_PREFIX_UNITS:
        ax.enableAutoSIPrefix(False)
    if side in ("left", "right"):  # short plots: fewer tick labels, never written over each other
        ax.setStyle(textFillLimits=[(0, 0.8), (2, 0.45), (4, 0.25), (6, 0.15)])
    plot.setLabel(side, text, units=units)


def legend(plot: pg.PlotItem, cols: int = 4, title: str | None = None) -> pg.LegendItem:
    """The plot's legend in a header above the curves, under its title: it names every curve (items
    plotted with a ``name`` join it) and never covers one.  ``title`` defaults to the plot's title;
    ``cols`` entries a row (the header's width is the plot's minimum width)."""
    if plot.legend is not None:
        return plot.legend
    if title is None:
        title = plot.titleLabel.text if plot.titleLabel.isVisible() else ""
    # the header takes the title's place in the plot's layout (row 0), sized by its contents
    plot.titleLabel.setVisible(False)
    plot.layout.removeItem(plot.titleLabel)
    plot.layout.setRowMinimumHeight(0, 0)
    plot.layout.setRowMaximumHeight(0, 200)
    header = pg.GraphicsLayout()
    header.layout.setContentsMargins(2, 0, 2, 0)
    header.layout.setVerticalSpacing(0)
    leg = _HeaderLegend(
        offset=None, colCount=cols, frame=False, labelTextSize="8pt", labelTextColor=LEGEND_TEXT, verSpacing=-8
    )
    leg.layout.setContentsMargins(0, 0, 0, 0)
    head = None
    if title:
        head = _TitleLabel(title, size="9pt", color=LEGEND_TEXT, bold=True, justify="left")
        head.setMaximumHeight(20)
        header.addItem(head, 0, 0)
    header.addItem(leg, 1, 0)
    header.layout.setAlignment(leg, Qt.AlignLeft | Qt.AlignVCenter)
    plot.layout.addItem(header, 0, 1)
    plot.legend = leg
    plot.header_title = head
    leg.max_cols = cols
    scene = plot.scene()
    for view in scene.views() if scene is not None else ():
        _LegendFitter.watch(view)
    return leg


class _TitleLabel(pg.LabelItem):
    """A plot's title that ends in "…" when its plot is narrower than the text (the whole title in the tool
    tip).  A title's full width was the plot's minimum width: two columns of titled plots were laid out
    wider than their view and cut at the right (the crane head's Figs. 9 and 12 in a 1280×800 window)."""

    MIN_WIDTH = 60.0

    def __init__(self, text: str, **args) -> None:
        self.full_text = text
        self._eliding = False
        super().__init__(text, **args)
        self.setToolTip(text)

    def setText(self, text, **args) -> None:
        if not self._eliding:
            self.full_text = text
            self.setToolTip(text)
        super().setText(text, **args)

    def updateMin(self) -> None:
        super().updateMin()
        self.setMinimumWidth(min(self.minimumWidth(), self.MIN_WIDTH))

    def sizeHint(self, hint, constraint):
        if hint == Qt.PreferredSize:  # the whole title when there is room
            return pg.QtCore.QSizeF(self.item.boundingRect().width(), super().sizeHint(hint, constraint).height())
        return super().sizeHint(hint, constraint)

    def resizeEvent(self, ev) -> None:
        super().resizeEvent(ev)
        if self._eliding:
            return
        from PyQt5.QtGui import QFontMetricsF

        font = self.item.font()
        font.setPointSizeF(float(str(self.opts.get("size", "9pt")).rstrip("pt") or 9))
        font.setBold(bool(self.opts.get("bold", False)))
        shown = QFontMetricsF(font).elidedText(self.full_text, Qt.ElideRight, max(10.0, self.width() - 6))
        if shown != self.text:
            self._eliding = True
            try:
                super().setText(shown)
            finally:
                self._eliding = False


class _HeaderLegend(pg.LegendItem):
    """A legend that reflows to its view's width also when curves join it later (:func:`fit_legends`)."""

    def addItem(self, item, name) -> None:
        super().addItem(item, name)
        scene = self.scene()
        for view in scene.views() if scene is not None else ():
            QTimer.singleShot(0, lambda v=view: fit_legends(v))


class _LegendFitter(QObject):
    """Reflows the legends of a plot view to the view's width: as many entries a row as fit (at most the
    ``cols`` asked for).  A legend's row is the plot's minimum width, so a fixed count wider than the
    panel pushed the plot out of its view and clipped its right side and labels."""

    AXES = 110  # px a plot spends on its y axes and margins

    @classmethod
    def watch(cls, view) -> None:
        if view.property("bosun_legend_fitter"):
            return
        view.setProperty("bosun_legend_fitter", True)
        view._bosun_legend_fitter = fitter = cls(view)  # a reference: PyQt would collect the wrapper
        view.installEventFilter(fitter)

    def eventFilter(self, obj, ev) -> bool:
        if ev.type() in (QEvent.Resize, QEvent.Show):  # after the view has laid out its new viewport
            QTimer.singleShot(0, lambda v=obj: fit_legends(v))
        return False


def fit_legends(view) -> None:
    """Give every header legend in ``view`` (a pyqtgraph GraphicsView) the columns that fit its plot's width."""
    if sip.isdeleted(view):  # a deferred call for a view closed meanwhile
        return
    scene = view.scene()
    if scene is None:
        return
    width = view.viewport().width()
    legends = [i for i in scene.items() if isinstance(i, pg.LegendItem) and hasattr(i, "max_cols")]
    central = getattr(view, "centralWidget", None)  # the layout the plots share
    total = (central.geometry().width() if central is not None else 0.0) or float(width) or 1.0
    changed = False
    for leg in legends:
        if not leg.items:
            continue
        plot = leg.parentItem()
        while plot is not None and not isinstance(plot, pg.PlotItem):
            plot = plot.parentItem()
        share = plot.geometry().width() / total if plot is not None else 1.0
        avail = max(60.0, width * min(1.0, share) - _LegendFitter.AXES)
        # the text's own width: a label item stretches to its cell, so its rect grows with fewer columns
        entry = max(s.boundingRect().width() + l.item.boundingRect().width() + 12 for s, l in leg.items)
        cols = int(max(1, min(leg.max_cols, len(leg.items), avail // max(entry, 1.0))))
        if cols != leg.columnCount:
            leg.setColumnCount(cols)
            changed = True
    too_wide = central is not None and central.geometry().width() > width + 0.5
    if (changed or too_wide) and isinstance(view, pg.GraphicsView):  # the plots laid out in the view's width
        QTimer.singleShot(0, lambda: _relayout(view))


def _relayout(view, tries: int = 8) -> None:
    """Lay the view's plots out again in its own width.  A legend that reflowed lowers the layout's minimum
    width only once Qt has passed the layout requests up the nested layouts (one level an event loop
    pass): until then the central item is clamped to the old, wider minimum and the plots stay cut at the
    right.  So it is tried again, a few times, until the layout fits."""
    if sip.isdeleted(view):
        return
    pg.GraphicsView.setRange(view, view.range, padding=0, disableAutoPixel=False)
    central = getattr(view, "centralWidget", None)
    if tries > 0 and central is not None and central.geometry().width() > view.viewport().width() + 0.5:
        QTimer.singleShot(25, lambda: _relayout(view, tries - 1))


def plot_title(plot: pg.PlotItem) -> str:
    """The title a plot shows (in its header beside the legend, or pyqtgraph's own)."""
    head = getattr(plot, "header_title", None)
    if head is not None:
        return getattr(head, "full_text", head.text)
    return plot.titleLabel.text if plot.titleLabel.isVisible() else ""


class TwinAxis:
    """A right-hand y axis on a PlotItem with its own ViewBox (x linked to the plot's), label and unit.

    Curves made with :meth:`plot` are drawn against it and join the plot's legend.
    """

    def __init__(self, plot: pg.PlotItem, text: str, units: str) -> None:
        self.host = plot
        self.vb = pg.ViewBox(enableMenu=False)
        scene = plot.scene()
        if scene is not None:
            scene.addItem(self.vb)
        else:  # not in a scene yet: the ViewBox follows the plot when it joins one
            self.vb.setParentItem(plot)
        plot.showAxis("right")
        plot.getAxis("right").linkToView(self.vb)
        self.vb.setXLink(plot.vb)
        self.vb.setZValue(plot.vb.zValue() + 1)
        axis_label(plot, "right", text, units)
        plot.vb.sigResized.connect(self._follow)
        self._follow()

    @property
    def axis(self) -> pg.AxisItem:
        return self.host.getAxis("right")

    def _follow(self) -> None:
        self.vb.setGeometry(self.host.vb.sceneBoundingRect())
        self.vb.linkedViewChanged(self.host.vb, self.vb.XAxis)

    def plot(self, *args, name: str | None = None, **kw) -> pg.PlotDataItem:
        item = pg.PlotDataItem(*args, **kw)
        item.setClipToView(True)
        item.setDownsampling(auto=True, method="peak")
        self.vb.addItem(item)
        if name is not None and self.host.legend is not None:
            self.host.legend.addItem(item, name)
        return item

    def set_visible(self, on: bool, keep_room: bool = False) -> None:
        """Show or hide the axis and its curves; ``keep_room`` leaves a blank axis (no values, no label) so
        plots stacked with this one keep the same width."""
        self.vb.setVisible(on)
        ax = self.axis
        if keep_room:
            self.host.showAxis("right")
            ax.setStyle(showValues=on)
            ax.showLabel(on)
        else:
            self.host.showAxis("right", on)


def view_boxes(plot: pg.PlotItem) -> list[pg.ViewBox]:
    """The plot's own ViewBox and those of its twin axes."""
    out = [plot.vb]
    ax = plot.getAxis("right")
    linked = ax.linkedView() if ax is not None else None
    if linked is not None and linked is not plot.vb:
        out.append(linked)
    return out


def refit(plot: pg.PlotItem, x: bool = True) -> None:
    """Bring every curve in view now (and keep following it): the auto range of each ViewBox is
    switched on again (an operator's zoom or a range fixed while hidden would keep the data out)."""
    for vb in view_boxes(plot):
        if not vb.isVisible():
            continue
        # a view whose x follows another's (a twin axis, plots sharing a time axis) keeps following it: its
        # own x auto range would fight the link (pyqtgraph then switches the other view's auto range off)
        follows = vb is not plot.vb or vb.linkedView(vb.XAxis) is not None
        vb.enableAutoRange(x=None if follows or not x else True, y=True)
        vb.updateAutoRange()


def blank_axis(plot: pg.PlotItem, side: str, width: int) -> None:
    """An empty axis (no values, no label) of a fixed width: plots stacked on one time axis line up."""
    plot.showAxis(side)
    ax = plot.getAxis(side)
    ax.setStyle(showValues=False)
    ax.showLabel(False)
    ax.setWidth(width)


class _ShowWatch(QObject):
    def __init__(self, widget: QWidget, action: Callable[[], None]) -> None:
        super().__init__(widget)
        self.action = action
        widget.installEventFilter(self)

    def eventFilter(self, obj, ev) -> bool:
        if ev.type() == QEvent.Show:
            QTimer.singleShot(0, self.action)  # after the layout gave the plots their size
        return False


def refit_on_show(widget: QWidget, action: Callable[[], None]) -> QObject:
    """Call ``action`` each time ``widget`` is shown (its tab chosen again)."""
    return _ShowWatch(widget, action)


def plot_items(widget: QWidget) -> list[pg.PlotItem]:
    """Every PlotItem shown in the widget's pyqtgraph views (PlotWidget and GraphicsLayoutWidget)."""
    items = []
    views = widget.findChildren(pg.GraphicsView)
    if isinstance(widget, pg.GraphicsView):
        views.insert(0, widget)
    for view in views:
        scene = view.scene()
        if scene is None:
            continue
        items += [it for it in scene.items() if isinstance(it, pg.PlotItem)]
    return items


# ---------------------------------------------------------------------------------------------- teleop plots
def _joint_kinds(desc) -> list[str] | None:
    """Revolute or prismatic per joint, read from the description's robot file (None: not known)."""
    xml = getattr(desc, "robot_xml", "")
    if not xml:
        return None
    try:
        from app.models.xml import parse_robot_xml

        spec = parse_robot_xml(xml)
    except Exception:
        return None
    serial = getattr(spec, "serial", None)
    if serial is None or len(serial.joints) != len(desc.joint_names):
        return None
    return [j.kind for j in serial.joints]


class LivePlots(QWidget):
    """X/Y/Z: the operator's command, the solver's target and the reached point; joints with limit
    bands (revolute [deg] left, prismatic [m] on a right axis); solver error [m] and time [ms] on
    two axes."""

    frame = pyqtSignal()  # emitted after each redraw: other views refresh at the same frame rate

    def __init__(self, seconds: float = 20.0, rate: float = 50.0, fps: float = 30.0, parent=None) -> None:
        super().__init__(parent)
        self.size = int(seconds * rate)
        self.seconds = seconds
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        self.glw = pg.GraphicsLayoutWidget()
        self.glw.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        lay.addWidget(self.glw)
        # no titles: each plot's legend (a header row above the curves) and its axis labels say what it
        # shows, and the room goes to the curves
        self.p_xyz = self.glw.addPlot(row=0, col=0)
        self.p_q = self.glw.addPlot(row=1, col=0)
        self.p_s = self.glw.addPlot(row=2, col=0)
        axis_label(self.p_xyz, "left", "tool", "m")
        axis_label(self.p_q, "left", "joints", "deg")
        axis_label(self.p_s, "left", "solve error", "m")
        for p in (self.p_xyz, self.p_q, self.p_s):
            p.showGrid(x=True, y=True, alpha=0.25)
            p.setClipToView(True)
            p.setDownsampling(auto=True, mode="peak")
            # a fixed time axis (−window … 0): its ticks are painted once and cached, where a
            # scrolling axis would re-render its text every frame (the main paint cost)
            p.setXRange(-seconds, 0.0, padding=0.0)
            p.disableAutoRange()  # y is re-fitted about once a second in redraw(), for the same reason
            p.getAxis("left").setWidth(58)  # the three plots' time axes line up
            p.setMinimumHeight(110)
        # one time axis for the three (linked): its values and label under the last plot only
        axis_label(self.p_s, "bottom", "time before now", "s")
        for p in (self.p_xyz, self.p_q):
            p.setXLink(self.p_s)
            p.getAxis("bottom").setStyle(showValues=False)
        self.p_xyz.setToolTip(
            "tool position in the robot's world frame [m]. Thick dotted: the operator's command (eq. 1 in position "
            "mode; eq. 7 integrated in velocity mode, from the reference when the stick was deflected; absent while "
            "nothing is commanded). Dashed: the solver's target this tick. Solid: the reached tool point."
        )
        self.p_q.setToolTip(
            "joint values with their limits as bands: revolute joints [deg] on the left axis, "
            "prismatic joints [m] on a right axis"
        )
        self.p_s.setToolTip("last solve: position error [m] (left axis) and solve time [ms] (right axis)")
        legend(self.p_xyz, cols=5)
        legend(self.p_q, cols=6)
        legend(self.p_s, cols=2)
        self.q_twin = TwinAxis(self.p_q, "prismatic", "m")
        for side in ("left", "right"):  # the joints' legend gives each its unit ("[m]"): the axes keep it
            self.p_q.getAxis(side).enableAutoSIPrefix(False)
        self.q_twin.set_visible(False, keep_room=True)
        self.s_twin = TwinAxis(self.p_s, "solve time", "ms")
        for twin in (self.q_twin, self.s_twin):
            twin.axis.setWidth(48)
            twin.vb.disableAutoRange()  # fitted in redraw(), like the left axes
        blank_axis(self.p_xyz, "right", 48)  # the three plots the same width: one time axis lines up
        grey = (170, 170, 170)
        for label, style, width in (("command", pg.QtCore.Qt.DotLine, 4), ("solver target", pg.QtCore.Qt.DashLine, 1)):
            self.p_xyz.plot([], [], pen=pg.mkPen(grey, width=width, style=style), name=label)  # legend keys
        self.cur_xyz = []
        for k, name in enumerate(XYZ):
            c = COLORS[k]
            self.cur_xyz.append(
                (
                    self.p_xyz.plot(pen=pg.mkPen(c, width=4, style=pg.QtCore.Qt.DotLine), connect="finite"),
                    self.p_xyz.plot(pen=pg.mkPen(c, width=1, style=pg.QtCore.Qt.DashLine)),
                    self.p_xyz.plot(pen=pg.mkPen(c, width=2), name=name),
                )
            )
        self.cur_q: list = []  # (curve, column, scale: deg per rad or 1)
        self.bands: list = []
        # named by their axis, not a unit: the error axis shows mm or µm as the values need (the legend's
        # "[m]" beside an axis in mm read as two units for one curve)
        self.cur_err = self.p_s.plot(pen=pg.mkPen((230, 80, 80), width=1.5), name="error (left axis)")
        self.cur_time = self.s_twin.plot(pen=pg.mkPen((80, 140, 230), width=1.5), name="time (right axis)")
        self.ring: Ring | None = None
        self.robot = None
        self.desc = None
        self.kinds: list[str] = []
        self._refit = True
        refit_on_show(self, self.refit)
        self.timer = QTimer(self)
        self.timer.setInterval(int(1000 / fps))
        self.timer.timeout.connect(self.redraw)
        self.timer.start()
        self.frames_drawn = 0

    @staticmethod
    def columns(n: int) -> tuple[str, ...]:
        """The ring's columns for an arm of n joints."""
        return (
            "t",
            *(f"command_{a}" for a in XYZ),
            *(f"target_{a}" for a in XYZ),
            *(f"tool_{a}" for a in XYZ),
            *(f"q{j + 1}" for j in range(n)),
            "solver_error",
            "solver_time_ms",
        )

    @staticmethod
    def _fit_y(vb, values: np.ndarray) -> None:
        v = values[np.isfinite(values)]
        if v.size:
            lo, hi = float(v.min()), float(v.max())
            pad = 0.08 * max(hi - lo, 1e-6 * max(1.0, abs(hi)))
            vb.setYRange(lo - pad, hi + pad, padding=0.0)

    def refit(self) -> None:
        """Shown again: the y ranges are fitted to the newest data at the next frame (not in up to a second)."""
        self._refit = True
        self.redraw()

    def set_description(self, desc) -> None:
        """Joint names, kinds and limits of the engine's robot (its ``description``)."""
        self.desc = desc
        if self.ring is not None:
            self._reset(self.n_joints, self.robot)

    @property
    def n_joints(self) -> int:
        return 0 if self.ring is None else self.ring.width - 12

    def _reset(self, n: int, robot: str) -> None:
        self.ring = Ring(self.size, self.columns(n))
        self.robot = robot
        desc = self.desc if self.desc is not None and len(self.desc.joint_names) == n else None
        kinds = (_joint_kinds(desc) if desc is not None else None) or ["revolute"] * n
        self.kinds = kinds
        for c, _, _ in self.cur_q:
            if c.getViewBox() is self.q_twin.vb:
                self.q_twin.vb.removeItem(c)
                self.p_q.legend.removeItem(c)
            else:
                self.p_q.removeItem(c)  # and from the legend
        for b, vb in self.bands:
            vb.removeItem(b)
        self.cur_q, self.bands = [], []
        # one unit per axis: revolute joints [deg] on the left, prismatic ones [m] on a right axis
        # (on the left when the arm has no revolute joint)
        left = "revolute" if "revolute" in kinds or n == 0 else "prismatic"
        self.q_twin.set_visible(left == "revolute" and "prismatic" in kinds, keep_room=True)
        if left == "revolute":
            axis_label(self.p_q, "left", "joints", "deg")
        else:
            axis_label(self.p_q, "left", "prismatic", "m")
        for j in range(n):
            c = COLORS[j % len(COLORS)]
            rev = kinds[j] == "revolute"
            scale = 180.0 / np.pi if rev else 1.0
            on_left = kinds[j] == left
            target = self.p_q if on_left else self.q_twin
            vb = self.p_q.vb if on_left else self.q_twin.vb
            if desc is not None:
                lo, hi = scale * desc.lower[j], scale * desc.upper[j]
                band = pg.LinearRegionItem(
                    (lo, hi), orientation="horizontal", movable=False, brush=pg.mkBrush(*c, 18), pen=pg.mkPen(*c, 60)
                )
                vb.addItem(band, ignoreBounds=True)
                self.bands.append((band, vb))
            name = desc.joint_names[j] if desc is not None else f"q{j + 1}"
            curve = target.plot(pen=pg.mkPen(c, width=2), name=f"{name} [{'deg' if rev else 'm'}]")
            self.cur_q.append((curve, f"q{j + 1}", scale))
        self._refit = True

    def add_state(self, state) -> None:
        if self.ring is None or state.robot != self.robot or len(state.q) != self.n_joints:
            self._reset(len(state.q), state.robot)
        err = state.solver_error
        command = state.command or (np.nan, np.nan, np.nan)
        self.ring.push(
            [
                state.t,
                *command,
                *state.target,
                *state.tool,
                *state.q,
                np.nan if err is None else err,
                1e3 * state.solver_time,
            ]
        )

    def redraw(self) -> None:
        if self.ring is None or self.ring.n == 0 or not self.isVisible():
            return
        r = self.ring
        t = r["t"] - r.latest("t")
        for a, (c_command, c_target, c_tool) in zip(XYZ, self.cur_xyz, strict=True):
            c_command.setData(t, r[f"command_{a}"], connect="finite")
            c_target.setData(t, r[f"target_{a}"])
            c_tool.setData(t, r[f"tool_{a}"])
        for c, col, scale in self.cur_q:
            c.setData(t, scale * r[col])
        self.cur_err.setData(t, r["solver_error"])
        self.cur_time.setData(t, r["solver_time_ms"])
        if self._refit or self.frames_drawn % 30 == 0:
            self._refit = False
            self._fit_y(self.p_xyz.vb, r[[f"{k}_{a}" for k in ("command", "target", "tool") for a in XYZ]])
            left = [scale * r[col] for c, col, scale in self.cur_q if c.getViewBox() is not self.q_twin.vb]
            right = [r[col] for c, col, scale in self.cur_q if c.getViewBox() is self.q_twin.vb]
            if left:
                self._fit_y(self.p_q.vb, np.stack(left))
            if right:
                self._fit_y(self.q_twin.vb, np.stack(right))
            self._fit_y(self.p_s.vb, r["solver_error"])
            self._fit_y(self.s_twin.vb, r["solver_time_ms"])
            self.p_s.setXRange(-self.seconds, 0.0, padding=0.0)  # the (linked) time axis: −window … 0 again
        self.frames_drawn += 1
        self.frame.emit()


class UtilisationBars(QWidget):
    """(q − q_min)/(q_max − q_min) per joint as bars."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.grid = QGridLayout(self)
        self.grid.setContentsMargins(4, 4, 4, 4)
        self.bars: list[QProgressBar] = []
        self.names: tuple = ()

    def update_state(self, state, desc) -> None:
        """Joint positions of a teleop snapshot against the limits of the engine's description."""
        if desc is None or len(desc.joint_names) != len(state.q):
            return
        names = tuple(desc.joint_names)
        if names != self.names:
            while self.grid.count():
                w = self.grid.takeAt(0).widget()
                if w is not None:
                    w.deleteLater()
            self.bars = []
            for j, n in enumerate(names):
                self.grid.addWidget(QLabel(n), j, 0)
                bar = QProgressBar()
                bar.setRange(0, 1000)
                bar.setTextVisible(True)
                bar.setToolTip(f"{n}: utilisation of the joint range, (q − q_min)/(q_max − q_min) [%]")
                self.grid.addWidget(bar, j, 1)
                self.bars.append(bar)
            self.names = names
            self.near = [None] * len(names)
        for j, bar in enumerate(self.bars):
            lo, hi, q = desc.lower[j], desc.upper[j], state.q[j]
            u = (q - lo) / (hi - lo) if hi > lo else 0.0
            value = round(1000 * min(max(u, 0.0), 1.0))
            if value != bar.value():
                bar.setValue(value)
                bar.setFormat(f"{100 * u:.0f} %")
            near = u < 0.05 or u > 0.95
            if near != self.near[j]:  # a style change relayouts: only when crossing the 5 % margin
                self.near[j] = near
                bar.setStyleSheet("QProgressBar::chunk { background: %s; }" % ("#d9534f" if near else "#5cb85c"))
