"""What an operator sees on a 1280×800 screen (Xvfb, Mesa software OpenGL), checked in the screen's pixels.

Issue 15: "draw the machines as they are" and "readable plots".  The window is driven through every tab
with its engines running; each check is on what the X server shows:

* no page needs scrolling (a Motion-Lab page was 890 px tall: its plots and the lab's 3D view were cut at
  the bottom of the visible part);
* the 3D views show the machines whole: the lab's EM1500 deck and the load inside the view, the crane
  head's view more than a strip (it was 130 px tall);
* no plot is laid out wider than its view (the teleop plots lost their right axes, the crane head's
  Figs. 9 and 12 their right side);
* the error distribution: projections fitted to the workspace box at one scale, enough height, side by
  side without overlap, a colour scale, unreachable targets ringed red with a legend that says so, in the
  3D scatter too (whole box in view); a tracking study hides the distribution's 3D scatter.
"""

import itertools

import numpy as np
import pytest

pytest.importorskip("PyQt5")

from tests.gui_rig import run_under_xvfb

SCRIPT = r"""
import json, sys
import numpy as np
from tests.gui_rig import gl_app, image_rgb, open_window, pump, scene_engines, screen_rgb, wait
app = gl_app()
import pyqtgraph as pg
from PyQt5.QtCore import QPoint
from PyQt5.QtGui import QGuiApplication
from PyQt5.QtWidgets import QTabWidget
from app.engine.session import Session
from tests.helpers import start_engine
from ui.widgets.plots import plot_items

def origin(w):
    p = w.mapToGlobal(QPoint(0, 0))
    return np.array([p.x(), p.y()], dtype=float)

def page_scrolls():
    area = QTabWidget.widget(win.tabs, win.tabs.currentIndex())  # the page's scroll area (ui/main_window.py)
    return area.verticalScrollBar().maximum()

def wholly_visible(w):
    return w.isVisible() and w.visibleRegion().boundingRect() == w.rect()

def cut_plots(page):
    out = []
    for p in plot_items(page):
        view = p.scene().views()[0]
        if not view.isVisible():
            continue
        r = p.mapRectToScene(p.boundingRect())
        if r.right() > view.viewport().width() + 1 or r.bottom() > view.viewport().height() + 1:
            out.append([p.getAxis("left").labelText, r.right(), view.viewport().width()])
    return out

def red(a):
    r, g, b = (a[..., i].astype(int) for i in range(3))
    return (r > 150) & (g < 110) & (b < 110)

def ring_at(mask, x, y, r_in=4, r_out=9):
    # red pixels in an annulus around (x, y): a ring, not a filled dot
    h, w = mask.shape
    yy, xx = np.mgrid[0:h, 0:w]
    d = np.hypot(xx - x, yy - y)
    return bool(mask[(d >= r_in) & (d <= r_out)].sum() >= 6)

teleop, _ = start_engine(Session(robot_name="knuckle_boom_crane"), 100, publish_rate=25, duration=400.0)
win = open_window(teleop.url, **scene_engines(start_engine, 400.0))
pump(2.0)
out = {"frame": [win.frameGeometry().width(), win.frameGeometry().height()]}

# teleop: the live plots inside their panel (right axes and all)
out["teleop_scrolls"] = page_scrolls()
out["teleop_cut"] = cut_plots(win.teleop)
out["teleop_twin_right"] = [max(t.axis.mapRectToScene(t.axis.boundingRect()).right() for t in
                                (win.teleop.plots.s_twin, win.teleop.plots.q_twin)),
                            win.teleop.plots.glw.viewport().width()]

# the crane head: the scene more than a strip, the vessel on screen in it, the plots whole
ch = win.crane_head
win.tabs.setCurrentWidget(ch)
assert wait(lambda: ch.state is not None), "no crane-head state"
pump(3.0)
out["crane_scrolls"] = page_scrolls()
box = ch.scene.machines.box
out["crane_view"] = [box.width(), box.height(), wholly_visible(box)]
s = screen_rgb()
x0, y0 = origin(box).astype(int)
a = s[y0: y0 + box.height(), x0: x0 + box.width()].astype(int)
r, g, b = a[..., 0], a[..., 1], a[..., 2]
out["crane_deck_px"] = int(((abs(r - g) < 14) & (abs(g - b) < 14) & (r > 120)).sum())  # the grey deck
out["crane_cut"] = cut_plots(ch)
QGuiApplication.primaryScreen().grabWindow(0).save(sys.argv[1] + ".crane.png")

# the Motion-Lab: no page scrolls; the scene shows both decks and the load inside the view
ml = win.motion_lab
win.tabs.setCurrentWidget(ml)
assert wait(lambda: ml.state is not None and ml.state.scene is not None), "no lab state"
scrolls, cut = [], []
for i in range(ml.tabs.count()):
    ml.tabs.setCurrentIndex(i)
    pump(1.0)
    scrolls.append(page_scrolls())
    cut += cut_plots(ml.tabs.widget(i))
out["lab_scrolls"], out["lab_cut"] = scrolls, cut
ml.tabs.setCurrentIndex(3)  # Scene & load (Load swing is the last page)
pump(1.0)
QGuiApplication.primaryScreen().grabWindow(0).save(sys.argv[1] + ".lab.png")
m = ml.scene.machines
pump(1.0)
sc = ml.state.scene
top2 = np.asarray(sc.platforms["em1500"]["top"], dtype=float)
base2 = np.asarray(sc.platforms["em1500"]["base"], dtype=float)
pts = m.project(np.vstack([top2, base2, [sc.payload]]))
out["lab_view"] = [m.box.width(), m.box.height(), wholly_visible(m.box)]
out["lab_points_in_view"] = bool(((pts[:, 0] >= 0) & (pts[:, 0] < m.box.width()) & (pts[:, 1] >= 0)
                                  & (pts[:, 1] < m.box.height())).all())
s = screen_rgb()
x0, y0 = origin(m.box)
c = pts[:6].mean(axis=0) + (x0, y0)  # EM1500's deck centre on screen
a = s[int(c[1]) - 6: int(c[1]) + 7, int(c[0]) - 6: int(c[0]) + 7].astype(int)
r, g, b = a[..., 0], a[..., 1], a[..., 2]
out["lab_deck_blue"] = int(((b > 80) & (b > 1.3 * r) & (b > 1.25 * g)).sum())

# Analysis: an error distribution of the knuckle-boom crane (most of its box is out of reach)
an = win.analysis
win.tabs.setCurrentWidget(an)
pump(0.5)
an.grid.setValue(4)
an.solver.setCurrentText("jacobian")
an.start("distribution")
assert wait(lambda: an.result is not None and not an.running, 200.0), "no study result"
pump(2.0)
res = an.result
bad = ~np.asarray(res.reachable, dtype=bool)
out["bad"] = int(bad.sum())
out["analysis_scrolls"] = page_scrolls()
out["analysis_cut"] = cut_plots(an)
lo, hi = np.asarray(res.box_lower, float), np.asarray(res.box_upper, float)
proj = []
for p, (i, j) in zip(an.projections, ((0, 1), (0, 2), (1, 2))):
    (x_lo, x_hi), (y_lo, y_hi) = p.vb.viewRange()
    px, py = p.vb.viewPixelSize()
    rect = p.vb.mapRectToScene(p.vb.boundingRect())
    proj.append({"contains": bool(x_lo <= lo[i] and x_hi >= hi[i] and y_lo <= lo[j] and y_hi >= hi[j]),
                 "span_ratio": max((x_hi - x_lo) / (hi[i] - lo[i]), (y_hi - y_lo) / (hi[j] - lo[j])),
                 "aspect": px / py, "rect": [rect.left(), rect.top(), rect.width(), rect.height()]})
out["projections"] = proj
out["legend"] = [label.text for _, label in an.key.items]
bar = an.colorbar.mapRectToScene(an.colorbar.boundingRect())
out["colorbar_inside"] = bool(bar.right() <= an.glw.viewport().width() + 1 and bar.height() > 100)
# the red rings in the 2D projections, where the unreachable targets are, on screen
QGuiApplication.primaryScreen().grabWindow(0).save(sys.argv[1] + ".analysis.png")
s = screen_rgb()
mask = red(s)
gx, gy = origin(an.glw)
rings2d = []
for p, (i, j) in zip(an.projections, ((0, 1), (0, 2), (1, 2))):
    k = int(np.flatnonzero(bad)[0])
    sp = p.vb.mapViewToScene(pg.Point(float(res.targets[k, i]), float(res.targets[k, j])))
    vp = an.glw.mapFromScene(sp)
    rings2d.append(ring_at(mask, gx + vp.x(), gy + vp.y()))
out["rings2d"] = rings2d
# and in the 3D scatter: the whole box in view, a red ring on screen around an unreachable target
sv = an.scatter
out["scatter_view"] = [sv.box.width(), sv.box.height(), wholly_visible(sv.box)]
from ui.widgets.view3d import RobotDrawing, _box_edges
draw = RobotDrawing(); draw.set_description(win.teleop.desc)
corners = sv.project(draw.up(_box_edges(lo, hi)))
out["box_in_3d_view"] = bool(((corners[:, 0] >= 0) & (corners[:, 0] < sv.box.width()) & (corners[:, 1] >= 0)
                              & (corners[:, 1] < sv.box.height())).all())
sx, sy = origin(sv.box)
tp = sv.project(draw.up(res.targets))
out["rings3d"] = float(np.mean([ring_at(mask, sx + tp[k, 0], sy + tp[k, 1], 3, 9) for k in np.flatnonzero(bad)]))
out["rings3d_on_reachable"] = float(np.mean([ring_at(mask, sx + tp[k, 0], sy + tp[k, 1], 3, 9)
                                             for k in np.flatnonzero(~bad)])) if (~bad).any() else 0.0
# a tracking study: the distribution's 3D scatter goes, the three plots get the room
an.start("tracking")
assert wait(lambda: hasattr(an.result, "t") and not an.running, 200.0), "no tracking result"
pump(1.0)
out["scatter_after_tracking"] = bool(sv.isVisible())
out["tracking_heights"] = [p.vb.mapRectToScene(p.vb.boundingRect()).height() for p in plot_items(an)]
out["analysis_cut_tracking"] = cut_plots(an)

# the camera fit: a box seen from every preset is whole in a square and in a wide, low view (the scatter's
# box was cut at the sides in a square view, the lab at the top and bottom of a wide one)
from ui.widgets.machines3d import MachineView3D, PRESETS
from ui.widgets.view3d import _box_edges as edges
fits = []
for size in ((520, 520), (760, 330)):
    mv = MachineView3D(background=(0, 0, 0))
    mv.resize(*size); mv.show()
    pump(0.5)
    lo3, hi3 = np.array([-25.0, -25.0, -10.0]), np.array([25.0, 25.0, 25.0])
    mv.set_line("box", edges(lo3, hi3), (1, 0, 1, 1), 2, mode="lines")
    mv.set_extent(lo3, hi3)
    for key in PRESETS:
        mv.set_preset(key)
        pump(0.2)
        img = image_rgb(mv.grab_image())
        h, w = img.shape[:2]
        r, g, b = (img[..., i].astype(int) for i in range(3))
        magenta = (r > 150) & (g < 90) & (b > 150)
        ys, xs = np.nonzero(magenta)
        c = mv.project(edges(lo3, hi3))
        fits.append({"size": [w, h], "preset": key, "px": int(magenta.sum()),
                     "corners_in": bool(((c[:, 0] >= 0) & (c[:, 0] < w) & (c[:, 1] >= 0) & (c[:, 1] < h)).all()),
                     "edge_free": bool(xs.size and xs.min() > 1 and ys.min() > 1 and xs.max() < w - 2
                                       and ys.max() < h - 2),
                     "fill": float(max((xs.max() - xs.min()) / w, (ys.max() - ys.min()) / h)) if xs.size else 0.0})
    mv.close()
out["fits"] = fits
print("RESULT " + json.dumps(out))
sys.stdout.flush()
import os
os._exit(0)
"""


