"""Cases whose wall loads are known exactly, built particle by particle where a scene file cannot
say them (no gravity, a wall standing free): what the wall pressure and the net force on a wall are
checked against (tests/test_wall_pressure.py, bench/jet_impingement.py).

An impinging jet: a 2D block of fluid b wide moving at U onto a wall of boundary particles (a body),
without gravity. Once the water-hammer transient of the first contact has passed and until the
jet's tail arrives, momentum gives the force per unit depth rho U^2 b, and the stagnation point
carries rho U^2 / 2 (Milne-Thomson, Theoretical Hydrodynamics, Section 11.52).

A thin sheet: in 3D, water ``depth`` spacings deep sliding at U over a horizontal plate and off its
sharp edge (issue 56). On the plate it is hydrostatic, rho g d at its bottom; off the edge it falls
freely at ambient pressure, 0: a fluid in tension there reads what no sheet of water holds.

A submerged box: in 3D, a box standing on the floor of a tank of still water (issue 68). Everywhere
the pressure is hydrostatic, rho g d; on the box's top d is the water over it, and no fluid, at its
edges least of all, is in tension.
"""
import numpy as np

from ..sph import BOUNDARY, FLUID, Particles, SolverConfig, boundaries

RHO0, U, WIDTH = 1000.0, 1.0, 0.1  # [kg/m^3], [m/s], [m]: the jet
LENGTH = 1.5  # [m] of jet: its tail reaches the wall at about (GAP + LENGTH) / U
GAP = 0.02  # [m] between the jet's head and the wall's face at t = 0
# [m] of wall above and below the jet's axis: the sheets run along it at about U and reach its ends
# after the window, no sheet turning round an end into the wall's back
WALL_HALF = 1.5
C0 = 15.0  # [m/s] the sound speed, 15 U: density within about 0.5% in the steady jet


# the thin sheet [m]: the plate fills x < PLATE_END up to PLATE_TOP, the sheet SHEET_START < x < SHEET_END on it
PLATE_END, PLATE_TOP, SHEET_START, SHEET_END = 0.6, 0.3, 0.1, 0.55
SHEET_SENSORS = (0.25, 0.40, 0.55)  # [m] x of the plate's sensors under the sheet, on its centre line


def thin_sheet(dx: float, depth: int = 3):
    """The thin sheet's scene (a schema Scene): a tank 1.0 m long, 0.5 m tall and 9 spacings wide,
    periodic across (a sheet of unbounded width in a 3D kernel; a periodic axis is at least 3.3
    kernel supports long); the plate an obstacle; on its top two sensors 2 spacings across at each
    of SHEET_SENSORS, ``plate_<x in cm>cm`` (the default transducer) and ``..._raw`` (each step's
    reading, its sign kept). The sheet starts at rest: give its fluid the speed U
    (``Model.particles.vel``) before the solver is made."""
    from .schema import parse_scene

    top, width = PLATE_TOP + depth * dx, 9 * dx
    probes = {}
    for x in SHEET_SENSORS:
        sensor = {"type": "pressure_sensor", "position": [x, width / 2, PLATE_TOP], "normal": [0, 0, 1],
                  "diameter": 2 * dx}
        probes[f"plate_{round(x * 100)}cm"] = sensor
        probes[f"plate_{round(x * 100)}cm_raw"] = {**sensor, "sampling": "step", "clip": False}
    return parse_scene({
        "name": "thin_sheet", "dim": 3, "tank": [1.0, width, 0.5], "depth": top, "walls": "particles",
        "periodic": [False, True, False],
        "fluid": [{"name": "sheet", "lo": [SHEET_START, 0.0, PLATE_TOP], "hi": [SHEET_END, width, top]}],
        "obstacles": [{"name": "plate", "lo": [0.0, 0.0, 0.0], "hi": [PLATE_END, width, PLATE_TOP]}],
        "probes": probes})


