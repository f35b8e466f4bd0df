"""The passes of one solver step, one Warp kernel each, compiled once per floating-point type.

Models are chosen at run time through integer ids held in ``Params`` (see kernels.KERNEL_ID,
viscosity.VISCOSITY_ID, density.DENSITY_DIFFUSION_ID; a wall treatment through the functions of
``boundaries``, which alone read its id); each equation lives in the module of its family (kernels,
eos, momentum, viscosity, density, xsph, shifting, boundaries/) and is only combined here. The
run-safety checks are health.py's.

Step (predictor-corrector as GPUSPH, Herault et al. 2010):
  neighbours(x_n) -> eos -> [sps] -> interact(n) -> choose_dt
  -> integrate(dt/2) -> eos -> [sps] -> interact(n+1/2) -> integrate(dt) into the candidate state
  -> health.check_particles(candidate) -> [health.census(candidate) (+ wall_energy on repulsive walls)
  -> health.census_check, every few steps] -> health.exclusion_check -> commit (only if healthy;
  excluding faulty fluid particles)
  -> tick -> [shepard every N steps]
The committed state is never overwritten by a candidate that failed a health check.
"""

import functools
from types import SimpleNamespace

import warp as wp

from . import boundaries, density, eos, health, kernels, momentum, neighbours, shifting, state, sums, viscosity, xsph

FLUID = state.FLUID
BOUNDARY = state.BOUNDARY
carries_fluid = state.carries_fluid
VACANT = state.VACANT
EXCLUDED = state.EXCLUDED
T, DT, DT_STABLE, T_FAILED, TARGET = state.T, state.DT, state.DT_STABLE, state.T_FAILED, state.TARGET
STEP, FAILED_STEP, LAUNCHED, IN_BLOCK = state.STEP, state.FAILED_STEP, state.LAUNCHED, state.IN_BLOCK
RUNNING, REORDER_DUE, CENSUS_DUE, SHEPARD_DUE = state.RUNNING, state.REORDER_DUE, state.CENSUS_DUE, state.SHEPARD_DUE
ENERGY = health.ENERGY
ARTIFICIAL = viscosity.VISCOSITY_ID["artificial"]
SPS = viscosity.VISCOSITY_ID["sps"]


def params(cfg) -> dict:
    """The Params fields of the step itself under ``cfg`` (a SolverConfig): the dimension, gravity,
    the domain and its periodic axes, the time step's CFL (or fixed step), and settling."""
    return {"dim": cfg.dim, "dx": cfg.dx, "gravity": cfg.gravity, "lo": cfg.domain_lo, "hi": cfg.domain_hi,
            "periodic": tuple(1 if a else 0 for a in cfg.periodic), "cfl": cfg.cfl, "dt_fixed": cfg.dt_fixed,
            "settle_tau": cfg.settle_tau, "settle_until": cfg.settle_until}


