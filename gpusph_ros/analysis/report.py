"""A recording's metrics in the thesis's form, beside the experiment and GPUSPH (thesis, same dx
and scenario), as a JSON record, a printed table and PNG charts.

DamBreak 1 (scenes dambreak1_*; thesis 4.2): peak x-velocity at the probe and its RMS error
against Yeh & Petroff's points; peak x-force on the obstruction from pressure blocks at its faces
and 0.06 m away, the RMS error of the latter against the measured force; the peak of the net force
on the obstruction's particles (what GPUSPH's and DualSPHysics' own force output give) and of the
force from the wall pressure over its faces (measure/sensors.py), with its RMS error; max
forward and return velocity at point D and the time between them. All series get the 0.04 s
moving average; velocity and force are shifted so their peaks meet the experiment's (the
thesis's alignment), point D is not. DamBreak 2 (dambreak2_*; thesis 4.3): bore arrival (greatest
acceleration), the mean depth-averaged velocity over 6 s behind the bore, and the profile
normalised by it. Lobovsky et al. 2014 (lobovsky_*): per wall sensor the peak pressure, its time,
the pressure-time integral of the first impact (metrics.first_impact) and the RMS error of the
series against the measured event; per water-level gauge the RMS error of the level; all in
the paper's units (p / (rho g H), h / H, t sqrt(g/H)), no time shift; and each sensor's
pressure-time integral over t sqrt(g/H) 2.3-3.3, 3.3-4.5 and 4.5-6.5 against the converged 2D SPH of
De Courcy et al. (2024), the reference for a 2D model's near-wall field, both clipped at 0.
"""
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from ..output.messages import block_topic
from ..share import config_dir
from . import metrics as M
from . import reference as R
from .bag import read

LABELS = {
    "peak_velocity": ("peak x-velocity at the probe", "m/s"),
    "velocity_rms": ("RMS error of the probe velocity", "m/s"),
    "peak_force_at_wall": ("peak x-force, pressure blocks at the faces", "N"),
    "peak_force_0p06m": ("peak x-force, pressure blocks 0.06 m out", "N"),
    "force_rms_0p06m": ("RMS error of the force (blocks 0.06 m out)", "N"),
    "peak_force_body": ("peak x-force on the obstruction's particles", "N"),
    "force_rms_body": ("RMS error of the force on the obstruction's particles", "N"),
    "peak_force_pressure_load": ("peak x-force from the wall pressure over its faces", "N"),
    "force_rms_pressure_load": ("RMS error of the force from the wall pressure", "N"),
    "D_max_velocity": ("max forward velocity at D", "m/s"),
    "D_return_time": ("time from max forward to max return flow at D", "s"),
    "bore_arrival": ("bore arrival (greatest acceleration)", "s"),
    "mean_velocity": ("mean depth-averaged velocity, 6 s behind the bore", "m/s"),
}
# the Lobovsky case's sensors and gauges (lobovsky(), which adds each sensor's height to its label)
SENSOR_LABELS = {"peak": ("peak pressure", "p/(rho g H)"), "t_peak": ("time of the peak", "t sqrt(g/H)"),
                 "impulse": ("first-impact pressure-time integral", "p t/(rho g H) sqrt(g/H)"),
                 "rms": ("RMS error of the pressure", "p/(rho g H)")}
LABELS.update({f"{kind}_sensor_{k}": (f"{label}, sensor {k}", unit) for kind, (label, unit) in SENSOR_LABELS.items()
               for k in (1, 2, 3, 4)})
LABELS.update({f"rms_{g}": (f"RMS error of the water level at {g}", "h/H") for g in ("H1", "H2", "H3", "H4")})


def _metric(key, value, experiment=None, gpusph=None, note=""):
    label, unit = LABELS[key] if key in LABELS else (key, "")
    row = {"key": key, "label": label, "unit": unit, "value": value, "experiment": experiment, "gpusph": gpusph,
           "note": note}
    if experiment is not None and value is not None and key.startswith(("peak", "mean", "profile", "impulse")):
        row["error_pct"] = M.percent_error(value, experiment)
        if gpusph is not None:
            row["gpusph_error_pct"] = M.percent_error(gpusph, experiment)
    return row


