"""Run-safety checks: the ways a run fails, checked on every candidate state before it is committed.

Each check has a named slot in the ``fail`` array (the id of the first particle that failed it, or
NO_FAILURE); a state with any slot set is never committed.

Faults of one particle (REASONS):
- non_finite: NaN or infinity in a position, velocity or density;
- outside_domain: a fluid particle left the domain (the tank, its walls and headroom) other than
  over the walls' top (left_tank);
- density_bounds: a density outside [rho_min, rho_max] (0.8 and 1.25 rho0 by default);
- wall_penetration: a fluid particle more than ``penetration_ratio`` dx beyond a wall face of the
  tank below the walls' top, or as deep inside a solid box: the boundary let it through;
- displacement: a fluid particle moved more than 0.9 of the kernel support 2h in one step (as
  DualSPHysics' CODE_OUTMOV, MovLimit = 0.9 of its 2h cell): its neighbour list no longer holds
  the particles it met;
- left_tank: a fluid particle went over the top of a wall, or out of the domain above it, at no
  more than the displacement limit: water leaving an open tank, which is physics, not a fault of
  the scheme (a frictionless run-up climbs a tank 1.67 H tall at 1.14 s in 2D; a scene with ``lid:
  true`` has none). It is excluded like a fault but counted apart, against ``max_left_fraction``
  (no limit by default), not ``max_excluded_fraction``.

A fluid particle at fault is excluded, as DualSPHysics excludes and counts its CODE_OUTRHO /
OUTPOS / OUTMOV particles: it keeps its id, last committed position and density, stops at rest
and drops out of every neighbour list (ptype EXCLUDED); its mass and reason are counted. The run
fails, with the state before that step kept, only once the excluded fluid passes
``max_excluded_fraction`` of the fluid mass (excluded_fraction); with max_excluded_fraction 0 a
particle's fault fails the run under its own name, as a fault of a boundary particle always does
(a wall cannot lose particles).

Faults of the whole state:
- clumping: more than ``clump_fraction`` of the fluid particles have a fluid neighbour closer
  than ``clump_ratio`` dx, marked in the force pass (the tensile and pairing instabilities pair
  particles long before anything is infinite; a few pairs in a splash are no failure). Particles
  within CLUMP_WALL_DX dx of a wall or solid are not counted: a thin layer of water pressed on a
  floor of boundary particles pairs without any instability of the flow (measured: DamBreak 1 at
  6 cm, a healthy run, reaches 24% clumped by t = 2.5 s, 82-87% of them within 1.5 dx of a wall;
  the 2D collapse at 1 cm, six particles across its column, pairs 28% of its fluid in the second
  layer of its two-particle-thin surge, 1.5-1.7 dx above the floor, at t = 0.34 s, with its density
  within 7% of rho0, its energy 0.07% above the start and the front within 12% of Martin & Moyce's;
  the tensile instability of tests/test_detectors.py pairs 20% of a block with no wall), nor
  fewer than CLUMP_MIN particles whatever their share (the 2D collapse at 2 cm has 18);
- energy_growth: the fluid's kinetic + potential + elastic energy (eos.elastic_energy) more than
  ``energy_growth_ratio`` M g H above its value at the start: in a closed tank with no inflow
  every term of the scheme conserves or dissipates it, so growth is the integrator going unstable;
- excluded_fraction: the excluded fluid would pass ``max_excluded_fraction`` of the fluid mass;
- left_fraction: the fluid that left the tank would pass ``max_left_fraction`` of its mass;
- zone_reserve: a refinement level needed more particles than the build reserved for it
  (levels.py: fluid arriving at a zone gets fine particles in slots reserved for them);
- zone_edge: a moving body came within levels.edge_margin of a refinement zone's face (a body
  crossing from one level to another is not carried: levels.py);
- body_outside: a floating body's centre left the domain (a push, cmd_wrench, past what the fluid
  and its weight hold: bodies.body_bounds); the slot holds the body's id;
- neighbour_overflow: a particle has more neighbours than the lists hold (neighbours.py); the solver
  widens them and takes the step again, unless their width was fixed.
"""

import functools
from types import SimpleNamespace

import warp as wp

from . import eos, kernels, state, sums

FLUID = state.FLUID
BOUNDARY = state.BOUNDARY

