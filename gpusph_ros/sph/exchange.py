"""One run across MPI ranks: each rank steps its slab and a halo, and the ranks exchange what they own
(issue 69; docs/ranks.md says why each choice is made).

- **The cut.** Slabs of whole cells along the longest axis, one list radius wide
  (decomposition.split), balanced on the particles at the start.
- **The halo.** Each rank holds the particles within HALO_CELLS cells of its slab (SPS_HALO_CELLS
  under SPS) besides its own. It steps them too, so that one exchange a step is enough
  (tests/test_halo_depth.py). It neither checks nor counts them, and its maxima do not bound the
  step (Solver's ``owned``).
- **Each step, on every rank alike:**
  - The lists are rebuilt where any rank's are stale or a reorder is due. Then, and only then,
    particles change hands: every rank takes the particles now in its slab and halo, in the order of
    their ids (`_migrate`). Between rebuilds a particle moves less than half the lists' skin, which the
    halo's depth covers, so it keeps its owner until the next rebuild.
  - The step's size takes every rank's maxima (an all-reduce in Solver.each_dt).
  - A failure on any rank fails every rank.
  - After the step, the owners' positions, velocities and densities overwrite the halo's (`_refresh`).
    The staleness of the lists is then found again on the refreshed state.
- **Bit for bit.** The particles are summed in the order of their ids whatever slots they stand in
  (neighbours.cell_keys). A rank's local ids keep the order of the run's ids. The ranks rebuild their
  lists at the steps one rank would. So a rank's particles step bit for bit as one rank's
  (tests/test_ranks.py).

- **Bodies.** Every rank holds every body's state and steps it alike. A moving body's particles are
  placed from where they stood at t = 0, found by their run ids (``_by_id``). A floating body's
  force and torque add every rank's owned particles' terms in the order of their run ids
  (body_sums.py, Solver.each_total), so it moves on every rank, and on one, bit for bit.

What this first form leaves out: refinement zones, refused by name (``supported``): a zone turns
particles passive and spawns finer ones into slots it reserves, which the change of hands does not
carry yet.

The census (the energy, the repulsive walls' among it, the density's extremes, the clumped
particles) is every rank's, gathered and added in rank order on every rank before its check
(Solver.each_census), and so is each step's exclusions before their limits are checked
(Solver.each_total): every rank holds the run's figures and decides alike.

Each rank sends every other rank the owned particles within ``depth`` + 1 cells of its slab's ends
(an all-gather): the neighbours alone need them, and a point-to-point exchange with each neighbour
would send less where there are many ranks.
"""
import os
import time

import numpy as np

from . import health, portable
from .config import ConfigError
from .decomposition import HALO_CELLS, SPS_HALO_CELLS, split
from .health import HealthError
from .neighbours import NeighbourOverflow, default_max_neighbours, list_skin
from .particles import Particles
from .solver import Solver
from .state import REORDER_DUE, VACANT

ROOM = 1.5  # slots a rank keeps over its first particle count: a flow brings it more than it starts with


# where an MPI launcher says how many ranks it started: MPICH's Hydra (and Slurm's PMI), Open MPI
LAUNCHED = ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE")


def world():
    """MPI's world communicator where ``mpiexec -n N`` (N > 1) started this process, else None: a
    process outside mpiexec never loads mpi4py. ConfigError saying what to install where mpiexec
    asked for ranks and mpi4py is missing."""
    sizes = [int(os.environ[name]) for name in LAUNCHED if os.environ.get(name, "").isdigit()]
    if not sizes or max(sizes) <= 1:
        return None
    try:
        from mpi4py import MPI
    except ImportError:
        raise ConfigError("ranks", max(sizes), "1, or more with mpi4py and an MPI installed (pip install mpi4py "
                                               "mpich, the versions requirements.txt pins)") from None
    return MPI.COMM_WORLD


def supported(model) -> None:
    """ConfigError naming what a run on ranks cannot take yet (the module's docstring)."""
    if model.config.zones:
        raise ConfigError("ranks", "refine", "a scene without refinement zones on more than one rank (not built yet)")


