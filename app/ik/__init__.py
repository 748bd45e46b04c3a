"""Pluggable inverse-kinematics solvers, registered by name (universal architecture eqs. 3–4)."""

from __future__ import annotations

from typing import Any

import numpy as np

from app.ik.analytic import AnalyticSolver
from app.ik.base import DEFAULT, IKError, IKResult, Replayed, Solver
from app.ik.genetic import GaTask, GeneticSolver, RestartGeneticSolver
from app.ik.jacobian import JacobianSolver

#: solver name -> class; a new method registers here (or via :func:`register_solver`)
SOLVERS: dict[str, type[Solver]] = {
    GeneticSolver.name: GeneticSolver,
    RestartGeneticSolver.name: RestartGeneticSolver,
    JacobianSolver.name: JacobianSolver,
    AnalyticSolver.name: AnalyticSolver,
}


def register_solver(cls: type[Solver]) -> type[Solver]:
    """Class decorator adding a solver to :data:`SOLVERS` under ``cls.name``."""
    if not cls.name:
        raise ValueError("a solver needs a name")
    SOLVERS[cls.name] = cls
    return cls


def solver_names() -> list[str]:
    return list(SOLVERS)


def make_solver(name: str, robot, *, seed: int | None = 0, **options: Any) -> Solver:
    """Instantiate solver ``name`` for ``robot`` with a generator seeded by ``seed``.

    Raises
    ------
    IKError
        Unknown name, or a solver that does not apply to the robot (analytic).
    """
    cls = SOLVERS.get(name)
    if cls is None:
        raise IKError(f"unknown solver '{name}' (available: {', '.join(SOLVERS)})")
    kind = getattr(robot, "kind", "serial")
    if kind != "serial":
        raise IKError(
            f"{robot.name} is a {kind} mechanism; the IK solvers take serial arms "
            f"(its own kinematics are in the {'Crane head' if kind == 'delta' else 'Motion-Lab'} simulation)"
        )
    return cls(robot, rng=np.random.default_rng(seed), **options)


def solvers_for(robot) -> list[str]:
    """Names of the solvers that apply to ``robot``."""
    names = []
    for name in SOLVERS:
        try:
            make_solver(name, robot)
        except IKError:
            continue
        names.append(name)
    return names


__all__ = [
    "DEFAULT",
    "SOLVERS",
    "AnalyticSolver",
    "GaTask",
    "GeneticSolver",
    "IKError",
    "IKResult",
    "JacobianSolver",
    "Replayed",
    "RestartGeneticSolver",
    "Solver",
    "make_solver",
    "register_solver",
    "solver_names",
    "solvers_for",
]
