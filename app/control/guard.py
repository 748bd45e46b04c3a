"""Direction-aware scaling of a serial arm's joint step (issue 32, item 5): four hazards, one compiled call a tick.

The hazards, each a distance with a gradient in joint space:

* a **joint limit** — the distance of each joint to its nearer limit [rad or m];
* a **singularity** — σ_min/σ_max of the speed-scaled position Jacobian (the ``near_singularity`` alarm's ratio);
* a **collision** between two of the arm's capsules (its links, as drawn, and the mounts or pedestal it stands
  on), or of a capsule with the **floor** the base plate stands on (for a crane in a vessel's frame, the deck);
* (the Delta head's and the platforms' workspace hulls are their scenes' own; see :mod:`app.engine.tac_session`.)

A step is scaled only along the directions that bring a hazard nearer (the velocity damper of Faverjon &
Tournassoud 1987, as a bound on each hazard's rate, Kanoun, Lamiraux & Wieber 2011 eq. 10): inside a hazard's
zone its rate of approach falls linearly to zero at its stop distance; the component of the step along the
hazard's gradient is all that is removed; a step that opens every clearance (or raises σ) is returned as it is —
MoveIt Servo's users asked for exactly this since 2021 (moveit2#409, moveit2#3411).  The arithmetic is
:func:`app.control.guard_kernels.guard_step`.

Capsules come from the robot file (``<collision radius=…>`` on a link); a link without one gets the radius it is
drawn with (:func:`app.models.drawing.machines.link_radius`, tapered along the chain).  Pairs joined along the
chain (the gap between them shorter than their radii and the zone: a joint's own housing) and pairs already
touching where the arm starts (mid-range) are not checked, nor pairs no pose brings within 0.15 m (over 3 000
seeded random poses: never in the zone); :attr:`HazardGuard.ignored` says which and why.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.control import guard_kernels as gk
from app.models.drawing.machines import link_radius
from app.models.serial import SerialRobot

__all__ = ["GuardReport", "GuardSettings", "HazardGuard", "scale_in_box"]

_UP = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
NEVER_SAMPLES = 3000  # random poses that find the pairs the joints can never bring together
NEVER_NEAR = 0.15  # [m]: a pair never nearer than this in them is not checked (the zone, 0.10 m, and a margin)
KINDS = {gk.LIMIT: "joint limit", gk.SINGULAR: "singularity", gk.PAIR: "collision", gk.PLANE: "collision"}


@dataclass(frozen=True)
class GuardSettings:
    """Zones (where scaling starts) and stops (where approach ends) of the four hazards.

    limit_zone, limit_stop : share of each joint's range (5 %, 0: the limit itself)
    sigma_zone, sigma_stop : the σ ratio (0.04; 0.01, the ``near_singularity`` alarm's threshold)
    clear_zone, clear_stop : capsule clearance [m] (0.10; 0.005)
    kink : the σ ratio under which σ_min has no gradient (|x|-like at a singularity: every direction opens it)
    passes : projection passes over the hazards in their zones
    hard_stop : the safe-braking rule's clearance [m] (:func:`app.scenes.teleop_guard.guard_tick`)

    The array's 11th entry (not a setting: :meth:`HazardGuard.in_tool_metric`) says how a step is corrected: 1 in
    the tool's metric (a velocity command: the tool's motion is what was asked, safety H121), 0 in the joints'
    (the position mode's walk to a joint goal, corrected in passes as before H121).
    """

    limit_zone: float = 0.05
    limit_stop: float = 0.0
    sigma_zone: float = 0.04
    sigma_stop: float = 0.01
    clear_zone: float = 0.10
    clear_stop: float = 0.005
    kink: float = 1e-6
    passes: int = 4
    hard_stop: float = 0.0025  # [m]: the safe-braking rule's clearance (half the scaling's stop: its losses pass)

    def array(self) -> NDArray[np.float64]:
        return np.array(
            [self.limit_zone, self.limit_stop, self.sigma_zone, self.sigma_stop, self.clear_zone, self.clear_stop,
             self.kink, float(self.passes), 0.0, self.hard_stop, 1.0]
        )  # fmt: skip


@dataclass(frozen=True)
class GuardReport:
    """What the guard did to one step.

    kind : "" (no hazard in its zone), "joint limit", "singularity" or "collision"
    name : the hazard as the operator reads it ("wrist_1 upper limit", "link 2 ↔ link 5", "link 3 ↔ floor")
    value : its clearance [m], σ ratio, or distance to the limit [rad or m] (nan: none)
    share : the share of its zone left, (value − stop)/(zone − stop): 1 at the zone's edge, 0 at the stop
    slowed : the step was scaled
    scale : |dq_out|/|dq|
    unit : a joint limit's joint: "rad" (revolute: read in degrees) or "m" (prismatic: read in mm)
    """

    kind: str = ""
    name: str = ""
    value: float = math.nan
    share: float = math.nan
    slowed: bool = False
    scale: float = 1.0
    unit: str = ""

    def text(self) -> str:
        """One line: the hazard and its distance."""
        if not self.kind:
            return ""
        if self.kind == "singularity":
            return f"singularity: σ ratio {self.value:.3f}"
        if self.kind == "joint limit":
            return f"{self.name}: {self.distance()} to go"
        return f"{self.name}: clearance {self.value * 1e3:.0f} mm"

    def distance(self) -> str:
        """A joint limit's distance as the operator reads it, with its unit: degrees for a revolute joint (as the
        joint plots), millimetres for a prismatic one."""
        if self.unit == "rad":
            return f"{math.degrees(self.value):.1f}°"
        if self.unit == "m":
            return f"{self.value * 1e3:.0f} mm"
        return f"{self.value:.3g}"


@dataclass
class HazardGuard:
    """The hazards of one serial arm and the scaling of its joint steps (:meth:`step`)."""

    robot: SerialRobot
    caps: NDArray[np.int64]  # (C, 2) link, part (guard_kernels.capsule_points)
    radii: NDArray[np.float64]  # (C,)
    labels: list[str]  # (C,) "link i", "mount i", "tool"
    pairs: NDArray[np.int64]  # (P, 2)
    plane: NDArray[np.float64]  # (4,) n, h: the floor n·x = h
    plane_caps: NDArray[np.int64]  # (Pl,)
    settings: GuardSettings = field(default_factory=GuardSettings)
    ignored: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._settings = self.settings.array()
        self.lever = self._levers()
        self.row_lever = self._row_levers()
        self._report = np.zeros(6)
        self.tick_report = np.zeros(8)  # app.scenes.teleop_guard's
        self._names: dict[tuple[int, int], str] = {}  # (kind, index) → the hazard's name (:meth:`report`)
        self._out = np.zeros(1 + len(self.pairs) + len(self.plane_caps))
        self._pts = np.zeros((len(self.caps), 2, 3))
        # the kernels' records (app/control/guard_kernels.py): the chain's constants, the capsule model, the limits
        r = self.robot
        f64 = lambda a: np.ascontiguousarray(a, dtype=float)  # noqa: E731
        i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64).reshape(np.shape(a))  # noqa: E731
        self._chain = (f64(r._M_theta), f64(r._M_d), f64(r.speed))
        self._model = (i64(self.caps), f64(self.radii), i64(self.pairs), f64(self.plane), i64(self.plane_caps))
        self._limits = (f64(r.lower), f64(r.upper))

    # ------------------------------------------------------------------ build
    @classmethod
    def for_robot(cls, robot: SerialRobot, settings: GuardSettings | None = None) -> HazardGuard:
        """The capsules, pairs and floor of ``robot`` as its file and its drawing give them."""
        settings = settings or GuardSettings()
        links = robot.links
        L = len(links)
        kinds = [link.kind for link in links]
        first = next((i for i, k in enumerate(kinds) if k != "fixed"), 0)
        r0 = link_radius(links)
        caps, radii, labels = [], [], []
        for i, link in enumerate(links):
            mount = i < first
            share = i / max(1, L - 1)
            drawn = r0 * (1.0 - 0.4 * share) * (0.45 if mount else 1.0)
            r = link.radius if getattr(link, "radius", None) is not None else drawn
            label = f"{'mount' if mount else 'link'} {i + 1}"
            d_moves = link.kind == "prismatic" or abs(link.d) > 1e-9
            if d_moves:
                caps.append((i, 0)), radii.append(r), labels.append(label)
            if abs(link.a) > 1e-9:
                caps.append((i, 1)), radii.append(r), labels.append(label)
        tool = np.asarray(robot.T_flange_tool)[:3, 3]
        if float(np.linalg.norm(tool)) > 1e-9:
            caps.append((L, 2)), radii.append(0.6 * r0), labels.append("tool")
        caps_a = np.array(caps, dtype=np.int64).reshape(-1, 2)
        radii_a = np.array(radii, dtype=float)
        # the floor: the plane of the base plate, normal the file's up axis (the drawing's floor)
        up = np.array(_UP.get(getattr(robot.spec.serial, "up", "+z"), (0, 0, 1)), dtype=float)
        q_home = 0.5 * (robot.lower + robot.upper)
        F = robot.frames(q_home)
        base_point = F[first, :3, 3]
        plane = np.array([*up, float(up @ base_point)])
        pts = np.zeros((len(caps_a), 2, 3))
        gk._capsule_points(F, caps_a, pts)
        # arc length along the chain at home, each capsule's start and end
        arc, s = [], 0.0
        for c in range(len(caps_a)):
            length = float(np.linalg.norm(pts[c, 1] - pts[c, 0]))
            arc.append((s, s + length))
            s += length
        ignored: list[str] = []
        pairs = []
        for a, b in itertools.combinations(range(len(caps_a)), 2):
            if caps_a[a, 0] == caps_a[b, 0]:
                continue  # one rigid link
            if labels[a].startswith("mount") and labels[b].startswith("mount"):
                continue
            gap = arc[b][0] - arc[a][1]
            if gap < radii_a[a] + radii_a[b] + settings.clear_zone:
                continue  # joined along the chain: a joint's own housing
            d = gk._segment_distance(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1]) - radii_a[a] - radii_a[b]
            if d <= settings.clear_stop:
                ignored.append(f"{labels[a]} ↔ {labels[b]}: touching at mid-range ({d * 1e3:.0f} mm), not checked")
                continue
            pairs.append((a, b))
        plane_caps = []
        below = set()
        for c in range(len(caps_a)):
            if caps_a[c, 0] <= first or labels[c].startswith("mount"):
                continue  # the mounts and the first moving link stand on the floor
            h = gk._plane_clearance(pts[c, 0], pts[c, 1], radii_a[c], plane)
            if h <= settings.clear_stop:
                below.add(labels[c])
                continue
            plane_caps.append(c)
        ignored += [f"{label} ↔ floor: below the floor at mid-range, not checked" for label in sorted(below)]
        guard = cls(
            robot=robot,
            caps=caps_a,
            radii=radii_a,
            labels=labels,
            pairs=np.array(pairs, dtype=np.int64).reshape(-1, 2),
            plane=plane,
            plane_caps=np.array(plane_caps, dtype=np.int64),
            settings=settings,
            ignored=ignored,
        )
        return guard._without_never_near()

    def _without_never_near(self, samples: int = NEVER_SAMPLES) -> HazardGuard:
        """The guard without the pairs (and floor checks) that no configuration brings near: over ``samples``
        seeded random configurations inside the limits (and mid-range), a pair never nearer than
        :data:`NEVER_NEAR` (0.15 m, beyond the 0.10 m zone) is never scaled for and costs a check every tick for
        nothing (MoveIt's setup assistant disables its "never in collision" pairs from random samples; a pair that
        came within 20 mm of touching in them is kept here, so the threshold is the zone's, not a collision's); nor
        a pair whose clearance no pose changes (two capsules of one rigid body)."""
        r = self.robot
        rng = np.random.default_rng(20261130)
        Q = np.vstack([0.5 * (r.lower + r.upper), rng.uniform(r.lower, r.upper, size=(samples, r.n_joints))])
        V = np.array([self.values(q)[1:] for q in Q]).reshape(len(Q), -1)
        least = V.min(axis=0)
        rigid = V.max(axis=0) - least < 1e-9  # two capsules no joint moves apart: one body (the Panda's hand)
        keep = (least <= NEVER_NEAR) & ~rigid
        P = len(self.pairs)
        for k in np.flatnonzero(~keep):
            what = (
                f"{self.labels[self.pairs[k][0]]} ↔ {self.labels[self.pairs[k][1]]}" if k < P
                else f"{self.labels[self.plane_caps[k - P]]} ↔ floor"
            )  # fmt: skip
            why = (
                "one rigid body (no joint between moves them)"
                if rigid[k]
                else (f"never nearer than {least[k] * 1e3:.0f} mm in {samples} random poses")
            )
            self.ignored.append(f"{what}: {why}")
        return HazardGuard(
            robot=r, caps=self.caps, radii=self.radii, labels=self.labels, pairs=self.pairs[keep[:P]],
            plane=self.plane, plane_caps=self.plane_caps[keep[P:]], settings=self.settings, ignored=self.ignored,
        )  # fmt: skip

    def _levers(self) -> NDArray[np.float64]:
        """Per joint j, a bound on how fast any point of the arm moves with it [m/rad or m/m]: from
        ∂p/∂q_j = Σ_l (M_θ[l, j] z_l × (p − o_l) + M_d[l, j] z_l), |∂p/∂q_j| ≤ Σ_l |M_θ[l, j]| R_l + |M_d[l, j]|, with
        R_l the reach of the chain after link l: Σ |a| + the largest |d| of the later links (a prismatic link's at
        the end of its stroke: the knuckle-boom crane's 4 m telescope, left out at first, let the safe-braking rule
        skip a check it needed, review), the tool's offset and the largest capsule radius."""
        r = self.robot
        tool = float(np.linalg.norm(np.asarray(r.T_flange_tool)[:3, 3]))
        span = np.maximum(np.abs(r.lower), np.abs(r.upper))
        d_max = np.abs(r._d0) + np.abs(r._M_d) @ span  # each link's largest |d| over the joints' ranges
        length = np.abs(r._a) + d_max
        R = np.array([float(length[l:].sum()) for l in range(len(length))]) + tool + float(self.radii.max(initial=0.0))
        return np.abs(r._M_theta).T @ R + np.abs(r._M_d).sum(axis=0)

    def _row_levers(self) -> NDArray[np.float64]:
        """Per checked clearance (the pairs, then the floor's) and joint j, a bound on how fast that clearance
        changes with q_j [m/rad or m/m]: W[c, j] = f · lever_j, with f how many of its two sides joint j moves
        other than rigidly together.  A capsule of link i (its points from frames i and i + 1) moves with every
        link l ≤ i; a joint whose links all come before both capsules' moves them as one rigid body, which keeps
        their distance (f = 0); else f counts the capsules it moves (a floor does not move).  Σ_j W[c, j]·|Δq_j|
        over a path on which each joint moves one way bounds that clearance's change along it
        (:func:`app.scenes.teleop_kernels.guard_tick`'s proven skip)."""
        r = self.robot
        acts = (np.abs(r._M_theta) + np.abs(r._M_d)) > 0.0  # (L, n): link l moves with joint j
        L, n = acts.shape
        moved = [np.flatnonzero(acts[:, j]) for j in range(n)]  # the links each joint moves, in chain order
        first = np.array([ls[0] if ls.size else L + 1 for ls in moved])
        last = np.array([ls[-1] if ls.size else -1 for ls in moved])
        link = self.caps[:, 0] if len(self.caps) else np.zeros(0, dtype=np.int64)
        rows = []
        for a, b in self.pairs:
            lo = min(link[a], link[b])
            f = (first <= link[a]).astype(float) + (first <= link[b]).astype(float)
            rows.append(np.where(last < lo, 0.0, f) * self.lever)
        for c in self.plane_caps:
            rows.append((first <= link[c]).astype(float) * self.lever)
        return np.ascontiguousarray(np.array(rows, dtype=float).reshape(len(rows), n))

    def margin(self, q_ref: ArrayLike, q_arm: ArrayLike) -> float:
        """How far any point of the arm at ``q_arm`` can be from where it is at ``q_ref`` [m]: Σ_j lever_j |Δq_j|
        (a Lipschitz bound of every clearance).  The servo lags its reference and brakes per joint, so the arm
        is not where the reference is: the capsules' stop is moved out by this much."""
        dq = np.abs(np.asarray(q_ref, dtype=float) - np.asarray(q_arm, dtype=float))
        return float(self.lever @ dq)

    def braking_path(self, q: ArrayLike, qdot: ArrayLike, accel: ArrayLike, samples: int = 5) -> NDArray[np.float64]:
        """``samples`` configurations along the joints' braking from (q, q̇), each joint at its acceleration limit
        until it stops (the last: where all have stopped), shape (samples, n)."""
        q = np.asarray(q, dtype=float)
        v = np.asarray(qdot, dtype=float)
        a = np.asarray(accel, dtype=float)
        finite = np.isfinite(a) & (a > 0)
        T = np.where(finite, np.abs(v) / np.where(finite, a, 1.0), 0.0)
        t = np.linspace(0.0, float(T.max(initial=0.0)), samples)[:, None]
        tau = np.minimum(t, T)
        return q + v * tau - 0.5 * np.where(finite, a, 0.0) * np.sign(v) * tau**2

    def braking_clearances(self, q: ArrayLike, qdot: ArrayLike, accel: ArrayLike) -> NDArray[np.float64]:
        """Every capsule clearance's least value along the braking from (q, q̇) [m] (:meth:`braking_path`)."""
        path = self.braking_path(q, qdot, accel)
        return np.min([self.values(p)[1:] for p in path], axis=0)

    # ------------------------------------------------------------------ use
    def values(self, q: ArrayLike) -> NDArray[np.float64]:
        """The σ ratio, then every checked pair's clearance [m], then every floor clearance [m] at q."""
        q = np.ascontiguousarray(q, dtype=float)
        gk.hazard_values(self.robot.kernel_record, self._chain, self._model, q, self._pts, self._out)
        return self._out.copy()

    def min_clearance(self, q: ArrayLike) -> float:
        """The least capsule clearance at q [m] (inf: nothing checked); negative is a penetration."""
        v = self.values(q)[1:]
        return float(v.min()) if v.size else math.inf

    def step(self, q: ArrayLike, dq: ArrayLike, margin: float = 0.0) -> tuple[NDArray[np.float64], GuardReport]:
        """The step ``dq`` from ``q`` scaled along the directions that bring a hazard nearer, and the report;
        ``margin`` [m] moves the capsules' zone and stop out (:meth:`margin`)."""
        settings = self._settings.copy()
        settings[8] = margin
        q = np.ascontiguousarray(q, dtype=float)
        dq = np.ascontiguousarray(dq, dtype=float)
        out = gk.guard_step(
            self.robot.kernel_record, self._chain, self._model, self._limits, q, dq, settings, self._report
        )
        return out, self.report(self._report)

    def in_tool_metric(self, tool: bool) -> None:
        """Correct the next steps in the tool's metric (a velocity command) or the joints' (a walk to a joint goal:
        the tool's motion along such a step is no command, and keeping it can lead a joint away from its goal
        for ever — the youBot's walk at its singularity's stop crept 20 s in ``bosun bench hold``)."""
        self._settings[10] = 1.0 if tool else 0.0

    def report(self, rep: NDArray[np.float64]) -> GuardReport:
        kind, idx, value, share, slowed, scale = rep[:6].tolist()  # every tick: Python floats at once
        if kind < 0:
            return GuardReport(slowed=bool(slowed), scale=scale)
        key = (int(kind), int(idx))
        name = self._names.get(key)
        if name is None:  # each hazard's name is formatted once
            name = self._names[key] = self.hazard_name(*key)
        unit = ""
        if key[0] == gk.LIMIT:
            unit = "m" if self.robot.joint_kinds[key[1] % self.robot.n_joints] == "prismatic" else "rad"
        return GuardReport(
            kind=KINDS[key[0]], name=name, value=value, share=share, slowed=bool(slowed), scale=scale, unit=unit
        )

    def hazard_name(self, kind: int, idx: int) -> str:
        r = self.robot
        if kind == gk.LIMIT:
            n = r.n_joints
            return f"{r.joint_names[idx % n]} {'upper' if idx >= n else 'lower'} limit"
        if kind == gk.SINGULAR:
            return "singularity"
        if kind == gk.PAIR:
            a, b = self.pairs[idx]
            return f"{self.labels[a]} ↔ {self.labels[b]}"
        return f"{self.labels[self.plane_caps[idx]]} ↔ floor"


