"""Find robot files by name or path and build their kinematic models.

Model classes register themselves per mechanism type in :data:`MODEL_FACTORIES`, so a
new mechanism is a new module, not an edit of the loader.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from app.errors import RobotNotFoundError, RobotTypeError, printable_path
from app.models.delta import DeltaHead
from app.models.serial import SerialRobot
from app.models.spec import RobotSpec
from app.models.stewart import StewartPlatform
from app.models.xml import MAX_FILE_BYTES, parse_robot_file, parse_robot_xml, read_robot_file
from app.resources import robot_library

#: mechanism type -> factory building its kinematic model from a spec
MODEL_FACTORIES: dict[str, Callable[[RobotSpec], Any]] = {
    "serial": SerialRobot,
    "delta": DeltaHead,
    "stewart": StewartPlatform,
}

ENV_ROBOTS_DIR = "BOSUN_ROBOTS_DIR"
LIBRARY_DIR = robot_library()  # package data (app/resources.py)


def robots_dir() -> Path:
    """The robot library: ``$BOSUN_ROBOTS_DIR`` if set, else the shipped one (package data ``app.robots``)."""
    env = os.environ.get(ENV_ROBOTS_DIR)
    return Path(env) if env else LIBRARY_DIR


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
    _no_nul(text)
    looks_like_path = text.endswith((".xml", ".urdf")) or os.sep in text or "/" in text
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


def allowed_dirs(extra: Sequence[str | os.PathLike[str]] = ()) -> list[Path]:
    """Folders a remote ``set_robot`` may read: the library, ``$BOSUN_ROBOTS_DIR`` and ``extra``."""
    out: list[Path] = []
    for d in (LIBRARY_DIR, robots_dir(), *map(Path, extra)):
        real = Path(d).expanduser().resolve()
        if real not in out:
            out.append(real)
    return out


def resolve_allowed(name_or_path: str, folders: Sequence[Path]) -> Path:
    """Like :func:`resolve`, but a path must lie inside one of ``folders`` (symlinks resolved).

    A path outside them is refused before anything on the disk is looked at, so the answer
    says nothing about which files exist; a relative path is looked up in each folder.
    """
    text = os.fspath(name_or_path)
    _no_nul(text)
    if not (text.endswith(".xml") or os.sep in text or "/" in text):
        return resolve(text)
    if not text.endswith(".xml"):
        raise RobotNotFoundError(f"a robot path must end in .xml: {_quoted(text)}")
    given = Path(text).expanduser()

    def inside(p: Path) -> bool:
        return any(p.is_relative_to(d) for d in folders)

    if given.is_absolute():
        # lexically first, so a path outside says nothing about what exists there
        if not inside(Path(os.path.normpath(given))) or not inside(given.resolve()):
            raise RobotNotFoundError(
                f"robot path {_quoted(text)} is outside the allowed robot folders "
                f"({', '.join(d.name or str(d) for d in folders)}); start the engine with --robots-dir to add one"
            )
        if not given.resolve().is_file():
            raise RobotNotFoundError(f"robot file not found: {_quoted(text)}")
        return given.resolve()
    for d in folders:
        real = (d / given).resolve()
        if inside(real) and real.is_file():
            return real
    raise RobotNotFoundError(f"robot file not found in the allowed robot folders: {_quoted(text)}")


def _quoted(text: str) -> str:
    return repr(printable_path(text, 120))


def _no_nul(text: str) -> None:
    """A NUL names no file (the OS refuses it: ``ValueError: embedded null byte``): one line instead."""
    if "\0" in text:
        raise RobotNotFoundError(f"robot name or path {_quoted(text)} holds a NUL character; no file is named so")


def shown_path(path: Path, folders: Sequence[Path]) -> str:
    """``path`` as a remote client is shown it: from its allowed folder's name on (``my_robots/arm.xml``),
    never the server's absolute path (issue 27, item 10)."""
    for d in folders:
        if path.is_relative_to(d):
            return (Path(d.name) / path.relative_to(d)).as_posix()
    return path.name


def load_spec(name_or_path: str | os.PathLike[str], allowed: Sequence[Path] | None = None) -> RobotSpec:
    """Parse and validate the robot file named by ``name_or_path`` (inside ``allowed`` when given)."""
    if allowed is None:
        return parse_robot_file(resolve(name_or_path))
    path = resolve_allowed(os.fspath(name_or_path), allowed)
    return parse_robot_file(path, shown_path(path.resolve(), allowed))


def build_model(spec: RobotSpec) -> Any:
    """The kinematic model of a parsed robot file."""
    factory = MODEL_FACTORIES.get(spec.type)
    if factory is None:
        raise RobotTypeError(
            f"robot '{spec.name}' is a {spec.type} mechanism; no {spec.type} kinematics are available yet"
        )
    return factory(spec)


def load_robot_text(text: str | bytes, label: str) -> Any:
    """The model of robot XML sent as text (a client's own file); ``label`` names it in errors."""
    size = len(text.encode("utf-8") if isinstance(text, str) else text)
    if size > MAX_FILE_BYTES:
        raise RobotNotFoundError(f"{label}: {size} bytes; a robot file is at most {MAX_FILE_BYTES}")
    return build_model(parse_robot_xml(text, label))


def load_robot_file(name_or_path: str | os.PathLike[str], allowed: Sequence[Path] | None = None) -> tuple[Any, str]:
    """The model of a robot and the text it was built from, the file read once (:func:`read_robot_file`).

    With ``allowed`` (a remote ``set_robot``) the path must lie inside those folders, and errors name
    the file from its folder's name on (:func:`shown_path`)."""
    if allowed is None:
        path = resolve(name_or_path)
        label = str(path)
    else:
        path = resolve_allowed(os.fspath(name_or_path), allowed)
        label = shown_path(path.resolve(), allowed)
    text = read_robot_file(path, label)
    return build_model(parse_robot_xml(text, label)), text


def load_robot(name_or_path: str | os.PathLike[str], allowed: Sequence[Path] | None = None) -> Any:
    """The kinematic model of a robot (``SerialRobot`` for serial chains).

    Raises
    ------
    RobotNotFoundError, RobotXmlError
        As :func:`resolve` and :func:`~app.models.xml.parse_robot_xml`.
    RobotTypeError
        The mechanism type has no kinematic model registered.
    """
    return build_model(load_spec(name_or_path, allowed))
