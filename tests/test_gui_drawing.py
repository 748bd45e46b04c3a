"""The machine views' pixels: the offshore crane right way up in OpenGL (Xvfb + Mesa), the lab's load above
EM1500's deck, and the 2D fallback without stray bars (offscreen)."""

import numpy as np
import pytest

pytest.importorskip("PyQt5")

from tests.gui_rig import image_rgb, run_under_xvfb


def _orange(a: np.ndarray) -> np.ndarray:
    """Pixels of the links' orange (0.90, 0.55, 0.15), lit or in shade, or its darker outline."""
    r, g, b = (a[..., i].astype(int) for i in range(3))
    return (r > 60) & (g > 0.35 * r) & (g < 0.8 * r) & (b < 0.45 * r)


# ---------------------------------------------------------------------------------------------- OpenGL
GL_SCRIPT = r"""
import json, sys
import numpy as np
from tests.gui_rig import gl_app, image_rgb
app = gl_app()
from tests.test_gui_drawing import _orange
from app.engine.lab_session import LabSession
from app.engine.session import Session
from app.models.drawing import up_rotation
from app.models.serial import SerialRobot
from app.models.xml import parse_robot_xml
from ui.lab.scene import LabScene3D
from ui.widgets.view3d import RobotView3D

out = {}
# the offshore crane in the teleop view, seen from the side: its boom rises from the deck
s = Session(robot_name="offshore_crane")
view = RobotView3D()
view.resize(640, 480); view.show(); app.processEvents()
desc, state = s.describe(), s.snapshot()
view.set_description(desc); view.update_state(state)
view.machines.set_preset("side"); app.processEvents()
img = image_rgb(view.grab_image())
spec = parse_robot_xml(desc.robot_xml)
F = SerialRobot(spec).frames(np.asarray(state.q))[:, :3, 3] @ up_rotation(spec.serial.up).T
px = view.machines.project(F)  # base (CO), crane base on deck, boom foot, boom tip, jib tip, tool
orange = _orange(img)
rows, cols = np.nonzero(orange)
def near(mask, p, r=6):
    c, rw = int(round(p[0])), int(round(p[1]))
    return bool(mask[max(0, rw - r): rw + r + 1, max(0, c - r): c + r + 1].any())
out["crane"] = {
    "size": img.shape[:2], "px": px.tolist(), "orange": int(orange.sum()),
    "tip_on_orange": near(orange, px[3]), "jib_on_orange": near(orange, px[4]),
    "top_orange_row": int(rows.min()) if rows.size else -1, "bottom_orange_row": int(rows.max()) if rows.size else -1,
}
view.machines.set_preset("top"); app.processEvents()
out["crane"]["orange_from_above"] = int(_orange(image_rgb(view.grab_image())).sum())
img.tofile(sys.argv[1] + ".crane.raw")

# the lab at rest, from the side: the red load above the blue EM1500 deck
ls = LabSession()
lab = LabScene3D()
lab.resize(640, 480); lab.show(); app.processEvents()
lab.set_description(ls.describe()); sc = ls.snapshot().scene; lab.update_scene(sc)
lab.machines.set_preset("side"); app.processEvents()
lab.grab_image().save(sys.argv[1] + ".lab.png")
a = image_rgb(lab.grab_image())
r, g, b = (a[..., i].astype(int) for i in range(3))
red = (r > 80) & (r > 2.2 * g) & (r > 2.2 * b)
blue = (b > 80) & (b > 1.3 * r) & (b > 1.25 * g) & (g > 0.8 * r)  # the decks, not the green work point
top2 = np.asarray(sc.platforms["em1500"]["top"])
p_load, p_deck = lab.machines.project([sc.payload, top2.mean(axis=0)])
col = int(round(p_load[0]))
deck_rows = np.nonzero(blue[:, col - 2: col + 3].any(axis=1))[0]
red_rows = np.nonzero(red[:, col - 3: col + 4].any(axis=1))[0]
out["lab"] = {
    "load_on_red": near(red, p_load, 4), "deck_on_blue": near(blue, p_deck, 4),
    "red_bottom": int(red_rows.max()) if red_rows.size else -1,
    "deck_top": int(deck_rows.min()) if deck_rows.size else -1,
    "orange": int(_orange(a).sum()),
}
print("RESULT " + json.dumps(out))
"""


@pytest.mark.gl
def test_gl_views_draw_the_machines_the_right_way_up(tmp_path):
    out = run_under_xvfb(GL_SCRIPT, tmp_path)
    c = out["crane"]
    px = np.array(c["px"])
    # the offshore crane (vessel frame z down) seen from the side: boom tip and jib tip are orange pixels,
    # ABOVE the crane base on deck (smaller rows are higher up)
    assert c["orange"] > 300
    assert c["tip_on_orange"] and c["jib_on_orange"], c
    assert px[3, 1] < px[1, 1] - 20 and px[4, 1] < px[1, 1] - 20, c
    assert c["top_orange_row"] < px[1, 1] - 20  # links drawn above the base's row
    assert c["bottom_orange_row"] <= px[1, 1] + 5  # and none hanging below the deck
    assert c["orange_from_above"] > 100
    # the lab at rest: the load is red pixels at its place, above the EM1500 deck's blue
    lab = out["lab"]
    assert lab["load_on_red"] and lab["deck_on_blue"], lab
    assert 0 <= lab["red_bottom"] < lab["deck_top"], lab
    assert lab["orange"] > 100  # the Comau


