"""The solver driver: owns the device state and launches the passes of each step.

State is structure-of-arrays on one Warp device (``cpu`` or ``cuda:N``) in one precision.
The device drives the step loop: each step's size, whether it reorders, sorts, takes the census or
filters, and when the loop stops at the target time are decided by the passes themselves (flags
that ``wp.capture_if`` and ``wp.capture_while`` branch on), so nothing is copied to the host
between two outputs and a captured graph can replay the loop. At the end the host reads a
handful of scalars (time, dt, step count, health flags).
"""
from __future__ import annotations

import math

import numpy as np
import warp as wp

from . import (
    bodies,
    body_sums,
    boundaries,
    density,
    eos,
    graph,
    health,
    kernels,
    levels,
    passes,
    scan,
    shifting,
    sums,
    viscosity,
    xsph,
)
from .boundaries import faces
from .config import RESET_FIELDS, SolverConfig, check_device
from .device import chosen_device
from .health import HealthError
from .kernels import COARSER_LEVELS, EVERY_LEVEL, FINEST_LEVEL
from .launch import Launcher
from .neighbours import NeighbourList, NeighbourOverflow, default_max_neighbours, measured_width
from .particles import Particles
from .state import (
    BOUNDARY,
    CENSUS_DUE,
    DT,
    DT_STABLE,
    EXCLUDED,
    FAILED_STEP,
    FLUID,
    LISTS_HOLD,
    N_CLOCK,
    N_FLAGS,
    N_STEPS,
    PASSIVE,
    REORDER_DUE,
    RUNNING,
    SHEPARD_DUE,
    STEP,
    T_FAILED,
    VACANT,
    T,
)

# steps between two looks of the host at an interruptible loop (a node asked to pause waits at most
# these); a loop nobody interrupts runs to its target without the host
_MAX_BATCH = 64
_UNBOUNDED = 2 ** 31 - 1
# a CPU run of fewer particles steps on one thread (cpu_threads 0): its loop then replays from a
# capture, with no launch from Python, and handing its passes to a pool of threads costs more than
# they save (paddle_2d on 2 cores: 483 particles, 2,684 steps/s replayed against 850 on two threads;
# 2,456, 426 against 409; 4,878, 207 against 245)
SMALL_RUN = 3000
# steps between two sorts of the particle arrays into cell order: neighbours then sit next to each
# other in memory, which the force passes (memory-bound on a CPU, coalesced on a GPU) need
_REORDER_EVERY = 16
# steps between two energy and clumping checks: the sums are one atomic launch, cheap but not free
# on a GPU
_CENSUS_EVERY = 16


