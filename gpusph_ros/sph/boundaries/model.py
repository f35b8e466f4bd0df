"""What a boundary model is to the rest of the package: the solver, the scene builder, the
measurements and the studies ask it instead of branching on its name.

Each model module (dynamic, mdbc, adami, lennard_jones, monaghan_kajtar, planes) defines one
``BoundaryModel`` as ``MODEL``; its name is the run setting ``boundary`` (``planes``: the run setting
``wall_planes``). The device side of a model (its pair term, its density) is in the same module;
``boundaries.build`` combines them for the passes.
"""
import math


class BoundaryModel:
    """A wall treatment. The defaults are those of a wall of particles that only pushes."""

    name = ""
    # the wall particles carry a density and a fluid volume: they enter the fluid's kernel sums, so a
    # wall is a kernel support of layers deep and each wall particle needs a neighbour list of its own
    volume = False
    # the wall particles' density follows the continuity equation (plain dynamic boundaries)
    continuity = False
    # the wall pushes with a force of its own that stores energy (the census counts it)
    repulsive = False
    # before_forces runs before every force evaluation (the half step's too), not once a step
    each_evaluation = False
    # the reach, in spacings, of a Lennard-Jones force on a fluid particle approaching a wall
    # particle (boundaries.backstop), 0 for none: for a wall that holds the fluid out by the fluid's
    # own pressure alone, where a thin, fast layer's pressure is near zero
    backstop = 0.0
    # the fluid-wall artificial viscosity, as a multiple of alpha, of a run that leaves
    # visco_bound_factor to the wall (-1): particle walls that push need it to damp the fluid's
    # approach (DualSPHysics' ViscoBoundFactor 1)
    wall_friction = 1.0

    def layers(self, hdx: float) -> int:
        """Layers of wall particles: a kernel support (2h) deep for walls with a volume, else one."""
        return int(math.ceil(2.0 * hdx)) if self.volume else 1

    def spacing(self, dx: float, mk_beta: float) -> float:
        """Spacing of the wall particles along a wall."""
        return dx

    def run_settings(self) -> dict:
        """The run settings that choose this model."""
        return {"boundary": self.name}

    def prepare(self, solver):
        """Once, after the solver has allocated its state."""

    def before_forces(self, solver, fields):
        """Each step of the finest level, before its first force pass, on the state ``fields``
        (the solver's Fields); with ``each_evaluation``, before every force pass."""

    def face_pressure(self, scalar):
        """A device pass that reads the pressure on a wall face from the wall itself, or None when
        the wall's own pressure is not usable there (the sensor then reads the fluid in front of it:
        measure/sensors.py)."""
        return None