@pytest.mark.gl
def test_every_tab_readable_on_a_1280x800_screen(tmp_path):
    out = run_under_xvfb(SCRIPT, tmp_path, screen="1280x800", timeout=420)
    assert out["frame"][0] <= 1280 and out["frame"][1] <= 800
    # no page scrolls: plots and views get the visible height
    assert out["teleop_scrolls"] == 0 and out["crane_scrolls"] == 0 and out["analysis_scrolls"] == 0, out
    assert out["lab_scrolls"] == [0] * 5, out["lab_scrolls"]  # the five Motion-Lab pages (with Load swing)
    # no plot wider or taller than its view (right axes, time axis and titles whole)
    for key in ("teleop_cut", "crane_cut", "lab_cut", "analysis_cut", "analysis_cut_tracking"):
        assert out[key] == [], (key, out[key])
    right, width = out["teleop_twin_right"]
    assert right <= width + 1, out["teleop_twin_right"]
    # the crane head's scene is a view, not a strip, and shows the vessel's deck
    w, h, whole = out["crane_view"]
    assert whole and h >= 300 and w >= 240, out["crane_view"]
    assert out["crane_deck_px"] > 200, out
    # the lab's scene: wholly visible, EM1500 (deck and base) and the load inside it, the deck blue on screen
    w, h, whole = out["lab_view"]
    assert whole and h >= 300, out["lab_view"]
    assert out["lab_points_in_view"], out
    assert out["lab_deck_blue"] > 20, out
    # the error distribution's projections: fitted to the box, one scale, tall enough, apart from each other
    assert out["bad"] > 0
    rects = []
    for p in out["projections"]:
        assert p["contains"] and p["span_ratio"] < 3.0, p
        assert abs(p["aspect"] - 1.0) < 0.03, p
        assert p["rect"][3] >= 150, p
        rects.append(p["rect"])
    for a, b in itertools.pairwise(rects):
        assert a[0] + a[2] <= b[0] + 1, (a, b)  # side by side, not over each other
    assert out["colorbar_inside"]
    assert any("not reachable" in t for t in out["legend"]) and "target" not in out["legend"], out["legend"]
    assert all(out["rings2d"]), out["rings2d"]
    # the 3D scatter: the whole box in view, rings around the unreachable targets
    w, h, whole = out["scatter_view"]
    assert whole and h >= 200, out["scatter_view"]
    assert out["box_in_3d_view"]
    assert out["rings3d"] > 0.6 and out["rings3d_on_reachable"] < out["rings3d"] - 0.3, out
    # tracking: the distribution's scatter is gone, the three plots have height
    assert not out["scatter_after_tracking"]
    assert len(out["tracking_heights"]) == 3 and min(out["tracking_heights"]) >= 60, out["tracking_heights"]
    # the camera fit: every preset shows the whole box, not lost in a corner either
    for f in out["fits"]:
        assert f["px"] > 50 and f["corners_in"] and f["edge_free"], f
        assert f["fill"] > 0.5, f
    assert np.isfinite(out["frame"]).all()