def _x(series, component="v"):
    return series["t"], series[component][:, 0]


def dambreak1(rec, meta, data, scenario, dx, same_case):
    out, curves = [], {}
    gp = (lambda table, column: R.gpusph_value(data, table, column, scenario, dx)) if same_case else (lambda *a: None)
    t, u = M.moving_average(*_x(rec.topic("probes/velocity")))
    exp_v = R.experiment_series(data, "velocity")
    t_ref = M.peak(*M.moving_average(*exp_v))[0] if exp_v else 0.0
    t_al = M.align_to(t, u, t_ref)
    out.append(_metric("peak_velocity", M.peak(t, u)[1],
                       R.experiment_value(data, "dambreak1", "peak_velocity_at_probe"),
                       gp("dambreak1_peak_velocity.csv", "peak_velocity_m_s")))
    if exp_v:
        first = exp_v[0] < 0.7  # the thesis used the first group of points only (4.2.1)
        out.append(_metric("velocity_rms", M.rms_error(t_al, u, exp_v[0][first], exp_v[1][first]), None,
                           gp("dambreak1_velocity_rms.csv", "rms_error_m_s"),
                           note="experimental scatter 0.39 m/s"))
    curves["velocity"] = (t_al, u, exp_v)
    # what each curve's time was moved by to put its peak on the measured one (export.py undoes it)
    curves["shift"] = {"velocity": float(t_al[0] - t[0]) if len(t) else 0.0}
    exp_f = R.experiment_series(data, "force")
    f_ref = M.peak(*M.moving_average(*exp_f))[0] if exp_f else 0.0
    f_exp_peak = R.experiment_value(data, "dambreak1", "peak_force_on_obstruction")
    body = next(iter(meta.get("bodies") or {"obstruction": 0}))
    forces = {}

    def force(key, topic, gpusph=None, rms_key=None, rms_gpusph=None, note=""):
        """The peak of one force series on the obstruction (0.04 s average, aligned to the
        measured peak for the curves) and, with ``rms_key``, its RMS error against the measurement."""
        tf, f = M.moving_average(*_x(rec.topic(topic), "force"))
        forces[key] = (M.align_to(tf, f, f_ref), f)
        curves["shift"][key] = float(forces[key][0][0] - tf[0]) if len(tf) else 0.0
        out.append(_metric(key, M.peak(tf, f)[1], f_exp_peak, gpusph, note=note))
        if rms_key and exp_f:
            out.append(_metric(rms_key, M.rms_error(*forces[key], *exp_f), None, rms_gpusph,
                               note="experimental scatter 1.50 N"))

    blocks = f"bodies/{body}/pressure_blocks"
    force("peak_force_at_wall", f"{blocks}/{block_topic(0.0)}", gp("dambreak1_peak_force_at_wall.csv", "peak_force_N"))
    force("peak_force_0p06m", f"{blocks}/{block_topic(0.06)}", gp("dambreak1_peak_force_0p06m.csv", "peak_force_N"),
          "force_rms_0p06m", gp("dambreak1_force_rms_0p06m.csv", "rms_error_N"))
    force("peak_force_body", f"bodies/{body}/wrench", rms_key="force_rms_body",
          note="no GPUSPH counterpart in the thesis")
    if any(name.endswith(f"bodies/{body}/pressure_load") for name in rec.series):  # newer recordings only
        force("peak_force_pressure_load", f"bodies/{body}/pressure_load", rms_key="force_rms_pressure_load",
              note="no GPUSPH counterpart in the thesis")
    curves["force"] = (forces, exp_f)
    td, ud = M.moving_average(*_x(rec.topic("probes/D")))
    fr = M.forward_return(td, ud)
    out.append(_metric("D_max_velocity", fr["max_forward"], None, gp("dambreak1_location_D_max_velocity.csv",
                                                                      "max_velocity_m_s")))
    out.append(_metric("D_return_time", fr["time_difference"], None, gp("dambreak1_location_D_return_time.csv",
                                                                         "time_difference_s")))
    curves["D"] = (td, ud, fr)
    return out, curves