# ---------------------------------------------------------------------------------------------- 2D fallback
def _plot_pixels(pw, pts_uv) -> np.ndarray:
    """Widget pixel positions (x, y) of data points in a PlotWidget."""
    from PyQt5.QtCore import QPointF

    vb = pw.getPlotItem().vb
    out = []
    for u, v in pts_uv:
        sp = vb.mapViewToScene(QPointF(float(u), float(v)))
        p = pw.mapFromScene(sp)
        out.append((p.x(), p.y()))
    return np.array(out, dtype=float)


def _outside_box(mask: np.ndarray, pix: np.ndarray, margin: float = 4) -> int:
    """How many pixels of ``mask`` lie outside the box around the pixel positions ``pix``, widened by ``margin``."""
    lo, hi = pix.min(axis=0) - margin, pix.max(axis=0) + margin
    ys, xs = np.nonzero(mask)
    return int(((xs < lo[0]) | (xs > hi[0]) | (ys < lo[1]) | (ys > hi[1])).sum())


def _shown(qtbot, view, width: int, height: int):
    """``view`` in qtbot's care, resized, shown and exposed."""
    qtbot.addWidget(view)
    view.resize(width, height)
    view.show()
    qtbot.waitExposed(view)
    return view


def test_2d_polylines_draw_no_stray_bars(qtbot):
    """A repeated point, or a segment seen end-on (a vertical wire from above), drew a bar across the plot:
    the views drop them, so the line's colour stays inside the line's own box."""
    from ui.widgets.machines3d import MachineView2D

    view = _shown(qtbot, MachineView2D(), 800, 400)
    view.set_extent([-5, -5, -5], [5, 5, 5])
    color = (255, 0, 255)
    pts = [[0, 0, 0], [0, 0, 0], [1, 0, 2], [1, 0, 2], [1, 0, 3], [1, 0, 3]]  # repeats; vertical from above
    view.set_line("wire", pts, color, 3)
    qtbot.wait(50)
    for key, v in view.plots.items():
        pw = v["plot"]
        a = image_rgb(pw.grab().toImage())
        r, g, b = (a[..., i].astype(int) for i in range(3))
        magenta = (r > 200) & (g < 60) & (b > 200)
        uv = np.asarray(pts, float) @ v["P"].T
        outside = _outside_box(magenta, _plot_pixels(pw, uv))
        assert magenta.sum() > (10 if key == "side" else 3)
        assert outside == 0, f"{key}: {outside} line pixels outside the line's box"


def test_2d_lab_view_has_no_stray_bars_and_the_load_above_the_deck(qtbot):
    from app.engine.lab_session import LabSession
    from app.models.drawing import outline
    from ui.lab.scene import LabScene2D

    s = LabSession()
    view = _shown(qtbot, LabScene2D(), 1000, 600)
    view.set_description(s.describe())
    sc = s.snapshot().scene
    view.update_scene(sc)
    qtbot.wait(50)
    meshes = view.draw.meshes(sc)
    robot = [m for m in meshes if m.name.startswith(("link", "joint", "base"))]
    for key, v in view.machines.plots.items():
        pw = v["plot"]
        a = image_rgb(pw.grab().toImage())
        orange = _orange(a)
        assert orange.sum() > 200, key  # the Comau is drawn
        uv = np.concatenate([outline(m, v["P"]) for m in robot])
        outside = _outside_box(orange, _plot_pixels(pw, uv))
        assert outside == 0, f"{key}: {outside} orange pixels beyond the robot (a stray bar)"
    # side view: the load's red square above the EM1500 deck's blue, in the load's column
    pw, P = view.machines.plots["side"]["plot"], view.machines.plots["side"]["P"]
    a = image_rgb(pw.grab().toImage())
    r, g, b = (a[..., i].astype(int) for i in range(3))
    red = (r > 150) & (g < 110) & (b < 110)
    blue = (b > 150) & (b > 1.3 * r) & (b > 1.25 * g)
    ((x_load, y_load),) = _plot_pixels(pw, np.array([sc.payload]) @ P.T)
    col = round(x_load)
    red_rows = np.nonzero(red[:, col - 2 : col + 3].any(axis=1))[0]
    blue_rows = np.nonzero(blue[:, col - 2 : col + 3].any(axis=1))[0]
    assert red_rows.size and blue_rows.size
    assert red_rows.max() < blue_rows.min()  # every red pixel of the load above the deck's top
    assert abs(red_rows.mean() - y_load) < 6


def test_2d_teleop_view_draws_the_offshore_crane_up(qtbot):
    from app.engine.session import Session
    from ui.widgets.view3d import RobotView2D

    s = Session(robot_name="offshore_crane")
    view = _shown(qtbot, RobotView2D(), 900, 500)
    view.set_description(s.describe())
    state = s.snapshot()
    view.update_state(state)
    qtbot.wait(50)
    pw = view.plots["side"]["plot"]
    orange = _orange(image_rgb(pw.grab().toImage()))
    ys, _ = np.nonzero(orange)
    base = next(m for m in view.draw.meshes(state) if m.name == "base")
    ((_, y_base),) = _plot_pixels(pw, [[base.vertices[:, 0].mean(), base.vertices[:, 2].max()]])
    assert ys.size > 200
    assert np.percentile(ys, 10) < y_base - 30  # the boom rises above the base on deck
