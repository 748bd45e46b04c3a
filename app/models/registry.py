"""Find robot files by name or path and build their kinematic models.

Model classes register themselves per mechanism type in :data:`MODEL_FACTORIES`, so a
new mechanism is a new module, not an edit of the loader.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from app.errors import RobotNotFoundError, RobotTypeError
from app.models.delta import DeltaHead
from app.models.serial import SerialRobot
from app.models.spec import RobotSpec
from app.models.stewart import StewartPlatform
from app.models.xml import parse_robot_file

#: mechanism type -> factory building its kinematic model from a spec
MODEL_FACTORIES: dict[str, Callable[[RobotSpec], Any]] = {
    "serial": SerialRobot,
    "delta": DeltaHead,
    "stewart": StewartPlatform,
}

ENV_ROBOTS_DIR = "BOSUN_ROBOTS_DIR"


def robots_dir() -> Path:
    """The robot library: ``$BOSUN_ROBOTS_DIR`` if set, else ``robots/`` of this checkout."""
    env = os.environ.get(ENV_ROBOTS_DIR)
    return Path(env) if env else Path(__file__).resolve().parents[2] / "robots"


def list_robots() -> list[str]:
    """Names of the robot files in the library, sorted."""
    return sorted(p.stem for p in robots_dir().glob("*.xml"))


def resolve(name_or_path: str | os.PathLike[str]) -> Path:
    """Path of a robot file given a library name (``scara``) or a path (``my/arm.xml``).

    Raises
    ------
    RobotNotFoundError
        Neither a file nor a library name; the message lists close names.
    """
    text = os.fspath(name_or_path)
    if not text.strip():
        raise RobotNotFoundError("no robot given; name one from the library or a path to an XML file")
    looks_like_path = text.endswith(".xml") or os.sep in text or "/" in text
    if looks_like_path:
        path = Path(text).expanduser()
        if not path.is_file():
            raise RobotNotFoundError(f"robot file not found: {text}")
        return path
    path = robots_dir() / f"{text}.xml"
    if path.is_file():
        return path
    names = list_robots()
    close = difflib.get_close_matches(text, names, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise RobotNotFoundError(f"unknown robot '{text}'{hint} (library: {', '.join(names)})")


def load_spec(name_or_path: str | os.PathLike[str]) -> RobotSpec:
    """Parse and validate the robot file named by ``name_or_path``."""
    return parse_robot_file(resolve(name_or_path))


def load_robot(name_or_path: str | os.PathLike[str]) -> Any:
    """The kinematic model of a robot (``SerialRobot`` for serial chains).

    Raises
    ------
    RobotNotFoundError, RobotXmlError
        As :func:`resolve` and :func:`~app.models.xml.parse_robot_xml`.
    RobotTypeError
        The mechanism type has no kinematic model registered.
    """
    spec = load_spec(name_or_path)
    factory = MODEL_FACTORIES.get(spec.type)
    if factory is None:
        raise RobotTypeError(
            f"robot '{spec.name}' is a {spec.type} mechanism; no {spec.type} kinematics are available yet"
        )
    return factory(spec)