def dambreak2(rec, meta, data, scenario, dx, upper, gpusph=True):
    out, curves = [], {}
    gp = R.gpusph_value if gpusph else (lambda *a: None)
    t, u = _x(rec.topic("probes/bore"))
    arrival = M.bore_arrival(t, u)
    mean, covered = M.mean_behind(t, u, arrival)
    case = f"dambreak2_{int(round(upper * 100)):03d}"
    table = f"{case}_mean_velocity.csv"
    out.append(_metric("bore_arrival", arrival, None,
                       gp(data, f"{case}_bore_arrival.csv", "arrival_time_s", scenario, dx, upper)))
    note = "" if covered >= M.BORE_WINDOW - 0.15 else f"the record covers only {covered:.1f} s behind the bore"
    out.append(_metric("mean_velocity", mean, R.experiment_value(data, case, "mean_bore_velocity_6s_window"),
                       gp(data, table, "mean_velocity_m_s", scenario, dx, upper), note=note))
    profile = []
    k = 0
    while True:
        try:
            tp, up = _x(rec.topic(f"probes/profile/h{k}"))
        except KeyError:
            break
        profile.append(M.mean_behind(tp, up, arrival)[0] / mean if mean else float("nan"))
        k += 1
    exp_p = R.experiment_profile(data) if case == "dambreak2_015" else None
    gp_p = R.gpusph_profile(data, scenario, dx) if case == "dambreak2_015" and gpusph else None
    for j, value in enumerate(profile):
        key = f"profile_{'ABCDEF'[j] if j < 6 else j}"
        e = float(exp_p[1][j]) if exp_p is not None and j < len(exp_p[1]) else None
        g = float(gp_p[1][j]) if gp_p is not None and j < len(gp_p[1]) else None
        row = _metric(key, value, e, g)
        row["label"], row["unit"] = f"normalised velocity at point {key[-1]}", "-"
        out.append(row)
    curves["bore"] = (t, u, arrival, mean)
    curves["profile"] = (profile, exp_p, gp_p)
    return out, curves


