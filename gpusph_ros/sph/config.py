"""Run configuration of the SPH solver: every numerical choice the thesis varies, by name.

``SolverConfig`` is three typed parts: ``Numerics`` (what a user sets), ``HealthLimits`` (the
failure detectors' limits) and ``Domain`` (what the scene decides). Each field carries its meaning,
its allowed values and when a change applies (``setting``), which validation, the run settings and
the node's parameters all read. A configuration is plain data. ``SolverConfig.validate`` checks
every field and raises ``ConfigError`` naming the field, the value and what is allowed, so that a
scene file, a CLI override or a ROS parameter all get the same message.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from . import boundaries, density, graph, kernels, neighbours, viscosity
from .device import default_device

# the names of each family's models, owned by its module
KERNELS = kernels.NAMES
VISCOSITIES = viscosity.NAMES
BOUNDARIES = boundaries.NAMES
MDBC_SLIPS = boundaries.mdbc.SLIPS
DENSITY_DIFFUSIONS = density.DIFFUSIONS
WALL_FLUXES = density.WALL_FLUXES
PRECISIONS = ("float32", "float64")
STEP_GRAPHS = graph.STEP_GRAPHS
NEIGHBOUR_SEARCHES = ("auto", "lists", "cells")

# guards against runs that could never finish or never fit (docs/limits.md)
MIN_CFL = 0.01  # a smaller Courant number takes > 100x the steps of the default for no accuracy
MIN_DT_FIXED = 1.0e-6  # [s] a fixed step below this is a million steps per simulated second
MAX_PARTICLES = 200_000_000  # default cap on a run's particles (max_particles): 10^8 with room
_SHOWN = 240  # characters of a refused value quoted in an error (a long path fits)


def shown(value) -> str:
    """A refused value as an error quotes it: its repr, cut to a line (never a file's contents)."""
    text = repr(value)
    return text if len(text) <= _SHOWN else text[:_SHOWN - 25] + f"... ({len(text)} characters)"


class ConfigError(ValueError):
    """A configuration field has a value the solver cannot use."""

    def __init__(self, field_name: str, value, allowed: str, quote: bool = True):
        self.field = field_name
        self.value = value
        self.allowed = allowed
        # quote=False: the value came from a file that may not be meant for us (a key no scene has:
        # the file may be anything a path names), so it is not repeated
        what = f"{shown(value)} is not allowed" if quote else "not allowed"
        super().__init__(f"{field_name}: {what}; expected {allowed}")


def unknown_key(where: str, key, keys, whole: str, noun: str = "fields") -> ConfigError:
    """The refusal of a key that is no field of ``keys`` (in the mapping at ``where``, of the file
    called ``whole``): named when it reads as a field name, and neither the value nor any other
    key quoted, since the file may be any file a path names (a key file, a password file)."""
    if isinstance(key, str) and key.isidentifier() and len(key) <= 64:
        return ConfigError(f"{where}.{key}" if where else key, None,
                           f"a known name; the {noun} are " + ", ".join(keys), quote=False)
    return ConfigError(where or whole, None, "keys that are field names (this file may be no "
                       f"{whole} file); the {noun} are " + ", ".join(keys), quote=False)


def check_device(device):
    """ConfigError unless ``device`` is one of this machine's Warp devices. Checked where a model is
    built, not in ``validate``: a study or plan may name a device of another machine."""
    import warp as wp

    names = [d.alias for d in wp.get_devices()]
    if device not in names:
        raise ConfigError("device", device, "a Warp device of this machine: " + ", ".join(names))
    found = wp.get_device(device)
    if found.is_cuda:
        from .cuda_build import oldest_arch

        # what this Warp's NVRTC cannot build for fails at the first kernel's load, not here; the
        # atomic minima and maxima of float64 (health.census) need sm_60 besides
        oldest = max(60, oldest_arch())
        if found.arch < oldest:
            raise ConfigError("device", device, f"a CUDA device of compute capability {oldest // 10}.{oldest % 10} "
                                                f"or later, the oldest this Warp's NVRTC builds for; {device} "
                                                f"({found.name}) is {found.arch // 10}.{found.arch % 10}")


@dataclass
class Plane:
    """A particle-less flat wall: a point on it and the normal pointing into the fluid."""

    point: tuple
    normal: tuple


# when a change of a setting reaches a running solver: from the next step (``Solver.reconfigure``),
# or only with new particles and buffers (a new solver; the node's ~/reset)
LIVE, RESET = "live", "reset"


def setting(default, doc: str, *, choices=None, lo=None, hi=None, applies=LIVE, node=False, factory=None):
    """A configuration field and what everyone else needs to know of it, in one place: ``doc`` (its
    meaning and units), ``choices`` or the range [lo, hi] that ``validate`` enforces, when a change
    ``applies``, and whether the node declares it as a parameter (``ros/node_params.py`` generates
    the declaration, its descriptor and its reset rule from this)."""
    meta = {"doc": doc, "choices": choices, "lo": lo, "hi": hi, "applies": applies, "node": node}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass
class Domain:
    """What the scene decides or the scene builder derives: never a run setting."""

    dim: int = setting(3, "2 or 3", applies=RESET)
    gravity: tuple = setting((0.0, 0.0, -9.81), "[m/s^2]", applies=RESET)
    depth: float = setting(0.4, "reference depth H [m] for c0 and the wall forces", applies=RESET)
    domain_lo: tuple = setting((0.0, 0.0, 0.0), "the domain's low corner [m]", applies=RESET)
    domain_hi: tuple = setting((1.0, 1.0, 1.0), "the domain's high corner [m]", applies=RESET)
    periodic: tuple = setting((False, False, False), "periodic axes", applies=RESET)
    planes: list = setting(None, "particle-less walls (Plane)", applies=RESET, factory=list)
    # the tank's inside [wall_lo, wall_hi] (beyond +-1e30 where there is no wall: periodic axes, the
    # open top) and the solid boxes (lo, hi) fluid must stay out of
    wall_lo: tuple = setting((-1.0e30, -1.0e30, -1.0e30), "the tank's inside, low corner [m]", applies=RESET)
    wall_hi: tuple = setting((1.0e30, 1.0e30, 1.0e30), "the tank's inside, high corner [m]", applies=RESET)
    wall_top: float = setting(1.0e30, "the top of the tank's walls [m]: a fluid particle beyond a wall and above "
                                      "it went over the wall", applies=RESET)
    solids: list = setting(None, "solid boxes (lo, hi) fluid must stay out of", applies=RESET, factory=list)
    motions: list = setting(None, "each body's prescribed motion by body id (bodies.Motion; None: fixed)",
                            applies=RESET, factory=list)
    # refinement zones (lo, hi, spacing), beyond +-1e30 where a zone reaches through a tank face
    zones: list = setting(None, "refinement zones (lo, hi, spacing): where each level is the flow (sph/levels.py)",
                          applies=RESET, factory=list)


@dataclass
class HealthLimits:
    """The failure detectors' limits (health.py, CHECKS): what does not show as NaN."""

    rho_min_ratio: float = setting(0.8, "density_bounds: lowest fluid density, as a fraction of rho0")
    rho_max_ratio: float = setting(1.25, "density_bounds: highest fluid density, as a fraction of rho0")
    # the first layer of wall particles sits dx/2 behind a wall face
    penetration_ratio: float = setting(0.5, "wall_penetration: how deep [dx] a fluid particle may go beyond a wall "
                                            "face or into a solid")
    clump_ratio: float = setting(0.25, "clumping: a fluid neighbour closer than this [dx] pairs a particle (tensile "
                                       "instability); 0 = off")
    clump_fraction: float = setting(0.2, "clumping: the share of the fluid that may be paired")
    # nothing feeds a closed tank
    energy_growth_ratio: float = setting(0.05, "energy_growth: the rise of the fluid's kinetic + potential + "
                                               "elastic energy above its start allowed, in M g H; 0 = off")
    max_excluded_fraction: float = setting(
        0.01, "share of the fluid mass that may be excluded (a particle whose density, position or step is at "
        "fault leaves the flow and is counted) before the run fails; 0 = the first fault fails it",
        lo=0.0, hi=0.99, node=True)
    max_left_fraction: float = setting(
        1.0, "share of the fluid mass that may leave an open tank over its walls (counted apart as left_tank: "
        "physics, not a fault) before the run fails; 1 = no limit, 0 = the first particle to leave fails it",
        lo=0.0, hi=1.0, node=True)


@dataclass
class Numerics:
    """The numerical choices of a run: the run settings a user sets (scene run section, run files,
    ``--set``, node parameters)."""

    dx: float = setting(0.02, "particle spacing [m]", lo=1.0e-4, hi=10.0, applies=RESET, node=True)
    hdx: float = setting(1.3, "smoothing length over dx: h = hdx dx, support 2h (thesis runs: 2.6 dx)",
                         applies=RESET)
    kernel: str = setting("cubic_spline", "smoothing kernel (quadratic: thesis Eq. 2.5-2.8; cubic_spline: "
                                          "Eq. 2.9-2.10; wendland: Wendland C2)", choices=KERNELS, node=True)
    # the node offers laminar + a switch for SPS (ros/node_params.py)
    viscosity: str = setting("artificial", "viscosity model: artificial (Monaghan 1992), laminar (thesis Eq. "
                                           "2.16-2.17) or sps (laminar + Eq. 2.18-2.21)", choices=VISCOSITIES)
    alpha: float = setting(0.1, "artificial viscosity coefficient (Monaghan 1992); DualSPHysics' dam-break value")
    # the artificial viscosity of a fluid particle sliding past wall particles at rest is a wall friction
    visco_bound_factor: float = setting(
        -1.0, "artificial viscosity between fluid and wall particles, as a multiple of alpha (DualSPHysics' "
        "ViscoBoundFactor); it acts as a wall friction: 0 lets a surge run free; -1 = the wall model's own "
        "(1 dynamic and mdbc, 0 adami)", lo=-1.0, hi=10.0, node=True)
    nu: float = setting(1.0e-6, "kinematic viscosity [m^2/s], laminar and SPS")
    sps_cs: float = setting(0.12, "Smagorinsky constant (thesis Eq. 2.20)")
    sps_ci: float = setting(6.6e-3, "isotropic SPS coefficient C_I (thesis Eq. 2.19)")
    boundary: str = setting("adami", "boundary particle model for walls the scene builds of particles: dynamic "
                                       "(Crespo et al. 2007), mdbc (English et al. 2021), adami (extrapolated "
                                       "pressure, Adami et al. 2012), lennard_jones (thesis Eq. 2.24), "
                                       "monaghan_kajtar (Eq. 2.26)", choices=BOUNDARIES,
                            applies=RESET, node=True)
    mdbc_slip: str = setting("none", "boundary velocity under mdbc: none (the wall's, zero), no_slip or free_slip "
                                     "(DualSPHysics' SlipMode)", choices=MDBC_SLIPS, node=True)
    mk_beta: float = setting(2.0, "fluid / boundary particle spacing ratio of Monaghan-Kajtar walls (thesis "
                                  "Eq. 2.26), >= 1", applies=RESET)
    density_diffusion: str = setting("delta", "density treatment: none, or delta-SPH (Molteni & Colagrossi 2009)",
                                     choices=DENSITY_DIFFUSIONS, node=True)
    wall_flux: str = setting("full", "the wall particles' term of the continuity equation: the full relative "
                                     "velocity, or over a flat face its part along the face's normal "
                                     "(docs/solver.md)", choices=WALL_FLUXES, applies=RESET)
    delta: float = setting(0.1, "delta-SPH coefficient (Molteni & Colagrossi 2009)")
    xsph: bool = setting(False, "XSPH (thesis Eq. 2.22): on in the thesis runs, off by default as in DualSPHysics")
    xsph_eps: float = setting(0.5, "XSPH's epsilon (thesis Eq. 2.22)")
    shifting: bool = setting(False, "particle shifting (Lind et al. 2012); off by default, as in DualSPHysics")
    shift_coef: float = setting(-2.0, "shifting's A, DualSPHysics' ShiftCoef")
    shift_tfs: float = setting(0.0, "free-surface threshold of div r; 0 = DualSPHysics' 1.5 in 2D, 2.75 in 3D")
    cavitation: bool = setting(False, "the fluid cavitates at ambient pressure: its density never falls below rho0, "
                                      "so it holds no tension (docs/solver.md)")
    shepard_every: int = setting(0, "steps between Shepard filters (thesis Eq. 2.28 used 40); 0 = off")
    rho0: float = setting(1000.0, "reference density [kg/m^3]")
    gamma: float = setting(7.0, "Tait exponent (thesis Eq. 2.12)")
    c0: float = setting(0.0, "speed of sound [m/s]; 0 = c0_coef sqrt(g H) with the scene's depth H (thesis "
                             "Section 2.3)", lo=0.0, hi=1000.0, node=True)
    c0_coef: float = setting(10.0, "c0 / sqrt(g H) when c0 is 0")
    cfl: float = setting(0.4, "Courant number of the adaptive time step (Monaghan 1992, as GPUSPH); docs/defaults.md: "
                              "0.2-0.4 give the same answers on the impact cases", lo=MIN_CFL, hi=1.0, node=True)
    dt_fixed: float = setting(0.0, "> 0 forces this time step [s] (tests, stability studies); with multirate, "
                                   "the finest level's")
    # the neighbour lists are sized for the steps a launch spans: a fresh solver takes a change
    multirate: bool = setting(True, "refinement zones: the coarser levels step at twice the finest level's step "
                                    "(sph/levels.py); off: every level at the finest's", applies=RESET)
    # a tank started at rest reaches its discrete equilibrium without bouncing on its walls
    settle_tau: float = setting(0.0, "settling: velocities relax with this time constant [s] until settle_until")
    settle_until: float = setting(0.0, "settling ends at this time [s]")
    precision: str = setting("float32", "floating-point precision of the solver state", choices=PRECISIONS,
                             applies=RESET, node=True)
    device: str = setting(None, "Warp device: cpu, cuda:N, or auto (the first CUDA device Warp sees, else cpu); "
                                "default $GPUSPH_ROS_DEVICE, else cpu: the GPU path is written for CUDA but has "
                                "not yet run on a GPU, docs/results/speed.md",
                          applies=RESET, node=True, factory=default_device)
    cpu_threads: int = setting(0, "threads for the heavy passes on a CPU device; 0 = every core, or one for a run "
                                  "of fewer than 3,000 particles (its loop then replays from a capture: faster)",
                               applies=RESET)
    neighbour_search: str = setting("auto", "how a pass finds a particle's neighbours (sph/neighbours.py): lists "
                                            "(a list per particle, 4 B an entry: faster on a CPU), cells (no "
                                            "lists: each pass walks the cells around it), auto (cells on a GPU, "
                                            "lists on a CPU)", choices=NEIGHBOUR_SEARCHES, applies=RESET)
    step_graph: str = setting("auto", "replay the step loop from a captured graph (sph/graph.py): auto (on a GPU "
                                      "and on one CPU thread; on more, the eager loop spreads the heavy passes over "
                                      "them), on, off",
                              choices=STEP_GRAPHS)
    max_particles: int = setting(MAX_PARTICLES, "a scene whose spacing needs more particles is refused before "
                                                "any allocation")


def settings_of(part) -> tuple:
    """The fields of a configuration part (Domain, HealthLimits, Numerics), in order."""
    return tuple(dataclasses.fields(part))


# the fields that only a new solver takes (Solver.reconfigure refuses them)
RESET_FIELDS = tuple(f.name for part in (Domain, HealthLimits, Numerics) for f in settings_of(part)
                     if f.metadata["applies"] == RESET)


@dataclass
class SolverConfig(Numerics, HealthLimits, Domain):
    """Everything one solver runs with: the scene's domain, the health limits and the numerics.
    Units are SI throughout."""

    # -- derived quantities -------------------------------------------------------------
    @property
    def h(self) -> float:
        return self.hdx * self.dx

    @property
    def g_norm(self) -> float:
        return math.sqrt(sum(c * c for c in self.gravity))

    @property
    def sound_speed(self) -> float:
        """c0 (thesis Eq. 2.14, there dp/drho at rho0): ``c0`` when set, else c0_coef sqrt(g H)."""
        if self.c0 > 0.0:
            return self.c0
        return self.c0_coef * math.sqrt(self.g_norm * self.depth)

    @property
    def wall_friction(self) -> float:
        """The fluid-wall artificial viscosity over alpha: visco_bound_factor, or the wall model's
        own when that is -1."""
        if self.visco_bound_factor < 0.0:
            return boundaries.model(self.boundary).wall_friction
        return self.visco_bound_factor

    @property
    def free_surface_threshold(self) -> float:
        """shift_tfs, or DualSPHysics' value for the dimension."""
        return self.shift_tfs or (1.5 if self.dim == 2 else 2.75)

    @property
    def cell_walks(self) -> bool:
        """Whether the passes walk the cells (no neighbour lists): neighbour_search, auto on a GPU."""
        if self.neighbour_search == "auto":
            return str(self.device).startswith("cuda")
        return self.neighbour_search == "cells"

    @property
    def eos_b(self) -> float:
        """Tait stiffness B = c0^2 rho0 / gamma (thesis Eq. 2.13)."""
        return self.sound_speed ** 2 * self.rho0 / self.gamma

    def replace(self, **changes) -> "SolverConfig":
        return dataclasses.replace(self, **changes)

    # -- validation ---------------------------------------------------------------------
    def validate(self) -> "SolverConfig":
        def choice(name, allowed):
            value = getattr(self, name)
            if value not in allowed:
                raise ConfigError(name, value, "one of " + ", ".join(allowed))

        def positive(name, strict=True):
            value = getattr(self, name)
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            if not ok or (value <= 0.0 if strict else value < 0.0):
                raise ConfigError(name, value, "a finite number " + ("> 0" if strict else ">= 0"))

        def within(name, lo, hi):
            value = getattr(self, name)
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            if not ok or not lo <= value <= hi:
                raise ConfigError(name, value, f"a number in [{lo:g}, {hi:g}]")

        def vector(name, length=3):
            value = getattr(self, name)
            try:
                ok = len(value) == length and all(math.isfinite(float(c)) for c in value)
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ConfigError(name, value, f"a list of {length} finite numbers")

        if self.dim not in (2, 3):
            raise ConfigError("dim", self.dim, "2 or 3")
        for f in dataclasses.fields(self):
            if f.metadata.get("choices"):
                choice(f.name, f.metadata["choices"])
            elif f.metadata.get("lo") is not None:
                within(f.name, f.metadata["lo"], f.metadata["hi"])
        for name in ("dx", "hdx", "rho0", "gamma", "depth", "cfl", "c0_coef", "xsph_eps", "mk_beta"):
            positive(name)
        for name in ("alpha", "nu", "sps_cs", "sps_ci", "delta", "c0", "dt_fixed", "settle_tau",
                     "settle_until", "penetration_ratio", "clump_ratio", "clump_fraction", "energy_growth_ratio"):
            positive(name, strict=False)
        if -1.0 < self.visco_bound_factor < 0.0:
            raise ConfigError("visco_bound_factor", self.visco_bound_factor,
                              "-1 (the wall model's own) or a number in [0, 10]")
        if self.mk_beta < 1.0:
            raise ConfigError("mk_beta", self.mk_beta, "a number >= 1 (boundary particles no sparser than fluid)")
        if isinstance(self.shift_coef, bool) or not isinstance(self.shift_coef, (int, float)) \
                or not -10.0 <= self.shift_coef < 0.0:
            raise ConfigError("shift_coef", self.shift_coef, "a number in [-10, 0) (DualSPHysics uses -2)")
        if isinstance(self.shift_tfs, bool) or not isinstance(self.shift_tfs, (int, float)) \
                or not 0.0 <= self.shift_tfs < self.dim:
            raise ConfigError("shift_tfs", self.shift_tfs, f"a number in [0, {self.dim}) (0 = 1.5 in 2D, 2.75 in 3D)")
        if 0.0 < self.dt_fixed < MIN_DT_FIXED:
            raise ConfigError("dt_fixed", self.dt_fixed, f"0 (adaptive) or a step >= {MIN_DT_FIXED:g} s")
        m = self.max_particles
        number = isinstance(m, (int, float)) and not isinstance(m, bool) and math.isfinite(m)
        if not (number and m >= 1 and m == int(m)):
            raise ConfigError("max_particles", m, "a whole number >= 1")
        if not isinstance(self.cpu_threads, int) or self.cpu_threads < 0:
            raise ConfigError("cpu_threads", self.cpu_threads, "an integer >= 0 (0 = every core)")
        if not isinstance(self.shepard_every, int) or self.shepard_every < 0:
            raise ConfigError("shepard_every", self.shepard_every, "an integer >= 0 (0 = off)")
        for name in ("gravity", "domain_lo", "domain_hi", "periodic", "wall_lo", "wall_hi"):
            vector(name)
        if self.g_norm <= 0.0:
            raise ConfigError("gravity", self.gravity, "a non-zero vector (it sets c0 and the wall forces)")
        if any(lo >= hi for lo, hi in zip(self.domain_lo, self.domain_hi)):
            raise ConfigError("domain_hi", self.domain_hi, f"every component above domain_lo {self.domain_lo}")
        if self.dim == 2 and (self.gravity[2] != 0.0 or self.periodic[2]):
            raise ConfigError("gravity", self.gravity, "a vector in the x-y plane for a 2D run (z is unused)")
        if not 0.0 < self.rho_min_ratio < 1.0 < self.rho_max_ratio:
            raise ConfigError("rho_min_ratio/rho_max_ratio", (self.rho_min_ratio, self.rho_max_ratio),
                              "0 < rho_min_ratio < 1 < rho_max_ratio")
        shortest = neighbours.shortest_period(self.h, kernels.coarse_stride(self, bool(self.zones)))
        for axis, periodic in enumerate(self.periodic):
            if periodic and (self.domain_hi[axis] - self.domain_lo[axis]) < shortest:
                raise ConfigError("periodic", self.periodic,
                                  f"periodic axes at least {shortest / (2 * self.h):.2f} kernel supports "
                                  f"({shortest:.4g} m) long; axis {axis} is shorter")
        # mDBC's ghost nodes and the walls' normals are fixed at the start
        moving = any(m is not None for m in self.motions)
        if moving and self.wall_flux == "normal":
            raise ConfigError("wall_flux", self.wall_flux, "full: a scene with a moving body (the walls' normals "
                                                           "do not follow it yet)")
        if moving and self.boundary == "mdbc":
            raise ConfigError("boundary", self.boundary, "dynamic or adami: a scene with a moving body (mdbc's "
                                                         "ghost nodes do not follow it yet)")
        for k, plane in enumerate(self.planes):
            normal = getattr(plane, "normal", None)
            try:
                norm = math.sqrt(sum(float(c) ** 2 for c in normal)) if len(normal) == 3 else 0.0
                ok = len(plane.point) == 3 and norm > 0.0
            except (TypeError, ValueError, AttributeError):
                ok = False
            if not ok:
                raise ConfigError(f"planes[{k}]", plane, "a Plane with a 3-vector point and a non-zero normal")
        return self