def impinging_jet(per_width: int, boundary: str = "dynamic", **settings):
    """(config, particles, x of the wall's face, dx) of the jet with ``per_width`` particles across
    it, its axis at y = 0, hitting a wall of the model ``boundary`` (body 0) at x = face."""
    dx = WIDTH / per_width
    layers = boundaries.model(boundary).layers(settings.get("hdx", SolverConfig.hdx))
    face = GAP + LENGTH  # the wall's face at x = face; the jet's axis at y = 0
    nx, ny = int(round(LENGTH / dx)), per_width
    xs = face - GAP - LENGTH + (np.arange(nx) + 0.5) * dx
    ys = -WIDTH / 2 + (np.arange(ny) + 0.5) * dx
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    fluid = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    nw = int(round(2 * WALL_HALF / dx))
    wx = face + (np.arange(layers) + 0.5) * dx
    wy = -WALL_HALF + (np.arange(nw) + 0.5) * dx
    hx, hy = np.meshgrid(wx, wy, indexing="ij")
    wall = np.column_stack([hx.ravel(), hy.ravel(), np.zeros(hx.size)])
    n_f, n_w = len(fluid), len(wall)
    particles = Particles(pos=np.vstack([fluid, wall]),
                          vel=np.vstack([np.tile([U, 0.0, 0.0], (n_f, 1)), np.zeros((n_w, 3))]),
                          rho=np.full(n_f + n_w, RHO0), mass=np.full(n_f + n_w, RHO0 * dx * dx),
                          ptype=np.concatenate([np.full(n_f, FLUID), np.full(n_w, BOUNDARY)]),
                          body=np.concatenate([np.full(n_f, -1), np.zeros(n_w, dtype=int)]))
    pad = 1.5  # the sheets leave the wall's ends at about U: room for them until the tail arrives
    cfg = SolverConfig(dim=2, dx=dx, gravity=(0.0, -1.0e-6, 0.0), depth=WIDTH, c0=C0, boundary=boundary,
                       domain_lo=(-pad, -WALL_HALF - pad, -1.0),
                       domain_hi=(face + (layers + 1) * dx, WALL_HALF + pad, 1.0),
                       solids=[((face, -WALL_HALF, -1.0), (face + layers * dx, WALL_HALF, 1.0))],
                       energy_growth_ratio=0.0, rho_min_ratio=0.5, max_excluded_fraction=0.5, **settings)
    return cfg, particles, face, dx


def jet_force() -> float:
    """rho U^2 b [N/m]: the momentum flux the wall stops."""
    return RHO0 * U ** 2 * WIDTH


def jet_stagnation_pressure() -> float:
    """rho U^2 / 2 [Pa] at the stagnation point."""
    return 0.5 * RHO0 * U ** 2


# the submerged box [m]: a tank 0.6 x 0.3 m, water 0.2 m deep, a box 0.2 x 0.1 x 0.1 m in its middle
BOX_TANK, BOX_DEPTH = (0.6, 0.3, 0.3), 0.2
BOX_LO, BOX_HI = (0.2, 0.1, 0.0), (0.4, 0.2, 0.1)


def submerged_box(dx: float, current: bool = False):
    """The submerged box's scene (a schema Scene): the box an obstacle on the tank's floor, its top
    0.1 m under the surface, every edge of it under water; sensors 2 spacings across on its top, at
    its centre (``top_centre``) and one sensor's diameter in from its upstream edge
    (``top_edge``), and on the tank's floor beside it (``floor``, 0.2 m deep). Still water is
    settled for 0.5 s (a still tank's start), as tests/test_sensors.py's tanks are. With
    ``current`` the tank is periodic along x, the flow's way, and not settled: give the fluid its
    speed (``Model.particles.vel``) before the solver is made."""
    from .schema import parse_scene

    (x0, y0, _), (x1, y1, top) = BOX_LO, BOX_HI
    middle = (y0 + y1) / 2
    probes = {name: {"type": "pressure_sensor", "position": position, "normal": [0, 0, 1], "diameter": 2 * dx}
              for name, position in (("top_centre", [(x0 + x1) / 2, middle, top]),
                                     ("top_edge", [x0 + 2 * dx, middle, top]),
                                     ("floor", [x0 / 2, middle, 0.0]))}
    return parse_scene({
        "name": "submerged_box", "dim": 3, "tank": list(BOX_TANK), "depth": BOX_DEPTH, "walls": "particles",
        "fluid": [{"name": "water", "lo": [0.0, 0.0, 0.0], "hi": [BOX_TANK[0], BOX_TANK[1], BOX_DEPTH]}],
        "obstacles": [{"name": "box", "lo": list(BOX_LO), "hi": list(BOX_HI), "displaces_fluid": True}],
        "probes": probes, **({"periodic": [True, False, False]} if current else
                             {"run": {"settle_tau": 0.05, "settle_until": 0.5}})})