# the checks, in the order they are reported; each name's index is its slot in ``fail``
CHECKS = ("non_finite", "outside_domain", "density_bounds", "wall_penetration", "displacement", "left_tank",
          "clumping", "energy_growth", "excluded_fraction", "left_fraction", "zone_reserve", "zone_edge",
          "body_outside", "neighbour_overflow")
(NON_FINITE, OUTSIDE_DOMAIN, DENSITY_BOUNDS, WALL_PENETRATION, DISPLACEMENT, LEFT_TANK, CLUMPING, ENERGY_GROWTH,
 EXCLUDED_FRACTION, LEFT_FRACTION, ZONE_RESERVE, ZONE_EDGE, BODY_OUTSIDE, NEIGHBOUR_OVERFLOW) = range(len(CHECKS))
N_CHECKS = len(CHECKS)
# why a fluid particle is excluded; each index is its slot in ``fail``: the faults of one particle
# (FAULTS), and water leaving the tank
REASONS = CHECKS[:LEFT_TANK + 1]
FAULTS = REASONS[:LEFT_TANK]
N_REASONS = len(REASONS)
# checks of the whole state, not of one particle
GLOBAL_CHECKS = ("energy_growth", "excluded_fraction", "left_fraction")
NO_FAILURE = 2 ** 31 - 1
CLUMP_WALL_DX = 2.0  # [dx] clumping is not counted this close to a wall or solid: a sheet two particles thin
CLUMP_MIN = 16  # clumped particles below which no fraction is a failure: in a run of 18 particles one pair is 11%
NO_ENERGY = 1.0e300  # the energy check's "no reference yet"
# slots of the census sums (census, census_check): the candidate's energy, the energy at the start,
# the largest clumped fraction, the largest energy rise, the lowest and highest healthy fluid density,
# and the work the moving bodies have done on the fluid (bodies.work_on_fluid), which its energy may gain
ENERGY, ENERGY_START, PEAK_CLUMPED, PEAK_ENERGY_GROWTH, RHO_LOW, RHO_HIGH, WORK = range(7)
CENSUS_START = (0.0, NO_ENERGY, 0.0, 0.0, 1.0e300, -1.0e300, 0.0)  # before any census
# slots of the clumping count: clumped fluid particles away from walls, the first of them
CLUMPED, FIRST_CLUMPED = range(2)
# slots of the excluded mass: the fluid mass excluded at fault, the time of the first such exclusion (-1
# before), the fluid mass that left the tank
MASS, FIRST_TIME, LEFT_MASS = range(3)
EXCLUDED_START = (0.0, -1.0, 0.0)
# slots of the pending mass: at fault, left the tank
PENDING_FAULT, PENDING_LEFT = range(2)
# the excluded mass of a step is summed as an integer, in units of 2^-MASS_BITS of the fluid mass, so
# that it is the same whatever order the particles are added in (a float atomic sum is not, on a
# GPU): a particle's mass is rounded by at most 4e-16 of the fluid's, and the whole fluid fits an int64
MASS_BITS = 50
T, DT = state.T, state.DT


class HealthError(RuntimeError):
    """A step failed a health check. The solver still holds the state from before that step."""

    def __init__(self, check: str, step: int, time: float, particle: int, detail: str = ""):
        self.check = check
        self.step = step
        self.time = time
        self.particle = particle
        self.detail = detail
        super().__init__(f"health check '{check}' failed at step {step} (t = {time:.6g} s), "
                         f"particle {particle}{': ' + detail if detail else ''}")


