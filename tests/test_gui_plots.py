"""Readable plots and controls (pytest-qt offscreen): legends and one unit per axis in every tab, named ring
columns, unapplied edits kept until Apply or Esc, plots refitted when their tab comes back, labels that
elide instead of being cut, and scene engines paused while no tab shows them (STOP still latches)."""

import itertools

import numpy as np
import pytest

pytest.importorskip("PyQt5")
import pyqtgraph as pg
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QLabel, QTabWidget

from app.engine.lab_session import LabSession
from app.engine.session import Session
from app.engine.tac_session import TacSession
from app.net.snapshots import TeleopSnapshot
from tests.gui_rig import image_rgb, main_window, scene_engines
from tests.helpers import GUI_WAIT
from ui.lab.scene import LabScene2D
from ui.lab_tab import MotionLabTab
from ui.marine_tab import CraneHeadTab, SceneView2D
from ui.widgets.fields import DIRTY_COLOR
from ui.widgets.labels import ElidedLabel
from ui.widgets.plots import LivePlots, Ring, plot_items, plot_title, view_boxes
from ui.widgets.view3d import RobotView2D

MACHINE_VIEWS = (RobotView2D, SceneView2D, LabScene2D)  # drawings of the machines, not plots of signals


@pytest.fixture
def window(qtbot, tmp_path, serve):
    teleop, _ = serve(Session(robot_name="comau_smart5_3dof"), rate=200, publish_rate=25)
    win = main_window(teleop.url, tmp_path / "s.ini", **scene_engines(serve))
    qtbot.addWidget(win)
    win.show()
    qtbot.waitUntil(lambda: win.teleop.state is not None and win.teleop.state.scaling is not None, timeout=GUI_WAIT)
    yield win
    win.close()


def _show(qtbot, win, tab):
    win.tabs.setCurrentWidget(tab)
    if tab is not win.teleop:
        qtbot.waitUntil(lambda: tab.state is not None, timeout=GUI_WAIT)


def _signal_plots(page):
    """The PlotItems of a page, without those inside drawings of the machines (another concern)."""
    out = []
    for item in plot_items(page):
        w = item.getViewWidget()
        if not any(isinstance(a, MACHINE_VIEWS) for a in _ancestors(w)):
            out.append(item)
    return out


def _ancestors(w):
    while w is not None:
        yield w
        w = w.parentWidget()


def _axis_problems(plot) -> list[str]:
    """Every axis that shows values has a label and exactly one unit; titles carry no units."""
    bad = []
    title = plot_title(plot)
    if "[" in title:
        bad.append(f"unit in the title {title!r}")
    for side in ("left", "right", "bottom"):
        ax = plot.getAxis(side)
        if not ax.isVisible() or not ax.style["showValues"]:
            continue
        units = ax.labelUnits or ""
        if not ax.labelText or not units:
            bad.append(f"{title or ax.labelText!r}: {side} axis without label or unit")
        elif any(sep in units for sep in (",", " and ", "[", "/ ")) or any(sep in ax.labelText for sep in ("[", "]")):
            bad.append(f"{title or ax.labelText!r}: {side} axis {ax.labelText!r} ({units}) mixes units")
    return bad


def test_ring_columns_are_named():
    r = Ring(4, ("t", "x", "y"))
    for k in range(6):
        r.push([k, 10 * k, 100 * k])
    assert r.columns == ("t", "x", "y") and r.n == 4
    assert r["x"].tolist() == [20, 30, 40, 50]  # oldest first after wrapping
    assert r["t", "y"].shape == (4, 2) and r.latest("y") == 500
    r.push(t=6, y=7)  # by name; a column not given is NaN
    assert np.isnan(r.latest("x")) and r.latest("y") == 7
    with pytest.raises(KeyError):
        r.push(z=1)
    with pytest.raises(ValueError):
        r.push([1, 2])
    assert LivePlots.columns(2)[7:12] == ("tool_x", "tool_y", "tool_z", "q1", "q2")


