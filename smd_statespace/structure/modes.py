"""The structure as modes: a modal model read from an FE program's export, checked, and built-in examples.

A structure is described by ``m`` vertical modes and the places people can stand:

``modes.csv``
    one row per mode: ``f_hz`` (natural frequency, Hz, > 0), ``zeta`` (damping
    ratio, fraction, > 0) and ``mass_kg`` (modal mass of the shapes as given, kg, > 0);
``shapes.csv``
    one row per point: ``point`` (a name), ``x_m``, ``y_m`` (position, m, for
    figures only) and ``phi_1 ... phi_m`` (the mode shapes' vertical ordinates
    there, -; any normalisation, consistent with ``mass_kg``).

Each problem is a :class:`~smd_statespace.errors.RecordError` of one line naming
the file, row and column. The examples: :func:`sdof` (one mode, one point),
:func:`beam` (a simply supported beam with its analytic modes) and :func:`plate`
(the article's plate, Table 3, at mid-span, as
:meth:`smd_statespace.simulation.floor.FloorModel.table3` reads it).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import OptionError, RecordError
from ..simulation.floor import FloorModel

__all__ = ["ModalModel", "read_modal_model", "sdof", "beam", "plate", "EXAMPLES"]

MODE_COLUMNS = ("f_hz", "zeta", "mass_kg")
"""Columns of ``modes.csv``."""


@dataclass(frozen=True, eq=False)
class ModalModel:
    """Vertical modes of a structure and the points people can stand on.

    Parameters
    ----------
    frequency : ndarray, shape (m,)
        Natural frequencies ``f_j`` (Hz).
    damping : ndarray, shape (m,)
        Damping ratios ``zeta_j`` (-).
    modal_mass : ndarray, shape (m,)
        Modal masses ``m_j`` (kg) of the shapes as given.
    points : tuple of str
        Point names.
    coordinates : ndarray, shape (P, 2)
        ``x_m, y_m`` of each point (m).
    shapes : ndarray, shape (P, m)
        Mode-shape ordinates ``phi_j`` at each point (-).
    name : str
        Label for summaries and figures.
    """

    frequency: np.ndarray
    damping: np.ndarray
    modal_mass: np.ndarray
    points: tuple
    coordinates: np.ndarray
    shapes: np.ndarray
    name: str = "structure"

    @property
    def n_modes(self) -> int:
        """Number of modes ``m``."""
        return int(self.frequency.size)

    @property
    def omega(self) -> np.ndarray:
        """Circular natural frequencies ``2 pi f_j`` (rad/s)."""
        return 2.0 * np.pi * self.frequency

    def empty_modes(self) -> list:
        """``[{"f_hz", "zeta"}, ...]`` of the empty structure."""
        return [{"f_hz": float(f), "zeta": float(z)} for f, z in zip(self.frequency, self.damping)]

    def index(self, names, source="people") -> np.ndarray:
        """Row numbers of the points ``names`` in :attr:`shapes`; a :class:`RecordError` for an unknown one.

        Parameters
        ----------
        names : sequence of str
            Point names, one per person.
        source : str
            How the message names the table the names come from.
        """
        where = {name: k for k, name in enumerate(self.points)}
        names = [str(n) for n in names]
        for row, name in enumerate(names, start=1):
            if name not in where:
                shown = ", ".join(self.points[:8]) + (", ..." if len(self.points) > 8 else "")
                raise RecordError(f"{source} row {row}, column point: {name!r} is not a point of the shapes "
                                  f"({len(self.points)} points: {shown})")
        return np.array([where[n] for n in names], dtype=int)

    def check_rate(self, rate, source="modes.csv") -> None:
        """An :class:`OptionError` when a mode is at or above the Nyquist frequency ``rate / 2`` (Hz)."""
        nyquist = 0.5 * float(rate)
        above = np.flatnonzero(self.frequency >= nyquist)
        if above.size:
            row = int(above[0])
            raise OptionError(f"{source} row {row + 1}, column f_hz: {self.frequency[row]:g} Hz is at or above the "
                              f"Nyquist frequency {nyquist:g} Hz of the rate {float(rate):g} Hz; use a rate above "
                              f"{2 * self.frequency.max():g} Hz or leave the mode out")

    def write(self, modes_path, shapes_path):
        """Write ``modes.csv`` and ``shapes.csv`` (the layout :func:`read_modal_model` reads)."""
        pd.DataFrame({"f_hz": self.frequency, "zeta": self.damping, "mass_kg": self.modal_mass}).to_csv(
            modes_path, index=False, float_format="%.10g")
        shapes = pd.DataFrame({"point": self.points, "x_m": self.coordinates[:, 0], "y_m": self.coordinates[:, 1]})
        for j in range(self.n_modes):
            shapes[f"phi_{j + 1}"] = self.shapes[:, j]
        shapes.to_csv(shapes_path, index=False, float_format="%.10g")
        return Path(modes_path), Path(shapes_path)


def _read_csv(path, label, **options):
    """A CSV file as a DataFrame, or a one-line :class:`RecordError` saying why it cannot be read."""
    try:
        return pd.read_csv(path, **options)
    except FileNotFoundError:
        raise RecordError(f"{label} {path}: no such file") from None
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise RecordError(f"{label} {path}: not a readable CSV ({' '.join(str(exc).split())})") from None


def _column(frame, name, path, low=0.0, strict=True, optional=False):
    """Column ``name`` of ``frame`` as finite floats, or a one-line error naming its row and what is valid.

    ``low``: the values must be above it (``strict``) or at least it; None for any finite number. ``optional``
    (a people table's cells, drawn where empty): a missing column or an empty cell is NaN.
    """
    if name not in frame.columns:
        if optional:
            return np.full(len(frame), np.nan)
        raise RecordError(f"{path}: missing column {name!r} (columns: {', '.join(map(str, frame.columns))})")
    values = pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
    valid = np.isfinite(values) & (True if low is None else (values > low) if strict else (values >= low))
    bad = ~valid & (frame[name].notna().to_numpy() if optional else True)
    if np.any(bad):
        row = int(np.flatnonzero(bad)[0])
        need = "a finite number" if low is None else f"a number {'>' if strict else '>='} {low:g}"
        raise RecordError(f"{path} row {row + 1}, column {name}: {frame[name].tolist()[row]!r} is not valid; "
                          f"it must be {need}" + (" (or empty, to draw it)" if optional else ""))
    return values


def read_modal_model(modes_path, shapes_path, name=None) -> ModalModel:
    """Read ``modes.csv`` and ``shapes.csv`` (module docstring) into a :class:`ModalModel`.

    Parameters
    ----------
    modes_path, shapes_path : str or path-like
    name : str, optional
        Label (default the modes file's stem).

    Raises
    ------
    RecordError
        A missing file or column, a value that is not a positive number (a
        negative or zero frequency, damping or mass), a shapes file whose
        ``phi_j`` columns do not match the modes' rows, a repeated point name.
    """
    modes, shapes = _read_csv(modes_path, "--modes"), _read_csv(shapes_path, "--shapes")
    if modes.empty:
        raise RecordError(f"{modes_path}: no modes (one row per mode: {', '.join(MODE_COLUMNS)})")
    values = {column: _column(modes, column, modes_path) for column in MODE_COLUMNS}
    m = len(modes)
    given = sorted(int(c[4:]) for c in shapes.columns if str(c).startswith("phi_") and str(c)[4:].isdigit())
    if given != list(range(1, m + 1)):
        raise RecordError(f"{shapes_path}: has mode-shape columns {', '.join(f'phi_{j}' for j in given) or 'none'}, "
                          f"{modes_path} has {m} modes; it needs phi_1 ... phi_{m}, one per mode row")
    if "point" not in shapes.columns or shapes.empty:
        raise RecordError(f"{shapes_path}: missing column 'point' or no rows (columns point, x_m, y_m, phi_1 ...)")
    points = tuple(str(p) for p in shapes["point"])
    seen = pd.Index(points)
    if seen.has_duplicates:
        row = int(np.flatnonzero(seen.duplicated())[0])
        raise RecordError(f"{shapes_path} row {row + 1}, column point: {points[row]!r} appears twice")
    coordinates = np.column_stack([_column(shapes, c, shapes_path, low=None) for c in ("x_m", "y_m")])
    phi = np.column_stack([_column(shapes, f"phi_{j}", shapes_path, low=None) for j in range(1, m + 1)])
    return ModalModel(values["f_hz"], values["zeta"], values["mass_kg"], points, coordinates, phi,
                      name=Path(modes_path).stem if name is None else str(name))


def sdof(f_hz=4.0, zeta=0.01, mass_kg=20000.0) -> ModalModel:
    """One mode, one point ``"P1"`` with ``phi = 1``: a single-degree-of-freedom structure.

    Parameters
    ----------
    f_hz : float
        Natural frequency (Hz); default 4, hit by the second harmonic of 2 Hz bouncing.
    zeta : float
        Damping ratio (-), default 0.01.
    mass_kg : float
        Modal mass (kg), default 20 t.
    """
    if not (f_hz > 0 and zeta > 0 and mass_kg > 0):
        raise OptionError(f"sdof: f_hz, zeta and mass_kg must be > 0, got {f_hz!r}, {zeta!r}, {mass_kg!r}")
    return ModalModel(np.array([float(f_hz)]), np.array([float(zeta)]), np.array([float(mass_kg)]), ("P1",),
                      np.zeros((1, 2)), np.ones((1, 1)), name=f"SDOF {f_hz:g} Hz")


def beam(length=15.0, mass_per_m=2000.0, f1_hz=4.0, zeta=0.01, n_modes=3, n_points=31) -> ModalModel:
    """A simply supported beam (or one-way slab strip) with its analytic modes.

    Mode ``j``: ``phi_j(x) = sin(j pi x / L)``, ``f_j = j^2 f_1`` (Euler-Bernoulli,
    ``f_1 = (pi / 2 L^2) sqrt(EI / m_bar)``), modal mass ``m_bar L / 2``; the points
    are equally spaced from one support to the other, ``x0 ... x30``.

    Parameters
    ----------
    length : float
        Span ``L`` (m).
    mass_per_m : float
        Mass per length ``m_bar`` (kg/m), the structure's own.
    f1_hz : float
        First natural frequency (Hz), which fixes ``EI``.
    zeta : float
        Damping ratio of every mode (-).
    n_modes : int
        Modes kept.
    n_points : int
        Points along the span (>= 3).
    """
    if not (length > 0 and mass_per_m > 0 and f1_hz > 0 and zeta > 0 and n_modes >= 1 and n_points >= 3):
        raise OptionError("beam: length, mass_per_m, f1_hz and zeta must be > 0, n_modes >= 1, n_points >= 3")
    orders = np.arange(1, int(n_modes) + 1)
    x = np.linspace(0.0, float(length), int(n_points))
    shapes = np.sin(np.outer(x, orders) * np.pi / float(length))
    shapes[np.abs(shapes) < 1e-12] = 0.0
    return ModalModel(orders**2 * float(f1_hz), np.full(orders.size, float(zeta)),
                      np.full(orders.size, 0.5 * float(mass_per_m) * float(length)),
                      tuple(f"x{k}" for k in range(int(n_points))), np.column_stack([x, np.zeros_like(x)]), shapes,
                      name=f"simply supported beam {length:g} m, f1 {f1_hz:g} Hz")


def plate(modes=None) -> ModalModel:
    """The article's laboratory plate (Table 3) at one point, ``"mid-span"``, with ``phi = 1``.

    The modes :meth:`~smd_statespace.simulation.floor.FloorModel.table3` keeps,
    with its reading of the modal masses as driving-point masses at mid-span
    (its module docstring says why that is exact for mode 1 and an upper bound
    for the others).

    Parameters
    ----------
    modes : sequence of int, optional
        Mode numbers 1-6 to keep (default all six).
    """
    floor = FloorModel.table3(modes)
    return ModalModel(np.array(floor.frequency), np.array(floor.damping), np.array(floor.modal_mass), ("mid-span",),
                      np.array([[5.0, 3.0]]), np.array([floor.shape]), name="plate of Table 3, mid-span")


EXAMPLES = {"sdof": sdof, "beam": beam, "plate": plate}
"""Built-in structures by name (``smd-statespace structure --example NAME``)."""
