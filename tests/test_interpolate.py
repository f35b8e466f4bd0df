"""The first-order corrected interpolation's solve (sph/interpolate.py), in the run's precision
(issue 67: Warp's own 4 x 4 inverse and determinant work in float64 whatever the matrix's type).

- ``inverse`` against numpy's float64 inverse and determinant: within 1e-5 of the largest entry on
  matrices whose condition number is at most 1e3, a zero first pivot included (the pivoting is
  exercised), (0, 0) on a singular matrix.
- On real ghost nodes: the systems mDBC solves for every wall particle of the Martin & Moyce column
  (``collapse_2d``, dx = 1 cm, boundary mdbc) at rest and after it has hit the far wall (t = 0.3 s),
  summed in float64 (66 and 130 nodes with a film of fluid or more, 63 and 113 of them well enough
  conditioned for the first order). The float32 ``corrected_density`` of each system rounded to
  float32 is compared with the float64 solve of the float64 system, at every node (a node whose
  branch differed would be off by the correction itself): within 1e-5 rho0 and within 4 times the
  floor that rounding the system to float32 sets (a float64 solve of the rounded system). Measured:
  3.3e-7 and 3.4e-6 rho0, against floors of 2.2e-7 and 1.7e-6 (3.4e-6 rho0 is 0.4 Pa at this
  case's sound speed); what Warp's float64 minors gave (the rounded system solved in float64, its
  inverse rounded to float32) sits at that floor.
"""
import numpy as np
import pytest
import warp as wp

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import interpolate, neighbours, state
from gpusph_ros.sph.boundaries.mdbc import FILM_SUM

DX = 0.01


def _inverse_kernel(scalar):
    interp = interpolate.build(scalar)

    @wp.kernel(enable_backward=False, module="unique")
    def solve(a: wp.array(dtype=interp.mat44), inv: wp.array(dtype=interp.mat44), det: wp.array(dtype=scalar)):
        i = wp.tid()
        m, d = interp.inverse(a[i])
        inv[i] = m
        det[i] = d
    return solve, interp.mat44


@pytest.mark.unit
def test_the_inverse_matches_float64_within_its_conditioning():
    rng = np.random.default_rng(7)
    mats = []
    while len(mats) < 500:
        m = rng.normal(size=(4, 4))
        if np.linalg.cond(m, np.inf) <= 1.0e3:
            mats.append(m)
    mats[0][0, 0] = 0.0  # the first pivot must come from below
    mats.append(np.diag([1.0, 2.0, 0.0, 3.0]))  # singular
    a = np.array(mats, dtype=np.float32)
    kernel, mat44 = _inverse_kernel(wp.float32)
    inv, det = wp.zeros(len(a), dtype=mat44, device="cpu"), wp.zeros(len(a), dtype=wp.float32, device="cpu")
    wp.launch(kernel, len(a), inputs=[wp.array(a, dtype=mat44, device="cpu"), inv, det], device="cpu")
    inv, det = inv.numpy().astype(np.float64), det.numpy().astype(np.float64)
    ref = np.linalg.inv(a[:-1].astype(np.float64))
    scale = np.abs(ref).max(axis=(1, 2))
    assert np.max(np.abs(inv[:-1] - ref).max(axis=(1, 2)) / scale) < 1.0e-5
    det_ref = np.linalg.det(a[:-1].astype(np.float64))
    assert np.max(np.abs(det[:-1] - det_ref) / np.abs(det_ref)) < 1.0e-5
    assert det[-1] == 0.0 and not inv[-1].any()