class Solver:
    """Weakly-compressible SPH (thesis Section 2.3) on Warp.

    The device arrays (pos, vel, rho, pressure, mass, ptype, body) are kept in cell order and
    re-sorted every few steps; ``ids`` gives the caller's index of each slot, and ``snapshot``
    returns host copies in the caller's order.
    """

    def __init__(self, config: SolverConfig, particles: Particles, max_neighbours: "int | None" = None,
                 body_names: "list | None" = None, owned: "np.ndarray | None" = None, fluid: "tuple | None" = None,
                 wrench_rows: "tuple | None" = None):
        self.config = config.replace(device=chosen_device(config.device)).validate()
        # each body's name by id, for what a report says of it (the scene's obstacles)
        self.body_names = list(body_names) if body_names else [f"body {k}" for k in range(len(config.motions))]
        cfg = self.config
        self.scalar = wp.float64 if cfg.precision == "float64" else wp.float32
        self.vec = wp.types.vector(3, self.scalar)
        check_device(cfg.device)
        self.device = wp.get_device(cfg.device)
        self.n = len(particles)
        if self.n == 0:
            raise ValueError("particles: the particle set is empty")
        # one rank's solver (docs/ranks.md): ``owned`` marks the particles it owns (True) and its
        # halo's (False), which it steps too but neither checks, counts nor lets bound the step
        self._owned = None if owned is None else np.asarray(owned, dtype=bool).reshape(self.n)
        self._passes = passes.build(self.scalar)
        self.boundary = boundaries.model(cfg.boundary)
        # the fluid the health checks' shares are of: the whole run's (``fluid``: mass, particles) on a rank
        self._fluid_mass = float(particles.mass[particles.ptype == FLUID].sum()) if fluid is None else float(fluid[0])
        self.n_fluid = int((particles.ptype == FLUID).sum()) if fluid is None else int(fluid[1])
        # the floating bodies' wrench table (body_sums.py): each particle's row by the caller's index
        # and each row's body, the whole run's on a rank (``wrench_rows``)
        self._wrench_table = self.wrench_table(config.motions, particles) if wrench_rows is None else wrench_rows
        spacing = particles.spacing if particles.spacing is not None else np.full(self.n, cfg.dx)
        if np.any(spacing <= 0.0) or np.any(spacing > cfg.dx * (1.0 + 1.0e-9)):
            raise ValueError(f"particles: spacings above 0 and at most dx = {cfg.dx:g} m (a refinement zone is "
                             f"finer than the scene), got {spacing.min():g} to {spacing.max():g} m")
        self._h_particles = cfg.hdx * spacing
        self._level_h = [float(h) for h in np.unique(self._h_particles)]  # the levels' h, finest first
        self.params = self._make_params()
        self.launch = Launcher(self.device, cfg.cpu_threads or (1 if self.n < SMALL_RUN else 0))
        self._allocate(particles)
        self.neighbours = NeighbourList(self.scalar, cfg.dim, 2.0 * cfg.h, cfg.domain_lo, cfg.domain_hi,
                                        cfg.periodic, self.ptype, self._needs_list, self.ghost,
                                        max_neighbours or 1, self.launch, self.hsml, self.ids,
                                        self.params.variable_h != 0,
                                        self.params.coarse_stride, fail=self._fail,
                                        fail_slot=health.NEIGHBOUR_OVERFLOW, hold=self.flag(LISTS_HOLD),
                                        cells=cfg.cell_walks)
        # the lists' width: the caller's, fixed, or measured on the particles as built (a first build
        # into lists one long counts the longest: neighbours.longest) and widened whenever a list
        # outgrows it, up to the lattice's estimate (what the plan prices; a list longer than that
        # is clumped particles, not a flow)
        self._measured_width = max_neighbours is None and not cfg.cell_walks
        self._widest = default_max_neighbours(cfg.dim, cfg.hdx, self.finest, self.params.coarse_stride)
        if self._measured_width:
            self.neighbours.rebuild(self.pos, force=True)
            self.neighbours.resize(min(measured_width(self.neighbours.longest()), self._widest))
            self.neighbours.builds.zero_()
            self.clear_failure()
        self._step_hooks = []
        self._dt_hooks = []
        self._census_hooks = []
        self._total_hooks = []
        self._graph = graph.LoopGraph(self)
        self.time, self.dt, self.dt_stable, self.steps = 0.0, 0.0, 0.0, 0
        self._excluded_host = (np.zeros(health.N_REASONS, dtype=np.int32), np.array(health.EXCLUDED_START))
        self._view_fresh = False  # measurement_view's pressure and cell sort are of the state now
        self._census_host = np.array(health.CENSUS_START)  # as of the last sync

    @property
    def finest(self) -> float:
        """The finest particle spacing over the scene's dx: 1 without refinement zones."""
        return float(self._h_particles.min()) / self.config.h

    # -- set-up -------------------------------------------------------------------------
    def _make_params(self):
        """The Params struct the passes read: each model module gives the fields of its model."""
        cfg = self.config
        p = self._passes.Params()
        fields = {**passes.params(cfg), **kernels.params(cfg, float(self._h_particles.min())), **eos.params(cfg),
                  **viscosity.params(cfg),
                  **density.params(cfg), **xsph.params(cfg), **shifting.params(cfg), **boundaries.params(cfg),
                  **health.params(cfg, self._fluid_mass, self.n_fluid), "ranked": int(self._owned is not None)}
        declared = self._passes.Params.vars
        for name, value in fields.items():
            kind = declared[name].type
            setattr(p, name, kind(*value) if wp.types.type_is_vector(kind) else value)
        missing = set(declared) - set(fields)
        if missing:
            raise RuntimeError(f"Params fields that no model module sets: {sorted(missing)}")
        self._energy_slack = fields["energy_slack"]
        return p

    def _allocate(self, particles: Particles):
        cfg, dev, n, s, v = self.config, self.device, self.n, self.scalar, self.vec

        def arr(data, dtype):
            return wp.array(data, dtype=dtype, device=dev)

        self.pos = arr(particles.pos, v)
        self.vel = arr(particles.vel, v)
        self.rho = arr(particles.rho, s)
        self.mass = arr(particles.mass, s)
        self.hsml = arr(self._h_particles, s)
        self.ptype = arr(particles.ptype, wp.int32)
        self.body = arr(particles.body, wp.int32)
        # the arrays are kept in cell order; ids maps each slot back to the caller's particle
        self.ids = arr(np.arange(n, dtype=np.int32), wp.int32)
        # boundary particles need their own list only for their density (walls with a volume: dynamic
        # by continuity; mDBC's list holds the fluid near the ghost node too) or to sum a body force; a
        # refinement level's vacant slot none until it holds a daughter (levels.spawn): searching for
        # its 21,000 slots took a quarter of DamBreak 1's zoned list builds
        self._needs_list = arr(self.needs_list(particles.ptype, particles.body), wp.int32)
        self.ghost = wp.zeros(n, dtype=v, device=dev)  # mDBC's ghost-node offsets (boundaries/mdbc.py); else zero
        self._spawned = wp.zeros(n, dtype=wp.int32, device=dev)  # refinement levels: which fluid has daughters
        # the reorder's scratch, one array of each type the state holds (passes.permute)
        self._gathered = {t: wp.empty(n, dtype=t, device=dev) for t in (v, s, wp.int32)}
        self.pressure = wp.zeros(n, dtype=s, device=dev)
        # half-step and candidate states, rates of change
        self._pos_h, self._vel_h, self._rho_h = (wp.zeros_like(a) for a in (self.pos, self.vel, self.rho))
        self._pos_c, self._vel_c, self._rho_c = (wp.zeros_like(a) for a in (self.pos, self.vel, self.rho))
        self.acc, self._xsph = wp.zeros(n, dtype=v, device=dev), wp.zeros(n, dtype=v, device=dev)
        self._shift = wp.zeros(n, dtype=v, device=dev)
        self._drho = wp.zeros(n, dtype=s, device=dev)
        # the SPS stress only under sps (24 B a particle; one entry, never read, otherwise): a live
        # change to sps allocates it (reconfigure)
        stress = n if cfg.viscosity == "sps" else 1
        shared = dict(pressure=self.pressure, p_rho2=wp.zeros(n, dtype=s, device=dev), mass=self.mass,
                      hsml=self.hsml, ptype=self.ptype, body=self.body, tau_diag=wp.zeros(stress, dtype=v, device=dev),
                      tau_off=wp.zeros(stress, dtype=v, device=dev), wall_acc=wp.zeros(n, dtype=v, device=dev),
                      wall_normal=wp.zeros(n if cfg.wall_flux == "normal" else 1, dtype=v, device=dev),
                      owned=arr(np.ones(1, dtype=np.int32) if self._owned is None else self._owned.astype(np.int32),
                                wp.int32))
        self.wall_acc = shared["wall_acc"]
        self.wall_normal = shared["wall_normal"]
        # the fixed obstacles' boxes: the health check's and the floating bodies' (at least one entry,
        # unread when there are none)
        solids = cfg.solids or [((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))]
        # prescribed motion (bodies.py): each body's law, and where its particles stood at t = 0 in
        # the caller's order (``ids`` finds them after a reorder); a scene without motion has none
        self._moving = any(m is not None for m in cfg.motions)
        self._floating = any(isinstance(m, bodies.Floating) for m in cfg.motions)
        if self._moving:
            B = bodies.build(s)
            self._law_list = B.law_list(cfg.motions)  # the host's copy, which drive() changes
            self._laws = wp.array(self._law_list, dtype=B.Law, device=dev)
            self._series = wp.array(bodies.series_table(cfg.motions), dtype=wp.float64, device=dev)
            self._rest = arr(np.asarray(particles.pos, dtype=np.float64), wp.vec3d)
            self._moves = wp.array([int(m is not None) for m in cfg.motions], dtype=wp.int32, device=dev)
            nb = len(cfg.motions)
            self._poses = wp.zeros(nb, dtype=B.Pose, device=dev)
            # the floating bodies' state, half step and candidate, and the last evaluation's force
            # and torque on each
            self._rigid, self._rigid_h, self._rigid_c = (B.rigid_states(cfg.motions, dev) for _ in range(3))
            # force and torque of body b at 2 b and 2 b + 1, summed in a fixed order (sums.py)
            self._body_sums = wp.zeros(2 * nb, dtype=wp.vec3d, device=dev)
            rows, row_body = self._wrench_table
            self._wrench_rows = arr(rows, wp.int32)
            self._row_body = wp.array(np.asarray(row_body, dtype=np.int32), dtype=wp.int32, device=dev)
            self._wrench_terms = wp.zeros((max(1, len(row_body)), 2), dtype=wp.vec3d, device=dev)
            self._wrench_part = sums.Partials(len(row_body), 2 * nb, wp.vec3d, dev)
            self._step_work = wp.zeros(1, dtype=wp.float64, device=dev)
            self._gravity64 = wp.vec3d(*cfg.gravity)
            self._walls64 = (wp.vec3d(*cfg.wall_lo), wp.vec3d(*cfg.wall_hi))
            # the fixed obstacles' boxes a floating body meets (in float64, as its state), and whether
            # two floating bodies may meet
            self._solids64 = tuple(wp.array(np.asarray([box[k] for box in solids], dtype=np.float64), dtype=wp.vec3d,
                                            device=dev) for k in (0, 1))
            self._pairs = sum(isinstance(m, bodies.Floating) for m in cfg.motions) > 1
        self.fields = self._make_fields(self.pos, self.vel, self.rho, shared)
        self._fields_h = self._make_fields(self._pos_h, self._vel_h, self._rho_h, shared)
        self._fields_c = self._make_fields(self._pos_c, self._vel_c, self._rho_c, shared)
        self._half, self._candidate = (self._pos_h, self._vel_h, self._rho_h), (self._pos_c, self._vel_c, self._rho_c)
        planes = cfg.planes or []
        pts = [p.point for p in planes] or [(0.0, 0.0, 0.0)]
        nrm = [np.asarray(p.normal, dtype=np.float64) / np.linalg.norm(p.normal) for p in planes] or [(0.0, 0.0, 1.0)]
        self._plane_pt, self._plane_n = arr(np.asarray(pts, dtype=np.float64), v), arr(np.asarray(nrm), v)
        self._maxima = wp.zeros(2 * self.launch.threads, dtype=s, device=dev)  # |a|max, |mu|max per chunk
        self.solid_lo = arr(np.asarray([lo for lo, _ in solids], dtype=np.float64), v)
        self.solid_hi = arr(np.asarray([hi for _, hi in solids], dtype=np.float64), v)
        zones = cfg.zones or [((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), cfg.dx)]
        self._zone_lo = arr(np.asarray([lo for lo, _, _ in zones], dtype=np.float64), v)
        self._zone_hi = arr(np.asarray([hi for _, hi, _ in zones], dtype=np.float64), v)
        self._zone_h = arr(np.asarray([cfg.hdx * spacing for _, _, spacing in zones], dtype=np.float64), s)
        # refinement levels (levels.py), with zones: which fluid wants daughters, the free slots,
        # their ranks, and the daughters' offsets in their parent's spacing
        m = n if cfg.zones else 1
        self._want, self._vacant, self._want_rank, self._vacant_rank, self._free = (
            wp.zeros(m, dtype=wp.int32, device=dev) for _ in range(5))
        self._offsets = arr(levels.sub_offsets(2, cfg.dim), v)
        self._scan = scan.Scan(m, dev)  # the slots' ranks: its scratch allocated here, never in the step
        self._fail = arr(np.full(health.N_CHECKS, health.NO_FAILURE, dtype=np.int32), wp.int32)
        # the census sums (health.CENSUS_START); clumped fluid particles and the first of them
        self._energy_sum = arr(np.array(health.CENSUS_START), wp.float64)
        # one float64 sum at a time in a fixed order (sums.py): the census's energies, the bodies' work
        self._sum64 = sums.Partials(n, 1, wp.float64, dev)
        self._clumped = wp.zeros(n, dtype=wp.int32, device=dev)
        self._clump_count = arr(np.array([0, health.NO_FAILURE], dtype=np.int32), wp.int32)
        # exclusions (health.py): fluid particles at fault in the candidate, their count by reason and
        # mass until the step commits; the run's counts, and [mass, time of the first or -1]
        self._faulty = wp.zeros(n, dtype=wp.int32, device=dev)
        self._pending = wp.zeros(health.N_REASONS, dtype=wp.int32, device=dev)
        self._pending_units = wp.zeros(2, dtype=wp.int64, device=dev)  # in Params.mass_units: health.PENDING_*
        self._excluded = wp.zeros(health.N_REASONS, dtype=wp.int32, device=dev)
        self._excluded_mass = arr(np.array(health.EXCLUDED_START), wp.float64)
        self._clock = wp.zeros(N_CLOCK, dtype=wp.float64, device=dev)  # slots state.T ... TARGET
        steps = np.zeros(N_STEPS, dtype=np.int32)  # slots state.STEP ... IN_BLOCK
        steps[FAILED_STEP] = -1
        self._steps = arr(steps, wp.int32)
        # the step loop's flags (state.RUNNING ...): the first step reorders and takes the census
        flags = np.zeros(N_FLAGS, dtype=np.int32)
        flags[[REORDER_DUE, CENSUS_DUE, LISTS_HOLD]] = 1
        self._flags = arr(flags, wp.int32)
        self._flag_views = tuple(self._flags[k:k + 1] for k in range(N_FLAGS))
        wp.launch(self._passes.equation_of_state, dim=n, inputs=[self.params, self.fields], device=dev)
        self._move_walls(0.0, self.pos, self.vel)  # the moving bodies' poses at t = 0, before any step
        self.boundary.prepare(self)
        if cfg.wall_flux == "normal":
            faces.normals(self, self.wall_normal)
        if cfg.zones:
            wp.launch(levels.build(s).mark_spawned, dim=n, inputs=[self.params, self.pos, self.hsml, self.ptype,
                                                                   self._zone_lo, self._zone_hi, self._zone_h,
                                                                   self._spawned], device=dev)

    def needs_list(self, ptype: np.ndarray, body: np.ndarray) -> np.ndarray:
        """Which particles of kinds ``ptype`` on bodies ``body`` keep a neighbour list (1) under this
        solver's boundary model (_allocate says why; exchange.py rewrites a rank's slots by it)."""
        needs = np.isin(ptype, (FLUID, PASSIVE)) | (body >= 0) | self.boundary.volume
        return (needs & (ptype != VACANT)).astype(np.int32)

    def _make_fields(self, pos, vel, rho, shared: dict):
        f = self._passes.Fields()
        f.pos, f.vel, f.rho = pos, vel, rho
        for name, array in shared.items():
            setattr(f, name, array)
        return f

    # -- stepping -----------------------------------------------------------------------
    def _forces(self, f, which: int = EVERY_LEVEL):
        """The rates of the particles of the levels ``which`` (kernels.selected) in the state ``f``."""
        n, p, nl, k = self.n, self.params, self.neighbours, self._passes
        if self.config.zones:
            # finest first: a coarser level's passive particles read the next finer level's
            for h in self._level_h[:1] if which == FINEST_LEVEL else self._level_h:
                self.launch(levels.build(self.scalar).passive_state, n, [p, nl.grid, nl.walk, f, self._zone_lo,
                                                                         self._zone_hi, self._zone_h, h])
        wp.launch(k.equation_of_state, dim=n, inputs=[p, f], device=self.device)
        if self.config.viscosity == "sps":
            self.launch(k.sps_strain, n, [p, nl.grid, nl.walk, f, which])
        self.launch(k.interact, n, [p, nl.grid, nl.walk, f, self._plane_pt, self._plane_n, self.acc,
                                    self._drho, self._xsph, self._shift, self._maxima, self._clumped, which])
        if which == EVERY_LEVEL:  # a floating body steps with the passes over every level (_two_rates)
            self._body_wrench(f)

    def _integrate(self, factor: float, base, vel_rate, out, which: int = EVERY_LEVEL):
        """out = base advanced by ``factor`` of each selected particle's own step (passes.integrate)
        with the rates of the last force pass; base and out are (pos, vel, rho) triples."""
        wp.launch(self._passes.integrate, dim=self.n,
                  inputs=[self.params, self._clock, factor, *base, self.ptype, self.hsml, vel_rate, self.acc,
                          self._drho, self._xsph, self._shift, *out, which], device=self.device)

    def _reorder(self):
        """The particles put in the cell order of a sort, and their lists built on it."""
        self._put_in(self.neighbours.sort(self.pos))
        self.neighbours.rebuild_sorted(self.pos)

    def _put_in(self, order: wp.array):
        """Each particle's state moved to the slot ``order`` gives it: slot k takes particle order[k]."""
        # a moving wall's acceleration too: left in its slot, a fixed wall particle sorted there read a
        # paddle's (the extrapolated-pressure wall's g - a_w), where a fixed wall's is zero
        state = [self.pos, self.vel, self.rho, self.mass, self.hsml, self.ptype, self.body, self.ids,
                 self._needs_list, self.ghost, self._spawned, self.wall_acc] + \
            [self.wall_normal] * (self.config.wall_flux == "normal")
        if self._owned is not None:
            state.append(self.fields.owned)
        for a in state:
            into = self._gathered[a.dtype]
            wp.launch(self._passes.permute[a.dtype], dim=self.n, inputs=[order, a, into], device=self.device)
            wp.copy(a, into)

    def permute(self, order):
        """Put the particles in another slot order (slot k takes the particle in slot order[k]; a
        permutation of the slots) between steps, and build their lists again. The run goes on bit for
        bit as it would have: a cell's particles are summed in the order of their ids (neighbours.py)."""
        order = np.asarray(order)
        if order.shape != (self.n,) or not np.array_equal(np.sort(order), np.arange(self.n)):
            raise ValueError(f"order: a permutation of this solver's {self.n} slots")
        self._put_in(wp.array(order.astype(np.int32), dtype=wp.int32, device=self.device))
        self.neighbours.rebuild(self.pos, force=True)

    def _launch_step(self, block: int = _UNBOUNDED):
        """One step towards the clock's TARGET, every decision in it taken on the device (the
        branches on the step loop's flags), so that a captured graph can replay it. ``block``:
        how many steps since the loop started the device may take before it stops for the host."""
        wp.capture_if(self.flag(REORDER_DUE), on_true=self._reorder)
        self._move_walls(0.0, self.pos, self.vel)  # the walls' acceleration in this slot order too
        self.neighbours.rebuild(self.pos)
        # a list that overflowed stops the step here, before any pass writes the state (the walls,
        # the passive particles): widened, the lists take the same step again (_sync)
        wp.capture_if(self.flag(LISTS_HOLD), on_true=self._evolve)
        wp.launch(self._passes.tick, dim=1, inputs=[self.params, self._fail, self._clock, self._steps, self._flags,
                                                    _REORDER_EVERY, _CENSUS_EVERY, self.config.shepard_every, block],
                  device=self.device)
        self.neighbours.moved(self.pos, self.vel, self._clock)
        wp.capture_if(self.flag(SHEPARD_DUE), on_true=self.shepard_filter, rebuild=False)
        if self._step_hooks:  # on the state the step ends on, its Shepard filter's too; none for a step not taken
            wp.capture_if(self.flag(LISTS_HOLD), on_true=self._after_step)

    def _after_step(self):
        for hook in self._step_hooks:
            hook()

    def _evolve(self):
        """The step from its lists on: rates, the predictor-corrector, the checks and the commit."""
        n, dev, p, k = self.n, self.device, self.params, self._passes
        self._maxima.zero_()
        self.boundary.before_forces(self, self.fields)
        self._forces(self.fields)
        for hook in self._dt_hooks:
            hook(self._maxima)
        wp.launch(k.choose_dt, dim=1, inputs=[p, self._maxima, self._fail, self._clock], device=dev)
        state, half, candidate = (self.pos, self.vel, self.rho), self._half, self._candidate
        if p.coarse_stride == 1:
            self._integrate(0.5, state, self.vel, half)
            self._move_walls(0.5, *half[:2], into=1)
            self._walls_again(self._fields_h)
            self._forces(self._fields_h)
            self._integrate(1.0, state, self._vel_h, candidate)
            self._move_walls(1.0, *candidate[:2], into=2)
            self._work_on_fluid()
        else:
            self._two_rates(state, half, candidate)
        wp.launch(k.check_particles, dim=n,
                  inputs=[p, self.pos, self._pos_c, self._vel_c, self._rho_c, self.mass, self.hsml, self.ptype,
                          self.ids, self.fields.owned, self.solid_lo, self.solid_hi, self._fail, self._faulty,
                          self._pending,
                          self._pending_units], device=dev)
        wp.capture_if(self.flag(CENSUS_DUE), on_true=self._census)
        for hook in self._total_hooks:  # the run's exclusions this step, which its limits are checked on
            hook(self._pending)
            hook(self._pending_units)
        wp.launch(k.exclusion_check, dim=1, inputs=[p, self._clock, self._pending, self._pending_units,
                                                    self._excluded, self._excluded_mass, self._fail], device=dev)
        wp.launch(k.commit, dim=n, inputs=[self._fail, self._faulty, self._pos_c, self._vel_c, self._rho_c, self.pos,
                                           self.vel, self.rho, self.ptype, self._needs_list, self.neighbours.stale],
                  device=dev)
        if self._floating:
            wp.launch(bodies.build(self.scalar).commit_rigid, dim=len(self.config.motions),
                      inputs=[self._fail, self._rigid_c, self._rigid], device=dev)
        if self.config.zones:
            self._relevel()

    def _work_on_fluid(self):
        """The moving bodies' work on the fluid over the step (bodies.work_on_fluid), from the rates
        just evaluated at its midpoint over every level."""
        if self._moving:
            part, S = self._sum64, body_sums.build(self.scalar)
            self.launch(S.work_on_fluid, part.count,
                        [self._laws, self._clock, self.params.coarse_stride, self.ptype, self.body, self.params.ranked,
                         self.fields.owned, self.mass, self.acc, self._vel_h, *part.args()])
            part.total(self._step_work)
            for hook in self._total_hooks:
                hook(self._step_work)
            wp.launch(S.add_into, dim=1, inputs=[self._step_work, self._energy_sum, health.WORK], device=self.device)

    def _move_walls(self, factor: float, pos, vel, into: int = 0):
        """The moving bodies' poses at t + factor dt (bodies.body_poses: a floating body's state
        advanced into the half step, ``into`` 1, with the rates at t, or into the candidate, 2, with
        those at the half step) and their particles on them, with their velocity and acceleration;
        nothing in a scene without motion."""
        if not self._moving:
            return
        B, dev = bodies.build(self.scalar), self.device
        base, rates_at, out = [(self._rigid, self._rigid, self._rigid), (self._rigid, self._rigid, self._rigid_h),
                               (self._rigid, self._rigid_h, self._rigid_c)][into]
        wp.launch(B.body_poses, dim=len(self.config.motions),
                  inputs=[self._laws, self._series, self._clock, factor, self._gravity64, *self._walls64,
                          *self._solids64, len(self.config.solids), base, rates_at, self._body_sums, out, self._poses],
                  device=dev)
        if self._pairs:
            wp.launch(B.body_contacts, dim=1, inputs=[self._laws, factor, out, self._poses], device=dev)
        if into == 2 and self._floating:
            wp.launch(B.body_bounds, dim=len(self.config.motions),
                      inputs=[self._laws, out, wp.vec3d(*self.config.domain_lo), wp.vec3d(*self.config.domain_hi),
                              self._fail], device=dev)
        wp.launch(B.move_walls, dim=self.n, inputs=[self._laws, self._poses, self.ptype, self.body, self.ids,
                                                    self._rest, pos, vel, self.wall_acc], device=dev)

    def _body_wrench(self, f):
        """Each floating body's force and torque from the fluid of the force pass just made on ``f``."""
        if self._floating:
            S, terms, part = body_sums.build(self.scalar), self._wrench_terms, self._wrench_part
            terms.zero_()  # on a rank, the rows of the particles it does not own
            wp.launch(S.wrench_terms, dim=self.n,
                      inputs=[self._poses, self.ptype, self.body, self.ids, self._wrench_rows, self.params.ranked,
                              self.fields.owned, f.pos, self.mass, self.acc, terms], device=self.device)
            for hook in self._total_hooks:
                hook(terms)
            self.launch(S.wrench_sums, part.count, [self._row_body, terms, *part.args()])
            part.total(self._body_sums)

    def drive(self, body: int, t0: float, position, quaternion, velocity, omega, acceleration,
              angular_acceleration):
        """Set driven body ``body``'s segment from t0 (bodies.driven_pose; the scene's axes, the
        quaternion x, y, z, w): between two outputs, by the run's driver (drive.py)."""
        motion = self._motion_of(body)
        if not isinstance(motion, bodies.Motion) or motion.law != "driven":
            raise ValueError(f"body {body} is not a driven body")
        self._set_law(body, "segment", t0, position, quaternion, velocity, omega, acceleration, angular_acceleration)

    def apply_wrench(self, body: int, force, torque):
        """Set floating body ``body``'s external force and torque (world axes, about its centre of
        mass) until set again: between two outputs, by the run's driver (drive.py)."""
        if not isinstance(self._motion_of(body), bodies.Floating):
            raise ValueError(f"body {body} is not a floating body")
        self._set_law(body, "external", force, torque)

    def _motion_of(self, body: int):
        return self.config.motions[body] if 0 <= body < len(self.config.motions) else None

    def _set_law(self, body: int, change: str, *values):
        """Body ``body``'s Law changed by ``bodies.<change>(law, *values)``, and the table copied to
        the device into the same array, which a captured step graph keeps reading."""
        B = bodies.build(self.scalar)
        getattr(B, change)(self._law_list[body], *values)
        wp.copy(self._laws, wp.array(self._law_list, dtype=B.Law, device="cpu"))

    def body_poses(self) -> list:
        """Each moving body's pose as of the last step (a host read: for outputs), by body id:
        its reference point's position and velocity, its rotation quaternion (x, y, z, w) and
        angular velocity, world frame; None for a fixed body."""
        if not self._moving:
            return [None] * len(self.config.motions)
        poses = self._poses.numpy()
        return [{"position": np.array(r["x"]), "quaternion": np.array(r["q"]), "velocity": np.array(r["v"]),
                 "omega": np.array(r["w"])} if m is not None else None for r, m in zip(poses, self.config.motions)]

    def body_states(self) -> list:
        """Each body's floating state as of the last step (a host read: for outputs), by body id:
        position of the centre of mass, velocity, rotation quaternion (x, y, z, w) and angular
        momentum (world frame); None for a body that does not float."""
        if not self._floating:
            return [None] * len(self.config.motions)
        rigid = self._rigid.numpy()
        return [{"position": np.array(r["x"]), "velocity": np.array(r["v"]), "quaternion": np.array(r["q"]),
                 "angular_momentum": np.array(r["ang"])} if isinstance(m, bodies.Floating) else None
                for r, m in zip(rigid, self.config.motions)]

    def _census(self):
        """The fluid's energy and clumping, checked against the run's limits (health.census), the
        energy summed in a fixed order (sums.py)."""
        p, k, part = self.params, self._passes, self._sum64
        wp.launch(k.census, dim=part.count, inputs=[p, self._pos_c, self._vel_c, self._rho_c, self.mass, self.ptype,
                                                    self.ids, self.fields.owned, self._clumped, self._faulty,
                                                    self.solid_lo,
                                                    self.solid_hi, self._energy_sum, self._clump_count,
                                                    *part.args()], device=self.device)
        part.total(self._energy_sum, health.ENERGY)
        if self.boundary.repulsive and self.n > self.n_fluid:
            nl = self.neighbours
            self.launch(k.wall_energy, part.count, [p, nl.grid, nl.walk, self._pos_c, self.mass, self.ptype,
                                                    self.fields.owned, *part.args()])
            part.total(self._energy_sum, health.ENERGY, add=True)
        for hook in self._census_hooks:
            hook(self._energy_sum, self._clump_count)
        wp.launch(k.census_check, dim=1, inputs=[p, self._energy_sum, self._clump_count, self._fail],
                  device=self.device)

    def each_step(self, hook):
        """Call ``hook()`` at the end of every step taken, on the state it ends on (its Shepard
        filter's too, as a rank's hooks read it: sph/exchange.py): a measurement that accumulates on
        the device over the steps between its samples (measure/forces.py). It may only launch: it
        runs inside the step, where the host reads nothing."""
        self._step_hooks.append(hook)
        self._graph.drop()

    def each_dt(self, hook):
        """Call ``hook(maxima)`` in every step between its first force pass and the choice of its
        size: ``maxima`` holds the largest |a| and |mu| the pass found (passes.choose_dt), and a rank
        puts every rank's there (an all-reduce). The hook reads the device, so a solver with one
        steps only with ``step``, as the host drives a rank's steps."""
        self._dt_hooks.append(hook)

    def each_census(self, hook):
        """Call ``hook(totals, counts)`` in every census between its sums and its check (health.census:
        the energy, the density's extremes, the clumped count and the first clumped id), so that a
        rank checks every rank's (an all-reduce): the run fails or goes on as one. The hook reads
        the device, as each_dt's does."""
        self._census_hooks.append(hook)

    def each_total(self, hook):
        """Call ``hook(array)`` where a pass has summed over this solver's particles what must be the
        whole run's before it is used (body_sums.py: the floating bodies' wrench table, a step's
        work of the moving bodies; a step's exclusions, health.exclusion_check): a rank adds every
        rank's there, on every rank in the same order, so that every rank holds the run's totals
        and decides alike. The hook reads the device, as each_dt's does."""
        self._total_hooks.append(hook)

    @staticmethod
    def wrench_table(motions, particles) -> tuple:
        """(row of each particle in the floating bodies' wrench table, -1 for a particle of none; each
        row's body): the floating bodies' wall particles in the order of ``particles``
        (body_sums.py)."""
        floating = [b for b, m in enumerate(motions or []) if isinstance(m, bodies.Floating)]
        body = np.asarray(particles.body)
        mine = (np.asarray(particles.ptype) == BOUNDARY) & np.isin(body, floating)
        rows = np.full(len(body), -1, dtype=np.int32)
        rows[mine] = np.arange(int(mine.sum()), dtype=np.int32)
        return rows, body[mine].astype(np.int32)

    @property
    def clock(self):
        """The device clock (float64 slots state.T, DT, DT_STABLE, T_FAILED)."""
        return self._clock

    @property
    def failures(self):
        """The device's failure flags of the step under way (health.healthy reads them)."""
        return self._fail

    def _walls_again(self, f):
        """The walls set from the fluid again before a later force pass of the step, for a model that
        sets them before every evaluation (boundaries.model: each_evaluation)."""
        if self.boundary.each_evaluation:
            self.boundary.before_forces(self, f)

    def _two_rates(self, state, half, candidate):
        """One step of the coarser levels, 2 dt, as two of the finest level, dt each, every level by
        the predictor-corrector (multirate; Params.coarse_stride). The rates at the step's start are
        in. The coarse levels' midpoint is the finest level's first end, where every level is
        evaluated; between, the finest level's passive particles read the coarse fluid on the path
        its predictor and then its corrector take (to round-off what a linear interpolation in time
        between the coarse states would give):

            t + dt/2: fine half step, coarse at x + dt/2 (rates at t)       -> fine rates
            t + dt:   fine state, coarse predictor x + dt (rates at t)     -> every level's rates
            t + 3dt/2: fine half step, coarse at x + 3dt/2 (midpoint rates) -> fine rates
            t + 2dt:  both levels' candidates

        A moving body stands on its pose at each of those times (its particles of every level: the
        integration leaves a boundary particle where its base state has it). A floating body steps
        as a coarse particle does, its predictor to t + dt with the force at t and its corrector to
        t + 2dt with the force at t + dt, both from the passes over every level; between, it is on
        that path (at t + dt/2 on the predictor's, at t + 3dt/2 on the corrector's).
        """
        self._integrate(0.5, state, self.vel, half, FINEST_LEVEL)
        self._integrate(0.25, state, self.vel, half, COARSER_LEVELS)
        self._move_walls(0.5, *half[:2], into=1)
        self._walls_again(self._fields_h)
        self._forces(self._fields_h, FINEST_LEVEL)
        self._integrate(1.0, state, self._vel_h, candidate, FINEST_LEVEL)  # the fine state at t + dt
        self._move_walls(1.0, *candidate[:2], into=1)
        # walls set from the fluid (mDBC) take the fine state; what the coarse walls take there, from
        # no coarse state, the coarse passes below overwrite from the launch's start
        self.boundary.before_forces(self, self._fields_c)
        for dst, src in zip(half, candidate):
            wp.copy(dst, src)
        self._integrate(0.5, state, self.vel, half, COARSER_LEVELS)
        self._move_walls(1.0, *half[:2], into=1)
        self._walls_again(self._fields_h)
        self._forces(self._fields_h)
        self._work_on_fluid()
        self._integrate(1.0, state, self._vel_h, candidate, COARSER_LEVELS)
        self._integrate(0.75, state, self._vel_h, half, COARSER_LEVELS)
        self._integrate(0.5, candidate, self._vel_c, half, FINEST_LEVEL)
        self._move_walls(1.5, *half[:2], into=2)
        self._walls_again(self._fields_h)
        self._forces(self._fields_h, FINEST_LEVEL)
        self._integrate(1.0, candidate, self._vel_h, candidate, FINEST_LEVEL)
        self._move_walls(2.0, *candidate[:2], into=2)

    def _relevel(self):
        """Each fluid particle's level kind from where it stands, daughters for the fluid that
        reaches a finer level's band, and the walls whose band reaches into a finer zone no lower
        than rho0 (levels.py)."""
        n, dev, p, L = self.n, self.device, self.params, levels.build(self.scalar)
        self._floor_walls()
        if self._moving:
            wp.launch(L.bodies_off_edges, dim=n, inputs=[p, self.pos, self.ptype, self.body, self._moves, self.ids,
                                                         self._zone_lo, self._zone_hi, self._zone_h, self._fail,
                                                         health.ZONE_EDGE], device=dev)
        wp.launch(L.relevel, dim=n, inputs=[p, self.pos, self.hsml, self.ptype, self._needs_list,
                                            self._zone_lo, self._zone_hi, self._zone_h, self._spawned, self._want,
                                            self._vacant], device=dev)
        self._scan(self._want, self._want_rank)
        self._scan(self._vacant, self._vacant_rank)
        wp.launch(L.free_slots, dim=n, inputs=[self._vacant, self._vacant_rank, self._free], device=dev)
        wp.launch(L.spawn, dim=n, inputs=[p, self._want, self._want_rank, self._vacant, self._vacant_rank, self._free,
                                          self._offsets, self.pos, self.vel, self.rho, self.mass, self.hsml,
                                          self.ptype, self.body, self._needs_list, self._spawned, self.ids,
                                          self.neighbours.x_build, self._fail, health.ZONE_RESERVE], device=dev)

    def _floor_walls(self):
        """The dynamic walls whose band reaches into a finer zone no lower than rho0 (levels.floor_walls)."""
        wp.launch(levels.build(self.scalar).floor_walls, dim=self.n,
                  inputs=[self.params, self.pos, self.hsml, self.ptype, self.rho, self._zone_lo, self._zone_hi,
                          self._zone_h], device=self.device)

    def shepard_filter(self, rebuild: bool = True):
        """Replace the fluid density by its Shepard average (thesis Eq. 2.28)."""
        nl = self.neighbours
        if rebuild:
            nl.rebuild(self.pos, force=True)
        self.launch(self._passes.shepard, self.n, [self.params, nl.grid, nl.walk, self.fields, self._rho_c])
        wp.copy(self.rho, self._rho_c)
        self._view_fresh = False

    def _sync(self) -> bool:
        """Read the clock and the health flags; raise if a step failed. A list that outgrew its
        measured width is widened (neighbours.measured_width of the longest) for the failed step
        to be taken again, and the answer is True."""
        clock = self._clock.numpy()
        steps = self._steps.numpy()
        fail = self._fail.numpy()
        self._view_fresh = False  # the steps since have moved the state
        self.time, self.dt, self.dt_stable = float(clock[T]), float(clock[DT]), float(clock[DT_STABLE])
        self.steps = int(steps[STEP])
        # copies: on a CPU numpy() is a view of the device's memory, which the next steps write
        self._excluded_host = (self._excluded.numpy().copy(), self._excluded_mass.numpy().copy())
        self._census_host = self._energy_sum.numpy().copy()
        longest = self.neighbours.longest() if fail[health.NEIGHBOUR_OVERFLOW] != health.NO_FAILURE else 0
        if longest and self._measured_width and longest <= self._widest:
            self.resize_lists(min(measured_width(longest), self._widest))
            self.clear_failure()
            return True
        for check, idx in zip(health.CHECKS, fail):
            if idx == health.NO_FAILURE:
                continue
            if check in ("excluded_fraction", "left_fraction"):
                counts = self._excluded_host[0] + self._pending.numpy()
                left = check == "left_fraction"
                pending = self._pending_units.numpy()[health.PENDING_LEFT if left else health.PENDING_FAULT]
                mass = self._excluded_host[1][health.LEFT_MASS if left else health.MASS] + \
                    float(pending) / self.params.mass_units
                what = (f"would have left the tank over its walls ({int(counts[health.LEFT_TANK])} particles), "
                        f"more than max_left_fraction {self.config.max_left_fraction:.2%}" if left else
                        f"would be excluded ({self.describe_excluded(counts)}), more than max_excluded_fraction "
                        f"{self.config.max_excluded_fraction:.2%}")
                raise HealthError(check, int(steps[FAILED_STEP]), float(clock[T_FAILED]), -1,
                                  f"{mass / self._fluid_mass:.2%} of the fluid mass {what}")
            if check in health.GLOBAL_CHECKS:
                e = self._energy_sum.numpy()
                raise HealthError(check, int(steps[FAILED_STEP]), float(clock[T_FAILED]), -1,
                                  f"fluid energy {e[health.ENERGY]:.6g} J, "
                                  f"{e[health.ENERGY] - e[health.ENERGY_START]:.3g} J above its start "
                                  f"({self.config.energy_growth_ratio:g} M g H = {self._energy_slack:.3g} J allowed)")
            detail = ""
            if check == "zone_reserve":
                detail = ("the fluid reaching a refinement zone (refine:) needs more fine particles than the "
                          "build reserved for it")
            if check == "body_outside":
                law = self._law_list[int(idx)]
                pushed = float(np.linalg.norm([float(law.ext_force[k]) for k in range(3)]))
                raise HealthError(check, int(steps[FAILED_STEP]), float(clock[T_FAILED]), -1,
                                  f"the floating body {self.body_names[int(idx)]!r} left the domain"
                                  + (f", pushed by an external force of {pushed:.4g} N (cmd_wrench)" if pushed else ""))
            if check == "zone_edge":
                detail = ("a moving body came to a refinement zone's face: a body stays inside its zone or clear "
                          "of it by levels.edge_margin (a larger zone about it, or one farther off)")
            if check == "clumping":
                clumped = self._energy_sum.numpy()[health.PEAK_CLUMPED]
                detail = (f"{clumped:.1%} of the fluid particles have a neighbour closer than "
                          f"{self.config.clump_ratio:g} dx (more than {self.config.clump_fraction:.0%} allowed)")
            if check == "neighbour_overflow":
                limit = (f"the lattice's estimate, {self._widest}, which the lists are widened to at most"
                         if self._measured_width else f"the lists' fixed {self.neighbours.max_neighbours}")
                raise NeighbourOverflow(f"a particle has {longest} neighbours at step "
                                        f"{int(steps[FAILED_STEP])}, more than {limit}: particles have clumped, "
                                        f"or give max_neighbours")
            raise HealthError(check, int(steps[FAILED_STEP]), float(clock[T_FAILED]), int(idx), detail)
        return False

    @property
    def excluded(self) -> dict:
        """Fluid particles excluded at fault so far, by fault (health.FAULTS), as of the last sync."""
        return {reason: int(c) for reason, c in zip(health.FAULTS, self._excluded_host[0])}

    @property
    def excluded_particles(self) -> int:
        return int(self._excluded_host[0][:len(health.FAULTS)].sum())

    @property
    def excluded_fraction(self) -> float:
        """The share of the fluid mass excluded at fault."""
        return self._mass_share(health.MASS)

    @property
    def left_tank_particles(self) -> int:
        """Fluid particles that left the tank over its walls (health.LEFT_TANK), as of the last sync."""
        return int(self._excluded_host[0][health.LEFT_TANK])

    @property
    def left_tank_fraction(self) -> float:
        """The share of the fluid mass that left the tank over its walls."""
        return self._mass_share(health.LEFT_MASS)

    def _mass_share(self, slot: int) -> float:
        return float(self._excluded_host[1][slot]) / self._fluid_mass if self._fluid_mass > 0.0 else 0.0

    @property
    def health_peaks(self) -> dict:
        """What the whole-state detectors have measured so far, every census (16 steps): the largest
        clumped fraction of the fluid (health.census: pairs closer than clump_ratio dx away from
        walls), the lowest and highest density of a healthy fluid particle as ratios of rho0, and
        the largest rise of the fluid's energy above its start in M g H, as of the last sync (host
        copies only, so any thread may ask). A limit is set against what healthy runs reach
        (docs/limits.md, docs/defaults.md)."""
        e = self._census_host
        cfg = self.config
        mgh = self._fluid_mass * cfg.g_norm * cfg.depth
        low, high = e[health.RHO_LOW], e[health.RHO_HIGH]
        seen = low <= high
        return {"peak_clumped_fraction": float(e[health.PEAK_CLUMPED]),
                "min_density_ratio": float(low) / cfg.rho0 if seen else None,
                "max_density_ratio": float(high) / cfg.rho0 if seen else None,
                "peak_energy_growth": float(e[health.PEAK_ENERGY_GROWTH]) / mgh if mgh > 0.0 else None}

    @property
    def first_excluded_time(self) -> "float | None":
        """Simulated time of the step that excluded the first particle; None before any."""
        t = float(self._excluded_host[1][health.FIRST_TIME])
        return None if t < 0.0 else t

    @staticmethod
    def describe_excluded(counts) -> str:
        """'density_bounds 3, wall_penetration 1' from counts by reason (the faults only); 'none' when
        all are 0."""
        return ", ".join(f"{r} {int(c)}" for r, c in zip(health.FAULTS, counts) if c) or "none"

    def kept(self) -> np.ndarray:
        """Which particles, in the caller's order, are the flow and its walls: not excluded, not a
        refinement level's passive particles (levels.py), which stand where another level is the
        flow, nor its vacant slots."""
        keep = np.empty(self.n, dtype=bool)
        keep[self.ids.numpy()] = ~np.isin(self.ptype.numpy(), (EXCLUDED, PASSIVE, VACANT))
        return keep

    def reached(self, t_target: float) -> bool:
        """Whether the simulated time has reached ``t_target`` (to rounding)."""
        return self.time >= t_target - 1.0e-12 * max(1.0, t_target)

    def advance(self, t_target: float, interrupt=None) -> float:
        """Step until the simulated time reaches ``t_target`` exactly; returns the time.

        The device runs the loop (``wp.capture_while`` on its RUNNING flag, or its captured graph:
        graph.py): it decides each step's size, when to stop and what each step does, and the host
        reads the clock and the health flags once, at the end. ``interrupt``, a callable, is asked
        before each step of the eager loop, and before the first and every _MAX_BATCH steps of a
        replayed one: when it
        answers true the solver stops early, between two steps (a node pausing mid-interval);
        ``reached`` tells.
        Raises HealthError when a step fails a check; the state is then the last healthy one.
        """
        if self._dt_hooks:
            raise RuntimeError("advance: a solver with an each_dt hook (a rank's) steps with step(), driven by the "
                               "host")
        self._sync()
        if self.reached(t_target) or (interrupt is not None and interrupt()):
            # asked before the first step, as the eager loop asks: a replayed loop that reaches each
            # target within a block would otherwise never ask, and a SIGTERM waited for the run's end
            return self.time
        before = self.time
        replay = graph.wanted(self.config.step_graph, self.device, self.launch.threads)
        block = _MAX_BATCH if replay and interrupt is not None else _UNBOUNDED
        while True:
            self.aim(t_target)
            if replay:
                self._graph.run(block)
            else:
                wp.capture_while(self.flag(RUNNING), self.loop_body, block=block, interrupt=interrupt)
            widened = self._sync()
            if self.reached(t_target) or (interrupt is not None and interrupt()):
                break
            if self.time <= before and not widened:
                raise RuntimeError(f"simulated time is stuck at {self.time!r} s short of {t_target!r} s")
            before = self.time
        return self.time

    def aim(self, t_target: float):
        """Point the step loop at ``t_target``: it runs while the state is healthy and short of it."""
        wp.launch(self._passes.aim, dim=1, inputs=[self._fail, self._clock, self._steps, self._flags,
                                                   float(t_target)], device=self.device)

    def flag(self, slot: int) -> wp.array:
        """The step loop's flag ``slot`` (state.RUNNING ...) as the one-element array a branch reads."""
        return self._flag_views[slot]

    def loop_body(self, block: int, interrupt=None):
        """One pass of the step loop: a step, unless ``interrupt`` asks to stop (which ends the loop)."""
        if interrupt is not None and interrupt():
            self._flags[RUNNING:RUNNING + 1].zero_()
            return
        self._launch_step(block)

    def step(self, t_target: float = math.inf) -> float:
        """One step of the adaptive size (or dt_fixed), cut short to end at ``t_target`` as
        ``advance`` cuts its last; returns the new time."""
        self._sync()
        while True:  # again where the lists were widened
            self.aim(t_target)
            self._launch_step()
            if not self._sync():
                return self.time

    # fields whose change needs new particles or new buffers: only a fresh Solver takes them
    REBUILD_FIELDS = RESET_FIELDS

    def reconfigure(self, **changes):
        """Change numerics that apply from the next step (cfl, dt_fixed, viscosity, ...)."""
        needs_rebuild = sorted(set(changes) & set(self.REBUILD_FIELDS))
        if needs_rebuild:
            raise ValueError(f"{', '.join(needs_rebuild)}: changing this needs new particles; build a new solver")
        self.config = self.config.replace(**changes).validate()
        self.params = self._make_params()
        self._graph.drop()
        self._view_fresh = False
        if self.config.viscosity == "sps" and self.fields.tau_diag.shape[0] != self.n:
            for name in ("tau_diag", "tau_off"):
                stress = wp.zeros(self.n, dtype=self.vec, device=self.device)
                setattr(self.fields, name, stress)
                setattr(self._fields_h, name, stress)

    def resize_lists(self, width: int):
        """Neighbour lists ``width`` long, built before the next pass reads them; a captured step
        loop, which holds the old lists, is captured again."""
        self.neighbours.resize(width)
        self._graph.drop()

    def clear_failure(self):
        """Forget a reported failure so the run can go on (e.g. after changing dt_fixed)."""
        self._fail.assign(np.full(health.N_CHECKS, health.NO_FAILURE, dtype=np.int32))
        self.flag(LISTS_HOLD).fill_(1)
        self._pending.zero_()
        self._pending_units.zero_()
        steps = self._steps.numpy()
        steps[FAILED_STEP] = -1
        self._steps.assign(steps)
        self.neighbours.overflow.zero_()

    # -- state out ------------------------------------------------------------------------
    def update_pressure(self):
        """Bring the pressure array up to the current density (the step loop keeps it only where
        the force passes need it)."""
        wp.launch(self._passes.equation_of_state, dim=self.n, inputs=[self.params, self.fields], device=self.device)

    def snapshot(self) -> dict:
        """Host copies of the state in the caller's particle order: pos, vel (n x 3), rho, pressure,
        mass (n), ptype, body (n); with SPS also the stress (sps_tau_diag, sps_tau_off)."""
        self.update_pressure()
        slot_of = np.empty(self.n, dtype=np.int64)
        slot_of[self.ids.numpy()] = np.arange(self.n)  # the inverse permutation, O(n) where a sort is O(n log n)
        arrays = {"pos": self.pos, "vel": self.vel, "rho": self.rho, "pressure": self.pressure, "mass": self.mass}
        snap = {name: a.numpy().astype(np.float64)[slot_of] for name, a in arrays.items()}
        snap["ptype"] = self.ptype.numpy()[slot_of]
        snap["body"] = self.body.numpy()[slot_of]
        if self.config.viscosity == "sps":
            # SPS stress / rho of the last force pass: (xx, yy, zz) and (xy, xz, yz)
            snap["sps_tau_diag"] = self.fields.tau_diag.numpy().astype(np.float64)[slot_of]
            snap["sps_tau_off"] = self.fields.tau_off.numpy().astype(np.float64)[slot_of]
        return snap

    def measurement_view(self):
        """(params, fields, neighbours) with pressure brought up to the current state and the cells
        valid for it, for measurements that run on the device between steps: once an output, however
        many measurements ask (each made its own equation-of-state pass and radix sort). The cells
        are the last build's: a walk one list radius around a point finds every particle within a
        kernel support of it until the lists go stale, and then the build the next step would make
        (at the same positions) is made now. A sort of the view's own would leave the cells other
        than the lists' build: a walk without lists would read them, and a state would not hold
        the build's (checkpoint.put builds the lists again from it)."""
        if not self._view_fresh:
            self.update_pressure()
            self.neighbours.rebuild(self.pos)
            self._view_fresh = True
        return self.params, self.fields, self.neighbours

    def device_bytes(self) -> int:
        """Bytes of every array this solver holds on its device: state, half-step and candidate
        copies, scratch, the cell sort and the neighbour lists."""
        seen, total = set(), 0

        def arrays(value):
            if isinstance(value, dict):
                yield from arrays(list(value.values()))
            elif isinstance(value, (list, tuple)):
                for item in value:
                    yield from arrays(item)
            elif isinstance(value, wp.array):
                yield value
            elif isinstance(value, (sums.Partials, scan.Scan)):  # scratch of fixed-order sums and scans
                yield from arrays(list(vars(value).values()))
            elif hasattr(value, "_cls"):  # a Warp struct instance: its array members
                for name in getattr(value._cls, "vars", {}):
                    yield from arrays(getattr(value, name))

        for owner in (self, self.neighbours):
            for value in vars(owner).values():
                for a in arrays(value):
                    if a.ptr is not None and a.ptr not in seen:
                        seen.add(a.ptr)
                        total += a.size * wp.types.type_size_in_bytes(a.dtype)  # a view's capacity is not its bytes
        return total

    def mean_neighbours(self) -> float:
        """Mean neighbour-list length of the fluid particles (list radius 1.1 x 2h), freshly built."""
        self.neighbours.rebuild(self.pos, force=True)
        return self.neighbours.mean_neighbours()
