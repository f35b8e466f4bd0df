"""Run configuration of the SPH solver: every numerical choice the thesis varies, by name.

A configuration is plain data. ``SolverConfig.validate`` checks every field and raises
``ConfigError`` naming the field, the value and what is allowed, so that a scene file, a CLI
override or a ROS parameter all get the same message.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from . import boundaries, density, kernels, neighbours, viscosity
from .device import default_device

# the names of each family's models, owned by its module
KERNELS = kernels.NAMES
VISCOSITIES = viscosity.NAMES
BOUNDARIES = boundaries.NAMES
MDBC_SLIPS = boundaries.mdbc.SLIPS
DENSITY_DIFFUSIONS = density.DIFFUSIONS
PRECISIONS = ("float32", "float64")

# guards against runs that could never finish or never fit (docs/limits.md)
MIN_CFL = 0.01  # a smaller Courant number takes > 100x the steps of the default for no accuracy
MIN_DT_FIXED = 1.0e-6  # [s] a fixed step below this is a million steps per simulated second
MAX_PARTICLES = 50_000_000  # default cap on a run's particles (max_particles)
_SHOWN = 240  # characters of a refused value quoted in an error (a long path fits)


def shown(value) -> str:
    """A refused value as an error quotes it: its repr, cut to a line (never a file's contents)."""
    text = repr(value)
    return text if len(text) <= _SHOWN else text[:_SHOWN - 25] + f"... ({len(text)} characters)"


class ConfigError(ValueError):
    """A configuration field has a value the solver cannot use."""

    def __init__(self, field_name: str, value, allowed: str):
        self.field = field_name
        self.value = value
        self.allowed = allowed
        super().__init__(f"{field_name}: {shown(value)} is not allowed; expected {allowed}")


def check_device(device):
    """ConfigError unless ``device`` is one of this machine's Warp devices. Checked where a model is
    built, not in ``validate``: a study or plan may name a device of another machine."""
    import warp as wp

    names = [d.alias for d in wp.get_devices()]
    if device not in names:
        raise ConfigError("device", device, "a Warp device of this machine: " + ", ".join(names))


@dataclass
class Plane:
    """A particle-less flat wall: a point on it and the normal pointing into the fluid."""

    point: tuple
    normal: tuple


@dataclass
class SolverConfig:
    """Numerics of one run. Units are SI throughout."""

    dim: int = 3
    dx: float = 0.02
    hdx: float = 1.3  # h = hdx * dx; support 2h (thesis runs: 2.6 dx)
    kernel: str = "cubic_spline"
    viscosity: str = "artificial"
    alpha: float = 0.1  # artificial viscosity coefficient (Monaghan 1992); DualSPHysics dam-break value
    # alpha's multiplier between fluid and boundary particles (DualSPHysics' ViscoBoundFactor): the
    # artificial viscosity of a fluid particle sliding past wall particles at rest is a wall friction
    visco_bound_factor: float = 1.0
    nu: float = 1.0e-6  # kinematic viscosity of water [m^2/s], laminar and SPS
    sps_cs: float = 0.12  # Smagorinsky constant (thesis Eq. 2.20)
    sps_ci: float = 6.6e-3  # isotropic SPS coefficient C_I (thesis Eq. 2.19)
    boundary: str = "dynamic"
    mdbc_slip: str = "none"  # mdbc.py: the boundary velocity under mDBC (DualSPHysics SlipMode)
    mk_beta: float = 2.0  # fluid / boundary particle spacing ratio (thesis Eq. 2.26), >= 1
    density_diffusion: str = "delta"
    delta: float = 0.1  # delta-SPH coefficient (Molteni & Colagrossi 2009)
    xsph: bool = False  # on in the thesis runs; off by default as in DualSPHysics
    xsph_eps: float = 0.5  # thesis Eq. 2.22
    # particle shifting (shifting.py, Lind et al. 2012); off by default, as in DualSPHysics
    shifting: bool = False
    shift_coef: float = -2.0  # A, DualSPHysics' ShiftCoef
    shift_tfs: float = 0.0  # free-surface threshold of div r; 0 = DualSPHysics' 1.5 in 2D, 2.75 in 3D
    shepard_every: int = 0  # steps between Shepard filters (thesis Eq. 2.28 used 40); 0 = off
    rho0: float = 1000.0
    gamma: float = 7.0
    c0: float = 0.0  # sound speed [m/s]; 0 = c0_coef * sqrt(g * H)
    c0_coef: float = 10.0
    depth: float = 0.4  # reference depth H [m] for c0 and the wall forces
    gravity: tuple = (0.0, 0.0, -9.81)
    cfl: float = 0.4  # docs/defaults.md: 0.2-0.4 give the same answers on the impact cases
    dt_fixed: float = 0.0  # > 0 forces this time step (tests, stability studies); at least MIN_DT_FIXED
    # settling: until settle_until [s], velocities relax with time constant settle_tau [s], so a
    # tank started at rest reaches its discrete equilibrium without bouncing on its walls
    settle_tau: float = 0.0
    settle_until: float = 0.0
    precision: str = "float32"
    device: str = field(default_factory=default_device)
    cpu_threads: int = 0  # threads for the heavy passes on a CPU device; 0 = every core
    max_particles: int = MAX_PARTICLES  # a scene whose spacing needs more is refused before any allocation
    domain_lo: tuple = (0.0, 0.0, 0.0)
    domain_hi: tuple = (1.0, 1.0, 1.0)
    periodic: tuple = (False, False, False)
    planes: list = field(default_factory=list)
    rho_min_ratio: float = 0.8  # health check: density bounds as fractions of rho0
    rho_max_ratio: float = 1.25
    # failure detectors for what does not show as NaN (health.py, CHECKS):
    # wall_penetration: a fluid particle deeper than penetration_ratio dx beyond a wall face (the
    # first layer of wall particles sits dx/2 behind it) or inside a solid
    penetration_ratio: float = 0.5
    # clumping: more than clump_fraction of the fluid particles have a fluid neighbour closer than
    # clump_ratio dx (tensile instability, pairing); clump_ratio 0 = off
    clump_ratio: float = 0.25
    clump_fraction: float = 0.2
    # energy_growth: kinetic + potential + elastic energy of the fluid above its start by more than
    # energy_growth_ratio x M g H (M the fluid's mass, H = depth); nothing feeds a closed tank; 0 = off
    energy_growth_ratio: float = 0.05
    # a fluid particle at fault (health.REASONS) is excluded and counted; the run fails once the
    # excluded fluid passes this fraction of the fluid mass; 0 = a fault fails the run
    max_excluded_fraction: float = 0.01
    # the tank's inside [wall_lo, wall_hi] (beyond +-1e30 where there is no wall: periodic axes, the
    # open top) and the solid boxes (lo, hi) fluid must stay out of; set by the scene builder
    wall_lo: tuple = (-1.0e30, -1.0e30, -1.0e30)
    wall_hi: tuple = (1.0e30, 1.0e30, 1.0e30)
    solids: list = field(default_factory=list)

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
    def free_surface_threshold(self) -> float:
        """shift_tfs, or DualSPHysics' value for the dimension."""
        return self.shift_tfs or (1.5 if self.dim == 2 else 2.75)

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
        choice("kernel", KERNELS)
        choice("viscosity", VISCOSITIES)
        choice("boundary", BOUNDARIES)
        choice("mdbc_slip", MDBC_SLIPS)
        choice("density_diffusion", DENSITY_DIFFUSIONS)
        choice("precision", PRECISIONS)
        for name in ("dx", "hdx", "rho0", "gamma", "depth", "cfl", "c0_coef", "xsph_eps", "mk_beta"):
            positive(name)
        for name in ("alpha", "visco_bound_factor", "nu", "sps_cs", "sps_ci", "delta", "c0", "dt_fixed", "settle_tau",
                     "settle_until", "penetration_ratio", "clump_ratio", "clump_fraction", "energy_growth_ratio"):
            positive(name, strict=False)
        if self.mk_beta < 1.0:
            raise ConfigError("mk_beta", self.mk_beta, "a number >= 1 (boundary particles no sparser than fluid)")
        f = self.max_excluded_fraction
        if isinstance(f, bool) or not isinstance(f, (int, float)) or not 0.0 <= f < 1.0:
            raise ConfigError("max_excluded_fraction", f, "a fraction of the fluid mass in [0, 1) (0 = strict)")
        if isinstance(self.shift_coef, bool) or not isinstance(self.shift_coef, (int, float)) \
                or not -10.0 <= self.shift_coef < 0.0:
            raise ConfigError("shift_coef", self.shift_coef, "a number in [-10, 0) (DualSPHysics uses -2)")
        if isinstance(self.shift_tfs, bool) or not isinstance(self.shift_tfs, (int, float)) \
                or not 0.0 <= self.shift_tfs < self.dim:
            raise ConfigError("shift_tfs", self.shift_tfs, f"a number in [0, {self.dim}) (0 = 1.5 in 2D, 2.75 in 3D)")
        if not MIN_CFL <= self.cfl <= 1.0:
            raise ConfigError("cfl", self.cfl, f"a number in [{MIN_CFL:g}, 1]")
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
        shortest = neighbours.shortest_period(self.h)
        for axis, periodic in enumerate(self.periodic):
            if periodic and (self.domain_hi[axis] - self.domain_lo[axis]) < shortest:
                raise ConfigError("periodic", self.periodic,
                                  f"periodic axes at least {shortest / (2 * self.h):.2f} kernel supports "
                                  f"({shortest:.4g} m) long; axis {axis} is shorter")
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
