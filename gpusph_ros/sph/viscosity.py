"""Diffusion terms of the momentum equation (thesis Eq. 2.15), chosen by name.

- artificial: Monaghan 1992 artificial viscosity (not in the thesis, which ran laminar and SPS),
  Pi_ab = -alpha c_ab mu_ab / rho_ab for approaching pairs, mu_ab = h u_ab.r_ab / (r_ab^2 + 0.01 h^2)
  (the 0.01 h^2 regulariser as GPUSPH and DualSPHysics).
- laminar: thesis Eq. 2.16-2.17 (Lo & Shao 2002; Morris et al. 1997 form).
- sps: laminar plus the Sub-Particle-Scale stress of Dalrymple & Rogers 2006, thesis Eq.
  2.18-2.21. The thesis prints the isotropic part as C_I dl^2 |S|; dimensional consistency and
  the source (Dalrymple & Rogers 2006, Eq. 13) give C_I dl^2 |S|^2, used here.
"""

import functools
from types import SimpleNamespace

import warp as wp

NAMES = ("artificial", "laminar", "sps")  # the run setting ``viscosity``
VISCOSITY_ID = {name: k for k, name in enumerate(NAMES)}


def params(cfg) -> dict:
    """The Params fields of the viscosity of ``cfg`` (a SolverConfig): its id, alpha and alpha at the
    wall (x the wall friction, SolverConfig.wall_friction), nu, and the SPS constants times the
    spacing, (Cs dl)^2 and CI dl^2."""
    return {"viscosity": VISCOSITY_ID[cfg.viscosity], "alpha": cfg.alpha,
            "alpha_wall": cfg.alpha * cfg.wall_friction, "nu": cfg.nu, "cs_dl2": (cfg.sps_cs * cfg.dx) ** 2,
            "ci_dl2": cfg.sps_ci * cfg.dx ** 2}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.func
    def artificial(alpha: scalar, h: scalar, c_mean: scalar, rho_mean: scalar, m_b: scalar,
                   u_ab: vec, r_ab: vec, r2_eta: scalar, grad: vec) -> vec:
        """``r2_eta`` = r^2 + 0.01 h^2."""
        vr = wp.dot(u_ab, r_ab)
        if vr >= scalar(0.0):
            return vec(scalar(0.0))
        mu = h * vr / r2_eta
        pi_ab = -alpha * c_mean * mu / rho_mean
        return -m_b * pi_ab * grad

    @wp.func
    def laminar(nu: scalar, rho_a: scalar, rho_b: scalar, m_b: scalar, u_ab: vec, r_ab: vec,
                r2_eta: scalar, grad: vec) -> vec:
        """``r2_eta`` = r^2 + 0.01 h^2."""
        return m_b * scalar(4.0) * nu * wp.dot(r_ab, grad) / ((rho_a + rho_b) * r2_eta) * u_ab

    @wp.func
    def sps_stress(grad_u: wp.types.matrix((3, 3), scalar), cs_dl2: scalar, ci_dl2: scalar):
        """tau / rho from the velocity gradient: 2 nu_t (S - tr(S)/3 I) - 2/3 C_I dl^2 |S|^2 I.

        Returned as the diagonal (xx, yy, zz) and off-diagonal (xy, xz, yz) parts.
        """
        s = scalar(0.5) * (grad_u + wp.transpose(grad_u))
        s_norm = wp.sqrt(scalar(2.0) * wp.ddot(s, s))
        nu_t = cs_dl2 * s_norm
        trace3 = (s[0, 0] + s[1, 1] + s[2, 2]) / scalar(3.0)
        iso = scalar(2.0) / scalar(3.0) * ci_dl2 * s_norm * s_norm
        diag = vec(scalar(2.0) * nu_t * (s[0, 0] - trace3) - iso,
                   scalar(2.0) * nu_t * (s[1, 1] - trace3) - iso,
                   scalar(2.0) * nu_t * (s[2, 2] - trace3) - iso)
        off = vec(scalar(2.0) * nu_t * s[0, 1], scalar(2.0) * nu_t * s[0, 2], scalar(2.0) * nu_t * s[1, 2])
        return diag, off

    @wp.func
    def sps_accel(m_b: scalar, rho_a: scalar, rho_b: scalar, diag_a: vec, off_a: vec, diag_b: vec,
                  off_b: vec, grad: vec) -> vec:
        """m_b (tau_a / rho_a^2 + tau_b / rho_b^2) . grad_a W, with tau / rho stored per particle."""
        d = diag_a / rho_a + diag_b / rho_b
        o = off_a / rho_a + off_b / rho_b
        return m_b * vec(d[0] * grad[0] + o[0] * grad[1] + o[1] * grad[2],
                         o[0] * grad[0] + d[1] * grad[1] + o[2] * grad[2],
                         o[1] * grad[0] + o[2] * grad[1] + d[2] * grad[2])

    return SimpleNamespace(artificial=artificial, laminar=laminar, sps_stress=sps_stress, sps_accel=sps_accel)
