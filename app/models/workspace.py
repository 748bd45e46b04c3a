"""Reachable-workspace estimates of serial robots from seeded joint-space sampling."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

DEFAULT_SAMPLES = 20_000


@dataclass(frozen=True, eq=False)
class WorkspaceBox:
    """Axis-aligned box enclosing the reachable tool positions (world frame) [m]."""

    lower: NDArray[np.float64]
    upper: NDArray[np.float64]

    @property
    def extent(self) -> NDArray[np.float64]:
        """Side lengths [m]; a flat axis gets 1e-3 of the largest side so it can be divided by."""
        ext = self.upper - self.lower
        return np.maximum(ext, 1e-3 * ext.max())

    @property
    def center(self) -> NDArray[np.float64]:
        return 0.5 * (self.lower + self.upper)

    @property
    def diagonal(self) -> float:
        return float(np.linalg.norm(self.upper - self.lower))

    def normalise(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        """Map positions into the unit cube of the box: (p − lower) / extent, shape of p."""
        return (np.asarray(p, dtype=float) - self.lower) / self.extent

    def grid(self, n: int) -> NDArray[np.float64]:
        """n × n × n equally spaced points spanning the box (corners included), shape (n³, 3)."""
        axes = [np.linspace(lo, hi, n) for lo, hi in zip(self.lower, self.upper, strict=True)]
        X, Y, Z = np.meshgrid(*axes, indexing="ij")
        return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])


def sample_configurations(robot, n: int, rng: np.random.Generator) -> NDArray[np.float64]:
    """n joint vectors uniform inside the joint limits, shape (n, dof)."""
    return rng.uniform(robot.lower, robot.upper, size=(n, robot.n_joints))


def sample_positions(robot, n: int, rng: np.random.Generator) -> NDArray[np.float64]:
    """Tool positions of n random configurations inside the limits, shape (n, 3)."""
    return robot.position(sample_configurations(robot, n, rng))


MAX_CORNERS = 4096


def limit_corners(robot, rng: np.random.Generator) -> NDArray[np.float64]:
    """Joint vectors with every joint at a limit: all 2ⁿ when 2ⁿ ≤ 4,096, else 4,096 seeded ones."""
    n = robot.n_joints
    if 2**n <= MAX_CORNERS:
        pick = (np.arange(2**n)[:, None] >> np.arange(n)) & 1
    else:
        pick = rng.integers(0, 2, size=(MAX_CORNERS, n))
    return np.where(pick.astype(bool), robot.upper, robot.lower)


def workspace_box(robot, n_samples: int = DEFAULT_SAMPLES, seed: int = 0, pad: float = 0.01) -> WorkspaceBox:
    """Box enclosing the tool positions of ``n_samples`` seeded random configurations.

    Joint-limit corners are sampled too (all 2ⁿ of them up to n = 12, else 4,096 seeded
    ones: never a 2ⁿ array), and the box is grown by ``pad`` of its size on every side, since random
    samples fall just short of the true extremes.  Cached on the robot for the default
    arguments.
    """
    cache_key = (n_samples, seed, pad)
    cached = getattr(robot, "_workspace_box_cache", None)
    if cached is not None and cached[0] == cache_key:
        return cached[1]
    rng = np.random.default_rng(seed)
    q = sample_configurations(robot, n_samples, rng)
    p = robot.position(np.vstack([q, limit_corners(robot, rng)]))
    lo, hi = p.min(axis=0), p.max(axis=0)
    margin = pad * (hi - lo).max()
    box = WorkspaceBox(lo - margin, hi + margin)
    robot._workspace_box_cache = (cache_key, box)
    return box
