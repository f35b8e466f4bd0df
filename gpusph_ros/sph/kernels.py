"""Smoothing kernels W(r, h) with compact support 2h, in 2D and 3D, for the SPH interpolant
f(x) = sum_j f_j W(x - x_j) V_j (thesis Eq. 2.4).

- quadratic: thesis Eq. 2.5-2.8 (Johnson et al. 1996; Gomez-Gesteira et al. 2010).
  W = a_D (3/16 q^2 - 3/4 q + 3/4), a_D = 5 / (4 pi h^3) in 3D, 2 / (pi h^2) in 2D.
- cubic_spline: thesis Eq. 2.9-2.10 (Monaghan & Lattanzio 1985).
  W = a_D (1 - 1.5 q^2 + 0.75 q^3) for q < 1, a_D 0.25 (2 - q)^3 for 1 <= q < 2,
  a_D = 1 / (pi h^3) in 3D, 10 / (7 pi h^2) in 2D.
- wendland: Wendland C2 (Wendland 1995), W = a_D (1 - q/2)^4 (2q + 1),
  a_D = 21 / (16 pi h^3) in 3D, 7 / (4 pi h^2) in 2D.

q = r / h. The kernel is chosen at run time by an integer id so that one compiled force pass
serves every kernel; the branch costs nothing next to the neighbour loop.

Where particles differ in smoothing length (refinement levels, levels.py) only particles of one
level interact (``same_level``); a passive particle reads another level at the mean of the two,
h_ab = (h_a + h_b) / 2 (the symmetrised h of Vacondio et al. 2013, CMAME 256, Eq. 9).
"""

import functools
import math
from types import SimpleNamespace

import numpy as np
import warp as wp

from . import state
from .device import default_device

NAMES = ("quadratic", "cubic_spline", "wendland")  # the run setting ``kernel``
KERNEL_ID = {name: k for k, name in enumerate(NAMES)}
QUADRATIC, CUBIC_SPLINE, WENDLAND = (KERNEL_ID[name] for name in ("quadratic", "cubic_spline", "wendland"))

_NORM = {
    ("quadratic", 2): 2.0 / math.pi,
    ("quadratic", 3): 5.0 / (4.0 * math.pi),
    ("cubic_spline", 2): 10.0 / (7.0 * math.pi),
    ("cubic_spline", 3): 1.0 / math.pi,
    ("wendland", 2): 7.0 / (4.0 * math.pi),
    ("wendland", 3): 21.0 / (16.0 * math.pi),
}


def normalisation(kernel: str, dim: int, h: float) -> float:
    """a_D of the kernel in ``dim`` dimensions for smoothing length ``h``."""
    return _NORM[(kernel, dim)] / h ** dim


def params(cfg, h_min: "float | None" = None) -> dict:
    """The Params fields of the kernel of ``cfg`` (a SolverConfig): its id, a_D, h, 1/h and the
    0.01 h^2 that regularises 1/r^2 in the viscous and diffusive terms; with ``h_min``, the smallest
    smoothing length of a refined particle set (pairs then read each particle's own)."""
    h_min = cfg.h if h_min is None else h_min
    refined = h_min < cfg.h * (1.0 - 1.0e-9)
    return {"kernel": KERNEL_ID[cfg.kernel], "norm": normalisation(cfg.kernel, cfg.dim, cfg.h), "h": cfg.h,
            "inv_h": 1.0 / cfg.h, "eta2": 0.01 * cfg.h ** 2, "norm_unit": _NORM[(cfg.kernel, cfg.dim)],
            "variable_h": int(refined), "h_min": min(h_min, cfg.h), "coarse_stride": coarse_stride(cfg, refined)}


def coarse_stride(cfg, refined: bool) -> int:
    """How many of the finest level's steps one step of the coarser levels spans: 2 with
    refinement levels (``refined``) and ``multirate``, else 1. What the neighbour lists are sized
    for (neighbours.list_skin), before a solver exists too (config, resources)."""
    return 2 if refined and cfg.multirate else 1


# which particles a pass of a multi-rate step takes (``selected``)
EVERY_LEVEL, FINEST_LEVEL, COARSER_LEVELS = 0, 1, 2