class RankedRun:
    """This rank's part of a run of ``model`` (scenes.build.Model) on ``comm``'s ranks: its solver
    (``solver``), which particles it holds (``gid``: the run's id of each local id) and which it owns."""

    def __init__(self, model, comm, rebalance: float = 0.1, rebalance_every: int = 100, state: dict = None):
        from mpi4py import MPI

        supported(model)
        self.comm, self._max, self._sum = comm, MPI.MAX, MPI.SUM
        cfg = model.config
        p = model.particles
        spacing = p.spacing if p.spacing is not None else np.full(len(p), cfg.dx)
        tank = [*model.scene.tank, 0.0, 0.0][:3]  # a 2D tank's third axis is none to cut along
        # a run going on from ``state`` (``portable()``, checked by portable.mismatch) is cut where its
        # particles stood at the lists' last build, and each rank takes what that build's change of
        # hands gave it: built as the run was at its start (what the build fixes for each particle,
        # its walls' geometry, found where one solver found it), then put in the state
        records = {"pos": p.pos, "vel": p.vel, "rho": p.rho, "mass": p.mass, "ptype": p.ptype, "body": p.body}
        at = p.pos if state is None else state["particles"]["x_build"]
        self.slabs = split(at, (0.0, 0.0, 0.0), tank, cfg.periodic, list_skin() * 2.0 * cfg.h, comm.size)
        self.depth = SPS_HALO_CELLS if cfg.viscosity == "sps" else HALO_CELLS
        self.first, self.end = self.slabs.bounds()[comm.rank]
        # a CUDA device is this node's GPU of the rank's own number among the node's ranks
        self.local_rank = comm.Split_type(MPI.COMM_TYPE_SHARED).Get_rank()
        if str(cfg.device).startswith("cuda"):
            cfg = cfg.replace(device=f"cuda:{self.local_rank}")
        self.n = len(p)  # the run's particles, every rank's together
        fluid = p.ptype == 0
        members, owned = self._members(at, np.arange(len(p)))
        self.capacity = int(np.ceil(ROOM * len(members))) + 8
        part = self._particles({k: v[members] for k, v in (records | {"spacing": spacing}).items()})
        self.gid = self._padded(members, -1)  # the run's id of each local id; -1: a vacant slot
        # what the run's build fixes for each particle by its run id: a moving body's particle's place
        # at t = 0 (bodies.move_walls) and its row in the floating bodies' wrench table (body_sums.py)
        self._rest = p.pos
        self._wrench_rows, row_body = Solver.wrench_table(cfg.motions, p)
        # lists as wide as the lattice's estimate from the start (what the plan prices): one solver
        # widens its lists and takes the step again when one outgrows them, which a rank alone may
        # not do, its collectives then no longer matching the others'
        self.solver = Solver(cfg, part, max_neighbours=default_max_neighbours(cfg.dim, cfg.hdx),
                             owned=self._padded(owned, False), fluid=(float(p.mass[fluid].sum()), int(fluid.sum())),
                             wrench_rows=(self._padded(self._wrench_rows[members], -1), row_body))
        self.solver.each_dt(self._all_maxima)
        self.solver.each_census(self._all_census)
        self.solver.each_total(self._all_total)
        # a change of hands recuts the slabs where the fullest rank owns more than ``rebalance`` over
        # the mean, at most every ``rebalance_every`` steps (issue 69 item 3)
        self.rebalance, self.rebalance_every, self._recut_at = rebalance, rebalance_every, 0
        self.recuts = 0
        self._hooks = []  # each_step's
        self.exchange_s = 0.0  # wall time in the exchange (hands changed, the halo refreshed), for bench/ranks.py
        # mDBC's ghost-node offsets and the walls' face normals (wall_flux: normal) by run id, each a
        # wall particle's own geometry (boundaries/faces.py), found once at the start: a wall
        # particle's stays its own as the slots are rewritten
        self._geometry = {}
        for key in ("ghost", "wall_normal"):
            found = getattr(self.solver, key).numpy()
            if len(found) == self.capacity:  # wall_normal is one entry under wall_flux: full
                self._geometry[key] = np.zeros((len(p), 3), dtype=found.dtype)
                self._geometry[key][members] = found[:len(members)]
        if state is not None:
            portable.put(self.solver, {k: v[members] for k, v in state["particles"].items()}, state["counters"],
                         state["bodies"])

    # -- who holds what ----------------------------------------------------------------------
    def _members(self, pos: np.ndarray, gid: np.ndarray) -> tuple:
        """The run's ids this rank holds among ``gid`` at ``pos`` (in id order) and which it owns."""
        cell = self.slabs.cell_of(pos)
        n = self.slabs.n_cells
        below = np.mod(self.first - cell, n) if self.slabs.periodic else self.first - cell
        above = np.mod(cell - self.end + 1, n) if self.slabs.periodic else cell - self.end + 1
        own = (cell >= self.first) & (cell < self.end)
        near = own | ((below > 0) & (below <= self.depth)) | ((above > 0) & (above <= self.depth))
        order = np.argsort(gid[near], kind="stable")
        return gid[near][order], own[near][order]

    def _padded(self, values: np.ndarray, fill) -> np.ndarray:
        out = np.full(self.capacity, fill, dtype=np.asarray(values).dtype)
        out[:len(values)] = values
        return out

    def _particles(self, rec: dict) -> Particles:
        """The rank's particles, local id k the k-th of ``rec``, then vacant slots up to capacity (a
        vacant slot is read by no pass and sorts past every cell)."""
        pad = self.capacity - len(rec["pos"])
        return Particles(pos=np.vstack([rec["pos"], np.zeros((pad, 3))]),
                         vel=np.vstack([rec["vel"], np.zeros((pad, 3))]),
                         rho=np.concatenate([rec["rho"], np.ones(pad)]),
                         mass=np.concatenate([rec["mass"], np.zeros(pad)]),
                         ptype=np.concatenate([rec["ptype"], np.full(pad, VACANT)]).astype(np.int32),
                         body=np.concatenate([rec["body"], np.full(pad, -1)]).astype(np.int32),
                         spacing=np.concatenate([rec["spacing"], np.full(pad, float(rec["spacing"].max()))]))

    # -- the collectives ------------------------------------------------------------------------
    def _all_maxima(self, maxima):
        m = maxima.numpy()
        local = np.array([m[0::2].max(), m[1::2].max()], dtype=np.float64)
        every = np.empty_like(local)
        self.comm.Allreduce(local, every, op=self._max)
        m[:] = 0.0
        m[0], m[1] = every
        maxima.assign(m)

    def _all_census(self, totals, counts):
        """Every rank's census in each rank's: the energies added, the density's extremes, the
        clumped particles added and the first of them by its run id."""
        e, c = totals.numpy().copy(), counts.numpy().copy()
        first = c[health.FIRST_CLUMPED]
        first = health.NO_FAILURE if first == health.NO_FAILURE else int(self.gid[first])
        # gathered and added in rank order on every rank: the same float64 sum everywhere, so that
        # every rank's check decides alike
        parts = self.comm.allgather((float(e[health.ENERGY]), float(e[health.RHO_LOW]), float(e[health.RHO_HIGH]),
                                     int(c[health.CLUMPED]), first))
        energy, low, high, clumped, first = zip(*parts)
        e[health.ENERGY], e[health.RHO_LOW], e[health.RHO_HIGH] = sum(energy), min(low), max(high)
        c[health.CLUMPED], c[health.FIRST_CLUMPED] = sum(clumped), min(first)
        totals.assign(e)
        counts.assign(c)

    def _all_total(self, array):
        """Every rank's ``array`` (Solver.each_total) added, in rank order on every rank: the same
        float64 sum everywhere (a wrench table's row, one rank's term and zeros, exactly that term)."""
        parts = self.comm.allgather(array.numpy().copy())
        total = parts[0]
        for part in parts[1:]:
            total += part
        array.assign(total)

    def _held(self, keys, owned_only: bool, near_ends: bool = False) -> dict:
        """This rank's particles (its owned ones only where ``owned_only``): ``keys`` of their state
        and their run ids. ``near_ends``: only those within ``depth`` + 1 cells of its slab's ends or
        outside it, the only ones another rank's halo can hold until the next rebuild (a particle
        moves less than a cell between rebuilds)."""
        s = self.solver
        ids = s.ids.numpy()
        keep = s.ptype.numpy() != VACANT
        if owned_only:
            keep &= s.fields.owned.numpy().astype(bool)
        if near_ends:
            cell = self.slabs.cell_of(s.pos.numpy())
            n = self.slabs.n_cells
            inner = np.mod(cell - self.first, n) if self.slabs.periodic else cell - self.first
            deep = (inner > self.depth) & (inner < self.end - self.first - 1 - self.depth)
            keep &= ~deep
        mine = np.flatnonzero(keep)
        local = {"gid": self.gid[ids[mine]]}
        arrays = portable.particle_arrays(s)  # each key's array, x_build's among them
        for k in keys:
            local[k] = (arrays[k] if k in arrays else getattr(s, k)).numpy()[mine]
        return local

    def _gathered(self, local: dict) -> dict:
        """``local`` of every rank, concatenated."""
        parts = self.comm.allgather(local)
        return {k: np.concatenate([q[k] for q in parts]) for k in local}

    # -- the step -------------------------------------------------------------------------------
    def each_step(self, hook):
        """Call ``hook()`` after every step, once the halo is its owners' state again: a measurement
        that adds up over the steps between its samples (measure/ranks.py)."""
        self._hooks.append(hook)

    def advance(self, t_target: float, interrupt=None) -> float:
        """Step until the simulated time reaches ``t_target`` exactly, as Solver.advance does;
        ``interrupt``, asked before each step on every rank, stops them all when it answers true on
        any (a Ctrl-C that reached one rank first)."""
        s = self.solver
        while not s.reached(t_target):
            if interrupt is not None and self.comm.allreduce(bool(interrupt()), op=self._max):
                break
            self.step(t_target)
        return s.time

    def view(self):
        """Solver.measurement_view on every rank together: where any rank's lists are stale, the
        particles change hands first, as the next step would have them do."""
        self._change_hands()
        return self.solver.measurement_view()

    def _change_hands(self, due: bool = False):
        """Where any rank's lists are stale, or where ``due``, the slabs cut again if they have
        drifted (``_balance``) and the particles change hands (``_migrate``), on every rank alike."""
        if self.comm.allreduce(int(self.solver.neighbours.stale.numpy()[0]), op=self._max) or due:
            self._balance()
            self._migrate()

    def step(self, t_target: float = float("inf")) -> float:
        s = self.solver
        start = time.perf_counter()
        # a reorder is due at the same step on every rank (the step counts are the run's)
        self._change_hands(due=bool(s.flag(REORDER_DUE).numpy()[0]))
        self.exchange_s += time.perf_counter() - start
        failed = None
        try:
            s.step(t_target)
        except HealthError as err:
            # a particle's check names its local id, the run's id said instead; a census names the
            # run's already (_all_census), a body's check its body, an exclusion limit none
            local = err.particle >= 0 and err.check not in ("clumping", "body_outside")
            failed = (err.check, err.step, err.time, int(self.gid[err.particle]) if local else err.particle,
                      err.detail)
        except NeighbourOverflow as err:
            failed = (None, 0, 0.0, 0, str(err))
        why = self.comm.allgather(failed)
        ranks = [r for r, w in enumerate(why) if w]
        if ranks:  # every rank raises the first failing rank's failure, and says which ranks found one
            check, step, t, particle, detail = why[ranks[0]]
            where = "" if len(ranks) == len(why) else f" (found on rank {', '.join(map(str, ranks))})"
            if check is None:
                raise NeighbourOverflow(detail + where)
            raise HealthError(check, step, t, particle, detail + where)
        start = time.perf_counter()
        self._refresh()
        self.exchange_s += time.perf_counter() - start
        for hook in self._hooks:
            hook()
        return s.time

    def _balance(self):
        """The slabs cut again from every rank's owned particles per cell, the same on every rank,
        where they have drifted past ``rebalance``: the cells stay, the cuts move by whole cells, and
        the change of hands that follows moves the particles."""
        s = self.solver
        if self.rebalance <= 0.0 or s.steps < self._recut_at + self.rebalance_every:
            return
        mine = self._held(("pos",), owned_only=True)["pos"]
        local = np.bincount(self.slabs.cell_of(mine), minlength=self.slabs.n_cells).astype(np.int64)
        counts = np.empty_like(local)
        self.comm.Allreduce(local, counts, op=self._sum)
        below = np.concatenate([[0], np.cumsum(counts)])
        owned = self.slabs.per_rank(below)
        if owned.max() <= (1.0 + self.rebalance) * owned.mean():
            return
        self._recut_at = s.steps  # tried: not again for rebalance_every steps, moved or not
        cut = self.slabs.cut_at(below, self.comm.size)
        if cut.cuts != self.slabs.cuts:  # whole cells may balance no better than they do
            self.slabs = cut
            self.first, self.end = cut.bounds()[self.comm.rank]
            self.recuts += 1

    def _refresh(self):
        """The halo's positions, velocities and densities from their owners; the lists' staleness
        found again on them (the step found it on the halo before this)."""
        s = self.solver
        every = self._gathered(self._held(("pos", "vel", "rho"), owned_only=True, near_ends=True))
        order = np.argsort(every["gid"])
        ids = s.ids.numpy()
        held = s.ptype.numpy() != VACANT
        owned = s.fields.owned.numpy().astype(bool)
        halo = np.flatnonzero(held & ~owned)
        at = order[np.searchsorted(every["gid"], self.gid[ids[halo]], sorter=order)]
        for k in ("pos", "vel", "rho"):
            a = getattr(s, k).numpy()
            a[halo] = every[k][at]
            getattr(s, k).assign(a)
        s.neighbours.stale.zero_()
        s.neighbours.moved(s.pos, s.vel, s.clock)

    def _migrate(self):
        """Every rank takes the particles now in its slab and halo (the module's docstring)."""
        # a moving wall's acceleration too: the extrapolated-pressure wall reads the last stage's
        # (boundaries/adami.py) before the next step moves it
        keys = ("pos", "vel", "rho", "mass", "ptype", "body", "hsml", "wall_acc")
        # what it holds (its halo refreshed after the last step) and what the others hold near their
        # ends: every particle that can be in its slab or halo now
        near = self._gathered(self._held(keys, owned_only=True, near_ends=True))
        here = self._held(keys, owned_only=False)
        both = {k: np.concatenate([near[k], here[k]]) for k in near}
        _, first = np.unique(both["gid"], return_index=True)
        every = {k: v[first] for k, v in both.items()}
        members, owned = self._members(every["pos"], every["gid"])
        self._take({k: v[np.searchsorted(every["gid"], members)] for k, v in every.items() if k != "gid"}, members,
                   owned)  # np.unique left ``every`` in id order

    def _take(self, fields: dict, members: np.ndarray, owned: np.ndarray):
        """Slot k holds particle members[k] (``fields``, one row each), owned where ``owned``; the
        other slots vacant; the lists to be built again."""
        s = self.solver
        m = len(members)
        full = [f"rank {r}: {k} particles, more than its {c} slots" for r, (k, c) in
                enumerate(self.comm.allgather((m, self.capacity))) if k > c]
        if full:  # on every rank: one rank's error alone would leave the others waiting for it
            raise RuntimeError("; ".join(full))
        vacant = {"pos": np.zeros(3), "vel": np.zeros(3), "rho": 1.0, "mass": 0.0, "ptype": VACANT, "body": -1,
                  "hsml": s.config.hdx * s.config.dx, "wall_acc": np.zeros(3)}
        for k, fill in vacant.items():
            a = getattr(s, k).numpy()
            a[:m] = fields[k]
            a[m:] = fill
            getattr(s, k).assign(a)
        s.ids.assign(np.arange(self.capacity, dtype=np.int32))
        s.fields.owned.assign(self._padded(owned.astype(np.int32), 0))
        s._needs_list.assign(self._padded(s.needs_list(fields["ptype"], fields["body"]), 0))
        for key, table in self._geometry.items():
            values = np.zeros((self.capacity, 3), dtype=table.dtype)
            values[:m] = np.where((fields["ptype"] != 0)[:, None], table[members], 0.0)
            getattr(s, key).assign(values)
        self.gid = self._padded(members, -1)
        self._by_id(members)
        s.neighbours.stale.fill_(1)

    def _by_id(self, members: np.ndarray):
        """What the run's build fixes for each of ``members`` (local id k the run's members[k]) into
        the solver's tables by local id: a moving body's particle's place at t = 0, its wrench row.
        At each change of hands: the solver, built from its first members as the run started,
        holds theirs already."""
        s = self.solver
        if s._moving:
            rest = np.zeros((self.capacity, 3))
            rest[:len(members)] = self._rest[members]
            s._rest.assign(rest)
        if s._floating:
            s._wrench_rows.assign(self._padded(self._wrench_rows[members], -1))

    def portable(self) -> "dict | None":
        """Rank 0: the run's state, whatever its cut (sph/portable.py), taken between two steps on
        every rank together; None elsewhere."""
        parts = self.comm.gather(self._held(portable.PARTICLE_KEYS, owned_only=True), root=0)
        if parts is None:
            return None
        every = {k: np.concatenate([q[k] for q in parts]) for k in parts[0]}
        order = np.argsort(every.pop("gid"))
        # every rank's counters and bodies are the run's (the census and the exclusions added up each
        # step, the bodies stepped alike): rank 0's
        return {"format": portable.FORMAT, "particles": {k: every[k][order] for k in portable.PARTICLE_KEYS},
                "counters": portable.counters(self.solver), "bodies": portable.body_arrays(self.solver)}

    def rows(self, rows: np.ndarray) -> "np.ndarray | None":
        """Rank 0: of ``rows`` (one a local id, as measure/cloud.py packs them), those of every rank's
        owned particles that are the flow or its walls (Solver.kept), in the order of their run ids:
        what one rank packs. None elsewhere."""
        s = self.solver
        keep = s.kept()
        keep[s.ids.numpy()] &= s.fields.owned.numpy() != 0
        parts = self.comm.gather((self.gid[keep], rows[keep]), root=0)
        if parts is None:
            return None
        gid = np.concatenate([g for g, _ in parts])
        return np.concatenate([r for _, r in parts])[np.argsort(gid)]

    def describe(self) -> str:
        """Rank 0: how the run is cut and where each rank steps ('2 ranks along x: cells 0-11 on cpu,
        ...'); "" elsewhere."""
        where = self.comm.gather((self.first, self.end, str(self.solver.device)), root=0)
        if where is None:
            return ""
        axis = "xyz"[self.slabs.axis]
        return (f"{self.comm.size} ranks along {axis} ({self.slabs.n_cells} cells of {self.slabs.cell:.4g} m): "
                + ", ".join(f"rank {r} cells {a}-{b - 1} on {d}" for r, (a, b, d) in enumerate(where)))

    def gather(self, keys=("pos", "vel", "rho")) -> "dict | None":
        """Rank 0: the owned particles' ``keys`` in the solver's precision, by run id; None elsewhere."""
        every = self._gathered(self._held(keys, owned_only=True))
        if self.comm.rank != 0:
            return None
        order = np.argsort(every["gid"])
        return {k: every[k][order] for k in ("gid", *keys)}
