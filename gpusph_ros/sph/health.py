"""Run-safety checks: the ways a run fails, checked on every candidate state before it is committed.

Each check has a named slot in the ``fail`` array (the id of the first particle that failed it, or
NO_FAILURE); a state with any slot set is never committed.

- non_finite: NaN or infinity in a position, velocity or density;
- outside_domain: a fluid particle left the domain (the tank, its walls and headroom);
- density_bounds: a density outside [rho_min, rho_max] (0.8 and 1.25 rho0 by default);
- wall_penetration: a fluid particle more than ``penetration_ratio`` dx beyond a wall face of the
  tank, or as deep inside a solid box: the boundary let it through;
- clumping: more than ``clump_fraction`` of the fluid particles have a fluid neighbour closer
  than ``clump_ratio`` dx, marked in the force pass (the tensile and pairing instabilities pair
  particles long before anything is infinite; a few pairs in a splash are no failure);
- energy_growth: the fluid's kinetic + potential + elastic energy (eos.elastic_energy) more than
  ``energy_growth_ratio`` M g H above its value at the start: in a closed tank with no inflow
  every term of the scheme conserves or dissipates it, so growth is the integrator going unstable.
"""

import functools
from types import SimpleNamespace

import warp as wp

from . import eos, state

FLUID = state.FLUID

# the checks, in the order they are reported; each name's index is its slot in ``fail``
CHECKS = ("non_finite", "outside_domain", "density_bounds", "wall_penetration", "clumping", "energy_growth")
NON_FINITE, OUTSIDE_DOMAIN, DENSITY_BOUNDS, WALL_PENETRATION, CLUMPING, ENERGY_GROWTH = range(len(CHECKS))
N_CHECKS = len(CHECKS)
# checks of the whole state, not of one particle
GLOBAL_CHECKS = ("energy_growth",)
NO_FAILURE = 2 ** 31 - 1
NO_ENERGY = 1.0e300  # the energy check's "no reference yet"


class HealthError(RuntimeError):
    """A step failed a health check. The solver still holds the state from before that step."""

    def __init__(self, check: str, step: int, time: float, particle: int, detail: str = ""):
        self.check = check
        self.step = step
        self.time = time
        self.particle = particle
        super().__init__(f"health check '{check}' failed at step {step} (t = {time:.6g} s), "
                         f"particle {particle}{': ' + detail if detail else ''}")


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    Params = state.build(scalar).Params
    elastic_energy = eos.build(scalar).elastic_energy

    @wp.func
    def healthy(fail: wp.array(dtype=wp.int32)) -> bool:
        bad = int(0)
        for k in range(N_CHECKS):
            if fail[k] != NO_FAILURE:
                bad = 1
        return bad == 0

    @wp.kernel(enable_backward=False, module="unique")
    def check_particles(p: Params, pos: wp.array(dtype=vec), vel: wp.array(dtype=vec), rho: wp.array(dtype=scalar),
                        ptype: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32),
                        solid_lo: wp.array(dtype=vec), solid_hi: wp.array(dtype=vec), fail: wp.array(dtype=wp.int32)):
        """Flags each check a particle of the candidate state fails, by the caller's particle id
        (the slots are re-sorted by later steps of the batch)."""
        i = wp.tid()
        pid = ids[i]
        x = pos[i]
        r = rho[i]
        if wp.isnan(x) or wp.isinf(x) or wp.isnan(vel[i]) or wp.isinf(vel[i]) or wp.isnan(r) or wp.isinf(r):
            wp.atomic_min(fail, NON_FINITE, pid)
            return
        if ptype[i] == FLUID:
            for ax in range(3):
                if x[ax] < p.lo[ax] or x[ax] > p.hi[ax]:
                    wp.atomic_min(fail, OUTSIDE_DOMAIN, pid)
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
            wp.atomic_min(fail, DENSITY_BOUNDS, pid)

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
        e = mass[i] * (scalar(0.5) * wp.dot(u, u) - wp.dot(p.gravity, pos[i])
                       + elastic_energy(rho[i], p.rho0, p.eos_b, p.gamma))
        wp.atomic_add(total, 0, wp.float64(e))

    @wp.kernel(enable_backward=False, module="unique")
    def census_check(p: Params, total: wp.array(dtype=wp.float64), count: wp.array(dtype=wp.int32),
                     fail: wp.array(dtype=wp.int32)):
        """total = [candidate's energy, energy at the start (or NO_ENERGY before the first check),
        the largest clumped fraction seen]: flags energy_growth when the candidate exceeds the start
        by the slack, clumping when too many particles have clumped."""
        e = total[0]
        if total[1] == wp.float64(1.0e300):  # NO_ENERGY, written as a literal: a Python float would be float32
            total[1] = e
        if p.energy_slack > wp.float64(0.0) and e > total[1] + p.energy_slack:
            fail[ENERGY_GROWTH] = 0
        fraction = wp.float64(count[0]) / wp.float64(p.n_fluid)
        total[2] = wp.max(total[2], fraction)
        if p.clump_r > scalar(0.0) and fraction > p.clump_fraction:
            fail[CLUMPING] = count[1]
        count[0] = 0  # ready for the next census
        count[1] = NO_FAILURE

    return SimpleNamespace(healthy=healthy, check_particles=check_particles, census=census, census_check=census_check)