def lobovsky(rec, scene, run, data):
    """Lobovsky et al. (2014)'s measures: wall sensors 1-4 (probes sensor_1 ... sensor_4,
    pressure_sensor or point probes) and the water-level gauges H1-H4 against the measured series;
    beside them each sensor's pressure-time integral over the three windows of
    metrics.REFERENCE_WINDOWS against the converged 2D reference's same sensor."""
    out, curves = [], {"pressure": {}, "levels": {}}
    depth = float(scene.get("depth", 0.3))
    g = float(np.linalg.norm(scene.get("gravity") or [0.0, 0.0, 9.81]))
    rho0 = float(run.get("rho0", 1000.0))
    t_unit, p_unit = np.sqrt(g / depth), rho0 * g * depth
    exp_p = R.lobovsky_pressures(data) or {}
    exp_h = R.lobovsky_levels(data) or {}
    converged = R.decourcy_pressures(data) or {}
    for k in (1, 2, 3, 4):
        try:  # a pressure_sensor probe's reading, or a point probe's pressure (recordings before sensors)
            s = rec.topic(f"probes/sensor_{k}")
            if np.ndim(s["v"]) != 1:
                s = rec.topic(f"probes/sensor_{k}/pressure")
        except KeyError:
            continue
        t, p = s["t"] * t_unit, s["v"] / p_unit
        exp = exp_p.get(k)
        span = t <= exp[0][-1] if exp else np.ones(len(t), dtype=bool)  # the peak within the measured record
        t_pk, p_pk = M.peak(t[span], p[span])
        e_t_pk, e_pk = M.peak(*exp) if exp else (None, None)
        start, impulse = M.first_impact(t, p)
        e_start, e_impulse = M.first_impact(*exp) if exp else (None, None)
        where = f"sensor {k}, {1000 * scene['probes'][f'sensor_{k}']['position'][-1]:g} mm"
        rows = [_metric(f"peak_sensor_{k}", p_pk, e_pk), _metric(f"t_peak_sensor_{k}", t_pk, e_t_pk),
                _metric(f"impulse_sensor_{k}", impulse, e_impulse,
                        note=f"impact starts at {start:.3g}" + (f", measured {e_start:.3g}" if exp else "")),
                _metric(f"rms_sensor_{k}", M.rms_error(t, p, *exp) if exp else None,
                        note=f"of a measured peak {e_pk:.3g}" if exp else "")]
        for row, (label, _) in zip(rows, SENSOR_LABELS.values()):
            row["label"] = f"{label}, {where}"
        if k in converged:  # the same nondimensional sensor of the converged 2D reference, both clipped at 0
            for w, (lo, hi) in enumerate(M.REFERENCE_WINDOWS):
                row = _metric(f"impulse_converged_w{w + 1}_sensor_{k}", M.window_impulse(t, np.maximum(p, 0.0), lo, hi),
                              M.window_impulse(*converged[k], lo, hi),
                              note="the 'experiment' is converged 2D SPH (De Courcy et al. 2024, H/400), clipped at 0")
                row["label"], row["unit"] = (f"pressure-time integral, t sqrt(g/H) {lo:g}-{hi:g}, {where}",
                                             "p t/(rho g H) sqrt(g/H)")
                rows.append(row)
        out += rows
        curves["pressure"][k] = (t, p, exp)
    # z is up in every recording that names its axes (output.frames); a 2D scene's y before
    vertical = 1 if scene.get("dim") == 2 and "axes" not in rec.metadata else 2
    for gauge in ("H1", "H2", "H3", "H4"):
        try:
            s = rec.topic(f"probes/{gauge}")
        except KeyError:
            continue
        t, h = s["t"] * t_unit, s["v"][:, vertical] / depth
        exp = exp_h.get(gauge)
        out.append(_metric(f"rms_{gauge}", M.rms_error(t, h, *exp) if exp else None))
        curves["levels"][gauge] = (t, h, exp)
    curves["units"] = {"time": t_unit, "pressure": p_unit, "depth": depth}  # what the curves are divided by
    return out, {"lobovsky": curves}


@dataclass
class Case:
    """What an analysis reads: the recording, its metadata, the scene and run settings it records,
    the reference folder, the thesis scenario its numerics match, the spacing, and whether the
    thesis's GPUSPH results are of this scene."""

    rec: object
    meta: dict
    scene: dict
    run: dict
    data: object
    scenario: object
    dx: float
    gpusph: bool


def _analyse_dambreak1(c: Case):
    rows, curves = dambreak1(c.rec, c.meta, c.data, c.scenario, c.dx, same_case=c.gpusph)
    # the thesis's probe is 0.146 m before the obstruction's face; PySPH reads it as before its centre
    return rows, curves, {"gpusph_case": "DamBreak 1, 0.4 m column" if c.gpusph else None,
                          "velocity_probe": (c.scene.get("probes") or {}).get("velocity", {}).get("position")}


def _analyse_dambreak2(c: Case):
    depth = float(c.scene.get("depth", 0.1))
    rows, curves = dambreak2(c.rec, c.meta, c.data, c.scenario, c.dx, depth, gpusph=c.gpusph)
    return rows, curves, {"gpusph_case": f"DamBreak 2, {c.scene.get('depth')} m" if c.gpusph else None}


def _analyse_lobovsky(c: Case):
    rows, curves = lobovsky(c.rec, c.scene, c.run, c.data)
    return rows, curves, {}


