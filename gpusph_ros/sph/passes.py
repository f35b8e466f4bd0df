"""The passes of one solver step, one Warp kernel each, compiled once per floating-point type.

Models are chosen at run time through integer ids held in ``Params`` (see kernels.KERNEL_ID,
viscosity.VISCOSITY_ID, boundaries.BOUNDARY_ID, density.DENSITY_DIFFUSION_ID); the physics of
each model lives in its own module and is only combined here.

Step (predictor-corrector as GPUSPH, Herault et al. 2010):
  neighbours(x_n) -> eos -> [sps] -> interact(n) -> choose_dt
  -> integrate(dt/2) -> eos -> [sps] -> interact(n+1/2) -> integrate(dt) into the candidate state
  -> health(candidate) -> [census(candidate) -> census_check, every few steps]
  -> commit (only if healthy) -> tick -> [shepard every N steps]
The committed state is never overwritten by a candidate that failed a health check.

Health checks (CHECKS), each a way a run fails:
- non_finite: NaN or infinity in a position, velocity or density;
- outside_domain: a fluid particle left the domain (the tank, its walls and headroom);
- density_bounds: a density outside [rho_min, rho_max] (0.8 and 1.25 rho0 by default);
- wall_penetration: a fluid particle more than ``penetration_ratio`` dx beyond a wall face of the
  tank, or as deep inside a solid box: the boundary let it through;
- clumping: more than ``clump_fraction`` of the fluid particles have a fluid neighbour closer
  than ``clump_ratio`` dx, marked in the force pass (the tensile and pairing instabilities pair
  particles long before anything is infinite; a few pairs in a splash are no failure);
- energy_growth: the fluid's kinetic + potential + elastic energy (Tait law integrated,
  e(rho) = B/rho0 ((rho/rho0)^(gamma-1) - 1)/(gamma-1) + B (1/rho - 1/rho0)) more than
  ``energy_growth_ratio`` M g H above its value at the start: in a closed tank with no inflow
  every term of the scheme conserves or dissipates it, so growth is the integrator going unstable.
"""

import functools

import warp as wp

from . import boundaries, density, eos, kernels, neighbours, viscosity

FLUID = 0
BOUNDARY = 1