def params(cfg, fluid_mass: float, n_fluid: int) -> dict:
    """The Params fields of the checks under ``cfg`` (a SolverConfig) for a fluid of ``fluid_mass``
    in ``n_fluid`` particles: the density bounds, the tank's inside and the solids, the penetration
    depth, clumping's distances and share, the energy slack (energy_growth_ratio M g H), the
    displacement limit (0.9 x 2h, squared), the exclusion limit and the excluded mass's units."""
    return {"rho_min": cfg.rho_min_ratio * cfg.rho0, "rho_max": cfg.rho_max_ratio * cfg.rho0,
            "wall_lo": cfg.wall_lo, "wall_hi": cfg.wall_hi, "wall_top": cfg.wall_top,
            "penetration": cfg.penetration_ratio * cfg.dx,
            "n_solids": len(cfg.solids), "n_zones": len(cfg.zones),
            "clump_r": cfg.clump_ratio * cfg.dx, "clump_wall": CLUMP_WALL_DX * cfg.dx,
            "clump_fraction": cfg.clump_fraction, "n_fluid": max(1, n_fluid),
            "energy_slack": cfg.energy_growth_ratio * fluid_mass * cfg.g_norm * cfg.depth,
            "move_limit2": (0.9 * 2.0 * cfg.h) ** 2, "exclude": 1 if cfg.max_excluded_fraction > 0.0 else 0,
            "excluded_limit": cfg.max_excluded_fraction * fluid_mass, "left_limit": cfg.max_left_fraction * fluid_mass,
            "mass_units": 2.0 ** MASS_BITS / fluid_mass if fluid_mass > 0.0 else 1.0}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    Params = state.build(scalar).Params
    elastic_energy = eos.build(scalar).elastic_energy
    own_scale = kernels.build(scalar).own_scale

    @wp.func
    def healthy(fail: wp.array(dtype=wp.int32)) -> bool:
        bad = int(0)
        for k in range(N_CHECKS):
            if fail[k] != NO_FAILURE:
                bad = 1
        return bad == 0

    @wp.func
    def in_box(x: vec, lo: vec, hi: vec, grow: scalar, axes: int) -> bool:
        """Whether x lies in [lo - grow, hi + grow] along the first ``axes`` axes (grow < 0 shrinks)."""
        inside = int(1)
        for ax in range(axes):
            if x[ax] < lo[ax] - grow or x[ax] > hi[ax] + grow:
                inside = 0
        return inside == 1

    @wp.func
    def in_solid(p: Params, x: vec, solid_lo: wp.array(dtype=vec), solid_hi: wp.array(dtype=vec),
                 grow: scalar) -> bool:
        """Whether x lies in one of the solid boxes, each grown by ``grow``."""
        hit = int(0)
        for k in range(p.n_solids):
            if in_box(x, solid_lo[k], solid_hi[k], grow, p.dim):
                hit = 1
        return hit == 1

    @wp.func
    def fault(p: Params, x: vec, x_before: vec, u: vec, r: scalar, t: int, scale: scalar,
              solid_lo: wp.array(dtype=vec), solid_hi: wp.array(dtype=vec)) -> int:
        """The first of REASONS a particle of the candidate state fails (x_before its committed
        position; ``scale`` its spacing over the scene's, which the lengths set in dx follow), or -1."""
        if wp.isnan(x) or wp.isinf(x) or wp.isnan(u) or wp.isinf(u) or wp.isnan(r) or wp.isinf(r):
            return NON_FINITE
        bad_density = r < p.rho_min or r > p.rho_max
        if t != FLUID:
            if bad_density:
                return DENSITY_BOUNDS
            return -1
        d = x - x_before
        for ax in range(3):
            if p.periodic[ax] != 0:  # a particle that wrapped moved by the minimum image
                span = p.hi[ax] - p.lo[ax]
                d[ax] = d[ax] - span * wp.round(d[ax] / span)
        jumped = wp.dot(d, d) > p.move_limit2 * scale * scale
        # beyond a tank wall's face (or the domain) above the walls' top, at a flow's pace: over the walls
        depth = p.penetration * scale
        outside = not in_box(x, p.lo, p.hi, scalar(0.0), 3)
        beyond = not in_box(x, p.wall_lo, p.wall_hi, depth, 3)
        if (outside or beyond) and x[p.dim - 1] > p.wall_top and not jumped:
            return LEFT_TANK
        if outside:
            return OUTSIDE_DOMAIN
        if bad_density:
            return DENSITY_BOUNDS
        if beyond:
            return WALL_PENETRATION
        if in_solid(p, x, solid_lo, solid_hi, -depth):
            return WALL_PENETRATION
        if jumped:
            return DISPLACEMENT
        return -1

    @wp.kernel(enable_backward=False, module="unique")
    def check_particles(p: Params, pos: wp.array(dtype=vec), pos_c: wp.array(dtype=vec), vel_c: wp.array(dtype=vec),
                        rho_c: wp.array(dtype=scalar), mass: wp.array(dtype=scalar), hsml: wp.array(dtype=scalar),
                        ptype: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), owned: wp.array(dtype=wp.int32),
                        solid_lo: wp.array(dtype=vec), solid_hi: wp.array(dtype=vec),
                        fail: wp.array(dtype=wp.int32), faulty: wp.array(dtype=wp.int32),
                        pending: wp.array(dtype=wp.int32), pending_mass: wp.array(dtype=wp.int64)):
        """Checks each particle of the candidate state (pos_c, vel_c, rho_c). A fluid particle at
        fault, when exclusion is on, or that left the tank is marked in ``faulty`` for commit to exclude
        and counted in ``pending`` (by reason) and ``pending_mass`` (PENDING_FAULT or PENDING_LEFT, in
        p.mass_units); any other fault flags its slot in ``fail`` with the caller's particle id (the
        slots are re-sorted by later steps of the batch). A rank checks only the particles it owns."""
        i = wp.tid()
        t = ptype[i]
        if t != FLUID and t != BOUNDARY:
            return  # already excluded
        if p.ranked != 0 and owned[i] == 0:
            return
        reason = fault(p, pos_c[i], pos[i], vel_c[i], rho_c[i], t, own_scale(p, hsml[i]), solid_lo, solid_hi)
        if reason < 0:
            return
        if t == FLUID and (p.exclude != 0 or reason == LEFT_TANK):
            faulty[i] = 1
            wp.atomic_add(pending, reason, 1)
            wp.atomic_add(pending_mass, wp.where(reason == LEFT_TANK, PENDING_LEFT, PENDING_FAULT),
                          wp.int64(wp.round(wp.float64(mass[i]) * p.mass_units)))
        else:
            wp.atomic_min(fail, reason, ids[i])

    @wp.kernel(enable_backward=False, module="unique")
    def exclusion_check(p: Params, clock: wp.array(dtype=wp.float64), pending: wp.array(dtype=wp.int32),
                        pending_mass: wp.array(dtype=wp.int64), excluded: wp.array(dtype=wp.int32),
                        excluded_mass: wp.array(dtype=wp.float64), fail: wp.array(dtype=wp.int32)):
        """After every other check of the candidate: flags excluded_fraction when the fluid excluded
        at fault would pass its limit, left_fraction when the fluid that left the tank would; else,
        if the candidate is to be committed, adds this step's exclusions to the run's (excluded_mass:
        MASS, FIRST_TIME of an exclusion at fault or -1, LEFT_MASS). A failed step's exclusions stay
        pending for the report."""
        if pending_mass[PENDING_FAULT] <= wp.int64(0) and pending_mass[PENDING_LEFT] <= wp.int64(0):
            return
        fault_kg = wp.float64(pending_mass[PENDING_FAULT]) / p.mass_units
        left_kg = wp.float64(pending_mass[PENDING_LEFT]) / p.mass_units
        if excluded_mass[MASS] + fault_kg > p.excluded_limit:
            fail[EXCLUDED_FRACTION] = 0
        if excluded_mass[LEFT_MASS] + left_kg > p.left_limit:
            fail[LEFT_FRACTION] = 0
        if not healthy(fail):
            return
        if excluded_mass[FIRST_TIME] < wp.float64(0.0) and fault_kg > wp.float64(0.0):
            excluded_mass[FIRST_TIME] = clock[T] + wp.float64(p.coarse_stride) * clock[DT]  # the step's end
        excluded_mass[MASS] = excluded_mass[MASS] + fault_kg
        excluded_mass[LEFT_MASS] = excluded_mass[LEFT_MASS] + left_kg
        pending_mass[PENDING_FAULT] = wp.int64(0)
        pending_mass[PENDING_LEFT] = wp.int64(0)
        for k in range(N_REASONS):
            excluded[k] = excluded[k] + pending[k]
            pending[k] = 0

    @wp.func
    def near_wall(p: Params, x: vec, solid_lo: wp.array(dtype=vec), solid_hi: wp.array(dtype=vec)) -> bool:
        """Whether x lies within p.clump_wall of a tank wall face or of a solid box."""
        return not in_box(x, p.wall_lo, p.wall_hi, -p.clump_wall, p.dim) or in_solid(p, x, solid_lo, solid_hi,
                                                                                       p.clump_wall)

    @wp.kernel(enable_backward=False, module="unique")
    def census(p: Params, pos: wp.array(dtype=vec), vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar),
               mass: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32),
               owned: wp.array(dtype=wp.int32),
               clumped: wp.array(dtype=wp.int32), faulty: wp.array(dtype=wp.int32), solid_lo: wp.array(dtype=vec),
               solid_hi: wp.array(dtype=vec), total: wp.array(dtype=wp.float64), count: wp.array(dtype=wp.int32),
               part: wp.array2d(dtype=wp.float64), lead: int, step: int, members: int):
        """Block k's share of the fluid's kinetic + potential + elastic energy into part[k, 0]
        (sums.py: a fixed order of the terms); total[RHO_LOW], total[RHO_HIGH] hold the lowest and
        highest density of a fluid particle not at fault seen in any census; count[CLUMPED] counts
        the clumped fluid particles away from walls and count[FIRST_CLUMPED] holds the first of them.
        Each block takes its own extremes and count and makes one atomic of each (minima, maxima and
        integers: the same in any order), not one per particle on the same address. One launch: a
        CPU's atomics are not atomic across the threads of a split launch."""
        k = wp.tid()
        n = ptype.shape[0]
        energy = wp.float64(0.0)
        low = wp.float64(1.0e300)
        high = wp.float64(-1.0e300)
        clumps = int(0)
        first = int(NO_FAILURE)
        for j in range(members):
            i = sums.member(k, j, lead, step)
            if i < n:
                if ptype[i] == FLUID and (p.ranked == 0 or owned[i] != 0):
                    if faulty[i] == 0:
                        low = wp.min(low, wp.float64(rho[i]))
                        high = wp.max(high, wp.float64(rho[i]))
                    if clumped[i] != 0 and not near_wall(p, pos[i], solid_lo, solid_hi):
                        clumps += 1
                        first = wp.min(first, ids[i])
                    u = vel[i]
                    e = mass[i] * (scalar(0.5) * wp.dot(u, u) - wp.dot(p.gravity, pos[i])
                                   + elastic_energy(rho[i], p.rho0, p.eos_b, p.gamma))
                    energy = energy + wp.float64(e)
        part[k, 0] = energy
        if low <= high:
            wp.atomic_min(total, RHO_LOW, low)
            wp.atomic_max(total, RHO_HIGH, high)
        if clumps > 0:
            wp.atomic_add(count, CLUMPED, clumps)
            wp.atomic_min(count, FIRST_CLUMPED, first)

    @wp.kernel(enable_backward=False, module="unique")
    def census_check(p: Params, total: wp.array(dtype=wp.float64), count: wp.array(dtype=wp.int32),
                     fail: wp.array(dtype=wp.int32)):
        """Flags energy_growth when the candidate's energy exceeds the start's (NO_ENERGY before the
        first check) and the work the moving bodies did on the fluid by the slack, clumping when too
        many particles have clumped; keeps the peaks."""
        e = total[ENERGY] - total[WORK]
        if total[ENERGY_START] == wp.float64(1.0e300):  # NO_ENERGY as a literal: a Python float would be float32
            total[ENERGY_START] = e
        total[PEAK_ENERGY_GROWTH] = wp.max(total[PEAK_ENERGY_GROWTH], e - total[ENERGY_START])
        if p.energy_slack > wp.float64(0.0) and e > total[ENERGY_START] + p.energy_slack:
            fail[ENERGY_GROWTH] = 0
        fraction = wp.float64(count[CLUMPED]) / wp.float64(p.n_fluid)
        total[PEAK_CLUMPED] = wp.max(total[PEAK_CLUMPED], fraction)
        if p.clump_r > scalar(0.0) and fraction > p.clump_fraction and count[CLUMPED] > CLUMP_MIN:
            fail[CLUMPING] = count[FIRST_CLUMPED]
        count[CLUMPED] = 0  # ready for the next census
        count[FIRST_CLUMPED] = NO_FAILURE

    return SimpleNamespace(healthy=healthy, check_particles=check_particles, exclusion_check=exclusion_check,
                           census=census, census_check=census_check)
