"""Linear heave of a floating 2D section (as Newman 1977, Marine Hydrodynamics, Section 6.15; Faltinsen
1990, Sea Loads on Ships and Offshore Structures, Ch. 3): the section of mass M per metre and beam B
at the waterline, its added mass a33(omega) and radiation damping b33(omega) per metre, free to heave
about its draft, oscillates at the natural frequency that solves

    omega^2 (M + a33(omega)) = rho g B,

and a 3D body the same with its whole mass, added mass and damping and its waterplane area for B.

decaying with the damping ratio zeta = b33 / (2 (M + a33) omega), at the damped period
2 pi / (omega sqrt(1 - zeta^2)). a33 and b33 come from a table (data/heave_added_mass/: a boundary
element solution of the section), interpolated linearly in omega.
"""
import csv
import math
from pathlib import Path

import numpy as np


def table(path: Path) -> tuple:
    """(omega [rad/s], a33 [kg/m], b33 [N s/m^2]) of a data/heave_added_mass CSV of a section, or
    (omega, a33 [kg], b33 [N s/m]) of a 3D body's."""
    with open(path) as f:
        reader = csv.DictReader(f)
        a33, b33 = ("a33_kg", "b33_Ns_per_m") if "a33_kg" in reader.fieldnames else ("a33_kg_per_m", "b33_Ns_per_m2")
        rows = [(float(r["omega_rad_s"]), float(r[a33]), float(r[b33])) for r in reader]
    return tuple(np.array(c) for c in zip(*rows))


def natural(mass: float, beam: float, coefficients: tuple, rho: float = 1000.0, g: float = 9.81) -> dict:
    """The natural frequency [rad/s], added mass, damping ratio and damped period [s] of a section of
    ``mass`` [kg/m] and waterline ``beam`` [m] (a 3D body: [kg] and its waterplane area [m^2]) with
    ``coefficients`` (omega, a33, b33), by fixed-point iteration from the frequency without added
    mass."""
    omega_t, a33_t, b33_t = coefficients
    omega = math.sqrt(rho * g * beam / mass)
    for _ in range(200):
        a33 = float(np.interp(omega, omega_t, a33_t))
        new = math.sqrt(rho * g * beam / (mass + a33))
        if abs(new - omega) < 1.0e-12 * omega:
            break
        omega = new
    if not omega_t[0] <= omega <= omega_t[-1]:
        raise ValueError(f"the natural frequency {omega:.3f} rad/s is outside the table's {omega_t[0]:g}-"
                         f"{omega_t[-1]:g} rad/s")
    a33 = float(np.interp(omega, omega_t, a33_t))
    zeta = float(np.interp(omega, omega_t, b33_t)) / (2.0 * (mass + a33) * omega)
    return {"omega": omega, "added_mass": a33, "damping_ratio": zeta,
            "damped_period": 2.0 * math.pi / (omega * math.sqrt(1.0 - zeta * zeta))}