@functools.lru_cache(maxsize=None)
def build(scalar):
    """Kernel functions for one floating-point type (wp.float32 or wp.float64)."""

    @wp.func
    def shape(kernel: int, q: scalar) -> scalar:
        """W / a_D as a function of q; zero outside the support."""
        if q >= scalar(2.0):
            return scalar(0.0)
        if kernel == QUADRATIC:
            return scalar(0.1875) * q * q - scalar(0.75) * q + scalar(0.75)
        if kernel == CUBIC_SPLINE:
            if q < scalar(1.0):
                return scalar(1.0) - scalar(1.5) * q * q + scalar(0.75) * q * q * q
            t = scalar(2.0) - q
            return scalar(0.25) * t * t * t
        t = scalar(1.0) - scalar(0.5) * q
        return t * t * t * t * (scalar(2.0) * q + scalar(1.0))

    @wp.func
    def shape_dq(kernel: int, q: scalar) -> scalar:
        """d(W / a_D) / dq; zero outside the support."""
        if q >= scalar(2.0):
            return scalar(0.0)
        if kernel == QUADRATIC:
            return scalar(0.375) * q - scalar(0.75)
        if kernel == CUBIC_SPLINE:
            if q < scalar(1.0):
                return scalar(-3.0) * q + scalar(2.25) * q * q
            t = scalar(2.0) - q
            return scalar(-0.75) * t * t
        t = scalar(1.0) - scalar(0.5) * q
        return scalar(-5.0) * q * t * t * t

    @wp.func
    def w(kernel: int, norm: scalar, inv_h: scalar, r: scalar) -> scalar:
        """W(r, h) with ``norm`` = a_D."""
        return norm * shape(kernel, r * inv_h)

    @wp.func
    def grad_factor(kernel: int, norm: scalar, inv_h: scalar, r: scalar) -> scalar:
        """F(r) = (dW/dr) / r, so that grad_a W_ab = r_ab F(r_ab). Finite as r -> 0."""
        q = r * inv_h
        if kernel == QUADRATIC:
            # the quadratic kernel's slope does not vanish at q = 0; guard the division
            return norm * inv_h * shape_dq(kernel, q) / wp.max(r, scalar(1.0e-3) / inv_h)
        if q < scalar(1.0e-6):
            return scalar(0.0)
        return norm * inv_h * shape_dq(kernel, q) / r

    Params = state.build(scalar).Params

    @wp.func
    def smoothing(p: Params, h_a: scalar, h_b: scalar):
        """(h, 1/h, a_D, h / the scene's h) of the pair a, b: the scene's own values when every
        particle has the same h (so that a uniform run computes exactly what it did before zones
        existed), else those of h_ab = (h_a + h_b) / 2."""
        if p.variable_h == 0:
            return p.h, p.inv_h, p.norm, scalar(1.0)
        h = scalar(0.5) * (h_a + h_b)
        inv_h = scalar(1.0) / h
        norm = p.norm_unit * inv_h * inv_h
        if p.dim == 3:
            norm = norm * inv_h
        return h, inv_h, norm, h * p.inv_h

    @wp.func
    def same_level(p: Params, h_a: scalar, h_b: scalar) -> bool:
        """Whether particles of smoothing lengths h_a and h_b are of one refinement level: only
        such pairs interact; another level reaches a particle through its passive particles
        (levels.py). Always true when every particle has the same h."""
        return p.variable_h == 0 or h_a == h_b

    @wp.func
    def finest_level(p: Params, h_a: scalar) -> bool:
        """Whether a particle of smoothing length h_a is of the finest level (every particle is
        when all have the same h)."""
        return h_a < p.h_min * scalar(1.001)

    @wp.func
    def stride(p: Params, h_a: scalar) -> int:
        """How many of the finest level's steps one step of a particle of smoothing length h_a spans:
        1 on the finest level, ``coarse_stride`` (2 with multirate, else 1) on every coarser one."""
        if p.coarse_stride == 1 or finest_level(p, h_a):
            return 1
        return p.coarse_stride

    @wp.func
    def selected(p: Params, h_a: scalar, levels: int) -> bool:
        """Whether a pass over ``levels`` (EVERY_LEVEL, FINEST_LEVEL, COARSER_LEVELS) takes a
        particle of smoothing length h_a."""
        if levels == EVERY_LEVEL:
            return True
        return (levels == FINEST_LEVEL) == finest_level(p, h_a)

    @wp.func
    def own_scale(p: Params, h_a: scalar) -> scalar:
        """h_a / the scene's h: what a length set in dx (a cap, a threshold) is scaled by for a
        refined particle; exactly 1 when every particle has the scene's h."""
        if p.variable_h == 0:
            return scalar(1.0)
        return h_a * p.inv_h

    @wp.kernel(enable_backward=False, module="unique")
    def evaluate(kernel: int, norm: scalar, inv_h: scalar, r: wp.array(dtype=scalar),
                 w_out: wp.array(dtype=scalar), dw_out: wp.array(dtype=scalar)):
        i = wp.tid()
        w_out[i] = w(kernel, norm, inv_h, r[i])
        dw_out[i] = grad_factor(kernel, norm, inv_h, r[i]) * r[i]

    return SimpleNamespace(shape=shape, shape_dq=shape_dq, w=w, grad_factor=grad_factor, smoothing=smoothing,
                           same_level=same_level, own_scale=own_scale, finest_level=finest_level, stride=stride,
                           selected=selected,
                           evaluate=evaluate)


def evaluate(kernel: str, dim: int, h: float, r, precision: str = "float64", device: str = None):
    """W(r) and dW/dr at the distances ``r`` (host arrays), computed by the device functions (on
    ``device``, default device.default_device())."""
    device = device or default_device()
    scalar = wp.float64 if precision == "float64" else wp.float32
    kern = build(scalar).evaluate
    r_dev = wp.array(np.asarray(r, dtype=np.float64), dtype=scalar, device=device)
    w_dev = wp.zeros_like(r_dev)
    dw_dev = wp.zeros_like(r_dev)
    wp.launch(kern, dim=len(r_dev), inputs=[KERNEL_ID[kernel], normalisation(kernel, dim, h), 1.0 / h,
                                            r_dev, w_dev, dw_dev], device=device)
    return w_dev.numpy(), dw_dev.numpy()
