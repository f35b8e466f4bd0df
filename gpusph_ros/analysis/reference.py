"""The comparison material the package carries in data/ (share.data_dir): the thesis's GPUSPH
results (thesis_2011/), the experimental values behind its percent errors, and the digitised
experimental series. Every function takes that folder (``data``) and answers None when it is None.
"""
import csv
from pathlib import Path

import numpy as np

from ..share import data_dir as _package_data

THESIS = Path("thesis_2011")
SCENARIOS = {1: "quadratic kernel + SPS", 2: "quadratic kernel, no SPS", 3: "cubic spline + SPS"}


def data_dir():
    """The package's reference folder, or None when an install lost it (the analysis then says so
    and reports our numbers alone)."""
    try:
        return _package_data(str(THESIS)).parent
    except FileNotFoundError:
        return None


def thesis_scenario(kernel: str, viscosity: str):
    """The thesis scenario (Table 1) with this kernel and turbulence choice, or the one sharing
    the kernel: (number, exact match?). None for kernels the thesis did not run."""
    if kernel == "cubic_spline":
        return 3, viscosity == "sps"
    if kernel == "quadratic":
        return (1, True) if viscosity == "sps" else (2, viscosity == "laminar")
    return None, False


def _rows(data, name):
    with open(data / THESIS / name, newline="") as f:
        return list(csv.DictReader(f))


def gpusph_value(data, table: str, column: str, scenario: int, dx: float, upper_depth=None):
    """GPUSPH's value in ``table`` for the scenario at spacing ``dx`` (matched to 0.1 mm), or None."""
    if data is None or scenario is None:
        return None
    for row in _rows(data, table):
        if int(row["scenario"]) != scenario or abs(float(row["dx_m"]) - dx) > 1e-4:
            continue
        if upper_depth is not None and abs(float(row["upper_depth_m"]) - upper_depth) > 1e-6:
            continue
        return float(row[column])
    return None


def experiment_value(data, case: str, quantity: str):
    if data is None:
        return None
    for row in _rows(data, "experiment_reference.csv"):
        if row["case"] == case and row["quantity"] == quantity:
            return float(row["value"])
    return None


def experiment_series(data, name: str):
    """A digitised Yeh & Petroff series, (t, value) sorted by time: 'velocity' or 'force'."""
    if data is None:
        return None
    stem = "v" if name == "velocity" else "force"
    path = data / "yeh_petroff_dambreak_column/pysph" / f"yeh_and_petroff_{stem}_data.txt"
    data = np.loadtxt(path, comments="#")
    data = data[np.argsort(data[:, 0], kind="stable")]
    return data[:, 0], data[:, 1]


def experiment_profile(data):
    """Measured normalised velocity profile of the 0.15 m case (thesis Table 33): heights [m], u/U."""
    if data is None:
        return None
    rows = _rows(data, "dambreak2_015_profile_experiment.csv")
    return (np.array([float(r["height_mm"]) / 1000 for r in rows]),
            np.array([float(r["normalized_velocity"]) for r in rows]))


def gpusph_profile(data, scenario, dx):
    """GPUSPH's normalised profile at the Table 33 heights for the scenario and dx, or None."""
    if data is None or scenario is None:
        return None
    rows = [r for r in _rows(data, "dambreak2_015_profile_normalized.csv")
            if int(r["scenario"]) == scenario and abs(float(r["dx_m"]) - dx) < 1e-4]
    if not rows:
        return None
    return (np.array([float(r["height_mm"]) / 1000 for r in rows]),
            np.array([float(r["normalized_velocity"]) for r in rows]))


def gpusph_series(data, table: str, column: str, scenario: int):
    """(dx, value) arrays of every GPUSPH run of ``scenario`` in ``table`` (thesis order: fine to coarse)."""
    if data is None or scenario is None:
        return np.array([]), np.array([])
    rows = [r for r in _rows(data, table) if int(r["scenario"]) == scenario]
    return np.array([float(r["dx_m"]) for r in rows]), np.array([float(r[column]) for r in rows])


LOBOVSKY = Path("lobovsky_2014_dambreak")
DECOURCY = Path("decourcy_2024_dambreak_2d_converged")


def lobovsky_pressures(data):
    """Lobovsky et al. (2014)'s measured impact event ("peak event 5") by sensor, as the header of
    each file names it ('sensor 1' ... 'sensor 4'; the off-centre 'sensor 2L' is left out, it has no
    probe): {1: (t sqrt(g/H), p / (rho g H)), ...}. None without data."""
    if data is None:
        return None
    out = {}
    for path in sorted((data / LOBOVSKY / "pressure").glob("*.dat")):
        with open(path) as f:
            name = f.readline().lstrip("#").strip()
        number = name.removeprefix("sensor ")
        if number.isdigit():
            d = np.loadtxt(path, comments="#")
            out[int(number)] = (d[:, 0], d[:, 1])
    return out


def decourcy_pressures(data):
    """De Courcy et al. (2024)'s converged 2D delta-SPH wall pressures (H/400) on Lobovsky's geometry,
    by sensor (P1-P4 at H/100, H/20, H/10, 0.267 H: Lobovsky's sensors 1-4): {1: (t sqrt(g/H),
    p / (rho g H)), ...}, time-sorted with the digitisation's repeated stamps averaged. None without
    data."""
    if data is None or not (data / DECOURCY).is_dir():
        return None
    out = {}
    for k in (1, 2, 3, 4):
        d = np.loadtxt(data / DECOURCY / f"decourcy_pressure_sensor_P{k}.csv", delimiter=",", skiprows=1)
        t, inverse = np.unique(d[:, 0], return_inverse=True)
        p = np.bincount(inverse, weights=d[:, 1]) / np.bincount(inverse)
        out[k] = (t, p)
    return out


def lobovsky_levels(data):
    """The measured water levels by gauge, the mean of the repeats a gauge has (ETSIN 01 and 02):
    {'H1': (t sqrt(g/H), h / H), ...}. None without data."""
    if data is None:
        return None
    series = {}
    for path in sorted((data / LOBOVSKY / "waterLevel").glob("Fig16_WaterLevels_H*_*.dat")):
        gauge = path.stem.split("_")[2]
        d = np.loadtxt(path, comments="#")
        series.setdefault(gauge, []).append(d)
    out = {}
    for gauge, repeats in series.items():
        t = repeats[0][:, 0]
        out[gauge] = (t, np.mean([np.interp(t, r[:, 0], r[:, 1]) for r in repeats], axis=0))
    return out
