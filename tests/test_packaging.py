"""Issue 15, item 6: a package that works installed.  Robots, schema, lab layouts and device profiles
are package data found through importlib.resources; the extras split the GUI and joystick off the core.

The installed wheel itself is tested by scripts/core_job.sh (CI): the whole non-GUI suite against the
wheel in a clean environment where PyQt5, pyqtgraph and pygame cannot be imported."""

from __future__ import annotations

import subprocess
import sys
import tomllib
import zipfile

import pytest

from app.resources import device_profiles, robot_library
from tests.helpers import ROOT, needs_source

pytestmark = needs_source
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_every_package_folder_is_listed_for_the_wheel():
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    found = {
        ".".join(p.parent.relative_to(ROOT).parts)
        for top in ("app", "ui")
        for p in (ROOT / top).rglob("__init__.py")
        if "__pycache__" not in p.parts
    }
    assert found | {"app.robots"} == listed
    assert PYPROJECT["tool"]["setuptools"]["package-dir"] == {"app.robots": "robots"}


def test_the_core_does_not_depend_on_qt_or_pygame():
    core = " ".join(PYPROJECT["project"]["dependencies"]).lower()
    assert not any(name in core for name in ("pyqt5", "pyqtgraph", "pyopengl", "pygame"))
    extras = PYPROJECT["project"]["optional-dependencies"]
    assert {"gui", "joystick", "bench", "test"} <= set(extras)
    assert any("pygame" in d for d in extras["joystick"]) and any("PyQt5" in d for d in extras["gui"])
    assert extras["all"] == [
        "bosun[gui,joystick,bench,test,test-gui,plc,marine,study,urdf,docs]"
    ]  # what setup.sh installs
    assert any(d.startswith("mkdocs-material") for d in extras["docs"])  # the documentation site (issue 28)
    assert any(d.startswith("pyads") for d in extras["plc"])  # the real Motion-Lab's PLC (issue 16)
    assert any(d.startswith("capytaine") for d in extras["marine"])  # bosun vessel rao (issue 17)
    assert any(d.startswith("dask[distributed]") for d in extras["study"])  # bosun study operability (issue 17)


def test_shipped_data_is_found_through_importlib_resources():
    lib = robot_library()
    assert (lib / "robot.xsd").is_file() and (lib / "labs" / "motionlab.xml").is_file()
    assert (lib / "urdf" / "ur5.urdf").is_file() and (lib / "urdf" / "franka_panda.urdf").is_file()
    assert {p.stem for p in lib.glob("*.xml")} >= {"scara", "offshore_crane", "em8000", "tac_delta_head"}
    assert {p.stem for p in device_profiles().glob("*.toml")} >= {"xbox_gamepad", "logitech_extreme_3d_pro"}


def test_bosun_robots_dir_still_replaces_the_library(tmp_path, monkeypatch):
    from app.models.registry import list_robots

    (tmp_path / "arm.xml").write_text((robot_library() / "scara.xml").read_text(encoding="utf-8"), encoding="utf-8")
    monkeypatch.setenv("BOSUN_ROBOTS_DIR", str(tmp_path))
    assert list_robots() == ["arm"]


@pytest.mark.slow
def test_the_wheel_carries_the_data(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-w", str(tmp_path), str(ROOT)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    (wheel,) = tmp_path.glob("bosun-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    robots = {f"app/robots/{p.name}" for p in (ROOT / "robots").glob("*.xml")}
    assert robots and robots <= names
    assert {"app/robots/robot.xsd", "app/robots/labs/motionlab.xml", "app/robots/README.md"} <= names
    assert {f"app/teleop/profiles/{p.name}" for p in (ROOT / "app/teleop/profiles").glob("*.toml")} <= names
    assert "app/marine/data/supply_bem.csv" in names  # the default vessel's RAOs (issue 17)
    assert "ui/app.py" in names and not any(n.startswith(("tests/", "robots/")) for n in names)