def test_every_plot_has_a_legend_and_one_unit_per_axis(qtbot, window):
    win = window
    pages = {"teleop": (win.teleop, [None])}
    _show(qtbot, win, win.crane_head)
    pages["crane head"] = (win.crane_head, [None])
    _show(qtbot, win, win.motion_lab)
    pages["Motion-Lab"] = (win.motion_lab, list(range(win.motion_lab.tabs.count())))
    win.tabs.setCurrentWidget(win.teleop)
    problems, seen = [], {}
    for name, (page, subtabs) in pages.items():
        win.tabs.setCurrentWidget(page)
        for sub in subtabs:
            if sub is not None:
                page.tabs.setCurrentIndex(sub)
            qtbot.wait(200)
            for plot in _signal_plots(page):
                seen[id(plot)] = name
                label = plot_title(plot) or plot.getAxis("left").labelText
                if plot.legend is None or len(plot.legend.items) < 1:
                    problems.append(f"{name}: {label!r} has no legend")
                problems += [f"{name}: {p}" for p in _axis_problems(plot)]
    counts = {n: list(seen.values()).count(n) for n in pages}
    assert counts["teleop"] == 3 and counts["crane head"] == 6 and counts["Motion-Lab"] >= 7, counts
    assert problems == []
    # the solver's error [m] and time [ms] on two axes of one plot, the vessel's heave [m] and angles [deg] too
    assert win.teleop.plots.p_s.getAxis("right").labelUnits == "ms"
    assert win.crane_head.p_eta.getAxis("left").labelUnits == "m"
    assert win.crane_head.p_eta.getAxis("right").labelUnits == "deg"


def test_typed_edit_survives_engine_states_until_apply_and_esc_reverts(qtbot, window):
    win = window
    tab = win.teleop
    k_p = tab.k_p
    engine_kp = tab.state.scaling.k_p[0]
    typed = round(engine_kp + 0.25, 3)
    k_p.setFocus()
    k_p.selectAll()
    qtbot.keyClicks(k_p, f"{typed:.3f}")
    assert k_p.value() == pytest.approx(typed)
    tab.x_w[0].setFocus()  # the operator moves on to another field without applying
    seq0 = tab.link._worker.state_seq
    qtbot.wait(1800)  # > 1.5 s of engine states
    assert tab.link._worker.state_seq - seq0 > 10
    assert tab.state.scaling.k_p[0] == pytest.approx(engine_kp, abs=1e-9)  # the engine still has its value …
    assert k_p.value() == pytest.approx(typed)  # … and the operator's edit stays
    assert k_p.property("dirty") and DIRTY_COLOR in k_p.styleSheet()
    assert "Esc reverts" in k_p.toolTip()
    k_p.setFocus()
    qtbot.keyClick(k_p, Qt.Key_Escape)
    assert k_p.value() == pytest.approx(engine_kp, abs=1e-3) and not k_p.property("dirty")
    assert DIRTY_COLOR not in k_p.styleSheet()
    # an applied edit: the engine takes it and the highlight goes
    k_p.setValue(typed)
    assert k_p.property("dirty")
    tab.apply_scaling.click()
    qtbot.waitUntil(lambda: tab.state.scaling.k_p[0] == pytest.approx(typed), timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: not k_p.property("dirty"), timeout=GUI_WAIT)
    assert k_p.value() == pytest.approx(typed)

    # the crane head's sea fields follow the engine's sea the same way
    ch = win.crane_head
    _show(qtbot, win, ch)
    qtbot.waitUntil(lambda: ch.state.sea is not None, timeout=GUI_WAIT)
    ch.hs.setValue(5.5)
    qtbot.wait(1800)
    assert ch.state.sea.hs == 3.0 and ch.hs.value() == 5.5 and ch.hs.property("dirty")
    qtbot.keyClick(ch.hs, Qt.Key_Escape)
    assert ch.hs.value() == 3.0 and not ch.hs.property("dirty")


def _teleop_snapshot(t, tool):
    return TeleopSnapshot(
        t=t, robot="r", solver="jacobian", q=[0.1, 0.2], qdot=[0, 0], tool=list(tool), target=list(tool),
        solver_error=1e-4, solver_time=0.002,
    )  # fmt: skip


def _in(lo_hi, values) -> bool:
    lo, hi = lo_hi
    return all(lo <= v <= hi for v in np.atleast_1d(values))


