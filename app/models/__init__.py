"""Robot specifications (parsed from XML) and their kinematic models."""

from app.models.registry import list_robots, load_robot, load_spec, robots_dir
from app.models.serial import SerialRobot
from app.models.spec import DeltaSpec, JointSpec, LinkSpec, RobotSpec, SerialSpec, StewartSpec

__all__ = [
    "DeltaSpec",
    "JointSpec",
    "LinkSpec",
    "RobotSpec",
    "SerialRobot",
    "SerialSpec",
    "StewartSpec",
    "list_robots",
    "load_robot",
    "load_spec",
    "robots_dir",
]
