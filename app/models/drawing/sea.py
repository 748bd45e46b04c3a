"""The vessel's hull and the sea: elevation, profile and surface from the wave components."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.models.drawing.mesh import HULL_COLOR, RGBA, SEA_COLOR, SHIP_DECK_COLOR, Mesh, extrusion, signed_volume

__all__ = [
    "WAVE_FIELDS",
    "grid_surface",
    "hull_mesh",
    "sea_profile",
    "sea_surface",
    "strongest_components",
    "wave_elevation",
]


# ---------------------------------------------------------------------------------------------- vessel and sea
def hull_mesh(length: float, beam: float, deck_z: float, keel_z: float, n: int = 12) -> Mesh:
    """A ship hull in its body frame {b} (x forward, y starboard, z down, origin at CO) [m].

    Parallel sides over the aft 65 % of the length, a rounded bow (half-beam √(1 − s²) over the
    fore part), a flat deck at ``deck_z`` and a narrower flat bottom at ``keel_z`` that starts a
    little forward of the transom and ends short of the stem (a raked bow).  Deck faces are grey,
    the rest red.  Needs keel_z > deck_z (the deck above the keel in a z-down frame).
    """
    if not (length > 0 and beam > 0 and keel_z > deck_z):
        raise ValueError("a hull needs a positive length and beam and its keel below its deck (z down)")
    s = np.concatenate([[0.0, 0.3, 0.65], 0.65 + 0.35 * np.sin(0.5 * np.pi * np.arange(1, n + 1) / n)])

    def half_beam(s):
        f = np.ones_like(s)
        fore = s > 0.65
        f[fore] = np.sqrt(np.clip(1 - ((s[fore] - 0.65) / 0.35) ** 2, 0, 1))
        return f

    f = half_beam(s)

    def ring(x0, x1, hb, z):
        x = x0 + (x1 - x0) * s
        side = np.column_stack([x, hb * f, np.full_like(x, z)])  # starboard, stern to bow
        port = side[-2::-1] * [1, -1, 1]  # bow excluded, back to the stern
        return np.vstack([side, port[:-1] if f[0] == 0 else port])

    deck = ring(-length / 2, length / 2, beam / 2, deck_z)
    keel = ring(-0.47 * length, 0.38 * length, 0.8 * beam / 2, keel_z)
    # seen from the deck side (−z in {b}) the starboard-first ring runs clockwise: swap for the loft
    m = extrusion(keel, deck, HULL_COLOR, "hull")
    if signed_volume(m) < 0:
        m = Mesh(m.vertices, m.faces[:, ::-1], HULL_COLOR, name="hull")
    colors = m.colors()
    k = len(deck)
    top_fan = np.all(m.faces >= k, axis=1) & np.any(m.faces == 2 * k + 1, axis=1)
    colors[top_fan] = SHIP_DECK_COLOR
    m.face_colors = colors
    return m


def wave_elevation(
    amplitude: ArrayLike,
    omega: ArrayLike,
    k: ArrayLike,
    heading: ArrayLike,
    phase: ArrayLike,
    t: float,
    x: ArrayLike,
    y: ArrayLike,
) -> NDArray[np.float64]:
    """ζ(x, y, t) = Σ a cos(ω t − k (x cos μ + y sin μ) + φ) (app/marine/waves.py), ζ up [m].

    x, y : arrays of one shape (north, east in {n}) [m]; returns that shape.
    """
    a = np.asarray(amplitude, dtype=float)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    kx = np.asarray(k, dtype=float) * np.cos(heading)
    ky = np.asarray(k, dtype=float) * np.sin(heading)
    arg = np.asarray(omega) * t + np.asarray(phase) - (x[..., None] * kx + y[..., None] * ky)
    return np.cos(arg) @ a


def strongest_components(amplitude: ArrayLike, share: float = 0.99) -> NDArray[np.intp]:
    """Indices of the fewest wave components whose a²/2 add up to ``share`` of the variance."""
    a2 = np.asarray(amplitude, dtype=float) ** 2
    if a2.size == 0:
        return np.zeros(0, dtype=np.intp)
    order = np.argsort(a2)[::-1]
    cum = np.cumsum(a2[order])
    n = int(np.searchsorted(cum, share * cum[-1])) + 1
    return np.sort(order[:n])


#: a ``WaveField``'s arrays, in :func:`wave_elevation`'s order
WAVE_FIELDS = ("amplitude", "omega", "k", "heading_rad", "phase")


def sea_profile(waves, t: float, p0: ArrayLike, p1: ArrayLike, n: int = 80, share: float = 0.99) -> NDArray[np.float64]:
    """The sea surface along the segment p0 → p1 (north, east in {n}) as points (n, 3) in the display frame
    (x north, y west, z up) [m]."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    ne = np.asarray(p0, dtype=float) + s * (np.asarray(p1, dtype=float) - np.asarray(p0, dtype=float))
    keep = strongest_components(waves.amplitude, share)
    parts = (np.asarray(getattr(waves, f), dtype=float)[keep] for f in WAVE_FIELDS)
    zeta = wave_elevation(*parts, t, ne[:, 0], ne[:, 1])
    return np.column_stack([ne[:, 0], -ne[:, 1], zeta])


def grid_surface(x: ArrayLike, y: ArrayLike, z: ArrayLike, color: RGBA = SEA_COLOR, name: str = "sea") -> Mesh:
    """A height field as triangles: vertices (x[j], y[i], z[i, j]), two faces per cell, facing +z.

    x : (nx,), y : (ny,), z : (ny, nx) [m].  Open (a surface, not a solid).
    """
    x, y, z = np.asarray(x, dtype=float), np.asarray(y, dtype=float), np.asarray(z, dtype=float)
    ny, nx = z.shape
    X, Y = np.meshgrid(x, y)
    verts = np.column_stack([X.ravel(), Y.ravel(), z.ravel()])
    idx = np.arange(nx * ny, dtype=np.int32).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return Mesh(verts, faces, color, name=name)


def sea_surface(
    waves, t: float, center: ArrayLike = (0.0, 0.0), size: float = 200.0, n: int = 41, share: float = 0.99
) -> Mesh:
    """The sea around a point as a grid in the display frame (x north, y west, z up) [m].

    Parameters
    ----------
    waves : object with amplitude, omega, k, heading_rad, phase (a ``WaveField``)
        Components in {n}.
    t : float
        Time of the sea record [s].
    center : (2,)
        North, east of the grid centre in {n} [m] (the vessel).
    size : float
        Edge of the square grid [m]; ``n`` × ``n`` vertices.
    share : float
        Only the strongest components that carry this share of the variance are summed (a picture,
        not a measurement: a 200-component sea costs a frame's time otherwise).
    """
    c = np.asarray(center, dtype=float)
    north = c[0] + np.linspace(-size / 2, size / 2, n)
    east = c[1] + np.linspace(-size / 2, size / 2, n)
    N, E = np.meshgrid(north, east)  # rows: east, columns: north
    keep = strongest_components(waves.amplitude, share)
    parts = (np.asarray(getattr(waves, f), dtype=float)[keep] for f in WAVE_FIELDS)
    zeta = wave_elevation(*parts, t, N, E)
    # display: y = −east; flip the rows so y increases along them
    return grid_surface(north, -east[::-1], zeta[::-1])