def test_teleop_plots_come_back_fitted_to_the_newest_data(qtbot):
    tabs = QTabWidget()
    plots = LivePlots()
    tabs.addTab(plots, "plots")
    tabs.addTab(QLabel("other"), "other")
    qtbot.addWidget(tabs)
    tabs.resize(600, 700)
    tabs.show()
    for k in range(100):
        plots.add_state(_teleop_snapshot(0.02 * k, (1.0, 1.0, 1.0)))
    qtbot.waitUntil(lambda: plots.frames_drawn > 2, timeout=GUI_WAIT)
    tabs.setCurrentIndex(1)
    qtbot.wait(100)
    for k in range(100, 200):  # the tool moves far while the tab is hidden
        plots.add_state(_teleop_snapshot(0.02 * k, (40.0, -30.0, 55.0)))
    plots.frames_drawn = 1  # mid-second: the once-a-second fit is 29 frames away
    tabs.setCurrentIndex(0)
    qtbot.waitUntil(lambda: plots.frames_drawn >= 3, timeout=GUI_WAIT)
    assert _in(plots.p_xyz.viewRange()[1], (40.0, -30.0, 55.0))
    assert _in(plots.p_xyz.viewRange()[0], 0.0)  # the newest sample is at "0 s before now"


def _tac_states(session, n, t0, offset=0.0):
    out = []
    for k in range(n):
        session.tick(t0 + 0.04 * k, 0.04)
        st = session.snapshot()
        st.sample.e_s += offset
        st.sample.eta[2] += offset
        out.append(st)
    return out


def test_crane_head_plots_come_back_fitted_to_the_newest_data(qtbot):
    tabs = QTabWidget()
    tab = CraneHeadTab(None, use_gl=False)
    tabs.addTab(tab, "crane head")
    tabs.addTab(QLabel("other"), "other")
    qtbot.addWidget(tabs)
    tabs.resize(1200, 800)
    tabs.show()
    session = TacSession()
    for st in _tac_states(session, 60, 0.0):
        tab.on_state(st)
    qtbot.wait(200)
    for p in (tab.p_err, tab.p_eta):  # the operator zoomed into the first second, then left the tab
        p.vb.setRange(xRange=(0.0, 1.0), yRange=(0.0, 0.001))
    tabs.setCurrentIndex(1)
    qtbot.wait(100)
    for st in _tac_states(session, 150, 3.0, offset=20.0):
        tab.on_state(st)
    last = st.sample
    tabs.setCurrentIndex(0)

    def fitted():  # the re-fit runs on the next paint, which a busy machine delays (seen beside a CPU hog)
        assert _in(tab.p_err.viewRange()[0], last.t) and _in(tab.p_err.viewRange()[1], last.e_s)
        assert _in(tab.p_eta.viewRange()[1], last.eta[2])  # heave [m]
        roll_range = view_boxes(tab.p_eta)[1].viewRange()[1]  # the twin axis of the angles [deg]
        assert _in(roll_range, np.degrees(last.eta[3]))

    qtbot.waitUntil(fitted, timeout=30_000)


def test_lab_plots_come_back_fitted_to_the_newest_data(qtbot):
    tab = MotionLabTab(None, use_gl=False)
    qtbot.addWidget(tab)
    tab.resize(1200, 800)
    tab.show()
    tab.tabs.setCurrentIndex(2)  # Comau & winch
    session = LabSession()

    def feed(n, t0, offset):
        for k in range(n):
            session.tick(t0 + 0.04 * k, 0.04)
            st = session.snapshot()
            st.comau.q = [q + offset for q in st.comau.q]
            tab.on_state(st)
        return st

    feed(60, 0.0, 0.0)
    qtbot.wait(200)
    tab.comau.joint_plot.getPlotItem().vb.setRange(xRange=(0.0, 0.5), yRange=(-1.0, 1.0))  # zoomed in, then left
    tab.tabs.setCurrentIndex(0)
    qtbot.wait(100)
    last = feed(100, 3.0, 2.0)  # +2 rad: far out of the zoomed range
    tab.tabs.setCurrentIndex(2)
    qtbot.wait(500)
    x_range, y_range = tab.comau.joint_plot.getPlotItem().viewRange()
    assert _in(x_range, tab.ring.view()[-1, 0])  # the newest sample plotted (25 per second of engine time)
    assert _in(y_range, np.degrees(last.comau.q))


