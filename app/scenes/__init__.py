"""Scenes: plants (app.sim) and controllers (app.control) wired as a diagram (issue 29, item 3)."""
