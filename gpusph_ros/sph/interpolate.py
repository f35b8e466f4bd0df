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
    def inverse(a: mat44):
        """(A^-1, det A) by Gauss-Jordan elimination with partial pivoting, in the run's precision
        ((0, 0) where A is singular). Warp's own 4 x 4 ``inverse`` and ``determinant`` (mat.h) work
        in float64 whatever the matrix's type: about a hundred float64 instructions in each float32
        CUDA kernel that solves for a density, at 1/64 of the float32 rate on the RTX cards many users
        have (issue 67). The pivot is brought up by swaps with each row below in turn, so every
        index is a constant once Warp unrolls the loops and the matrices stay in registers."""
        inv = wp.identity(4, scalar)
        det = scalar(1.0)
        for k in range(4):
            for i in range(4):
                if i > k and wp.abs(a[i, k]) > wp.abs(a[k, k]):
                    row = a[k]
                    a[k] = a[i]
                    a[i] = row
                    row = inv[k]
                    inv[k] = inv[i]
                    inv[i] = row
                    det = -det
            pivot = a[k, k]
            det *= pivot
            if pivot == scalar(0.0):
                return mat44(scalar(0.0)), scalar(0.0)
            a[k] = a[k] / pivot
            inv[k] = inv[k] / pivot
            for i in range(4):
                if i != k:
                    f = a[i, k]
                    a[i] = a[i] - f * a[k]
                    inv[i] = inv[i] - f * inv[k]
        return inv, det

    @wp.func
    def corrected_density(p: Params, a: mat44, rhs: vec4, h_x: scalar) -> scalar:
        """The density from the sums (a[0, 0] > 0): first order where A is well conditioned (its
        determinant at least DETERMINANT_LIMIT and its condition number, scaled by dx^2, at most
        CONDITION_LIMIT), else the Shepard sum. A is solved as D A D^-1, D = diag(1, h, h, h), whose
        entries are all of order one (A's first row is of order h, its first column of 1/h): the
        same determinant, a float32 solve as accurate as the float64 one within what rounding A's
        entries to float32 already costs (tests/test_interpolate.py)."""
        if p.dim == 2:
            a[3, 3] = scalar(1.0)  # the unused axis
        d = wp.diag(vec4(scalar(1.0), h_x, h_x, h_x))
        d_inv = wp.diag(vec4(scalar(1.0), scalar(1.0) / h_x, scalar(1.0) / h_x, scalar(1.0) / h_x))
        inv_scaled, det = inverse(d * a * d_inv)
        if wp.abs(det) >= scalar(DETERMINANT_LIMIT):
            inv = d_inv * inv_scaled * d
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
                           wet_share=wet_share, inverse=inverse, corrected_density=corrected_density)