def test_long_texts_elide_and_nothing_is_cut(qtbot, window):
    win = window
    light = win.status.lights["input"]
    assert isinstance(light, ElidedLabel)
    light.set("warn", "not armed: on-screen stick / keyboard and a long device name " * 3)
    qtbot.wait(50)
    assert light.elided() and light.shown_text().endswith("…")
    assert light.width() < win.width()  # it elides, never widens the window
    # the teleop controls: the scroll area is as wide as the controls need
    controls = win.teleop.k_p.parentWidget().parentWidget()
    area = controls.parentWidget().parentWidget()
    assert area.viewport().width() >= controls.minimumSizeHint().width()
    # the scaling grid: x, y, z headed over the x_w fields, every row label left of its fields
    tab = win.teleop
    grid = tab.k_p.parentWidget().layout()
    heads = [grid.itemAtPosition(0, 1 + k).widget() for k in range(3)]
    assert [h.text() for h in heads] == ["x", "y", "z"]
    for head, field in zip(heads, tab.x_w, strict=True):
        assert abs(head.geometry().center().x() - field.geometry().center().x()) <= 2
    for row, fields in ((1, tab.x_w), (2, [tab.k_p]), (3, [tab.k_v])):
        label = grid.itemAtPosition(row, 0).widget()
        assert label.geometry().right() < fields[0].geometry().left()
        assert abs(label.geometry().center().y() - fields[0].geometry().center().y()) <= 3


def _paused(tab):
    return tab.state is not None and tab.state.engine.paused


def test_hidden_scene_engines_pause_and_still_latch_stop(qtbot, window):
    win = window
    ch, lab = win.crane_head, win.motion_lab
    _show(qtbot, win, ch)
    qtbot.waitUntil(lambda: ch.state.sample is not None and not _paused(ch), timeout=GUI_WAIT)
    win.tabs.setCurrentWidget(win.teleop)  # no tab shows the crane head: its engine pauses
    qtbot.waitUntil(lambda: _paused(ch), timeout=GUI_WAIT)
    t0 = ch.state.sample.t
    qtbot.wait(600)
    assert ch.state.sample.t == t0  # its time stands still
    # STOP is not held back by the pause: the paused engine latches it and the window confirms it
    win.estop("test")
    qtbot.waitUntil(lambda: ch.state.estop and "crane head" not in win.estop_pending, timeout=GUI_WAIT)
    assert _paused(ch) and ch.state.engine.estops >= 1
    win.reset()
    qtbot.waitUntil(lambda: not ch.state.estop and not win.teleop.state.estop, timeout=GUI_WAIT)
    # shown again: it resumes; the lab, shown now, runs while the crane head pauses again
    _show(qtbot, win, lab)
    qtbot.waitUntil(lambda: _paused(ch) and lab.state is not None and not _paused(lab), timeout=GUI_WAIT)
    win.tabs.setCurrentWidget(ch)
    qtbot.waitUntil(lambda: not _paused(ch) and _paused(lab), timeout=GUI_WAIT)
    qtbot.waitUntil(lambda: ch.state.sample.t > t0 + 0.2, timeout=GUI_WAIT)
    win.tabs.setCurrentWidget(win.analysis)
    qtbot.waitUntil(lambda: _paused(ch) and _paused(lab), timeout=GUI_WAIT)


def test_plots_are_pyqtgraph_plot_items(qtbot):
    """plot_items() finds the PlotItems of PlotWidgets and GraphicsLayoutWidgets alike (the legend test's base)."""
    w = pg.GraphicsLayoutWidget()
    qtbot.addWidget(w)
    w.addPlot(row=0, col=0)
    w.addPlot(row=1, col=0)
    pw = pg.PlotWidget(parent=w)
    assert len(plot_items(w)) == 3 and pw.getPlotItem() in plot_items(w)


def _crane_plots(qtbot, width: int) -> LivePlots:
    """The teleop plots of the knuckle-boom crane, shown ``width`` × 600 px."""
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.set_description(Session(robot_name="knuckle_boom_crane").describe())
    plots.resize(width, 600)
    plots.show()
    qtbot.waitExposed(plots)
    return plots


def _right_edges(plots: LivePlots) -> list[float]:
    """The right edges of the three plots in their scene [px], to compare with the view's width."""
    return [p.mapRectToScene(p.boundingRect()).right() for p in (plots.p_xyz, plots.p_q, plots.p_s)]


