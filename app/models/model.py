"""What the kinematic models share: :class:`~app.models.serial.SerialRobot`,
:class:`~app.models.delta.DeltaHead` and :class:`~app.models.stewart.StewartPlatform` are each built from
the part of a robot spec of their kind, and the first two are driven by joints with limits."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.errors import JointInputError
from app.models.spec import RobotSpec


class Model:
    """A kinematic model of a robot spec of type :attr:`kind` (the spec's part of that name): keeps the spec
    and the robot's name."""

    kind: ClassVar[str]
    #: what a spec of another type raises
    wrong_type: ClassVar[type[Exception]] = TypeError

    def __init__(self, spec: RobotSpec) -> None:
        if getattr(spec, self.kind) is None:
            raise self.wrong_type(f"robot {spec.name} is of type {spec.type}, not {self.kind}")
        self.spec = spec
        self.name = spec.name


class JointModel(Model):
    """A model driven by joints: their names ``joint_names`` (``n_joints`` of them) and position limits
    ``lower``, ``upper`` [rad or m], set by the model, and the checks of a configuration q against them."""

    n_joints: int
    joint_names: list[str]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]

    def check_q(self, q: ArrayLike) -> NDArray[np.float64]:
        """Validate one configuration: n finite numbers. Returns a float array.

        Raises
        ------
        JointInputError
            Wrong count or a value that is NaN or infinite.
        """
        arr = np.asarray(q, dtype=float).reshape(-1)
        if arr.size != self.n_joints:
            raise JointInputError(
                f"{self.name} has {self.n_joints} joints ({', '.join(self.joint_names)}); got {arr.size} value(s)"
            )
        bad = ~np.isfinite(arr)
        if bad.any():
            names = ", ".join(self.joint_names[i] for i in np.flatnonzero(bad))
            raise JointInputError(f"{self.name}: joint value for {names} is not a finite number")
        return arr

    def within_limits(self, q: ArrayLike, tol: float = 1e-12) -> NDArray[np.bool_]:
        """Per-joint flag: is q inside [lower, upper] (with a tolerance)? Shape of q."""
        q = np.asarray(q, dtype=float)
        return (q >= self.lower - tol) & (q <= self.upper + tol)

    def clip(self, q: ArrayLike) -> NDArray[np.float64]:
        """q clipped into the joint limits."""
        return np.minimum(np.maximum(np.asarray(q, dtype=float), self.lower), self.upper)  # ufuncs: no np.clip overhead
