"""The cut of one run into slabs of whole cells, a slab a rank (sph/decomposition.py, issue 69 items
1 and 6): the slabs balance the particles to within a cell, every neighbour a rank does not own lies
in its halo (across the period too), too many ranks are refused with the most the axis allows, and
``gpusph-plan --ranks`` prices each rank from the particles the build makes."""
import re

import numpy as np
import pytest

from gpusph_ros.sph import ConfigError
from gpusph_ros.sph.decomposition import MIN_CELLS, exchange_bytes, split

pytestmark = pytest.mark.unit


def _cloud(seed=3, n=4000):
    """A 2D cloud denser at one end (a column of water at one end of a tank) in [0, 2] x [0, 0.5]."""
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform(0.0, 0.5, n), rng.uniform(0.0, 2.0, n // 4)])
    z = rng.uniform(0.0, 0.5, len(x))
    return np.stack([x, z, np.zeros_like(x)], axis=1)


@pytest.mark.parametrize("ranks", [1, 2, 3, 4])
def test_slabs_are_whole_cells_at_least_a_support_wide_and_balance_to_within_a_cell(ranks):
    pos = _cloud()
    support = 0.05
    slabs = split(pos, (0, 0, 0), (2.0, 0.5, 0), (False, False, False), support, ranks)
    assert slabs.axis == 0 and slabs.cell >= support and slabs.n_cells * slabs.cell == pytest.approx(2.0)
    assert all(end - first >= MIN_CELLS for first, end in slabs.bounds())
    owner = slabs.rank_of(pos)
    counts = np.bincount(owner, minlength=ranks)
    assert counts.sum() == len(pos) and np.array_equal(counts, slabs.counts(pos))
    # every rank's own cells, and each cut no further from its share than the busiest cell holds
    cell = slabs.cell_of(pos)
    for rank, (first, end) in enumerate(slabs.bounds()):
        assert np.all((cell[owner == rank] >= first) & (cell[owner == rank] < end))
    busiest = np.bincount(cell).max()
    below = np.cumsum(counts)[:-1]
    assert np.all(np.abs(below - len(pos) * np.arange(1, ranks) / ranks) <= busiest)


@pytest.mark.parametrize("periodic", [False, True])
def test_every_neighbour_a_rank_does_not_own_is_in_its_halo(periodic):
    """Brute force over every pair closer than the support (the distance across the period where x
    is periodic): a particle of another rank near one of a rank's is in that rank's halo, and nothing
    in the halo is further than one cell from the slab."""
    pos = _cloud(seed=5, n=1500)
    support = 0.07
    slabs = split(pos, (0, 0, 0), (2.0, 0.5, 0), (periodic, False, False), support, 4)
    owner = slabs.rank_of(pos)
    halos = [set(h.tolist()) for h in slabs.halos(pos)]
    d = pos[:, None, :2] - pos[None, :, :2]
    if periodic:
        d[..., 0] -= 2.0 * np.round(d[..., 0] / 2.0)
    near = np.argwhere((d ** 2).sum(-1) < support ** 2)
    crossing = near[owner[near[:, 0]] != owner[near[:, 1]]]
    assert len(crossing) > 100  # the test has pairs across every cut
    for i, j in crossing:
        assert j in halos[owner[i]]
    wraps = any(owner[i] == 0 and owner[j] == 3 for i, j in crossing)
    assert wraps == periodic  # the first and last ranks meet only across the period
    for rank, halo in enumerate(halos):
        assert not any(owner[j] == rank for j in halo)
        first, end = slabs.bounds()[rank]
        lo, hi = slabs.lo + first * slabs.cell, slabs.lo + end * slabs.cell
        x = pos[list(halo), 0]
        gap = np.minimum(np.abs(x - lo), np.abs(x - hi))
        if periodic:
            gap = np.minimum(gap, np.minimum(np.abs(x - lo - 2.0), np.abs(x + 2.0 - hi)))
        assert np.all(gap <= slabs.cell + 1e-12)


def test_too_many_ranks_are_refused_with_the_most_the_axis_allows():
    pos = _cloud()
    with pytest.raises(ConfigError) as err:
        split(pos, (0, 0, 0), (2.0, 0.5, 0), (False, False, False), 0.1, 7)  # 20 cells: 6 ranks at most
    assert err.value.field == "ranks" and "at most 6" in str(err.value) and "20 cells" in str(err.value)
    assert split(pos, (0, 0, 0), (2.0, 0.5, 0), (False, False, False), 0.1, 6).ranks == 6
    with pytest.raises(ConfigError, match="ranks: 0 is not allowed"):
        split(pos, (0, 0, 0), (2.0, 0.5, 0), (False, False, False), 0.1, 0)


def test_a_coarse_lattice_spread_over_its_spacing_counts_as_the_fine_one_it_stands_for():
    """Fine points every d along x and a coarse lattice every 4 d (each at the middle of the four it
    stands for): spread over 4 d, four coarse counts are the fine count at every cell face, to within
    half a fine point; unspread, whole coarse planes fall on one side of a face and miss by up to two."""
    d, n = 0.01, 400
    fine = np.stack([(np.arange(n) + 0.5) * d, np.zeros(n), np.zeros(n)], axis=1)
    coarse = np.stack([(4 * np.arange(n // 4) + 2.0) * d, np.zeros(n // 4), np.zeros(n // 4)], axis=1)
    args = ((0, 0, 0), (n * d, 1, 0), (False, False, False), 0.033, 1)
    exact = split(fine, *args)
    assert exact.n_cells == 121  # cells of 4 / 1.21 d: the coarse planes do not line up with the faces
    spread = split(coarse, *args, spread=4 * d)
    faces = exact.lo + np.arange(exact.n_cells + 1) * exact.cell
    truth = np.searchsorted(fine[:, 0], faces)
    from gpusph_ros.sph.decomposition import _below

    assert np.max(np.abs(4 * _below(spread, coarse, 4 * d) - truth)) <= 0.5 + 1e-9
    assert np.max(np.abs(4 * _below(spread, coarse, 0.0) - truth)) >= 1.5


def test_the_halo_refresh_is_priced_from_the_state_each_evaluation_reads():
    # 7 scalars after each step, 2 more and 16 bytes as a particle changes hands: 52 B a particle in float32
    assert exchange_bytes(1000, 4) == 1000 * (7 * 4 + 2 * 4 + 16)
    assert exchange_bytes(0, 8) == 0


def test_gpusph_plan_prices_each_rank_from_the_particles_the_build_makes(capsys):
    """DamBreak 1 lab at 3 cm on 2 ranks: the two slabs hold every particle the build makes, within
    a few percent of each other, each with a halo 3 cells deep (the exchange's: 3 of the 20 cells
    across the tank, a fifth to a quarter of a rank's particles, measured); 9 ranks are refused
    (exit 1)."""
    from gpusph_ros.cli import plan_main
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve

    scene = load_scene("dambreak1_lab")
    n = len(build_run(scene, resolve(scene, dx=0.03)).particles.pos)
    assert plan_main(["dambreak1_lab", "--set", "dx=0.03", "--ranks", "2"]) == 0
    out = capsys.readouterr().out
    rows = re.findall(r"^ +(\d) +([\d,]+) +([\d,]+) +([\d.]+)% +([\d.]+) GiB +([\d.]+) MiB$", out, re.M)
    assert len(rows) == 2 and "slabs along x" in out
    own = [int(r[1].replace(",", "")) for r in rows]
    halo = [int(r[2].replace(",", "")) for r in rows]
    assert sum(own) == n and abs(own[0] - own[1]) < 0.1 * n / 2
    assert all(0.1 * o < h < 0.3 * o for h, o in zip(halo, own))
    assert plan_main(["dambreak1_lab", "--set", "dx=0.03", "--ranks", "9"]) == 1
    assert "ranks: 9 is not allowed; expected at most" in capsys.readouterr().err


def test_a_rebalance_moves_the_cuts_by_whole_cells_where_the_water_went():
    """Cuts balanced on a dam break's column at rest, then the column spread along the tank (its
    particles moved right as a surge moves them): the fullest rank holds far over the mean, so
    ``rebalanced`` cuts the same cells again, every particle still owned once and each rank back
    within the busiest cell of its share; under the threshold it keeps the cuts."""
    pos = _cloud(seed=11)
    args = ((0, 0, 0), (2.0, 0.5, 0), (False, False, False), 0.05, 3)
    at_rest = split(pos, *args)
    assert at_rest.imbalance(pos) < 0.1
    moved = pos.copy()
    moved[:, 0] = np.where(moved[:, 0] < 0.5, moved[:, 0] * 3.0, moved[:, 0])  # the column over 1.5 m
    assert at_rest.imbalance(moved) > 0.5
    again = at_rest.rebalanced(moved, threshold=0.2)
    assert (again.axis, again.lo, again.cell, again.n_cells) == (at_rest.axis, at_rest.lo, at_rest.cell,
                                                               at_rest.n_cells)
    assert again.cuts != at_rest.cuts and again.cuts == split(moved, *args).cuts
    counts = again.counts(moved)
    assert counts.sum() == len(moved)
    assert np.abs(counts - len(moved) / 3).max() <= np.bincount(again.cell_of(moved)).max()
    assert again.rebalanced(moved, threshold=0.2) is again  # balanced now: kept