def test_legends_reflow_so_a_narrow_panel_shows_whole_plots(qtbot):
    """A legend row is a plot's minimum width: five entries in one row pushed the teleop plots out of a
    280 px panel and cut their right side ("solver ta", "time be").  The legends reflow to the width."""
    plots = _crane_plots(qtbot, 280)
    # the layout settles over a few events (slow on a loaded machine); with one-row legends it never fits
    qtbot.waitUntil(lambda: max(_right_edges(plots)) <= plots.glw.viewport().width() + 1, timeout=GUI_WAIT)
    assert plots.p_xyz.legend.columnCount < 5
    plots.resize(1100, 600)
    qtbot.waitUntil(lambda: plots.p_xyz.legend.columnCount == 5, timeout=GUI_WAIT)
    assert max(_right_edges(plots)) <= plots.glw.viewport().width() + 1


def test_plots_narrowed_after_a_wide_start_are_laid_out_in_the_narrow_view(qtbot):
    """In the 1280×800 window the plot panel is first laid out wide (five legend entries a row), then the
    splitter narrows it to ~265 px: the legends reflowed, but the plots kept the wide layout and were cut at
    the right (no right axes, no "0" on the time axis).  The plots follow the view's width."""
    plots = _crane_plots(qtbot, 1100)
    qtbot.waitUntil(lambda: plots.p_xyz.legend.columnCount == 5, timeout=GUI_WAIT)
    qtbot.wait(100)
    plots.resize(265, 600)
    qtbot.waitUntil(lambda: plots.p_xyz.legend.columnCount < 5, timeout=GUI_WAIT)
    qtbot.wait(300)
    width = plots.glw.viewport().width()
    assert max(_right_edges(plots)) <= width + 1, (_right_edges(plots), width)
    # the right axes (solve time, prismatic joints) are inside the view
    for twin in (plots.s_twin, plots.q_twin):
        ax = twin.axis
        assert ax.mapRectToScene(ax.boundingRect()).right() <= plots.glw.viewport().width() + 1


def test_teleop_legend_units_are_the_units_their_axes_show(qtbot):
    """A solve error of 0.1 mm: the axis shows "µm" or "mm" (SI prefix), so a legend entry "error [m]" read as
    another unit for the same curve.  A unit in a legend entry is the one its axis shows."""
    import re

    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.resize(700, 700)
    plots.show()
    qtbot.waitExposed(plots)
    for k in range(100):
        plots.add_state(_teleop_snapshot(0.02 * k, (1.0, 1.0, 1.0)))
    plots.refit()
    qtbot.waitUntil(lambda: plots.frames_drawn > 2, timeout=GUI_WAIT)
    qtbot.wait(100)
    axes = {id(plots.p_s.vb): plots.p_s.getAxis("left"), id(plots.s_twin.vb): plots.s_twin.axis,
            id(plots.p_q.vb): plots.p_q.getAxis("left"), id(plots.q_twin.vb): plots.q_twin.axis}  # fmt: skip
    checked = 0
    for p in (plots.p_q, plots.p_s):
        for sample, label in p.legend.items:
            m = re.search(r"\[(.+?)\]", label.text)
            if m is None:
                continue
            ax = axes[id(sample.item.getViewBox())]
            assert f"{ax.labelUnitPrefix}{ax.labelUnits}" == m.group(1), (label.text, ax.labelUnitPrefix)
            checked += 1
    assert checked >= 2  # the joints' entries at least
    err_axis = plots.p_s.getAxis("left")
    assert err_axis.labelUnitPrefix in ("µ", "m")  # the error axis does scale its unit: the reason for the test


def test_long_plot_titles_elide_so_two_columns_fit_their_view(qtbot):
    """The crane head's 2×2 figures in a 540 px column: a bold title's width was its plot's minimum width, so the
    layout was wider than the view and Figs. 9 and 12 were cut at the right.  Titles end in "…" instead."""
    from ui.widgets.plots import legend

    glw = pg.GraphicsLayoutWidget()
    qtbot.addWidget(glw)
    titles = ["Fig. 11 compensation error of the head", "Fig. 12 Delta arm angles and commands"]
    plots = []
    for col, title in enumerate(titles):
        p = glw.addPlot(row=0, col=col, title=title)
        p.getAxis("left").setWidth(54)
        p.showAxis("right")
        p.getAxis("right").setWidth(50)
        legend(p, cols=2)
        p.plot([0, 1], [0, 1], name="a")
        plots.append(p)
    glw.resize(420, 300)
    glw.show()
    qtbot.waitExposed(glw)
    qtbot.wait(300)
    width = glw.viewport().width()
    rects = [p.mapRectToScene(p.boundingRect()) for p in plots]
    assert rects[0].right() <= rects[1].left() + 1 and rects[1].right() <= width + 1, (rects, width)
    for p, title in zip(plots, titles, strict=True):
        assert plot_title(p) == title and p.header_title.toolTip() == title  # the whole title stays known
    assert any(p.header_title.text.endswith("…") for p in plots)
    glw.resize(1400, 300)  # room again: the whole titles
    qtbot.waitUntil(lambda: all(p.header_title.text == t for p, t in zip(plots, titles, strict=True)), timeout=GUI_WAIT)


