"""First-order kernel-corrected interpolation of the fluid at a point (Liu & Liu 2006, Appl. Numer.
Math. 56:19-36; the form DualSPHysics 5.4 solves for mDBC's ghost nodes and its variable-resolution
buffers, ``JSphCpu::InteractionMdbc2CorrectionT2``, ``JSphVRes``):

    A [f(x), grad f(x)]^T = [sum_j m_j W_xj, sum_j m_j grad_x W_xj]^T, over fluid j, with
    A = sum_j V_j [W_xj; grad_x W_xj] (x) [1, x_j - x],  V_j = m_j / rho_j,

solved for f(x) = rho(x) where A is well conditioned: its determinant at least 1e-3 and its
condition number, scaled by dx^2, at most 50; elsewhere the Shepard sum m W / sum V W. The same
sums give the Shepard velocity sum V W u / sum V W. In 2D the unused third axis is padded with the
identity, so one 4 x 4 system serves both dimensions. Used by mDBC's ghost nodes
(boundaries/mdbc.py) and by the passive particles of a refinement level (levels.py).
"""

import functools
from types import SimpleNamespace

import warp as wp

from . import kernels, neighbours, state

DETERMINANT_LIMIT = 1.0e-3  # DualSPHysics' determlimit for the first-order correction
# DualSPHysics 5.4 (JSphCpu::InteractionMdbc2CorrectionT2): the first-order correction only where A's
# condition number, scaled by dx^2, is at most this
CONDITION_LIMIT = 50.0


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    vec4 = wp.types.vector(4, scalar)
    mat44 = wp.types.matrix((4, 4), scalar)
    K = kernels.build(scalar)
    kernel_w, grad_factor, smoothing, own_scale = K.w, K.grad_factor, K.smoothing, K.own_scale
    same_level = K.same_level
    N = neighbours.grid(scalar)
    Grid, separation = N.Grid, N.separation
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields

    @wp.func
    def no_sums():
        """The sums (A, the right-hand side, sum V W u) before any particle is added."""
        return mat44(scalar(0.0)), vec4(scalar(0.0)), vec(scalar(0.0))

    @wp.func
    def corrected_term(p: Params, grid: Grid, f: Fields, x: vec, h_x: scalar, j: int, a: mat44, rhs: vec4, u: vec):
        """Fluid particle j's part of the correction matrix A, of the right-hand side
        [sum m W, sum m grad W] and of sum V W u at the point x of smoothing length h_x (nothing
        beyond the support)."""
        r_xj = separation(grid, x, f.pos[j])
        r = wp.length(r_xj)
        h, inv_h, norm, scale = smoothing(p, h_x, f.hsml[j])
        if r < scalar(2.0) * h:
            w = kernel_w(p.kernel, norm, inv_h, r)
            gw = r_xj * grad_factor(p.kernel, norm, inv_h, r)
            m = f.mass[j]
            v = m / f.rho[j]
            row = vec4(w, gw[0], gw[1], gw[2])
            a += v * wp.outer(row, vec4(scalar(1.0), -r_xj[0], -r_xj[1], -r_xj[2]))
            rhs += m * row
            u += v * w * f.vel[j]
        return a, rhs, u

    @wp.func
    def inf_norm(m: mat44) -> scalar:
        """The largest row sum of |m|."""
        out = scalar(0.0)
        for r in range(4):
            out = wp.max(out, wp.abs(m[r, 0]) + wp.abs(m[r, 1]) + wp.abs(m[r, 2]) + wp.abs(m[r, 3]))
        return out

    @wp.func
    def corrected_density(p: Params, a: mat44, rhs: vec4, h_x: scalar) -> scalar:
        """The density from the sums (a[0, 0] > 0): first order where A is well conditioned (its
        determinant at least DETERMINANT_LIMIT and its condition number, scaled by dx^2, at most
        CONDITION_LIMIT), else the Shepard sum."""
        if p.dim == 2:
            a[3, 3] = scalar(1.0)  # the unused axis
        if wp.abs(wp.determinant(a)) >= scalar(DETERMINANT_LIMIT):
            inv = wp.inverse(a)
            dx = p.dx * own_scale(p, h_x)
            if dx * dx * inf_norm(a) * inf_norm(inv) <= scalar(CONDITION_LIMIT):
                return (inv * rhs)[0]
        return rhs[0] / a[0, 0]

    @wp.func
    def occupied(p: Params, grid: Grid, f: Fields, x: vec, h_x: scalar, j: int, fluid: scalar, wall: scalar):
        """Particle j's part of the kernel sums sum V W at x of the fluid and of the walls of x's level."""
        if same_level(p, h_x, f.hsml[j]):
            r = wp.length(separation(grid, x, f.pos[j]))
            h, inv_h, norm, scale = smoothing(p, h_x, f.hsml[j])
            if r < scalar(2.0) * h:
                vw = f.mass[j] / f.rho[j] * kernel_w(p.kernel, norm, inv_h, r)
                if state.carries_fluid(f.ptype[j]):
                    fluid += vw
                elif f.ptype[j] == state.BOUNDARY:
                    wall += vw
        return fluid, wall

    @wp.func
    def wet_share(fluid: scalar, wall: scalar) -> scalar:
        """The share of a support's room beside the walls that the fluid fills, sum_f V W /
        (1 - sum_w V W), at most 1: a face reading's weight where part of the support is dry (air
        at ambient), which a Shepard mean would fill with the fluid present."""
        room = scalar(1.0) - wall
        if fluid < room:
            return fluid / room
        return scalar(1.0)

    return SimpleNamespace(vec4=vec4, mat44=mat44, no_sums=no_sums, corrected_term=corrected_term, occupied=occupied,
                           wet_share=wet_share,
                           corrected_density=corrected_density)
