"""Stoker's dam break over a wet bed (Stoker 1957, Water Waves, Section 10.8): the shallow-water
solution that a surge running over a thin layer of still water tends to once the flow is long
against the depth (Chanson 2009 compares it with experiments).

Still water of depth H behind a dam at x0 and h0 < H in front of it; the dam goes at t = 0. The
solution is self-similar in xi = (x - x0) / t: the undisturbed column up to xi = -c_H
(c = sqrt(g h)), a centred rarefaction
    h = (2 c_H - xi)^2 / (9 g),  u = 2 (c_H + xi) / 3,
down to the intermediate state (h_m, u_m) from xi = u_m - c_m on, that state up to the bore at
xi = S, and the still bed beyond it. The intermediate state joins the rarefaction's Riemann
invariant u_m = 2 (c_H - c_m) to the bore's jump conditions into still water,
    S = sqrt(g h_m (h_m + h0) / (2 h0)),  u_m = S (1 - h0 / h_m),
solved here for h_m by bisection.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StokerState:
    """The wet-bed dam break's intermediate state and bore: depth h_m [m], velocity u_m [m/s],
    bore speed S [m/s], and where the rarefaction ends, xi_m = u_m - c_m [m/s]."""

    h_m: float
    u_m: float
    bore_speed: float
    xi_m: float


def stoker(depth: float, bed: float, g: float = 9.81) -> StokerState:
    """The solution for a column ``depth`` H deep released over a bed ``bed`` h0 deep (0 < h0 < H)."""
    if not 0.0 < bed < depth:
        raise ValueError(f"bed: {bed!r} is not allowed; expected a depth in (0, {depth!r}) (the column's)")
    c_h = math.sqrt(g * depth)

    def mismatch(h):
        s = math.sqrt(g * h * (h + bed) / (2.0 * bed))
        return 2.0 * (c_h - math.sqrt(g * h)) - s * (1.0 - bed / h)

    lo, hi = bed, depth  # mismatch > 0 at h0 (no jump yet), < 0 at H (no rarefaction left)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mismatch(mid) > 0.0:
            lo = mid
        else:
            hi = mid
    h_m = 0.5 * (lo + hi)
    u_m = 2.0 * (c_h - math.sqrt(g * h_m))
    return StokerState(h_m=h_m, u_m=u_m, bore_speed=math.sqrt(g * h_m * (h_m + bed) / (2.0 * bed)),
                       xi_m=u_m - math.sqrt(g * h_m))


def depth_at(xi: float, depth: float, bed: float, g: float = 9.81) -> float:
    """h at xi = (x - x0) / t."""
    s = stoker(depth, bed, g)
    c_h = math.sqrt(g * depth)
    if xi <= -c_h:
        return depth
    if xi <= s.xi_m:
        return (2.0 * c_h - xi) ** 2 / (9.0 * g)
    return s.h_m if xi <= s.bore_speed else bed


@dataclass(frozen=True)
class Surge:
    """What a particle snapshot shows of the surge at time t: the bore's position [m], and the
    depth [m] and depth-mean velocity [m/s] over the middle half of the plateau Stoker predicts."""

    bore: float
    depth: float
    velocity: float


def surge(pos, vel, t: float, x0: float, depth: float, bed: float, dx: float, dim: int = 2,
          g: float = 9.81) -> Surge:
    """Measure the surge in the fluid particles' positions and velocities (n x 3, the vertical
    axis the last of ``dim``) at time t after a dam at x0 broke: columns 2 dx wide, each one's
    surface dx/2 over its highest particle; the bore is the most downstream column deeper than
    halfway from the bed to Stoker's h_m."""
    s = stoker(depth, bed, g)
    up = dim - 1
    x, y, u = np.asarray(pos)[:, 0], np.asarray(pos)[:, up], np.asarray(vel)[:, 0]
    width = 2.0 * dx
    edges = np.arange(x.min(), x.max() + width, width)
    k = np.digitize(x, edges) - 1
    top = np.full(len(edges), -np.inf)
    np.maximum.at(top, k, y)
    centres = edges + 0.5 * width
    wet = np.isfinite(top)
    surface = np.where(wet, top + 0.5 * dx, 0.0)
    deep = np.nonzero(wet & (surface > 0.5 * (bed + s.h_m)))[0]
    bore = float(centres[deep.max()]) if len(deep) else float("nan")
    a, b = x0 + s.xi_m * t, x0 + s.bore_speed * t
    lo, hi = a + 0.25 * (b - a), b - 0.25 * (b - a)
    plateau = wet & (centres >= lo) & (centres <= hi)
    inside = (x >= lo) & (x <= hi)
    return Surge(bore=bore, depth=float(np.median(surface[plateau])), velocity=float(u[inside].mean()))
