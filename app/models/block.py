"""The one shape of a plant, a sensor or a controller (issue 29, item 1), after python-control's
``update(t, x, u, params)`` / ``output(…)`` and Drake's systems.

A :class:`Block` names its state, inputs, outputs and parameters and has one pure step

    step(x, u, p, dt) -> (x', y)

with each of ``x``, ``u``, ``p`` and ``y`` a *record*: a tuple of arrays and numbers in the order of the
names (a tuple is what a compiled kernel takes and returns as one argument, so a step has four arguments
whatever the block).  The compiled kernel and the NumPy reference are two implementations of the same step,
with the same records and the same numbers; :meth:`Block.implementation` is the one place that chooses
between them.  Nothing in a step keeps state: what changes is in ``x'``.

The blocks so far: the joint actuators of a simulated arm (:data:`app.sim.actuators.JOINT_ACTUATORS`), the
Motion-Lab's plants and controllers (:mod:`app.sim.motionlab`, :mod:`app.control.lab`) and the crane head's
DC motors and PID (:data:`app.sim.head.HEAD_MOTORS`, :data:`app.control.tac.HEAD_PID`, TAC paper eqs. 57–58).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from app.models.kernels import ENABLED

Record = tuple[Any, ...]
Step = Callable[[Record, Record, Record, float], tuple[Record, Record]]


@dataclass(frozen=True)
class Block:
    """A named step (see the module text).  ``kernel`` is None where only the reference exists."""

    name: str
    state: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    params: tuple[str, ...]
    reference: Step
    kernel: Step | None = None

    def implementation(self, use_kernels: bool | None = None) -> Step:
        """The compiled kernel where kernels are on (``use_kernels`` None: as the installation says) and the
        block has one; else the NumPy reference."""
        on = ENABLED if use_kernels is None else use_kernels
        return self.kernel if on and self.kernel is not None else self.reference

    def step(self, x: Record, u: Record, p: Record, dt: float, use_kernels: bool | None = None):
        """(x', y) after ``dt`` [s] with inputs ``u`` held."""
        return self.implementation(use_kernels)(x, u, p, dt)

    def record(self, kind: str, **values: Any) -> Record:
        """The record of ``kind`` (state, inputs, outputs or params) from named values, in the block's order;
        a missing or unknown name is a ValueError."""
        names = getattr(self, kind)
        if set(values) != set(names):
            raise ValueError(f"{self.name} {kind}: expected {', '.join(names)}; got {', '.join(values)}")
        return tuple(values[n] for n in names)

    def named(self, kind: str, record: Record) -> dict[str, Any]:
        """A record of ``kind`` as a dict by name (for reading, printing, describing)."""
        return dict(zip(getattr(self, kind), record, strict=True))