# each scene.analysis case (scenes/schema.py, ANALYSES): what its recordings are compared with
ANALYSES = {"dambreak1": _analyse_dambreak1, "dambreak2": _analyse_dambreak2, "lobovsky": _analyse_lobovsky}
def analysis_of(scene: dict, name: str) -> dict:
    """The comparison a recording's scene asks for ({case, gpusph}), or {} for none. A recording
    made before scenes named their analysis gets its built-in scene's section, read from the
    shipped scene file of that name."""
    if "analysis" not in scene and name.isidentifier():
        shipped = config_dir("scenes") / f"{name}.yaml"
        if shipped.is_file():
            scene = yaml.safe_load(shipped.read_text()) or {}
    section = scene.get("analysis")
    if isinstance(section, dict) and section.get("case") in ANALYSES:
        return {"case": section["case"], "gpusph": bool(section.get("gpusph", False))}
    return {}


def analyse(path, data=None, rec=None) -> tuple:
    """(report, curves): the metrics of the recording at ``path`` (a bag directory) as a JSON-ready
    dict, and the curves behind them; the comparison is the one the recorded scene names in its
    ``analysis:`` section. ``data``: the reference folder (default: the package's own, R.data_dir());
    ``rec``: the recording, when the caller has read it already."""
    rec = rec or read(path)
    meta = rec.metadata
    data = data or R.data_dir()
    scene = yaml.safe_load(meta.get("scene", "")) or {}
    name = meta.get("scene_name", scene.get("name", "?"))
    run = meta.get("run_config") or {}
    dx = float(meta.get("dx", run.get("dx", 0.0)))
    scenario, exact = R.thesis_scenario(meta.get("kernel", ""), meta.get("viscosity", ""))
    report = {"recording": str(path), "scene": name, "dx": dx, "kernel": meta.get("kernel"),
              "viscosity": meta.get("viscosity"), "boundary": meta.get("boundary"), "precision": meta.get("precision"),
              "device": meta.get("device"), "particles": int(meta.get("particles", 0)),
              "fluid_particles": int(meta.get("fluid_particles", 0)), "result": rec.result,
              "complete": rec.complete, "reference_data": str(data) if data else None,
              "gpusph_scenario": scenario, "gpusph_scenario_exact": exact,
              "covers_until": max(rec.clock) if rec.clock else 0.0}
    case = analysis_of(scene, name)
    rows, curves = [], {}
    if case:
        try:
            rows, curves, extra = ANALYSES[case["case"]](Case(rec, meta, scene, run, data, scenario, dx,
                                                               case["gpusph"]))
        except KeyError as err:  # a probe the comparison reads is not in the scene
            raise KeyError(f"analysis {case['case']} (the scene's analysis section): {err.args[0]}") from None
        report.update(extra)
    motion_rows, curves["bodies"] = body_motions(rec)
    report["metrics"] = rows + motion_rows
    return report, curves


def rotation_vectors(q: np.ndarray) -> np.ndarray:
    """Each unit quaternion (x, y, z, w) as its rotation vector (axis times angle [rad], the
    shorter way)."""
    q = np.where(q[:, 3:4] < 0.0, -q, q)
    s = np.linalg.norm(q[:, :3], axis=1)
    angle = 2.0 * np.arctan2(s, q[:, 3])
    return q[:, :3] * np.where(s > 0.0, angle / np.where(s > 0.0, s, 1.0), 0.0)[:, None]


