"""The results table and the charts drawn from it (gpusph_ros.study.table, .charts), on a fixture
table with known answers: the series each chart holds, the Pareto front, the headline."""
import numpy as np
import pyarrow.parquet as pq
import pytest

from gpusph_ros.study import charts, table

pytestmark = pytest.mark.unit


def _row(scenario, dx, err, wall, gpusph_scenario, status="completed"):
    return {"case": f"dambreak1_thesis-{scenario}-dx={dx:g}", "scene": "dambreak1_thesis", "scenario": scenario,
            "dx": dx, "status": status, "particles": int(1000 / dx), "steps": 1000, "wall_time_s": wall,
            "particle_steps": int(1000 / dx) * 1000, "gpusph_scenario": gpusph_scenario,
            "peak_velocity": 2.21 * (1 + err / 100), "peak_velocity_experiment": 2.21,
            "peak_velocity_error_pct": err, "peak_velocity_gpusph": None, "peak_velocity_gpusph_error_pct": None,
            "velocity_rms": abs(err) / 100}


ROWS = [_row("s1", 0.03, -30.0, 100.0, 1), _row("s1", 0.02, -12.0, 400.0, 1), _row("s1", 0.015, -5.0, 1200.0, 1),
        _row("s3", 0.03, 8.0, 150.0, 3), _row("s3", 0.02, 20.0, 500.0, 3),
        _row("s3", 0.015, 0.0, 50.0, 3, status="failed: health check 'density_bounds' failed")]


def test_pareto_front_and_the_cheapest_within_ten_percent():
    points = [(r["wall_time_s"], *table.error_of(r, "peak_velocity"), r) for r in ROWS
              if table.error_of(r, "peak_velocity")[0] is not None]
    front = table.pareto([(c, e, r["case"]) for c, e, _, r in points])
    assert [(c, e) for c, e, _ in front] == [(100.0, 30.0), (150.0, 8.0), (1200.0, 5.0)]
    best = table.cheapest_within(ROWS, "peak_velocity", 10.0)
    assert best["case"] == "dambreak1_thesis-s3-dx=0.03"  # the failed case's 0% does not count
    assert "cheapest within 10%: dambreak1_thesis-s3-dx=0.03" in table.headline(ROWS, ["peak_velocity"])


def test_csv_and_parquet_hold_every_row_and_column(tmp_path):
    csv_path, parquet_path = table.write(ROWS, tmp_path)
    back = table.read(csv_path)
    assert [r["case"] for r in back] == [r["case"] for r in ROWS]
    assert back[1]["peak_velocity_error_pct"] == -12.0 and back[0]["peak_velocity_gpusph"] is None
    pt = pq.read_table(parquet_path)
    assert pt.num_rows == 6 and set(pt.column_names) == set(table.columns(ROWS))
    assert pt.column("wall_time_s").to_pylist() == [r["wall_time_s"] for r in ROWS]


def test_error_against_dx_has_ours_and_gpusphs_series_per_scenario(reference_data):
    fig = charts.error_vs_dx(ROWS, "peak_velocity", reference_data)
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    assert set(lines) == {"ours: dambreak1_thesis, s1", "ours: dambreak1_thesis, s3", "GPUSPH (thesis scenario 1)",
                          "GPUSPH (thesis scenario 3)"}
    ours = lines["ours: dambreak1_thesis, s1"]
    assert list(ours.get_xdata()) == [15.0, 20.0, 30.0] and list(ours.get_ydata()) == [5.0, 12.0, 30.0]
    assert list(lines["ours: dambreak1_thesis, s3"].get_xdata()) == [20.0, 30.0]  # the failed case is left out
    gp = lines["GPUSPH (thesis scenario 1)"]
    assert len(gp.get_xdata()) == 18 and min(gp.get_xdata()) == pytest.approx(3.5)
    assert gp.get_ydata()[0] == pytest.approx(0.73)  # thesis Table 6: 2.23 m/s, +0.73% at 3.5 mm
    assert "dx [mm]" in fig.axes[0].get_xlabel() and "[%]" in fig.axes[0].get_ylabel()


