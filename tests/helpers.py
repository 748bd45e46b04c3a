"""Small helpers shared by tests."""

from __future__ import annotations

import numpy as np


def random_q(robot, rng: np.random.Generator, n: int) -> np.ndarray:
    """n configurations drawn uniformly inside the joint limits, shape (n, dof)."""
    return rng.uniform(robot.lower, robot.upper, size=(n, robot.n_joints))