@functools.lru_cache(maxsize=None)
def _force_passes(scalar):
    """The passes that evaluate the equations: the equation of state, the SPS strain, the pair
    interactions (forces, density rates, XSPH, shifting) and the Shepard filter."""
    vec = wp.types.vector(3, scalar)
    mat33 = wp.types.matrix((3, 3), scalar)
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields
    K = kernels.build(scalar)
    kernel_w, grad_factor, smoothing, own_scale, same_level = K.w, K.grad_factor, K.smoothing, K.own_scale, K.same_level
    stride, selected = K.stride, K.selected
    E = eos.build(scalar)
    eos_pressure, cavitation_floor = E.pressure, E.cavitation_floor
    pressure_gradient = momentum.build(scalar).pressure_gradient
    V = viscosity.build(scalar)
    visc_artificial, visc_laminar, sps_stress, sps_accel = V.artificial, V.laminar, V.sps_stress, V.sps_accel
    D = density.build(scalar)
    continuity, wall_flux = D.continuity, D.wall_flux
    delta_diffusion, shepard_density = D.delta_diffusion, D.shepard
    xsph_velocity = xsph.build(scalar).xsph_velocity
    Sh = shifting.build(scalar)
    concentration_terms, shift_velocity = Sh.concentration_terms, Sh.shift_velocity
    B = boundaries.build(scalar)
    repulsion, backstop, repulsion_potential = B.repulsion, B.backstop, B.repulsion_potential
    wall_density_rate = B.wall_density_rate
    plane_wall, plane_corners = B.plane_wall, B.plane_corners
    N = neighbours.grid(scalar)
    Grid, separation = N.Grid, N.separation
    Walk, walk_from, walk_cells, walk_span, walk_at = N.Walk, N.walk_from, N.walk_cells, N.walk_span, N.walk_at

    @wp.func
    def pair(p: Params, f: Fields, a: int, b: int, r_ab: vec, n_a: vec):
        """What particle b does to fluid particle a: (acceleration, drho/dt, XSPH velocity, |mu|,
        grad_a W_ab), the kernel gradient zero beyond the support and for walls whose particles carry
        no fluid volume (Lennard-Jones, Monaghan-Kajtar); nothing from another refinement level.
        ``n_a``: the normal of the flat wall face near a (wall_normal_at), zero for the full term.

        Only the fields a model needs are loaded: the pair loop is where the time goes.
        """
        zero = vec(scalar(0.0))
        r = wp.length(r_ab)
        h, inv_h, norm, scale = smoothing(p, f.hsml[a], f.hsml[b])
        if r >= scalar(2.0) * h or not same_level(p, f.hsml[a], f.hsml[b]):
            return zero, scalar(0.0), zero, scalar(0.0), zero
        t_b = f.ptype[b]
        if t_b == VACANT:  # a slot a refinement level vacated this step (levels.py)
            return zero, scalar(0.0), zero, scalar(0.0), zero
        if t_b == BOUNDARY and p.wall_volume == 0:  # walls without fluid volume push
            return repulsion(p, f.mass[a], f.mass[b], r_ab, r), scalar(0.0), zero, scalar(0.0), zero
        m_b = f.mass[b]
        rho_a = f.rho[a]
        rho_b = f.rho[b]
        u_ab = f.vel[a] - f.vel[b]
        grad = r_ab * grad_factor(p.kernel, norm, inv_h, r)
        r2_eta = wp.dot(r_ab, r_ab) + p.eta2 * scale * scale
        if t_b == BOUNDARY:
            drho = continuity(m_b, wall_flux(u_ab, n_a), grad)
        else:
            drho = continuity(m_b, u_ab, grad)
        if carries_fluid(t_b) and p.delta_hc0 > scalar(0.0):
            drho += delta_diffusion(p.delta_hc0 * scale, rho_a, rho_b, m_b, r_ab, grad, r2_eta, p.gravity, p.rho0, p.c0)
        acc = pressure_gradient(m_b, f.p_rho2[a], f.p_rho2[b], grad)
        if t_b == BOUNDARY:
            acc += backstop(p, r_ab, r, u_ab, scale)
        if p.viscosity == ARTIFICIAL:
            # c0 for the mean sound speed, as GPUSPH: weak compressibility keeps c within ~1% of c0
            alpha = p.alpha
            if t_b == BOUNDARY:
                alpha = p.alpha_wall
            acc += visc_artificial(alpha, h, p.c0, scalar(0.5) * (rho_a + rho_b), m_b, u_ab, r_ab, r2_eta,
                                   grad)
        else:
            acc += visc_laminar(p.nu, rho_a, rho_b, m_b, u_ab, r_ab, r2_eta, grad)
            if p.viscosity == SPS and carries_fluid(t_b):
                acc += sps_accel(m_b, rho_a, rho_b, f.tau_diag[a], f.tau_off[a], f.tau_diag[b], f.tau_off[b], grad)
        xsph = zero
        if carries_fluid(t_b) and p.xsph_eps > scalar(0.0):
            xsph = xsph_velocity(p.xsph_eps, m_b, rho_a, rho_b, kernel_w(p.kernel, norm, inv_h, r), u_ab)
        mu = wp.abs(wp.dot(u_ab, r_ab)) / r2_eta
        return acc, drho, xsph, mu, grad

    @wp.func
    def wall_normal_at(p: Params, grid: Grid, nb: Walk, f: Fields, i: int) -> vec:
        """Under ``wall_flux: normal``, the normal of the one flat wall face near fluid particle i:
        its listed wall neighbours' face normals (faces.py; the lists reach a little beyond the
        support, so an edge just outside it counts too) where they all agree; zero (the full
        relative velocity) near an edge or a corner, where they do not, where no wall of its level
        is near, and under ``wall_flux: full``. Not the direction of the walls' kernel
        gradient sum: the continuity term projected on that is the full one, lattice noise and all."""
        n = vec(scalar(0.0))
        if p.wall_flux == 0:
            return n
        count = int(0)
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(grid, nb, i, slot)
                if j >= 0:
                    if f.ptype[j] == BOUNDARY and same_level(p, f.hsml[i], f.hsml[j]):
                        n += f.wall_normal[j]
                        count += 1
        # unit normals that all agree sum to count of them; one edge or corner particle among
        # them pulls the mean's length below 0.999
        if count > 0 and wp.length(n) >= scalar(0.999) * scalar(count):
            return wp.normalize(n)
        return vec(scalar(0.0))

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
    def sps_strain(p: Params, grid: Grid, nb: Walk,
                   f: Fields, levels: int, chunk: int, threads: int):
        i = wp.tid() * threads + chunk
        zero = vec(scalar(0.0))
        if not selected(p, f.hsml[i], levels):
            return
        if f.ptype[i] != FLUID:
            f.tau_diag[i] = zero
            f.tau_off[i] = zero
            return
        grad_u = mat33(scalar(0.0))
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(grid, nb, i, slot)
                if j >= 0:
                    if (carries_fluid(f.ptype[j]) or p.wall_volume != 0) and same_level(p, f.hsml[i], f.hsml[j]):
                        r_ab = separation(grid, f.pos[i], f.pos[j])
                        r = wp.length(r_ab)
                        h, inv_h, norm, scale = smoothing(p, f.hsml[i], f.hsml[j])
                        if r < scalar(2.0) * h:
                            grad = r_ab * grad_factor(p.kernel, norm, inv_h, r)
                            grad_u += f.mass[j] / f.rho[j] * wp.outer(f.vel[j] - f.vel[i], grad)
        s2 = own_scale(p, f.hsml[i])
        s2 = s2 * s2  # the Smagorinsky length is the particle's own spacing
        d, o = sps_stress(grad_u, p.cs_dl2 * s2, p.ci_dl2 * s2)
        f.tau_diag[i] = d
        f.tau_off[i] = o

    @wp.kernel(enable_backward=False, module="unique")
    def interact(p: Params, grid: Grid, nb: Walk, f: Fields,
                 plane_point: wp.array(dtype=vec), plane_normal: wp.array(dtype=vec),
                 acc: wp.array(dtype=vec), drho: wp.array(dtype=scalar), xsph: wp.array(dtype=vec),
                 shift: wp.array(dtype=vec), maxima: wp.array(dtype=scalar), clumped: wp.array(dtype=wp.int32),
                 levels: int, chunk: int, threads: int):
        """The rates of every particle of ``levels`` (kernels.selected): a fluid particle's
        acceleration, density rate, XSPH velocity and shifting from its pairs; a boundary particle's
        density rate and, on a body, the reaction it takes. The others keep the rates they have."""
        i = wp.tid() * threads + chunk
        if not selected(p, f.hsml[i], levels):
            return
        xi = f.pos[i]
        a = vec(scalar(0.0))
        dr = scalar(0.0)
        xs = vec(scalar(0.0))
        grad_c = vec(scalar(0.0))
        div_r = scalar(0.0)
        close = int(0)
        scale_i = own_scale(p, f.hsml[i])
        if f.ptype[i] == FLUID:
            a = p.gravity
            mu_max = scalar(0.0)
            clump_r = p.clump_r * scale_i
            n_i = wall_normal_at(p, grid, nb, f, i)
            cell_i, reach_i = walk_from(grid, nb, i)
            for w in range(walk_cells(reach_i)):
                span = walk_span(grid, nb, i, cell_i, reach_i, w)
                for slot in range(span[0], span[1]):
                    j = walk_at(grid, nb, i, slot)
                    if j >= 0:
                        r_ij = separation(grid, xi, f.pos[j])
                        if carries_fluid(f.ptype[j]) and same_level(p, f.hsml[i], f.hsml[j]) \
                                and wp.dot(r_ij, r_ij) < clump_r * clump_r:
                            close = 1
                        da, ddr, dxs, mu, grad = pair(p, f, i, j, r_ij, n_i)
                        a += da
                        dr += ddr
                        xs += dxs
                        mu_max = wp.max(mu_max, mu)
                        if p.shift_a_h != scalar(0.0):  # grad is zero for walls without fluid volume
                            dc, ddiv = concentration_terms(f.mass[j] / f.rho[j], r_ij, grad)
                            grad_c += dc
                            div_r += ddiv
            if p.n_planes > 0:
                h_i, inv_h_i, norm_i, unused = smoothing(p, f.hsml[i], f.hsml[i])
                ui = f.vel[i]
                rho_i = f.rho[i]
                p_i = wp.max(f.pressure[i], scalar(0.0))
                for k in range(p.n_planes):
                    n_k = plane_normal[k]
                    da, ddr = plane_wall(p.kernel, norm_i, inv_h_i, p.dim, wp.dot(xi - plane_point[k], n_k), n_k,
                                         p_i, rho_i, ui, p.lj_d, p.plane_r0, p.gravity)
                    a += da
                    dr += ddr
                if p.n_planes > 1:
                    a += plane_corners(p.kernel, norm_i, inv_h_i, p.dim, xi, plane_point, plane_normal, p.n_planes,
                                       p_i, rho_i)
            if p.ranked != 0 and f.owned[i] == 0:
                pass  # a halo particle's rates are wrong at the halo's edge: its owner bounds the step
            elif p.variable_h != 0:
                # choose_dt reads the scene's h and sets the finest level's step: a particle of
                # h_i = s h stepping m of those at once limits it as one of the scene's h with
                # m^2 |a| / s and m mu + c0 (m / s - 1) / h would (Monaghan 1992's bounds
                # sqrt(h_i / |a|) and h_i / (c0 + h_i mu), over m)
                m = scalar(stride(p, f.hsml[i]))
                track_max(maxima, 2 * chunk, m * m * wp.length(a) / scale_i)
                track_max(maxima, 2 * chunk + 1, m * mu_max + p.c0 * (m / scale_i - scalar(1.0)) * p.inv_h)
            else:
                track_max(maxima, 2 * chunk, wp.length(a))
                track_max(maxima, 2 * chunk + 1, mu_max)
        elif f.ptype[i] == BOUNDARY and (p.wall_continuity != 0 or f.body[i] >= 0):
            # a boundary particle: its density where it follows the continuity equation (dynamic
            # boundaries; mDBC sets it before the step) and, on a body, the reaction of every fluid
            # neighbour, so that mass x acc sums to the force on it. Only its level's active fluid:
            # a passive particle follows another level, and nothing pushes it off a wall, so the
            # wall would integrate its drift
            ui = f.vel[i]
            cell_i, reach_i = walk_from(grid, nb, i)
            for w in range(walk_cells(reach_i)):
                span = walk_span(grid, nb, i, cell_i, reach_i, w)
                for slot in range(span[0], span[1]):
                    j = walk_at(grid, nb, i, slot)
                    if j >= 0:
                        if f.ptype[j] == FLUID and same_level(p, f.hsml[j], f.hsml[i]):
                            r_ji = separation(grid, f.pos[j], xi)
                            r = wp.length(r_ji)
                            h, inv_h, norm, scale = smoothing(p, f.hsml[j], f.hsml[i])
                            if p.wall_continuity != 0 and r < scalar(2.0) * h:
                                dr += wall_density_rate(p.kernel, norm, inv_h, f.mass[j], ui, f.vel[j], r_ji, r)
                            if f.body[i] >= 0:
                                da, ddr, dxs, mu, grad = pair(p, f, j, i, r_ji, vec(scalar(0.0)))  # its drho unread
                                a -= f.mass[j] / f.mass[i] * da
        acc[i] = a
        drho[i] = dr
        xsph[i] = xs
        if p.shift_a_h != scalar(0.0):
            shift[i] = vec(scalar(0.0))
            if f.ptype[i] == FLUID:
                shift[i] = shift_velocity(p.shift_a_h * scale_i, wp.length(f.vel[i]), grad_c, div_r, p.shift_tfs,
                                          p.dim)
        clumped[i] = close

    @wp.kernel(enable_backward=False, module="unique")
    def wall_energy(p: Params, grid: Grid, nb: Walk,
                    pos: wp.array(dtype=vec), mass: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
                    owned: wp.array(dtype=wp.int32),
                    part: wp.array2d(dtype=wp.float64), lead: int, step: int, members: int, chunk: int, stride: int):
        """Block k's share (part[k, 0], sums.py) of the energy the repulsive walls (Lennard-Jones,
        Monaghan-Kajtar) hold, which the census adds to the fluid's, so that it sums what a
        conservative wall conserves: a fluid particle pressed against such a wall gives that energy
        back as motion. Each pair counted from its fluid particle, on a rank only its owned ones':
        the ranks' sums add up to the run's (sph/exchange.py)."""
        k = wp.tid() * stride + chunk
        n = ptype.shape[0]
        held = wp.float64(0.0)
        for q in range(members):
            i = sums.member(k, q, lead, step)
            if i < n:
                if ptype[i] == FLUID and (p.ranked == 0 or owned[i] != 0):
                    e = scalar(0.0)
                    cell_i, reach_i = walk_from(grid, nb, i)
                    for w in range(walk_cells(reach_i)):
                        span = walk_span(grid, nb, i, cell_i, reach_i, w)
                        for slot in range(span[0], span[1]):
                            j = walk_at(grid, nb, i, slot)
                            if j >= 0:
                                if ptype[j] == BOUNDARY:
                                    r = wp.length(separation(grid, pos[i], pos[j]))
                                    e += repulsion_potential(p, mass[i], mass[j], r)
                    if e > scalar(0.0):
                        held = held + wp.float64(mass[i] * e)
        part[k, 0] = held

    @wp.kernel(enable_backward=False, module="unique")
    def shepard(p: Params, grid: Grid, nb: Walk, f: Fields,
                rho_out: wp.array(dtype=scalar), chunk: int, stride: int):
        """The Shepard filter (density.shepard, thesis Eq. 2.28) on the fluid; boundaries keep theirs."""
        i = wp.tid() * stride + chunk
        if f.ptype[i] != FLUID:
            rho_out[i] = f.rho[i]
            return
        rho_out[i] = cavitation_floor(shepard_density(p, grid, nb, i, f), p.rho_floor)

    return SimpleNamespace(equation_of_state=equation_of_state, sps_strain=sps_strain, interact=interact,
                           wall_energy=wall_energy,
                           shepard=shepard)