@pytest.mark.parametrize("cost", ["wall_time_s", "particle_steps"])
def test_error_against_cost_marks_the_pareto_front(cost):
    fig = charts.error_vs_cost(ROWS, "peak_velocity", cost)
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    assert {"dambreak1_thesis, s1", "dambreak1_thesis, s3", "Pareto front"} == set(lines)
    front = lines["Pareto front"]
    costs = sorted((r[cost], abs(r["peak_velocity_error_pct"])) for r in ROWS if r["status"] == "completed")
    best, expected = np.inf, []
    for c, e in costs:
        if e < best:
            expected.append((c, e))
            best = e
    assert list(zip(front.get_xdata(), front.get_ydata())) == expected
    assert fig.axes[0].get_xscale() == "log" and fig.axes[0].get_title()


def test_a_case_that_excluded_particles_is_ringed_with_its_share():
    rows = [dict(r) for r in ROWS]
    rows[1].update(excluded_particles=3, excluded_fraction=0.0004)
    fig = charts.error_vs_cost(rows, "peak_velocity")
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    ringed = lines["excluded particles"]
    assert list(zip(ringed.get_xdata(), ringed.get_ydata())) == [(400.0, 12.0)]
    assert "0.04% excluded" in [t.get_text() for t in fig.axes[0].texts]


def test_no_chart_without_an_error_measure(tmp_path):
    assert charts.error_vs_dx(ROWS, "D_return_time") is None
    paths = charts.write(ROWS, ["peak_velocity", "D_return_time"], tmp_path)
    assert sorted(p.name for p in paths) == ["peak_velocity_vs_dx.png", "peak_velocity_vs_particle_steps.png",
                                             "peak_velocity_vs_wall_time_s.png"]


def test_gpusph_analyze_on_a_study_folder_prints_the_thesis_style_tables(tmp_path, capsys):
    import json

    from gpusph_ros.cli import analyze_main

    table.write(ROWS, tmp_path)
    (tmp_path / "study.json").write_text(json.dumps({"name": "fixture", "metrics": ["peak_velocity"]}))
    assert analyze_main([str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "peak x-velocity at the probe [m/s], dambreak1_thesis; experiment 2.21" in out
    lines = out.splitlines()
    assert lines[1].split() == ["scenario", "dx", "[mm]", "ours", "GPUSPH", "(thesis)", "wall", "[s]", "status"]
    assert lines[3].split()[:5] == ["s1", "20", "1.94", "(-12.0%)", "-"]  # 2.21 x (1 - 12%)
    failed = next(line for line in lines if line.startswith("s3") and " 15 " in line)
    assert "health check 'density_bounds' failed" in failed and "(" not in failed.split()[2]
    assert "cheapest within 10%: dambreak1_thesis-s3-dx=0.03 (2.39, +8.0%) in 150 s" in out
    # and results.md, one line per case with its health peaks (none recorded in the fixture: "-")
    md = (tmp_path / "results.md").read_text().splitlines()
    assert md[0].startswith("| scenario | dx [mm] | status | steps | wall [s] | peak_velocity | excluded |")
    assert len(md) == 2 + len(ROWS)
    assert md[3].split(" | ")[:6] == ["| s1", "20", "completed", "1,000", "400.0", "1.94 (-12.0%)"]
    assert md[-1].split(" | ")[5] == "-"  # the failed case's metric is not reported


def test_a_case_that_raised_runs_again_and_one_that_failed_a_check_does_not(tmp_path):
    import json

    from gpusph_ros.study.case import case_dir, finished_row

    for name, status in (("done", "completed"), ("unstable", "failed: density_bounds at t = 0.4 s"),
                         ("crashed", "error: WarpCodegenTypeError: ...")):
        folder = case_dir(tmp_path, name)
        folder.mkdir(parents=True)
        (folder / "metrics.json").write_text(json.dumps({"row": {"case": name, "status": status}}))
    assert finished_row(tmp_path, "done")["status"] == "completed"
    assert finished_row(tmp_path, "unstable")["status"].startswith("failed")
    assert finished_row(tmp_path, "crashed") is None and finished_row(tmp_path, "never_ran") is None