def _ghost_systems(t_end: float):
    """(A, rhs, h) in float64 of every mDBC ghost node with a film or more of fluid around it, in
    ``collapse_2d`` at DX run in float64 to ``t_end``; a float32 solver of the same model."""
    scene = load_scene("collapse_2d")
    solver = build(scene, dx=DX, boundary="mdbc", precision="float64").solver()
    solver.advance(t_end)
    pos = solver.pos.numpy()
    ptype = solver.ptype.numpy()
    fluid = ptype == 0
    hsml = solver.fields.hsml.numpy()
    walls = np.flatnonzero(ptype == 1)
    xg = pos[walls] + solver.ghost.numpy()[walls]
    interp, S = interpolate.build(wp.float64), state.build(wp.float64)
    params, fields, nl = solver.measurement_view()

    @wp.kernel(enable_backward=False, module="unique")
    def sums(p: S.Params, grid: neighbours.grid(wp.float64).Grid, f: S.Fields, xg: wp.array(dtype=solver.vec),
             h: wp.array(dtype=wp.float64), js: wp.array(dtype=wp.int32), a: wp.array(dtype=interp.mat44),
             b: wp.array(dtype=interp.vec4)):
        k = wp.tid()
        m, r, u = interp.no_sums()
        for n in range(js.shape[0]):
            m, r, u = interp.corrected_term(p, grid, f, xg[k], h[k], js[n], m, r, u)
        a[k] = m
        b[k] = r

    dev = solver.device
    a = wp.zeros(len(walls), dtype=interp.mat44, device=dev)
    b = wp.zeros(len(walls), dtype=interp.vec4, device=dev)
    wp.launch(sums, len(walls), inputs=[params, nl.grid, fields, wp.array(xg, dtype=solver.vec, device=dev),
                                        wp.array(hsml[walls], dtype=wp.float64, device=dev),
                                        wp.array(np.flatnonzero(fluid).astype(np.int32), device=dev), a, b],
              device=dev)
    A, rhs = a.numpy(), b.numpy()
    keep = A[:, 0, 0] >= FILM_SUM
    return A[keep], rhs[keep], hsml[walls][keep], build(scene, dx=DX, boundary="mdbc").solver()


def _first_order(A, rhs, h, dx):
    """numpy's float64 solve of each system as corrected_density decides it: (density, first order?)."""
    A = A.copy()
    A[:, 3, 3] = 1.0  # 2D
    out, first = rhs[:, 0] / A[:, 0, 0], np.zeros(len(A), dtype=bool)
    for k in range(len(A)):
        if abs(np.linalg.det(A[k])) >= interpolate.DETERMINANT_LIMIT:
            inv = np.linalg.inv(A[k])
            if dx * dx * np.abs(A[k]).sum(axis=1).max() * np.abs(inv).sum(axis=1).max() <= interpolate.CONDITION_LIMIT:
                out[k], first[k] = (inv @ rhs[k])[0], True
    return out, first


@pytest.mark.physics
@pytest.mark.parametrize("t_end", [0.0, 0.3])
def test_the_float32_solve_of_real_ghost_systems_matches_float64(t_end):
    A, rhs, h, solver32 = _ghost_systems(t_end)
    assert len(A) > 50
    ref, first = _first_order(A, rhs, h, DX)
    A32, rhs32, h32 = A.astype(np.float32), rhs.astype(np.float32), h.astype(np.float32)
    floor, _ = _first_order(A32.astype(np.float64), rhs32.astype(np.float64), h32.astype(np.float64), DX)
    interp = interpolate.build(wp.float32)
    params = solver32.measurement_view()[0]

    @wp.kernel(enable_backward=False, module="unique")
    def density(p: state.build(wp.float32).Params, a: wp.array(dtype=interp.mat44), b: wp.array(dtype=interp.vec4),
                h: wp.array(dtype=wp.float32), rho: wp.array(dtype=wp.float32)):
        k = wp.tid()
        rho[k] = interp.corrected_density(p, a[k], b[k], h[k])

    dev = solver32.device
    rho = wp.zeros(len(A), dtype=wp.float32, device=dev)
    wp.launch(density, len(A), inputs=[params, wp.array(A32, dtype=interp.mat44, device=dev),
                                       wp.array(rhs32, dtype=interp.vec4, device=dev),
                                       wp.array(h32, dtype=wp.float32, device=dev), rho], device=dev)
    rho = rho.numpy().astype(np.float64)
    rho0 = solver32.config.rho0
    assert first.sum() > 0.5 * len(A)
    err, err_floor = np.abs(rho - ref) / rho0, np.abs(floor - ref) / rho0
    print(f"t = {t_end}: {len(A)} ghost nodes, {first.sum()} first order; |rho32 - rho64| / rho0 at most "
          f"{err.max():.2e}, the float64 solve of the rounded systems {err_floor.max():.2e}")
    assert err.max() < 1.0e-5 and err.max() <= 4.0 * err_floor.max()