def test_error_distribution_projections_fit_the_box_with_a_scale_and_marked_unreachable_targets(qtbot):
    """Analysis (offscreen, without OpenGL): the three projections were ~60 px tall, ±300 m wide with every
    target in one block at 0 and a stray "target" legend entry.  Now: fitted to the workspace box at one scale
    on both axes, side by side with height, a colour scale, and the unreachable targets ringed red under a
    legend entry that says what the ring means."""
    from app.analysis.ik_studies import ErrorDistribution
    from ui.analysis_tab import UNREACHABLE_PEN, AnalysisTab

    lo, hi = np.array([-25.0, -25.0, -10.0]), np.array([25.0, 25.0, 25.0])
    axes = [np.linspace(lo[k], hi[k], 4) for k in range(3)]
    targets = np.array([[x, y, z] for x in axes[0] for y in axes[1] for z in axes[2]])
    reachable = np.abs(targets[:, 0]) < 10.0
    error = np.where(reachable, 1e-5, 3.0)
    n = len(targets)
    result = ErrorDistribution(
        robot="r", solver="jacobian", grid=4, targets=targets, reached=targets, error=error, time_s=np.zeros(n),
        success=reachable, reachable=reachable, box_lower=lo, box_upper=hi,
    )  # fmt: skip
    tab = AnalysisTab(None)
    qtbot.addWidget(tab)
    tab.resize(1276, 470)
    tab.show()
    qtbot.waitExposed(tab)
    tab.show_result(result)
    qtbot.wait(300)
    assert tab.colorbar is not None and len(tab.projections) == 3
    rects = []
    for p, (i, j) in zip(tab.projections, ((0, 1), (0, 2), (1, 2)), strict=True):
        (x0, x1), (y0, y1) = p.vb.viewRange()
        assert x0 <= lo[i] and x1 >= hi[i] and y0 <= lo[j] and y1 >= hi[j]  # the whole box …
        assert (x1 - x0) < 3 * (hi[i] - lo[i]) and (y1 - y0) < 3 * (hi[j] - lo[j])  # … and not hundreds of m
        px, py = p.vb.viewPixelSize()
        assert px == pytest.approx(py, rel=0.03)  # one scale on both axes
        r = p.vb.mapRectToScene(p.vb.boundingRect())
        assert r.height() >= 150
        rects.append(r)
    for a, b in itertools.pairwise(rects):
        assert a.right() <= b.left() + 1
    bar = tab.colorbar.mapRectToScene(tab.colorbar.boundingRect())
    assert bar.left() >= rects[-1].right() - 1 and bar.right() <= tab.glw.viewport().width() + 1
    texts = [label.text for _, label in tab.key.items]
    assert "target" not in texts and any("not reachable (32 of 64)" in t for t in texts), texts
    # the pixels: a red ring around an unreachable target, none around a reachable one (top view)
    img = image_rgb(tab.glw.grab().toImage()).astype(int)
    red = np.abs(img - np.array(UNREACHABLE_PEN)).max(axis=-1) < 40
    top = tab.projections[0]

    def ring(k):
        sp = top.vb.mapViewToScene(pg.Point(float(targets[k, 0]), float(targets[k, 1])))
        vp = tab.glw.mapFromScene(sp)
        yy, xx = np.mgrid[0 : red.shape[0], 0 : red.shape[1]]
        d = np.hypot(xx - vp.x(), yy - vp.y())
        return int(red[(d >= 4) & (d <= 8)].sum())

    bad = int(np.flatnonzero(~reachable)[0])
    good = int(np.flatnonzero(reachable)[0])
    assert ring(bad) >= 8 and ring(good) == 0, (ring(bad), ring(good))