# health checks, in the order they are reported
CHECKS = ("non_finite", "outside_domain", "density_bounds", "wall_penetration", "clumping", "energy_growth")
# checks of the whole state, not of one particle
GLOBAL_CHECKS = ("energy_growth",)
N_CHECKS = len(CHECKS)
NO_FAILURE = 2 ** 31 - 1
DYNAMIC = boundaries.BOUNDARY_ID["dynamic"]
LENNARD_JONES = boundaries.BOUNDARY_ID["lennard_jones"]
ARTIFICIAL = viscosity.VISCOSITY_ID["artificial"]
SPS = viscosity.VISCOSITY_ID["sps"]
WALL_PENETRATION = CHECKS.index("wall_penetration")
CLUMPING = CHECKS.index("clumping")
ENERGY_GROWTH = CHECKS.index("energy_growth")


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    mat33 = wp.types.matrix((3, 3), scalar)
    _, _, kernel_w, grad_factor, _ = kernels.build(scalar)
    eos_pressure, _, _ = eos.build(scalar)
    visc_artificial, visc_laminar, sps_stress, sps_accel = viscosity.build(scalar)
    continuity, delta_diffusion = density.build(scalar)
    lennard_jones, monaghan_kajtar, plane_kernel_flux = boundaries.build(scalar)
    Grid, separation, *_ = neighbours.build(scalar)

    @wp.struct
    class Params:
        dim: int
        kernel: int
        norm: scalar
        h: scalar
        inv_h: scalar
        eta2: scalar  # 0.01 h^2 regulariser
        viscosity: int
        alpha: scalar
        nu: scalar
        cs_dl2: scalar
        ci_dl2: scalar
        boundary: int
        lj_d: scalar
        lj_r0: scalar
        mk_k: scalar
        mk_beta: scalar
        plane_r0: scalar
        delta_hc0: scalar  # delta h c0, 0 when density diffusion is off
        xsph_eps: scalar  # 0 when XSPH is off
        rho0: scalar
        eos_b: scalar
        gamma: scalar
        c0: scalar
        gravity: vec
        lo: vec
        hi: vec
        periodic: wp.vec3i
        rho_min: scalar
        rho_max: scalar
        cfl: scalar
        dt_fixed: wp.float64
        settle_tau: wp.float64  # velocity relaxation time while settling; 0 = off
        settle_until: wp.float64
        n_planes: int
        wall_lo: vec
        wall_hi: vec
        penetration: scalar  # penetration_ratio dx
        n_solids: int
        clump_r: scalar  # clump_ratio dx
        clump_fraction: wp.float64
        n_fluid: int
        energy_slack: wp.float64  # energy_growth_ratio M g H; 0 = off

    @wp.struct
    class Fields:
        """One particle state (the committed one or the half step) and what every pass reads."""

        pos: wp.array(dtype=vec)
        vel: wp.array(dtype=vec)
        rho: wp.array(dtype=scalar)
        pressure: wp.array(dtype=scalar)
        p_rho2: wp.array(dtype=scalar)  # p / rho^2, once per particle instead of once per pair
        mass: wp.array(dtype=scalar)
        ptype: wp.array(dtype=wp.int32)
        body: wp.array(dtype=wp.int32)
        tau_diag: wp.array(dtype=vec)  # SPS stress / rho: xx, yy, zz
        tau_off: wp.array(dtype=vec)  # xy, xz, yz

    @wp.func
    def pair(p: Params, f: Fields, a: int, b: int, r_ab: vec):
        """What particle b does to fluid particle a: (acceleration, drho/dt, XSPH velocity, |mu|).

        Only the fields a model needs are loaded: the pair loop is where the time goes.
        """
        zero = vec(scalar(0.0))
        r = wp.length(r_ab)
        if r >= scalar(2.0) * p.h:
            return zero, scalar(0.0), zero, scalar(0.0)
        t_b = f.ptype[b]
        if t_b == BOUNDARY and p.boundary != DYNAMIC:
            if p.boundary == LENNARD_JONES:
                return lennard_jones(p.lj_d, p.lj_r0, r_ab, r), scalar(0.0), zero, scalar(0.0)
            return (monaghan_kajtar(p.mk_k, p.mk_beta, p.inv_h, f.mass[a], f.mass[b], r_ab, r), scalar(0.0), zero,
                    scalar(0.0))
        m_b = f.mass[b]
        rho_a = f.rho[a]
        rho_b = f.rho[b]
        u_ab = f.vel[a] - f.vel[b]
        grad = r_ab * grad_factor(p.kernel, p.norm, p.inv_h, r)
        r2_eta = wp.dot(r_ab, r_ab) + p.eta2
        drho = continuity(m_b, u_ab, grad)
        if t_b == FLUID and p.delta_hc0 > scalar(0.0):
            drho += delta_diffusion(p.delta_hc0, rho_a, rho_b, m_b, r_ab, grad, r2_eta, p.gravity, p.rho0, p.c0)
        acc = -m_b * (f.p_rho2[a] + f.p_rho2[b]) * grad
        if p.viscosity == ARTIFICIAL:
            # c0 for the mean sound speed, as GPUSPH: weak compressibility keeps c within ~1% of c0
            acc += visc_artificial(p.alpha, p.h, p.c0, scalar(0.5) * (rho_a + rho_b), m_b, u_ab, r_ab, r2_eta,
                                   grad)
        else:
            acc += visc_laminar(p.nu, rho_a, rho_b, m_b, u_ab, r_ab, r2_eta, grad)
            if p.viscosity == SPS and t_b == FLUID:
                acc += sps_accel(m_b, rho_a, rho_b, f.tau_diag[a], f.tau_off[a], f.tau_diag[b], f.tau_off[b], grad)
        xsph = zero
        if t_b == FLUID and p.xsph_eps > scalar(0.0):
            xsph = -p.xsph_eps * m_b / (scalar(0.5) * (rho_a + rho_b)) * kernel_w(p.kernel, p.norm, p.inv_h, r) * u_ab
        mu = wp.abs(wp.dot(u_ab, r_ab)) / r2_eta
        return acc, drho, xsph, mu

    @wp.func
    def healthy(fail: wp.array(dtype=wp.int32)) -> bool:
        bad = int(0)
        for k in range(N_CHECKS):
            if fail[k] != NO_FAILURE:
                bad = 1
        return bad == 0

    @wp.func
    def track_max(maxima: wp.array(dtype=scalar), k: int, value: scalar):
        # read before the atomic: after the first few threads almost none need to write
        if value > maxima[k]:
            wp.atomic_max(maxima, k, value)

    @wp.kernel(enable_backward=False, module="unique")
    def equation_of_state(p: Params, f: Fields):
        i = wp.tid()
        r = f.rho[i]
        pr = eos_pressure(r, p.rho0, p.eos_b, p.gamma)
        f.pressure[i] = pr
        f.p_rho2[i] = pr / (r * r)

    @wp.kernel(enable_backward=False, module="unique")
    def sps_strain(p: Params, grid: Grid, nbr: wp.array(dtype=wp.int32), count: wp.array(dtype=wp.int32),
                   f: Fields, chunk: int, stride: int):
        i = wp.tid() * stride + chunk
        zero = vec(scalar(0.0))
        if f.ptype[i] != FLUID:
            f.tau_diag[i] = zero
            f.tau_off[i] = zero
            return
        grad_u = mat33(scalar(0.0))
        base = i * grid.max_neighbours
        for k in range(count[i]):
            j = nbr[base + k]
            if f.ptype[j] == FLUID or p.boundary == DYNAMIC:
                r_ab = separation(grid, f.pos[i], f.pos[j])
                r = wp.length(r_ab)
                if r < scalar(2.0) * p.h:
                    grad = r_ab * grad_factor(p.kernel, p.norm, p.inv_h, r)
                    grad_u += f.mass[j] / f.rho[j] * wp.outer(f.vel[j] - f.vel[i], grad)
        d, o = sps_stress(grad_u, p.cs_dl2, p.ci_dl2)
        f.tau_diag[i] = d
        f.tau_off[i] = o

    @wp.kernel(enable_backward=False, module="unique")
    def interact(p: Params, grid: Grid, nbr: wp.array(dtype=wp.int32), count: wp.array(dtype=wp.int32), f: Fields,
                 plane_point: wp.array(dtype=vec), plane_normal: wp.array(dtype=vec),
                 acc: wp.array(dtype=vec), drho: wp.array(dtype=scalar), xsph: wp.array(dtype=vec),
                 maxima: wp.array(dtype=scalar), clumped: wp.array(dtype=wp.int32), chunk: int, stride: int):
        i = wp.tid() * stride + chunk
        xi = f.pos[i]
        base = i * grid.max_neighbours
        a = vec(scalar(0.0))
        dr = scalar(0.0)
        xs = vec(scalar(0.0))
        close = int(0)
        if f.ptype[i] == FLUID:
            a = p.gravity
            mu_max = scalar(0.0)
            for k in range(count[i]):
                j = nbr[base + k]
                r_ij = separation(grid, xi, f.pos[j])
                if f.ptype[j] == FLUID and wp.dot(r_ij, r_ij) < p.clump_r * p.clump_r:
                    close = 1
                da, ddr, dxs, mu = pair(p, f, i, j, r_ij)
                a += da
                dr += ddr
                xs += dxs
                mu_max = wp.max(mu_max, mu)
            if p.n_planes > 0:
                ui = f.vel[i]
                rho_i = f.rho[i]
                p_i = wp.max(f.pressure[i], scalar(0.0))
                for k in range(p.n_planes):
                    n_k = plane_normal[k]
                    d = wp.dot(xi - plane_point[k], n_k)
                    flux = plane_kernel_flux(p.kernel, p.norm, p.inv_h, p.dim, d)
                    if flux > scalar(0.0):
                        a += scalar(2.0) * p_i / rho_i * flux * n_k
                        dr -= scalar(2.0) * rho_i * wp.dot(ui, n_k) * flux
                        a += lennard_jones(p.lj_d, p.plane_r0, d * n_k, d)
            track_max(maxima, 2 * chunk, wp.length(a))
            track_max(maxima, 2 * chunk + 1, mu_max)
        else:
            # a boundary particle: density (dynamic boundaries) and, on a body, the reaction
            # of every fluid neighbour, so that mass x acc sums to the force on the body
            ui = f.vel[i]
            for k in range(count[i]):
                j = nbr[base + k]
                if f.ptype[j] == FLUID:
                    r_ji = separation(grid, f.pos[j], xi)
                    r = wp.length(r_ji)
                    if p.boundary == DYNAMIC and r < scalar(2.0) * p.h:
                        grad = -r_ji * grad_factor(p.kernel, p.norm, p.inv_h, r)
                        dr += continuity(f.mass[j], ui - f.vel[j], grad)
                    if f.body[i] >= 0:
                        da, ddr, dxs, mu = pair(p, f, j, i, r_ji)
                        a -= f.mass[j] / f.mass[i] * da
        acc[i] = a
        drho[i] = dr
        xsph[i] = xs
        clumped[i] = close

    @wp.kernel(enable_backward=False, module="unique")
    def choose_dt(p: Params, t_target: wp.float64, maxima: wp.array(dtype=scalar), fail: wp.array(dtype=wp.int32),
                  clock: wp.array(dtype=wp.float64)):
        """dt = CFL min(sqrt(h/|a|max), h/(c0 + h max|mu|), 0.125 h^2/nu) (Monaghan 1992; GPUSPH).

        Time is float64 whatever the precision: a float32 clock cannot land on an output time.
        """
        a_max = scalar(0.0)
        mu_max = scalar(0.0)
        for slot in range(maxima.shape[0] // 2):
            a_max = wp.max(a_max, maxima[2 * slot])
            mu_max = wp.max(mu_max, maxima[2 * slot + 1])
        dt = p.dt_fixed
        if dt <= wp.float64(0.0):
            h = wp.float64(p.h)
            cfl = wp.float64(p.cfl)
            dt = cfl * h / (wp.float64(p.c0) + h * wp.float64(mu_max))
            if a_max > scalar(0.0):
                dt = wp.min(dt, cfl * wp.sqrt(h / wp.float64(a_max)))
            if p.viscosity != ARTIFICIAL and p.nu > scalar(0.0):
                dt = wp.min(dt, cfl * wp.float64(0.125) * h * h / wp.float64(p.nu))
        clock[2] = dt  # the step the stability limits allow, before landing on t_target
        remaining = t_target - clock[0]
        if remaining <= wp.float64(1.0e-12) * wp.max(wp.float64(1.0), clock[0]):
            dt = wp.float64(0.0)
        elif dt > remaining:
            dt = remaining
        if not healthy(fail):
            dt = wp.float64(0.0)
        clock[1] = dt

    @wp.kernel(enable_backward=False, module="unique")
    def integrate(p: Params, clock: wp.array(dtype=wp.float64), factor: scalar, pos: wp.array(dtype=vec),
                  vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
                  vel_rate: wp.array(dtype=vec), acc: wp.array(dtype=vec), drho: wp.array(dtype=scalar),
                  xsph: wp.array(dtype=vec), pos_out: wp.array(dtype=vec), vel_out: wp.array(dtype=vec),
                  rho_out: wp.array(dtype=scalar)):
        """x_out = x + f dt (u_rate + xsph), u_out = u + f dt a, rho_out = rho + f dt drho.

        f = 1/2 with the rates at n (predictor), f = 1 with the rates at n + 1/2 (corrector).
        Boundary particles keep position and velocity; dynamic ones update density.
        """
        i = wp.tid()
        dt = factor * scalar(clock[1])
        rho_out[i] = rho[i] + dt * drho[i]
        if ptype[i] != FLUID:
            pos_out[i] = pos[i]
            vel_out[i] = vel[i]
            return
        x = pos[i] + dt * (vel_rate[i] + xsph[i])
        for ax in range(3):
            if p.periodic[ax] != 0:
                span = p.hi[ax] - p.lo[ax]
                x[ax] = x[ax] - span * wp.floor((x[ax] - p.lo[ax]) / span)
        pos_out[i] = x
        u = vel[i] + dt * acc[i]
        if p.settle_tau > wp.float64(0.0) and clock[0] < p.settle_until:
            u = u / (scalar(1.0) + dt / scalar(p.settle_tau))
        vel_out[i] = u

    @wp.kernel(enable_backward=False, module="unique")
    def health(p: Params, pos: wp.array(dtype=vec), vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar),
               ptype: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), solid_lo: wp.array(dtype=vec),
               solid_hi: wp.array(dtype=vec), fail: wp.array(dtype=wp.int32)):
        """Flags each check a particle of the candidate state fails, by the caller's particle id
        (the slots are re-sorted by later steps of the batch)."""
        i = wp.tid()
        pid = ids[i]
        x = pos[i]
        r = rho[i]
        if wp.isnan(x) or wp.isinf(x) or wp.isnan(vel[i]) or wp.isinf(vel[i]) or wp.isnan(r) or wp.isinf(r):
            wp.atomic_min(fail, 0, pid)
            return
        if ptype[i] == FLUID:
            for ax in range(3):
                if x[ax] < p.lo[ax] or x[ax] > p.hi[ax]:
                    wp.atomic_min(fail, 1, pid)
                if x[ax] < p.wall_lo[ax] - p.penetration or x[ax] > p.wall_hi[ax] + p.penetration:
                    wp.atomic_min(fail, WALL_PENETRATION, pid)
            for k in range(p.n_solids):
                lo = solid_lo[k]
                hi = solid_hi[k]
                outside = int(0)
                for ax in range(p.dim):
                    if x[ax] <= lo[ax] + p.penetration or x[ax] >= hi[ax] - p.penetration:
                        outside = 1
                if outside == 0:
                    wp.atomic_min(fail, WALL_PENETRATION, pid)
        if r < p.rho_min or r > p.rho_max:
            wp.atomic_min(fail, 2, pid)

    @wp.kernel(enable_backward=False, module="unique")
    def census(p: Params, pos: wp.array(dtype=vec), vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar),
               mass: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32),
               clumped: wp.array(dtype=wp.int32), total: wp.array(dtype=wp.float64), count: wp.array(dtype=wp.int32)):
        """total[0] += the fluid's kinetic + potential + elastic energy; count = [clumped fluid
        particles, the first of them] (one launch: atomics)."""
        i = wp.tid()
        if ptype[i] != FLUID:
            return
        if clumped[i] != 0:
            wp.atomic_add(count, 0, 1)
            wp.atomic_min(count, 1, ids[i])
        u = vel[i]
        ratio = rho[i] / p.rho0
        elastic = (p.eos_b / p.rho0 * (wp.pow(ratio, p.gamma - scalar(1.0)) - scalar(1.0)) / (p.gamma - scalar(1.0))
                   + p.eos_b * (scalar(1.0) / rho[i] - scalar(1.0) / p.rho0))
        e = mass[i] * (scalar(0.5) * wp.dot(u, u) - wp.dot(p.gravity, pos[i]) + elastic)
        wp.atomic_add(total, 0, wp.float64(e))

    @wp.kernel(enable_backward=False, module="unique")
    def census_check(p: Params, total: wp.array(dtype=wp.float64), count: wp.array(dtype=wp.int32),
                     fail: wp.array(dtype=wp.int32)):
        """total = [candidate's energy, energy at the start (or +inf before the first check), the
        largest clumped fraction seen]: flags energy_growth when the candidate exceeds the start by
        the slack, clumping when too many particles have clumped."""
        e = total[0]
        if total[1] == wp.float64(1.0e300):
            total[1] = e
        if p.energy_slack > wp.float64(0.0) and e > total[1] + p.energy_slack:
            fail[ENERGY_GROWTH] = 0
        fraction = wp.float64(count[0]) / wp.float64(p.n_fluid)
        total[2] = wp.max(total[2], fraction)
        if p.clump_r > scalar(0.0) and fraction > p.clump_fraction:
            fail[CLUMPING] = count[1]
        count[0] = 0  # ready for the next census
        count[1] = NO_FAILURE

    @wp.kernel(enable_backward=False, module="unique")
    def commit(fail: wp.array(dtype=wp.int32), pos_new: wp.array(dtype=vec), vel_new: wp.array(dtype=vec),
               rho_new: wp.array(dtype=scalar), pos: wp.array(dtype=vec), vel: wp.array(dtype=vec),
               rho: wp.array(dtype=scalar)):
        i = wp.tid()
        if healthy(fail):
            pos[i] = pos_new[i]
            vel[i] = vel_new[i]
            rho[i] = rho_new[i]

    @wp.kernel(enable_backward=False, module="unique")
    def permute(order: wp.array(dtype=wp.int32), pos: wp.array(dtype=vec), vel: wp.array(dtype=vec),
                rho: wp.array(dtype=scalar), mass: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
                body: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), needs: wp.array(dtype=wp.int32),
                pos_o: wp.array(dtype=vec), vel_o: wp.array(dtype=vec), rho_o: wp.array(dtype=scalar),
                mass_o: wp.array(dtype=scalar), ptype_o: wp.array(dtype=wp.int32), body_o: wp.array(dtype=wp.int32),
                ids_o: wp.array(dtype=wp.int32), needs_o: wp.array(dtype=wp.int32)):
        """Gather the per-particle state into cell order (``order`` from the cell sort)."""
        k = wp.tid()
        i = order[k]
        pos_o[k] = pos[i]
        vel_o[k] = vel[i]
        rho_o[k] = rho[i]
        mass_o[k] = mass[i]
        ptype_o[k] = ptype[i]
        body_o[k] = body[i]
        ids_o[k] = ids[i]
        needs_o[k] = needs[i]

    @wp.kernel(enable_backward=False, module="unique")
    def tick(fail: wp.array(dtype=wp.int32), clock: wp.array(dtype=wp.float64), steps: wp.array(dtype=wp.int32)):
        """Advance time and step count, or record when the first failing step would have ended."""
        if healthy(fail):
            if clock[1] > wp.float64(0.0):
                clock[0] = clock[0] + clock[1]
                steps[0] = steps[0] + 1
        elif steps[1] < 0:
            steps[1] = steps[0] + 1
            clock[3] = clock[0] + clock[1]

    @wp.kernel(enable_backward=False, module="unique")
    def shepard(p: Params, grid: Grid, nbr: wp.array(dtype=wp.int32), count: wp.array(dtype=wp.int32), f: Fields,
                rho_out: wp.array(dtype=scalar), chunk: int, stride: int):
        """rho_a = sum_b m_b W_ab / sum_b (m_b / rho_b) W_ab, the particle itself included (Eq. 2.28)."""
        i = wp.tid() * stride + chunk
        if f.ptype[i] != FLUID:
            rho_out[i] = f.rho[i]
            return
        w0 = kernel_w(p.kernel, p.norm, p.inv_h, scalar(0.0))
        num = f.mass[i] * w0
        den = f.mass[i] / f.rho[i] * w0
        base = i * grid.max_neighbours
        for k in range(count[i]):
            j = nbr[base + k]
            if f.ptype[j] == FLUID or p.boundary == DYNAMIC:
                wk = kernel_w(p.kernel, p.norm, p.inv_h, wp.length(separation(grid, f.pos[i], f.pos[j])))
                num += f.mass[j] * wk
                den += f.mass[j] / f.rho[j] * wk
        rho_out[i] = num / den

    return (Params, Fields, equation_of_state, sps_strain, interact, choose_dt, integrate, health, census,
            census_check, commit, tick, shepard, permute)