def body_motions(rec) -> tuple:
    """Each moving body the recording has odometry of (~/bodies/<name>/odom): its largest
    displacement from where it started, largest rotation, and the peak of its wrench's force, as
    metric rows; and its curves {name: (t, position, rotation vector, (t, force))}."""
    rows, curves = [], {}
    for topic in sorted(t for t in rec.series if t.endswith("/odom") and "/bodies/" in t):
        name = topic.split("/bodies/", 1)[1].rsplit("/odom", 1)[0]
        odom = rec.series[topic]
        position, turn = odom["position"], rotation_vectors(odom["orientation"])
        shift = float(np.linalg.norm(position - position[0], axis=1).max())
        rows.append({**_metric(f"{name}_displacement", shift), "label": f"{name}: largest distance from its start",
                     "unit": "m"})
        rows.append({**_metric(f"{name}_rotation", float(np.degrees(np.linalg.norm(turn, axis=1).max()))),
                     "label": f"{name}: largest rotation from its start", "unit": "deg"})
        force = (odom["t"], np.zeros((len(odom["t"]), 3)))
        wrench = topic.rsplit("/odom", 1)[0] + "/wrench"
        if wrench in rec.series:
            force = (rec.series[wrench]["t"], rec.series[wrench]["force"])
            rows.append({**_metric(f"{name}_peak_force", float(np.linalg.norm(force[1], axis=1).max())),
                         "label": f"{name}: peak force of the fluid on it (its axes)", "unit": "N"})
        curves[name] = (odom["t"], position, turn, force)
    return rows, curves


def excluded_line(result: dict) -> str:
    """'excluded 3 fluid particles (0.05% of the fluid mass: density_bounds 3; the first at
    t = 0.41 s)' or 'no particle excluded', from a result record (values may be text, as read
    back from a recording)."""
    if "excluded_particles" not in result:
        return "exclusions not recorded"
    n = int(float(result["excluded_particles"]))
    left = int(float(result.get("left_tank_particles", 0)))
    gone = (f"; {left} fluid particle{'s' if left > 1 else ''} left the tank over its walls "
            f"({float(result['left_tank_fraction']):.3%} of the fluid mass)") if left else ""
    if not n:
        return "no particle excluded" + gone
    first = result.get("first_excluded_time_s")
    return (f"excluded {n} fluid particle{'s' if n > 1 else ''} ({float(result['excluded_fraction']):.3%} of the "
            f"fluid mass: {result.get('excluded_by_reason')}; the first at t = {float(first):.4g} s)" + gone)


HEALTH_PEAKS = ("peak_clumped_fraction", "min_density_ratio", "max_density_ratio", "peak_energy_growth")


def health_line(result: dict) -> str:
    """'health peaks: clumped 8.6%, density 0.93-1.18 rho0, energy growth 0.2% M g H' from a
    result record (sph.Solver.health_peaks), what the run reached against the detectors' limits."""
    def number(key):
        try:
            return float(result.get(key))
        except (TypeError, ValueError):  # absent, or "None" read back from a recording
            return None
    clump, lo, hi, growth = (number(k) for k in HEALTH_PEAKS)
    if clump is None:
        return "health peaks not recorded"
    density = f"density {lo:.3f}-{hi:.3f} rho0" if lo is not None else "no fluid density seen"
    return (f"health peaks: clumped {clump:.1%}, {density}, energy growth "
            + (f"{growth:.2%} M g H" if growth is not None else "-"))


def fmt(value, err=None):
    """A value to three figures, its percent error in brackets; "-" for none."""
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "-"
    text = f"{value:.3g}" if abs(value) < 100 else f"{value:.1f}"
    return text + (f" ({err:+.1f}%)" if err is not None else "")


