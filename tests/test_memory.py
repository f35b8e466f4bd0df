"""What a run holds on its device, measured by Warp's own allocation tracker (every array Warp
allocates, the sorts' and scans' scratch among them) over a solver's build and its first steps:
at most 400 B a particle in 3D without neighbour lists (the cells walked: the GPU's default), 500 B
a slot with a zone under multirate; ``Solver.device_bytes`` counts it to the byte, and the plan
(scenes/resources.py) within 5% (issue 59)."""
import gc
import io
import re

import pytest
import warp as wp

from gpusph_ros.scenes import resources
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene

pytestmark = pytest.mark.physics

UNITS = {"B": 1, "KB": 2 ** 10, "MB": 2 ** 20, "GB": 2 ** 30}


def tracked(make):
    """(what ``make()`` returns, the bytes Warp's allocations made in it still hold) -- Warp's report
    gives three significant figures."""
    text = io.StringIO()
    gc.collect()
    with wp.ScopedMemoryTracker("run", print=False) as tracker:
        tracker.clear()  # the tracker's totals are global: an earlier run's arrays are not this one's
        made = make()
        tracker.report(file=text)
    live = re.search(r"Live allocations:\s*\n\s*\S+\s+\d+ \(([\d.]+) (B|KB|MB|GB)\)", text.getvalue())
    return made, float(live.group(1)) * UNITS[live.group(2)]


@pytest.mark.parametrize("scene, dx, per_particle", [
    ("dambreak1_lab", 0.03, 400),        # 3D, default numerics
    ("dambreak1_lab_zoned", 0.03, 500),  # 3D, the obstruction in a 1.5 cm zone, multirate
    ("lobovsky_2d", 0.01, 400),          # 2D
])
def test_a_run_without_lists_holds_what_the_plan_prices(scene, dx, per_particle):
    model = build(load_scene(scene), dx=dx, neighbour_search="cells")

    def run():
        solver = model.solver()
        solver.advance(0.01)
        return solver

    solver, live = tracked(run)
    n = solver.n
    assert solver.neighbours.cells and solver.steps > 5
    assert live / n <= per_particle
    assert solver.device_bytes() == pytest.approx(live, rel=0.01)
    planned = resources.device_bytes(n, model.config, refined=bool(model.config.zones))
    assert planned == pytest.approx(live, rel=0.05)