@functools.lru_cache(maxsize=None)
def _time_passes(scalar):
    """The passes that advance time: the step size, the integrator, commit, the cell-order
    permutation and the clock."""
    vec = wp.types.vector(3, scalar)
    Params = state.build(scalar).Params
    healthy = health.build(scalar).healthy
    capped = shifting.build(scalar).capped
    cavitation_floor = eos.build(scalar).cavitation_floor
    K = kernels.build(scalar)
    own_scale, stride, selected = K.own_scale, K.stride, K.selected

    @wp.kernel(enable_backward=False, module="unique")
    def choose_dt(p: Params, maxima: wp.array(dtype=scalar), fail: wp.array(dtype=wp.int32),
                  clock: wp.array(dtype=wp.float64)):
        """dt = CFL min(sqrt(h/|a|max), h/(c0 + h max|mu|), 0.125 h^2/nu) (Monaghan 1992; GPUSPH).

        Time is float64 whatever the precision: a float32 clock cannot land on an output time.
        With multirate the step launched spans ``coarse_stride`` steps dt of the finest level
        (interact scales the coarser levels' bounds), and lands on the clock's TARGET with all of them.
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
                h_min = wp.float64(p.h_min)  # the finest particles bound the viscous step
                dt = wp.min(dt, cfl * wp.float64(0.125) * h_min * h_min / wp.float64(p.nu))
        clock[DT_STABLE] = dt  # the step the stability limits allow, before landing on the TARGET
        remaining = (clock[TARGET] - clock[T]) / wp.float64(p.coarse_stride)
        if remaining <= wp.float64(1.0e-12) * wp.max(wp.float64(1.0), clock[T]):
            dt = wp.float64(0.0)
        elif dt > remaining:
            dt = remaining
        if not healthy(fail):
            dt = wp.float64(0.0)
        clock[DT] = dt

    @wp.kernel(enable_backward=False, module="unique")
    def integrate(p: Params, clock: wp.array(dtype=wp.float64), factor: scalar, pos: wp.array(dtype=vec),
                  vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
                  hsml: wp.array(dtype=scalar), vel_rate: wp.array(dtype=vec), acc: wp.array(dtype=vec),
                  drho: wp.array(dtype=scalar),
                  xsph: wp.array(dtype=vec), shift: wp.array(dtype=vec), pos_out: wp.array(dtype=vec),
                  vel_out: wp.array(dtype=vec), rho_out: wp.array(dtype=scalar), levels: int):
        """x_out = x + f dt (u_rate + xsph) [+ the shift f dt s, capped], u_out = u + f dt a,
        rho_out = rho + f dt drho (a fluid's no lower than rho0 where it cavitates: eos.cavitation_floor),
        for the particles of ``levels`` (kernels.selected), dt each one's own step (kernels.stride
        finest-level steps).

        f = 1/2 with the rates at n (predictor), f = 1 with the rates at n + 1/2 (corrector).
        Boundary particles keep position and velocity; dynamic ones update density. A passive
        particle (no rates) moves with the velocity its level's interpolation gave it (levels.py).
        """
        i = wp.tid()
        if not selected(p, hsml[i], levels):
            return
        dt = factor * scalar(clock[DT]) * scalar(stride(p, hsml[i]))
        r = rho[i] + dt * drho[i]
        if not carries_fluid(ptype[i]):
            rho_out[i] = r
            pos_out[i] = pos[i]
            vel_out[i] = vel[i]
            return
        rho_out[i] = cavitation_floor(r, p.rho_floor)
        x = pos[i] + dt * (vel_rate[i] + xsph[i])
        if p.shift_a_h != scalar(0.0):
            x += capped(dt * shift[i], p.shift_cap * own_scale(p, hsml[i]))
        for ax in range(3):
            if p.periodic[ax] != 0:
                span = p.hi[ax] - p.lo[ax]
                x[ax] = x[ax] - span * wp.floor((x[ax] - p.lo[ax]) / span)
        pos_out[i] = x
        u = vel[i] + dt * acc[i]
        if p.settle_tau > wp.float64(0.0) and clock[T] < p.settle_until:
            u = u / (scalar(1.0) + dt / scalar(p.settle_tau))
        vel_out[i] = u

    @wp.kernel(enable_backward=False, module="unique")
    def commit(fail: wp.array(dtype=wp.int32), faulty: wp.array(dtype=wp.int32), pos_new: wp.array(dtype=vec),
               vel_new: wp.array(dtype=vec), rho_new: wp.array(dtype=scalar), pos: wp.array(dtype=vec),
               vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
               needs_list: wp.array(dtype=wp.int32), stale: wp.array(dtype=wp.int32)):
        """The candidate becomes the state, if healthy; a particle marked faulty is excluded instead
        (health.py): it keeps its committed position and density, at rest, and the lists are
        rebuilt without it."""
        i = wp.tid()
        if healthy(fail):
            if faulty[i] != 0:
                ptype[i] = EXCLUDED
                needs_list[i] = 0
                vel[i] = vec(scalar(0.0))
                stale[0] = 1
            else:
                pos[i] = pos_new[i]
                vel[i] = vel_new[i]
                rho[i] = rho_new[i]
        faulty[i] = 0

    # Gather one per-particle array into cell order (``order`` from the cell sort), one array at a time
    # through a scratch array of its type: eleven shadow copies of the whole state (68 B a particle)
    # were held for a pass made every 16 steps. One kernel per type: Warp 1.19's CPU capture replayed
    # a generic kernel's launches with another type's overload (the vectors' x alone were moved)
    @wp.kernel(enable_backward=False, module="unique")
    def permute_vec(order: wp.array(dtype=wp.int32), array: wp.array(dtype=vec), into: wp.array(dtype=vec)):
        k = wp.tid()
        into[k] = array[order[k]]

    @wp.kernel(enable_backward=False, module="unique")
    def permute_scalar(order: wp.array(dtype=wp.int32), array: wp.array(dtype=scalar), into: wp.array(dtype=scalar)):
        k = wp.tid()
        into[k] = array[order[k]]

    @wp.kernel(enable_backward=False, module="unique")
    def permute_int(order: wp.array(dtype=wp.int32), array: wp.array(dtype=wp.int32), into: wp.array(dtype=wp.int32)):
        k = wp.tid()
        into[k] = array[order[k]]

    @wp.func
    def short_of(t: wp.float64, target: wp.float64) -> bool:
        """Whether time t is short of target beyond rounding (Solver.reached's complement)."""
        return t < target - wp.float64(1.0e-12) * wp.max(wp.float64(1.0), target)

    @wp.func
    def every(count: int, period: int) -> int:
        """1 when a cadence of ``period`` (0: never) falls on ``count``."""
        if period > 0 and count % period == 0:
            return 1
        return 0

    @wp.kernel(enable_backward=False, module="unique")
    def tick(p: Params, fail: wp.array(dtype=wp.int32), clock: wp.array(dtype=wp.float64),
             steps: wp.array(dtype=wp.int32), flags: wp.array(dtype=wp.int32), reorder_every: int,
             census_every: int, shepard_every: int, block: int):
        """Advance time and step count (the finest level's steps), or record when the first failing
        step would have ended; then say what comes next, on the device: whether the loop goes on
        (healthy, short of the target, time moving, fewer than ``block`` steps since the host last
        looked), whether the next step reorders and takes the census, and whether the Shepard
        filter is due now (every ``shepard_every`` finest-level steps). A failed step leaves the
        cadence where it was and filters nothing: taken again once its failure is cleared (lists
        widened, a smaller dt_fixed), it is the step that failed."""
        m = p.coarse_stride
        moving = clock[DT] > wp.float64(0.0)
        if healthy(fail):
            if moving:
                clock[T] = clock[T] + wp.float64(m) * clock[DT]
                steps[STEP] = steps[STEP] + m
        else:
            if steps[FAILED_STEP] < 0:
                steps[FAILED_STEP] = steps[STEP] + m
                clock[T_FAILED] = clock[T] + wp.float64(m) * clock[DT]
            flags[RUNNING] = 0
            flags[SHEPARD_DUE] = 0
            return
        launched = steps[LAUNCHED] + 1
        steps[LAUNCHED] = launched
        steps[IN_BLOCK] = steps[IN_BLOCK] + 1
        flags[RUNNING] = 0
        if healthy(fail) and moving and short_of(clock[T], clock[TARGET]) and steps[IN_BLOCK] < block:
            flags[RUNNING] = 1
        flags[REORDER_DUE] = every(launched, reorder_every)
        flags[CENSUS_DUE] = every(launched, census_every)
        flags[SHEPARD_DUE] = 0
        if shepard_every > 0 and launched * m / shepard_every > (launched - 1) * m / shepard_every:
            flags[SHEPARD_DUE] = 1

    @wp.kernel(enable_backward=False, module="unique")
    def aim(fail: wp.array(dtype=wp.int32), clock: wp.array(dtype=wp.float64), steps: wp.array(dtype=wp.int32),
            flags: wp.array(dtype=wp.int32), target: wp.float64):
        """Start the step loop towards ``target``: it runs if the state is healthy and short of it."""
        clock[TARGET] = target
        steps[IN_BLOCK] = 0
        flags[RUNNING] = 0
        if healthy(fail) and short_of(clock[T], target):
            flags[RUNNING] = 1

    return SimpleNamespace(choose_dt=choose_dt, integrate=integrate, commit=commit, tick=tick, aim=aim,
                           permute={vec: permute_vec, scalar: permute_scalar, wp.int32: permute_int})


@functools.lru_cache(maxsize=None)
def build(scalar):
    """Every pass of a step for one floating-point type, by name, with the structs they read."""
    S, H = state.build(scalar), health.build(scalar)
    return SimpleNamespace(Params=S.Params, Fields=S.Fields, check_particles=H.check_particles,
                           exclusion_check=H.exclusion_check, census=H.census,
                           census_check=H.census_check, **vars(_force_passes(scalar)), **vars(_time_passes(scalar)))
