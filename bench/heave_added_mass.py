"""The heave added mass and radiation damping of a 2D box section, by linear potential-flow theory:
a boundary element method (Capytaine, Ancellin & Dias 2019, https://github.com/capytaine/capytaine)
on long 3D boxes of the section, L = 20 B and 40 B, extrapolated to an infinite one (a33(L) = a33 +
c / L: a33 = 2 a33(2L) - a33(L)), per metre of length. Writes the table that
``tests/test_bodies.py`` compares a floating box's heave with (data/heave_added_mass/README.md).
With ``--length L``, those of the 3D box L x B itself (kg, N s/m: no extrapolation), which
``bench/floating_draft.py --dim 3`` compares the 3D box's heave with.

Capytaine is not a dependency of the package: ``pip install capytaine==3.0.0`` in a venv of its own.

    python bench/heave_added_mass.py [--beam 0.2] [--draft 0.05] [--depth 0.3] [--length L] [--out CSV]
"""
import argparse
import csv
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def per_length(length, beam, draft, depth, omegas, panel):
    """(a33, b33) per metre of a box length x beam of ``draft`` in water ``depth`` deep, at each of
    ``omegas`` [rad/s], its panels about ``panel`` [m]."""
    import capytaine as cpt

    res = (round(length / panel), round(beam / (panel / 2)), round(2 * draft / (panel / 2)))
    mesh = cpt.mesh_parallelepiped(size=(length, beam, 2 * draft), center=(0, 0, 0), resolution=res)
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(), name="box").immersed_part()
    solver = cpt.BEMSolver()
    out = []
    for omega in omegas:
        r = solver.solve(cpt.RadiationProblem(body=body, radiating_dof="Heave", omega=float(omega), water_depth=depth,
                                              rho=1000.0), keep_details=False)
        out.append((r.added_mass["Heave"] / length, r.radiation_damping["Heave"] / length))
    return np.array(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beam", type=float, default=0.2)
    ap.add_argument("--draft", type=float, default=0.05)
    ap.add_argument("--depth", type=float, default=0.3)
    ap.add_argument("--panel", type=float, default=0.05, help="[m] the panels' length (half that across)")
    ap.add_argument("--length", type=float, help="[m] a 3D box this long, its whole added mass and damping")
    ap.add_argument("--out", type=Path, help="default data/heave_added_mass/box_B0.2_T0.05_h0.3.csv (2D) or "
                                             "box3d_L0.2_B0.2_T0.05_h0.3.csv (--length)")
    args = ap.parse_args()
    omegas = np.arange(6.0, 12.01, 0.25)
    t0 = time.perf_counter()
    if args.length:
        out = args.out or REPO / "data/heave_added_mass/box3d_L0.2_B0.2_T0.05_h0.3.csv"
        whole = per_length(args.length, args.beam, args.draft, args.depth, omegas, args.panel) * args.length
        with open(out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["omega_rad_s", "a33_kg", "b33_Ns_per_m"])
            for omega, (a33, b33) in zip(omegas, whole):
                w.writerow([f"{omega:.2f}", f"{a33:.5f}", f"{b33:.5f}"])
                print(f"omega {omega:5.2f}: a33 {a33:.4f} kg, b33 {b33:.4f} N s/m")
        print(f"{out} written in {time.perf_counter() - t0:.0f} s")
        return
    args.out = args.out or REPO / "data/heave_added_mass/box_B0.2_T0.05_h0.3.csv"
    short = per_length(20 * args.beam, args.beam, args.draft, args.depth, omegas, args.panel)
    long = per_length(40 * args.beam, args.beam, args.draft, args.depth, omegas, args.panel)
    section = 2 * long - short
    with open(args.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["omega_rad_s", "a33_kg_per_m", "b33_Ns_per_m2", "a33_L20B", "a33_L40B", "b33_L20B", "b33_L40B"])
        for k, omega in enumerate(omegas):
            w.writerow([f"{omega:.2f}", f"{section[k, 0]:.4f}", f"{section[k, 1]:.4f}", f"{short[k, 0]:.4f}",
                        f"{long[k, 0]:.4f}", f"{short[k, 1]:.4f}", f"{long[k, 1]:.4f}"])
            print(f"omega {omega:5.2f}: a33 {section[k, 0]:.3f} kg/m (L = 20 B {short[k, 0]:.3f}, 40 B "
                  f"{long[k, 0]:.3f}), b33 {section[k, 1]:.3f} N s/m^2")
    print(f"{args.out} written in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
