"""A passive crowd on a bridge, measured: the occupied first mode against the coupled model's (issue 48).

The published numbers: Table 3 of "Experimental and numerical investigation of the effect of standing people on
dynamic properties of a beam-like bridge", Mathematical Problems in Engineering 2017, article 1710820 (read from
its stored page, https://preview.hindawi.com/journals/mpe/2017/1710820/tab3; the article's text was not
read). For 0-15 people standing on a purpose-built bridge, the first vertical bending mode measured with
straight and with bent knees, and the frequency of the authors' FE model with the occupants attached as
masses ("equivalent mass"), against a mass ratio occupants/bridge.

What is not in the table (the bridge's modal mass, where the people stood, their masses) is not needed
here, and nothing is invented for it: for one mode and people who are alike, the structure feels the crowd
only through ``sum_i phi_i^2 M_i`` (:class:`~smd_statespace.structure.Coupling`'s dynamic stiffness), and the
authors' FE frequency with the people as rigid masses gives that sum as a share of the modal mass,
``mu = (f_empty / f_mass)^2 - 1``. So each occupancy is the library's SDOF structure (the empty bridge's
2.83 Hz, 0.42 %) with one SMD person of mass ``mu`` times the modal mass at ``phi = 1``, and its occupied
mode (:func:`~smd_statespace.structure.occupied_eigenvalues`) is compared with the measured one for

- the passive person the library uses (:data:`~smd_statespace.structure.PASSIVE`, 5.0 Hz and 0.40), and
- the passive SMD that fits each posture best (least squares on frequency and damping, all occupancies),
  what the measurement says a standing person is in this model::

    python benchmarks/structure_published.py

Assumed: the "equivalent mass" column is the people's whole body mass at their places (if the authors used
a reduced equivalent mass, ``mu`` is too small by that factor); one mode; the people alike.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import optimize

from accuracy import markdown_table  # benchmarks/, the script's own folder
from smd_statespace.structure import PASSIVE, Coupling, occupied_eigenvalues, sdof
from smd_statespace.structure.coupled import modes_of

SOURCE = "Math. Probl. Eng. 2017, 1710820, Table 3"
TABLE3 = pd.DataFrame(
    [(0, 0.000, 2.82, 2.83, 0.42, 2.83, 0.42),
     (1, 0.025, 2.73, 2.73, 0.94, 2.73, 2.20),
     (3, 0.071, 2.62, 2.60, 1.05, 2.63, 5.61),
     (5, 0.110, 2.54, 2.57, 1.23, 2.59, 7.55),
     (7, 0.155, 2.48, 2.48, 1.43, 2.50, 8.16),
     (9, 0.182, 2.46, 2.42, 1.42, 2.47, 8.38),
     (13, 0.255, 2.43, 2.41, 1.45, 2.44, 9.19),
     (15, 0.291, 2.42, 2.40, 1.44, 2.42, 9.57)],
    columns=["people", "mass_ratio", "f_mass", "f_straight", "zeta_straight_pct", "f_bent", "zeta_bent_pct"])
"""The table as printed: people, mass ratio occupants/bridge, the FE frequency with the people as masses (Hz),
then frequency (Hz) and modal damping ratio (%) measured with straight knees and with bent knees."""

EMPTY = {"f_hz": 2.83, "zeta": 0.0042}
"""The empty bridge's first mode as measured (the table's first row)."""

MODAL_MASS = 1000.0
"""Any modal mass (kg): only the ratio ``mu`` enters."""


def crowd_share(row) -> float:
    """``mu``: the occupants' ``sum phi_i^2 M_i`` over the modal mass, from the FE frequency with them as masses."""
    return float((TABLE3["f_mass"].iloc[0] / row["f_mass"]) ** 2 - 1.0)


def occupied_mode(mu: float, f_p: float, zeta_p: float) -> dict:
    """The occupied first mode ``{"f_hz", "zeta"}`` of the empty bridge with a passive SMD of mass ``mu``."""
    structure = sdof(EMPTY["f_hz"], EMPTY["zeta"], MODAL_MASS)
    if mu <= 0:
        return {"f_hz": EMPTY["f_hz"], "zeta": EMPTY["zeta"]}
    coupling = Coupling(structure, [0], [mu * MODAL_MASS], [f_p], [zeta_p])
    return modes_of(occupied_eigenvalues(coupling))[0]


def predictions(f_p: float, zeta_p: float) -> pd.DataFrame:
    """The occupied mode at every occupancy of the table."""
    rows = [occupied_mode(crowd_share(row), f_p, zeta_p) for _, row in TABLE3.iterrows()]
    return pd.DataFrame(rows, index=TABLE3.index)


def best_passive(posture: str) -> tuple:
    """The passive SMD ``(f_p, zeta_p)`` whose occupied modes fit the posture's measured ones best (frequency
    in units of 0.01 Hz, damping in units of 0.1 %: the table's last digits)."""
    measured_f, measured_z = TABLE3[f"f_{posture}"], TABLE3[f"zeta_{posture}_pct"] / 100.0

    def misfit(x):
        modes = predictions(np.exp(x[0]), 2.0 / (1.0 + np.exp(-x[1])))
        return np.concatenate([(modes["f_hz"] - measured_f) / 0.01, (modes["zeta"] - measured_z) / 0.001])

    best = optimize.least_squares(misfit, x0=[np.log(5.0), 0.0])
    return float(np.exp(best.x[0])), float(2.0 / (1.0 + np.exp(-best.x[1])))


def main() -> int:
    out = TABLE3[["people", "mass_ratio"]].copy()
    out["mu"] = [crowd_share(row) for _, row in TABLE3.iterrows()]
    library = predictions(PASSIVE["f_h"], PASSIVE["xi_h"])
    fits = {posture: best_passive(posture) for posture in ("straight", "bent")}
    for posture in ("straight", "bent"):
        out[f"{posture}: f, zeta % measured"] = [f"{f:.2f}, {z:.2f}" for f, z in
                                                zip(TABLE3[f"f_{posture}"], TABLE3[f"zeta_{posture}_pct"])]
    out["PASSIVE 5.0 Hz, 0.40: f, zeta %"] = [f"{f:.2f}, {100 * z:.2f}" for f, z in
                                              zip(library["f_hz"], library["zeta"])]
    for posture, (f_p, zeta_p) in fits.items():
        fitted = predictions(f_p, zeta_p)
        out[f"best for {posture} ({f_p:.2f} Hz, {zeta_p:.2f}): f, zeta %"] = [
            f"{f:.2f}, {100 * z:.2f}" for f, z in zip(fitted["f_hz"], fitted["zeta"])]
    print(f"{SOURCE}; the occupied first mode of the bridge (2.83 Hz, 0.42 % empty) with mu = sum phi^2 M / "
          "modal mass from the FE frequency with the people as masses")
    print(markdown_table(out, {"mass_ratio": ".3f", "mu": ".3f"}))
    for posture in ("straight", "bent"):
        error_f = library["f_hz"] - TABLE3[f"f_{posture}"]
        error_z = 100 * library["zeta"] - TABLE3[f"zeta_{posture}_pct"]
        print(f"PASSIVE against {posture} knees (1-15 people): frequency {error_f[1:].min():+.3f} to "
              f"{error_f[1:].max():+.3f} Hz, damping {error_z[1:].min():+.2f} to {error_z[1:].max():+.2f} "
              "percentage points")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