def table(report) -> str:
    """The thesis-style table: experiment, GPUSPH (thesis), this run."""
    res = report.get("result") or {}
    scen = report.get("gpusph_scenario")
    if report.get("gpusph_case") and scen:
        gp = (f"GPUSPH: thesis scenario {scen} ({R.SCENARIOS[scen]}), {report['gpusph_case']}, dx = {report['dx']:g} m"
              + ("" if report.get("gpusph_scenario_exact")
                 else " [same kernel; our turbulence/viscosity model differs]"))
    else:
        gp = "GPUSPH: the thesis has no run of this scene with these numerics"
    head = [f"{report['scene']}: dx = {report['dx']:g} m, {report['kernel']} kernel, {report['viscosity']} viscosity, "
            f"{report['boundary']} boundaries, {report['precision']} on {report['device']}",
            f"{report['particles']:,} particles ({report['fluid_particles']:,} fluid); "
            f"status {res.get('status', 'unknown (no result record: killed?)')}, "
            f"wall {res.get('wall_time_s', '?')} s, {res.get('steps', '?')} steps, {res.get('mipps', '?')} MIPPS; "
            + excluded_line(res), health_line(res), gp, ""]
    if report.get("velocity_probe"):
        head.insert(-1, f"velocity probe at {report['velocity_probe']} m")
    if res.get("status") != "completed":
        head.insert(2, "WARNING: the run did not complete; these metrics cover "
                       f"t <= {report.get('covers_until', 0):.3g} s only "
                       "and are not comparable with a finished run")
    # a column with nothing to compare against goes, and one line says why
    columns = [0, 1, 2, 3, 4]
    if report.get("reference_data") is None:
        head[head.index(gp)] = ("no reference data found (the package's data/ folder is missing from this install): "
                                "this run's values alone, no experiment or GPUSPH columns")
        columns = [0, 1, 4]
    elif report["metrics"] and all(m["gpusph"] is None for m in report["metrics"]):
        if report.get("gpusph_case") and scen:
            head[head.index(gp)] = (f"GPUSPH: the thesis has no run of scenario {scen} at dx = {report['dx']:g} m "
                                    "(data/thesis_2011 lists its spacings): no GPUSPH column")
        columns.remove(3)
    rows = [("metric", "unit", "experiment", "GPUSPH (thesis)", "this run")]
    for m in report["metrics"]:
        rows.append((m["label"], m["unit"], fmt(m["experiment"]), fmt(m["gpusph"], m.get("gpusph_error_pct")),
                     fmt(m["value"], m.get("error_pct")) + (f"  [{m['note']}]" if m["note"] else "")))
    rows = [tuple(r[k] for k in columns) for r in rows]
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]) - 1)]
    lines = ["  ".join(r[k].ljust(widths[k]) for k in range(len(widths))) + "  " + r[-1] for r in rows]
    return "\n".join(head + lines)


