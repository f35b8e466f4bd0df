"""The converged 2D reference's geometry (De Courcy et al. 2024, delta-SPH at H/400 of Lobovsky's dam
break; data/decourcy_2024_dambreak_2d_converged, its README): ``lobovsky_2d`` with the reference's
four wall-pressure sensors and walls 3H high, the geometry of Colagrossi & Landrini (2003) and Marrone
et al. (2011) that the reference ran. Lobovsky's own tank is 2H: a run-up without wall friction spills
over its downstream wall from t sqrt(g/H) = 3.4."""
import yaml

from .schema import load_scene, parse_scene

HEIGHTS = (0.01, 0.05, 0.1, 0.8 / 3)  # [H] the reference's sensors P1-P4 up the downstream wall
FACE = 8.4 / 600  # [H] the reference's sensor face (8.4 mm at its H = 0.6 m)


def decourcy_scene(reading: str = "wall", height: float = 3.0):
    """(scene, H): lobovsky_2d with sensors ``sensor_1`` to ``sensor_4`` at HEIGHTS, read as
    ``reading`` says (measure/sensors.py), no level gauges, and walls ``height`` H high."""
    data = yaml.safe_load(load_scene("lobovsky_2d").text)
    H, L = data["depth"], data["tank"][0]
    data["tank"] = [L, height * H]
    data["probes"] = {f"sensor_{k + 1}": {"type": "pressure_sensor", "position": [L, z * H], "normal": [-1, 0],
                                          "diameter": FACE * H, "reading": reading} for k, z in enumerate(HEIGHTS)}
    data["analysis"] = {"case": "lobovsky"}
    return parse_scene(data), H
