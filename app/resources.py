"""Where the data that ships with Bosun is: the robot library, its schema, lab layouts, device profiles, the
marine tables (the default vessel's RAOs, the shipped scatter diagrams).

They are package data (``app.robots`` is the checkout's ``robots/`` folder, mapped in pyproject.toml;
``app/teleop/profiles/`` the device profiles), found through :mod:`importlib.resources`, so they are
there in an editable install, an installed wheel and a checkout run without installing alike.
``$BOSUN_ROBOTS_DIR`` replaces the library folder (:func:`app.models.registry.robots_dir`).
"""

from __future__ import annotations

import importlib.resources
from pathlib import Path

__all__ = ["device_profiles", "marine_data", "robot_library"]


def _package_dir(package: str, fallback: Path) -> Path:
    try:
        found = importlib.resources.files(package)
    except ModuleNotFoundError:  # a checkout used without installing: app.robots is not mapped
        return fallback
    path = Path(str(found))
    return path if path.is_dir() else fallback


def robot_library() -> Path:
    """The folder of the shipped robot files (``*.xml``, ``robot.xsd``, ``labs/``)."""
    return _package_dir("app.robots", Path(__file__).resolve().parents[1] / "robots")


def device_profiles() -> Path:
    """The folder of the shipped joystick profiles (``*.toml``)."""
    # a folder of app.teleop, not a package: app.teleop.profiles is the module reading them
    return _package_dir("app.teleop", Path(__file__).resolve().parent / "teleop") / "profiles"


def marine_data() -> Path:
    """The folder of the shipped marine tables (``app/marine/data``: RAO and scatter-diagram CSVs)."""
    # a folder of app.marine, not a package
    return _package_dir("app.marine", Path(__file__).resolve().parent / "marine") / "data"