def charts(report, curves, out_dir) -> list:
    """PNG charts: the time series with the experimental points, and our errors beside GPUSPH's."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    title = f"{report['scene']}, dx = {report['dx']:g} m, {report['kernel']}, {report['viscosity']}"
    written = []

    def save(fig, name):
        fig.tight_layout()
        fig.savefig(out_dir / name, dpi=110)
        plt.close(fig)
        written.append(str(out_dir / name))

    for name, (t, position, turn, (tf, force)) in curves.get("bodies", {}).items():
        fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
        for k, axis in enumerate("xyz"):
            axes[0].plot(t, position[:, k], label=axis)
            axes[1].plot(t, np.degrees(turn[:, k]), label=axis)
            axes[2].plot(tf, force[:, k], label=axis)
        axes[0].set(ylabel="position [m]", title=f"Body {name}: pose (world, z up) and force (its axes)\n{title}")
        axes[1].set(ylabel="rotation vector [deg]")
        axes[2].set(xlabel="time [s]", ylabel="force on it [N]")
        for ax in axes:
            ax.legend(loc="upper right", fontsize=7)
        save(fig, f"body_{name}.png")
    if "velocity" in curves:
        t, u, exp = curves["velocity"]
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(t, u, label="this run (0.04 s average, peak aligned)")
        if exp:
            ax.plot(*exp, "k.", ms=3, label="Yeh & Petroff (digitised)")
        ax.set(xlabel="time, peak aligned [s]", ylabel="x-velocity [m/s]", title=f"Probe velocity\n{title}")
        ax.legend()
        save(fig, "velocity.png")
        forces, exp = curves["force"]
        fig, ax = plt.subplots(figsize=(7, 4))
        for key, (tf, f) in forces.items():
            ax.plot(tf, f, label=LABELS[key][0].replace("peak x-force, ", "").replace("peak ", ""))
        if exp:
            ax.plot(*exp, "k.", ms=3, label="Yeh & Petroff (digitised)")
        ax.set(xlabel="time, peak aligned [s]", ylabel="x-force [N]", title=f"Force on the obstruction\n{title}")
        ax.legend(fontsize=8)
        save(fig, "force.png")
        td, ud, fr = curves["D"]
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(td, ud, label="this run (0.04 s average)")
        ax.plot([fr["t_forward"], fr["t_return"]], [fr["max_forward"], fr["max_return"]], "ro",
                label="max forward / return")
        ax.set(xlabel="time [s]", ylabel="x-velocity [m/s]", title=f"Point D\n{title}")
        ax.legend()
        save(fig, "point_D.png")
    if "bore" in curves:
        t, u, arrival, mean = curves["bore"]
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(t, u, label="depth-averaged x-velocity")
        ax.axvline(arrival, color="r", ls="--", label=f"bore arrival {arrival:.1f} s")
        ax.hlines(mean, arrival, arrival + M.BORE_WINDOW, colors="g", label=f"6 s mean {mean:.3f} m/s")
        ax.set(xlabel="time [s]", ylabel="velocity [m/s]", title=f"Bore at x = 11.1 m\n{title}")
        ax.legend()
        save(fig, "bore_velocity.png")
        profile, exp_p, gp_p = curves["profile"]
        if profile:
            fig, ax = plt.subplots(figsize=(5, 4))
            heights = exp_p[0] if exp_p is not None else np.arange(len(profile))
            ax.plot(profile, heights[:len(profile)], "o-", label="this run")
            if exp_p is not None:
                ax.plot(exp_p[1], exp_p[0], "ks", label="Arnason et al. (thesis Table 33)")
            if gp_p is not None:
                ax.plot(gp_p[1], gp_p[0], "^--", label="GPUSPH (thesis)")
            ax.set(xlabel="u / depth-averaged u [-]", ylabel="height [m]", title="Velocity profile")
            ax.legend(fontsize=8)
            save(fig, "profile.png")
    if "lobovsky" in curves:
        for kind, what, unit in (("pressure", "wall pressure", "p / (rho g H)"), ("levels", "water level", "h / H")):
            series = curves["lobovsky"][kind]
            if not series:
                continue
            fig, axes = plt.subplots(len(series), 1, figsize=(7, 2.2 * len(series)), sharex=True, squeeze=False)
            for ax, (name, (t, y, exp)) in zip(axes[:, 0], series.items()):
                if exp:
                    ax.plot(*exp, "k-", lw=0.6, label="Lobovsky et al. 2014 (measured)")
                ax.plot(t, y, lw=0.9, label="this run")
                ax.set(ylabel=unit, title=f"{what}, {'sensor ' if kind == 'pressure' else ''}{name}")
            axes[0, 0].legend(fontsize=8)
            axes[-1, 0].set(xlabel="t sqrt(g/H) [-]")
            fig.suptitle(title, fontsize=9)
            save(fig, f"{kind}.png")
    compared = [m for m in report["metrics"] if m.get("error_pct") is not None]
    if compared:
        fig, ax = plt.subplots(figsize=(7, 4))
        x = np.arange(len(compared))
        ax.bar(x - 0.2, [m["error_pct"] for m in compared], 0.4, label="this run")
        ax.bar(x + 0.2, [m.get("gpusph_error_pct") or 0.0 for m in compared], 0.4, label="GPUSPH (thesis, same dx)")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(x, [m["key"] for m in compared], rotation=20, fontsize=8)
        ax.set(ylabel="error against experiment [%] (Eq. 4.1)", title=f"Errors against experiment\n{title}")
        ax.legend()
        save(fig, "errors.png")
    return written


def write(report, out_dir) -> Path:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "metrics.json"
    path.write_text(json.dumps(report, indent=2, default=float))
    return path
