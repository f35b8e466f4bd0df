"""What every pass reads: the particle kinds, the run's constants (``Params``) and one particle
state (``Fields``), as Warp structs compiled once per floating-point type."""

import functools
from types import SimpleNamespace

import warp as wp

FLUID = 0
BOUNDARY = 1
EXCLUDED = 2  # a fluid particle taken out of the flow by a fault (health.py): no pass reads it
# a fluid particle of one refinement level where another level's fluid is the flow (levels.py):
# its own level's particles read it as fluid, its velocity and density are interpolated from the
# level that is active there, and nothing measured or counted reads it
PASSIVE = 3
# a free slot: a refinement level's particle that left its level's reach, or a slot the build
# reserved for the particles a level makes as fluid arrives (levels.py); no pass reads it
VACANT = 4


@wp.func
def carries_fluid(t: wp.int32) -> bool:
    """Whether a particle of kind t is fluid to its neighbours: active or passive fluid."""
    return t == FLUID or t == PASSIVE

# slots of the device clock (float64): the time, the step about to be taken, the step the stability
# limits allow, when the first failed step would have ended, and the time the steps run to
T, DT, DT_STABLE, T_FAILED, TARGET = range(5)
N_CLOCK = 5
# slots of the step counter: steps taken (the finest level's), the first failed step (-1 while
# none), steps launched, and steps launched since the host last started the loop
STEP, FAILED_STEP, LAUNCHED, IN_BLOCK = range(4)
N_STEPS = 4
# slots of the step loop's flags, each the condition of a branch of the step (wp.capture_if) or of
# the loop (wp.capture_while): go on stepping, which passes this step or its end are due, and
# whether the lists hold every neighbour (0 once one overflowed: the step goes no further)
RUNNING, REORDER_DUE, CENSUS_DUE, SHEPARD_DUE, LISTS_HOLD = range(5)
N_FLAGS = 5


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.struct
    class Params:
        dim: int
        dx: scalar  # the particle spacing
        kernel: int
        norm: scalar
        h: scalar  # the scene's smoothing length, hdx dx; a refined particle's own is f.hsml
        inv_h: scalar
        eta2: scalar  # 0.01 h^2 regulariser
        norm_unit: scalar  # a_D h^dim: the kernel's normalisation for h = 1
        variable_h: int  # 1: the particles' smoothing lengths differ (refinement zones): pairs use f.hsml
        h_min: scalar  # the smallest smoothing length of any particle
        viscosity: int
        alpha: scalar
        alpha_wall: scalar  # alpha x the wall friction, for pairs with a boundary particle
        nu: scalar
        cs_dl2: scalar
        ci_dl2: scalar
        boundary: int  # boundaries.BOUNDARY_ID: only boundaries/ reads it
        wall_volume: int  # 1: the wall particles carry a density and a fluid volume (boundaries.model)
        wall_continuity: int  # 1: the wall particles' density follows the continuity equation
        wall_backstop_r0: scalar  # the wall particles' backstop reach at the scene's spacing; 0: none
        mdbc_slip: int  # boundaries.mdbc.SLIP_ID
        lj_d: scalar
        lj_r0: scalar
        mk_k: scalar
        mk_beta: scalar
        mk_d: scalar  # the Monaghan-Kajtar force's singular distance
        plane_r0: scalar
        delta_hc0: scalar  # delta h c0, 0 when density diffusion is off
        wall_flux: int  # density.WALL_FLUX_ID: the wall particles' term of the continuity equation
        xsph_eps: scalar  # 0 when XSPH is off
        shift_a_h: scalar  # shifting's A h; 0 when shifting is off
        shift_tfs: scalar  # the free-surface threshold of div r
        shift_cap: scalar  # 0.1 dx: the largest shift of one step along an axis
        rho0: scalar
        rho_floor: scalar  # eos.cavitation_floor: rho0 where the fluid cavitates, else 0
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
        wall_top: scalar  # the top of the tank's walls: beyond a wall above it a particle went over it
        penetration: scalar  # penetration_ratio dx
        n_solids: int
        n_zones: int  # refinement zones (levels.py): where each level's particles are active
        coarse_stride: int  # finest-level steps per step of the coarser levels: 2 with multirate, else 1
        clump_r: scalar  # clump_ratio dx
        clump_wall: scalar  # health.CLUMP_WALL_DX dx: no clumping counted closer to a wall
        clump_fraction: wp.float64
        n_fluid: int
        ranked: int  # 1: the solver is one rank's, its halo in its slots too (Fields.owned); 0: one rank
        energy_slack: wp.float64  # energy_growth_ratio M g H; 0 = off
        move_limit2: scalar  # (0.9 x 2h)^2: the displacement check's limit, squared
        exclude: int  # 1: a fluid particle at fault is excluded; 0: it fails the run
        excluded_limit: wp.float64  # max_excluded_fraction x the fluid mass [kg]
        left_limit: wp.float64  # max_left_fraction x the fluid mass [kg]
        mass_units: wp.float64  # integer units per kg of the pending excluded mass (health.MASS_BITS)

    @wp.struct
    class Fields:
        """One particle state (the committed one or the half step) and what every pass reads."""

        pos: wp.array(dtype=vec)
        vel: wp.array(dtype=vec)
        rho: wp.array(dtype=scalar)
        pressure: wp.array(dtype=scalar)
        p_rho2: wp.array(dtype=scalar)  # p / rho^2, once per particle instead of once per pair
        mass: wp.array(dtype=scalar)
        hsml: wp.array(dtype=scalar)  # each particle's smoothing length, hdx x its spacing
        ptype: wp.array(dtype=wp.int32)
        body: wp.array(dtype=wp.int32)
        tau_diag: wp.array(dtype=vec)  # SPS stress / rho: xx, yy, zz
        tau_off: wp.array(dtype=vec)  # xy, xz, yz
        wall_acc: wp.array(dtype=vec)  # a moving body's particles' acceleration (bodies.py); zero elsewhere
        wall_normal: wp.array(dtype=vec)  # a wall particle's face's inward unit normal (wall_flux normal; else 1 entry)
        owned: wp.array(dtype=wp.int32)  # ranked: 1 where this rank owns the slot, 0 for its halo; else 1 entry

    return SimpleNamespace(Params=Params, Fields=Fields)
