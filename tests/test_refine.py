"""Refinement zones (scene ``refine:``, scenes/refine.py) and particles of differing smoothing
length (kernels.smoothing: pairs at h_ab = (h_a + h_b) / 2).

- A zone splits each particle in it into 2^dim daughters on its cell's sub-lattice: mass exact,
  the cells tiled, walls in the zone split too, densities on the hydrostatic profile.
- A zone over the whole tank runs as the uniform run at the zone's spacing, to round-off in
  float64 (the per-pair smoothing lengths, the lists, the step and mDBC's ghosts on that path).
- Across an interface between spacings the pair forces stay antisymmetric: in a periodic box the
  fluid's momentum changes by M g t only, to round-off.
- A zone that cannot be built is refused naming the field.
"""
import numpy as np
import pytest

from gpusph_ros.scenes import refine
from gpusph_ros.scenes.boxes import lattice
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import Zone, parse_scene
from gpusph_ros.sph import Solver, SolverConfig
from gpusph_ros.sph.config import ConfigError
from gpusph_ros.sph.eos import hydrostatic_density
from gpusph_ros.sph.particles import Particles

TANK = {"name": "tank", "dim": 2, "tank": [0.6, 0.32],
        "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.6, 0.2]}]}
MIDDLE = {"name": "middle", "lo": [0.2, 0.0], "hi": [0.4, 0.32], "ratio": 0.5}


def scene(**changes):
    return parse_scene({**TANK, **changes})


@pytest.mark.unit
def test_a_zone_splits_its_particles_into_daughters_that_tile_their_cells():
    dx = 0.02
    plain = build(scene(), dx=dx).particles
    zoned = build(scene(refine=[MIDDLE]), dx=dx)
    parts = zoned.particles
    inside = (plain.pos[:, 0] >= 0.2) & (plain.pos[:, 0] <= 0.4)  # the zone reaches the floor: its walls too
    assert len(parts) == (~inside).sum() + 4 * inside.sum()
    for kind in (0, 1):
        assert parts.mass[parts.ptype == kind].sum() == pytest.approx(plain.mass[plain.ptype == kind].sum(), rel=1e-12)
    fine = parts.spacing < dx
    assert np.all(parts.spacing[fine] == dx / 2) and fine.sum() == 4 * inside.sum()
    assert np.all((parts.pos[fine, 0] > 0.2) & (parts.pos[fine, 0] < 0.4))
    assert ((parts.ptype == 1) & fine).sum() == 4 * ((plain.ptype == 1) & inside).sum() > 0
    # each daughter a quarter spacing from its parent's centre along each axis, so the fine lattice
    # is the dx / 2 lattice: every fine fluid particle is a uniform dx / 2 fill's
    uniform = build(scene(), dx=dx / 2).particles
    fluid_fine = parts.pos[fine & (parts.ptype == 0)]
    ref = uniform.pos[(uniform.ptype == 0) & (uniform.pos[:, 0] > 0.2) & (uniform.pos[:, 0] < 0.4)]
    assert np.allclose(np.sort(fluid_fine[:, 0] + 1j * fluid_fine[:, 1]), np.sort(ref[:, 0] + 1j * ref[:, 1]))
    # each on the hydrostatic profile at its own depth below the surface
    cfg = zoned.config
    f = fine & (parts.ptype == 0)
    expected = hydrostatic_density(0.2 - parts.pos[f, 1], cfg.rho0, cfg.eos_b, cfg.gamma, cfg.g_norm)
    assert np.allclose(parts.rho[f], expected, rtol=1e-12)


@pytest.mark.physics
@pytest.mark.parametrize("boundary", ["dynamic", "mdbc"])
def test_a_zone_over_the_whole_tank_runs_as_the_uniform_run_at_its_spacing(boundary):
    column = {**TANK, "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.2, 0.2]}]}
    whole = {"name": "all", "lo": [0.0, 0.0], "hi": [0.6, 0.32], "ratio": 0.5}
    uniform = build(parse_scene(column), dx=0.01, boundary=boundary, precision="float64")
    zoned = build(parse_scene({**column, "refine": [whole]}), dx=0.02, boundary=boundary, precision="float64")
    runs = []
    for model in (uniform, zoned):
        solver = model.solver()
        solver.advance(0.1)
        fluid = model.particles.ptype == 0
        order = np.lexsort(model.particles.pos[fluid].T[::-1])  # the same lattice point to the same row
        snap = solver.snapshot()
        runs.append((solver.steps, snap["pos"][fluid][order], snap["vel"][fluid][order]))
    (steps_u, x_u, u_u), (steps_z, x_z, u_z) = runs
    assert steps_u == steps_z
    assert np.abs(x_u - x_z).max() < 1e-12  # the front has run 8 cm by then
    assert np.abs(u_u - u_z).max() < 1e-10 and np.abs(u_u).max() > 0.5


@pytest.mark.physics
def test_momentum_crosses_an_interface_between_spacings_to_round_off():
    L, dx = 0.2, 0.01
    cfg = SolverConfig(dim=2, dx=dx, gravity=(0.0, -9.81, 0.0), depth=0.1, domain_lo=(0.0, 0.0, -1.0),
                       domain_hi=(L, L, 1.0), periodic=(True, True, False), precision="float64",
                       energy_growth_ratio=0.0)  # falling through a periodic floor gains energy
    pos = lattice((0.0, 0.0), (L, L), dx, 2)
    n = len(pos)
    vel = np.zeros((n, 3))
    vel[:, :2] = 0.05 * np.random.default_rng(1).standard_normal((n, 2))
    columns = {"pos": pos, "vel": vel, "rho": np.full(n, 1000.0), "mass": np.full(n, 1000.0 * dx * dx),
               "ptype": np.zeros(n, np.int32), "body": np.full(n, -1, np.int32)}
    zone = Zone("middle", (0.06, 0.06, 0.0), (0.14, 0.14, 0.0), 0.5)
    columns, spacing = refine.split(columns, np.full(n, dx), [zone], (L, L, 0.0), 2, dx)
    parts = Particles(spacing=spacing, **columns)
    assert len(parts) == n + 3 * 64
    solver = Solver(cfg, parts)
    mass = parts.mass.sum()
    start = (parts.mass[:, None] * parts.vel).sum(axis=0)
    solver.advance(0.1)
    snap = solver.snapshot()
    momentum = (snap["mass"][:, None] * snap["vel"]).sum(axis=0) - mass * np.asarray(cfg.gravity) * solver.time
    scale = (snap["mass"] * np.linalg.norm(snap["vel"], axis=1)).sum()
    assert np.abs(momentum - start).max() < 1e-12 * scale
    assert snap["mass"].sum() == mass
    assert np.abs(snap["vel"] - parts.vel).max() > 0.01  # the particles did interact


@pytest.mark.unit
@pytest.mark.parametrize("refine_in, field, words", [
    ([{**MIDDLE, "ratio": 0.3}], "refine[0].ratio", "one of 0.5, 0.25, 0.125"),
    ([{**MIDDLE, "ratio": 0.25}], "refine[0]", "inside a zone of ratio 0.5"),
    ([{"name": "band", "around": "pier", "margin": 0.1, "ratio": 0.5}], "refine[0].around", "name of an obstacle"),
    ([{"name": "band", "ratio": 0.5, "lo": [0.1, 0.0], "hi": [0.2, 0.1], "margin": 0.1}], "refine[0].margin",
     "only a band"),
    ([MIDDLE, {**MIDDLE, "ratio": 0.25}], "refine", "not used by another entry"),
    ([{**MIDDLE, "hi": [0.7, 0.32]}], "refine[0].hi", "inside the tank"),
    ("middle", "refine", "a list of zones"),
])
def test_a_zone_that_cannot_be_built_is_refused_naming_its_field(refine_in, field, words):
    with pytest.raises(ConfigError, match=field.replace("[", r"\[").replace("]", r"\]") + ".*" + words):
        scene(refine=refine_in)


@pytest.mark.unit
def test_a_band_around_an_obstacle_and_nested_zones():
    pier = {"name": "pier", "lo": [0.4, 0.0], "hi": [0.44, 0.1]}
    zones = [{"name": "near", "around": "pier", "margin": 0.1, "ratio": 0.5},
             {"name": "close", "around": "pier", "margin": 0.04, "ratio": 0.25}]
    sc_fluid = [{"name": "water", "lo": [0.0, 0.0], "hi": [0.3, 0.2]}]
    sc = scene(fluid=sc_fluid, obstacles=[pier], refine=zones)
    assert [z.name for z in sc.refine] == ["near", "close"]
    assert np.allclose([z.lo[:2] + z.hi[:2] for z in sc.refine], [(0.3, 0.0, 0.54, 0.2), (0.36, 0.0, 0.48, 0.14)])
    with pytest.raises(ConfigError, match=r"refine\[1\].*at least 0.065 m"):
        build(sc, dx=0.05)  # 'close' sits 0.06 m inside 'near': less than the 0.5 level's support at this dx
    reversed_order = scene(fluid=sc_fluid, obstacles=[pier], refine=zones[::-1])
    with pytest.raises(ConfigError, match=r"refine\[0\].*at least 0.065 m"):  # the file's index, not the level's
        build(reversed_order, dx=0.05)
    parts = build(sc, dx=0.01).particles
    assert sorted(np.unique(parts.spacing)) == [0.0025, 0.005, 0.01]
    pier_particles = parts.body == 0
    assert np.all(parts.spacing[pier_particles] == 0.0025)


@pytest.mark.unit
def test_zones_that_would_pass_max_particles_are_refused_before_they_are_made():
    plain = len(build(scene(), dx=0.02).particles)  # 504; the uniform bound (resources.particle_bound) 612
    with pytest.raises(ConfigError, match=r"refine.*coarser or smaller zones: the zones make 894 particles.*"
                                          r"max_particles is 800"):
        build(scene(refine=[MIDDLE]), dx=0.02, max_particles=800)
    assert len(build(scene(refine=[MIDDLE]), dx=0.02, max_particles=894).particles) == 894 > plain


@pytest.mark.unit
@pytest.mark.parametrize("numerics, field", [({"boundary": "lennard_jones"}, "boundary"),
                                             ({"boundary": "monaghan_kajtar"}, "boundary")])
def test_walls_that_hold_one_spacing_are_refused_with_zones(numerics, field):
    with pytest.raises(ConfigError, match=f"{field}.*refinement zones"):
        build(scene(refine=[MIDDLE]), dx=0.02, **numerics)
    with pytest.raises(ConfigError, match="walls.*refinement zones"):
        build(scene(refine=[MIDDLE], walls={"x_min": "planes"}), dx=0.02)