# ---------------------------------------------------------------------------------------------- task-space hazards
def scale_in_box(
    step: ArrayLike, offset: ArrayLike, limit: ArrayLike, zone_share: float = 0.25
) -> tuple[NDArray[np.float64], int, float]:
    """A point's step inside the box ±``limit`` (per axis) around its centre, its offset from it ``offset``: each
    axis's outward component slowed linearly through the outer ``zone_share`` of the box to nothing at its face
    (the box's faces are the axes' planes, so an axis's component *is* the component along that face's normal);
    inward and along a face never slowed.  Returns the step, the axis nearest its face in its zone (−1: none) and
    that face's distance [m]."""
    step = np.asarray(step, dtype=float).copy()
    off = np.asarray(offset, dtype=float)
    lim = np.asarray(limit, dtype=float)
    gap = np.maximum(lim - np.abs(off), 0.0)
    zone = zone_share * lim
    axis, least = -1, math.inf
    for i in range(step.size):
        if gap[i] < zone[i] and gap[i] < least:
            axis, least = i, float(gap[i])
        outward = step[i] * off[i] > 0.0 or (off[i] == 0.0 and gap[i] <= 0.0)
        if outward and gap[i] < zone[i]:
            step[i] *= gap[i] / zone[i]
    return step, axis, least
