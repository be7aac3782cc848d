"""Reading identified cycles for the population statistics: ``results.csv`` tables, the parameters of Table 2, their checks."""

from __future__ import annotations

import os
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import pandas as pd

from ..errors import OptionError, RecordError
from ..identify.plausibility import implausible_reasons

__all__ = ["ParameterSpec", "PARAMETERS", "ADEQUATE_COLUMN", "parse_parameters", "read_results"]


class ParameterSpec(NamedTuple):
    """One parameter of Table 2: article name, ``results.csv`` column, unit, flags that say it is determined."""

    name: str
    column: str
    unit: str
    determined_by: tuple[str, ...]


PARAMETERS = MappingProxyType({
    "f_h": ParameterSpec("f_h", "f_h", "Hz", ("f_h_determined",)),
    "xi_h": ParameterSpec("xi_h", "xi_h", "-", ("xi_h_determined",)),
    "K_h": ParameterSpec("K_h", "k_h", "N/m", ("f_h_determined",)),
    "C_h": ParameterSpec("C_h", "c_h", "N s/m", ("f_h_determined", "xi_h_determined")),
    "BLF1": ParameterSpec("BLF1", "blf_1", "g", ("blf_1_determined",)),
    "BLF2": ParameterSpec("BLF2", "blf_2", "g", ("blf_2_determined",)),
    "BLF3": ParameterSpec("BLF3", "blf_3", "g", ("blf_3_determined",)),
})
"""The parameters of Table 2, in its order (see :data:`article.TABLE2_PARAMETERS`).

``K_h`` is determined when ``f_h`` is (Eq. 17), ``C_h`` when ``f_h`` and ``xi_h`` are (Eq. 18).
"""


ADEQUATE_COLUMN = "model_adequate"
"""Optional True/False column: False marks the cycles of a record whose model was found inadequate
(for example by ``smd-statespace diagnose``); they are left out like implausible cycles. Blank: adequate."""

_STATUS_OK = "ok"


_TRUE = {"true", "1", "1.0", "yes"}
_FALSE = {"false", "0", "0.0", "no"}


def _flags(values: pd.Series, source: str, column: str, missing: bool = False) -> np.ndarray:
    """A True/False column (bools, 'True'/'False', 1/0; blank -> ``missing``) or a RecordError naming the bad value."""
    if values.dtype == bool:
        return values.to_numpy()
    text = values.astype(str).str.strip().str.lower()
    blank = (values.isna() | (text == "")).to_numpy()
    true = text.isin(_TRUE).to_numpy()
    bad = ~(true | text.isin(_FALSE).to_numpy() | blank)
    if bad.any():
        row = int(np.argmax(bad))
        raise RecordError(f"{source}: column {column!r}, data row {row + 1}: {values.iloc[row]!r} is not True or False")
    return np.where(blank, missing, true)


def _numeric(values: pd.Series, source: str, column: str) -> np.ndarray:
    """A numeric column (blank -> NaN) or a RecordError naming the first value that is not a number."""
    numbers = pd.to_numeric(values, errors="coerce")
    bad = numbers.isna() & values.notna() & (values.astype(str).str.strip() != "")
    if bad.any():
        row = int(np.argmax(bad.to_numpy()))
        raise RecordError(f"{source}: column {column!r}, data row {row + 1}: {values.iloc[row]!r} is not a number")
    return numbers.to_numpy(dtype=float)


def _one_source(item, index: int) -> tuple[pd.DataFrame, str]:
    if isinstance(item, pd.DataFrame):
        return item.copy(), str(item.attrs.get("source", f"<DataFrame {index}>"))
    if not isinstance(item, (str, os.PathLike)):
        raise OptionError(f"results: expected a results.csv path or a DataFrame, got {type(item).__name__}")
    source = os.fspath(item)
    try:
        frame = pd.read_csv(source)
    except pd.errors.EmptyDataError:
        raise RecordError(f"{source}: empty file (expected a table of cycles with columns f_b and the "
                          "parameters, e.g. the results.csv of 'smd-statespace identify')") from None
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or exc
        raise RecordError(f"{source}: cannot read ({reason})") from None
    except pd.errors.ParserError as exc:
        raise RecordError(f"{source}: not a readable CSV ({' '.join(str(exc).split())})") from None
    return frame, source


def parse_parameters(parameters, *, option: str = "parameters") -> tuple[str, ...]:
    """Names of :data:`PARAMETERS` from names or columns, any case: ``"f_h,BLF1"``, ``["k_h", "blf_2"]``.

    Raises
    ------
    OptionError
        An unknown name (the message names ``option`` and lists the valid names), or none.
    """
    items = parameters.split(",") if isinstance(parameters, str) else list(parameters)
    lookup = {}
    for name, spec in PARAMETERS.items():
        lookup[name.lower()] = name
        lookup[spec.column.lower()] = name
    names = []
    for item in items:
        key = str(item).strip().lower()
        if key not in lookup:
            raise OptionError(f"{option}: unknown parameter {str(item).strip()!r}; valid: {', '.join(PARAMETERS)} "
                              "(or their columns f_h, xi_h, k_h, c_h, blf_1, blf_2, blf_3)")
        if lookup[key] not in names:
            names.append(lookup[key])
    if not names:
        raise OptionError(f"{option}: give at least one of {', '.join(PARAMETERS)}")
    return tuple(names)


_DERIVED = {"K_h": ("f_h",), "C_h": ("f_h", "xi_h")}  # Eq. 17, Eq. 18: computed from these and the mass


def _lacks(frame: pd.DataFrame, name: str, mass) -> str:
    """Why ``frame`` cannot give parameter ``name`` (empty when it can)."""
    spec = PARAMETERS[name]
    if spec.column in frame:
        return ""
    if name not in _DERIVED:
        return f"no column {spec.column!r} for {name}"
    missing = [column for column in _DERIVED[name] if column not in frame]
    if missing:
        return f"no column {spec.column!r} for {name}, nor {', '.join(missing)} to compute it"
    if "mass" not in frame and mass is None:
        equation = "Eq. 17" if name == "K_h" else "Eq. 18"
        return (f"no column {spec.column!r} for {name} and no body mass to compute it by {equation} "
                "(add a 'mass' column in kg or give --mass KG)")
    return ""


_SINGULAR = {"cycles": "cycle", "people": "person", "rows": "row"}


def row_noun(frame: pd.DataFrame) -> str:
    """What one row of an identification table is, in the plural: ``"people"`` or ``"cycles"``.

    The record-level model (``identify --estimator record``) writes one row per person
    (``n_cycles`` says how many cycles it saw, there is no ``cycle`` column); the per-cycle
    estimators write one row per cycle.
    """
    return "people" if "cycle" not in frame and "n_cycles" in frame else "cycles"


def _columns(frame: pd.DataFrame) -> str:
    names = [str(c) for c in frame.columns]
    return ", ".join(names[:15]) + (f", ... ({len(names)} columns)" if len(names) > 15 else "")


def _loaded_source(item, index: int) -> tuple[pd.DataFrame, str]:
    """One source as a table with stripped column names and an ``f_b`` column, or an error in words."""
    frame, source = _one_source(item, index)
    frame.columns = [str(c).strip() for c in frame.columns]
    if frame.empty:
        raise RecordError(f"{source}: no rows (a header only; expected one row per cycle)")
    if "f_b" not in frame:
        raise RecordError(f"{source}: no column 'f_b' (the bouncing frequency of each cycle, Hz); "
                          f"the columns are {_columns(frame)}")
    return frame, source


def _chosen_parameters(loaded, asked, explicit: bool, mass) -> tuple[list, list]:
    """The parameters every source gives, and a note for each one left out.

    A parameter asked for explicitly (``--parameters``) that a source cannot give is an error
    naming that source and its columns.
    """
    notes, chosen = [], []
    for name in asked:
        lacking = [(source, why) for frame, source in loaded if (why := _lacks(frame, name, mass))]
        if not lacking:
            chosen.append(name)
        elif explicit:
            source, why = lacking[0]
            frame = next(f for f, s in loaded if s == source)
            raise RecordError(f"{source}: {why}, asked for by --parameters; the columns are {_columns(frame)}")
        else:
            notes.append(f"{name} left out: {lacking[0][1]} in {', '.join(s for s, _ in lacking)}")
    if not chosen:
        frame, source = loaded[0]
        raise RecordError(f"{source}: none of the parameter columns f_h, xi_h, k_h, c_h, blf_1, blf_2, blf_3; "
                          f"the columns are {_columns(frame)}")
    return chosen, notes


class _Assumed:
    """What :func:`read_results` assumed for columns a source lacks, said once per source in its notes."""

    def __init__(self):
        self.derived = {}  # (source, where the mass came from) -> [K_h, C_h]
        self.unflagged = {}  # source -> [*_determined columns taken as True]
        self.unstatused = []  # sources without a status column
        self.unchecked = []  # sources checked here against the physical limits

    def notes(self, flags, noun: str = "cycles") -> list:
        notes = [f"{', '.join(names)} computed by Eq. 17-18 from f_h, xi_h and {where} ({source})"
                 for (source, where), names in self.derived.items()]
        if self.unstatused:
            notes.append(f"no status column in {', '.join(self.unstatused)}: every row taken as an identified "
                         f"{_SINGULAR.get(noun, noun)}")
        for source, columns in self.unflagged.items():
            named = "*_determined columns" if len(columns) == len(flags) > 1 else (
                f"{', '.join(columns)} column{'s' if len(columns) > 1 else ''}")
            notes.append(f"no {named} in {source}: its {noun} are treated as determined")
        if self.unchecked:
            notes.append(f"no implausible column in {', '.join(self.unchecked)}: {noun} checked here against the "
                         "physical limits (xi_h < 0, C_h < 0, BLF or floor-force harmonic > 2 g)")
        return notes


def _parameter_columns(frame, source, chosen, mass, assumed: _Assumed) -> None:
    """``f_b`` and the chosen parameters' columns as floats; ``K_h``/``C_h`` by Eq. 17-18 where absent."""
    from ..model import c_h, k_h

    frame["f_b"] = _numeric(frame["f_b"], source, "f_b")
    for name in chosen:
        column = PARAMETERS[name].column
        if column in frame:
            frame[column] = _numeric(frame[column], source, column)
            continue
        if "mass" in frame:
            masses = _numeric(frame["mass"], source, "mass")
            bad = ~(masses > 0) & np.isfinite(masses)
            if bad.any():
                row = int(np.argmax(bad))
                raise RecordError(f"{source}: column 'mass', data row {row + 1}: {frame['mass'].iloc[row]!r} "
                                  "is not a body mass (a positive number of kg)")
            where = "its 'mass' column"
        else:
            masses, where = np.full(len(frame), mass), f"--mass {mass:g} kg"
        f_h = _numeric(frame["f_h"], source, "f_h")
        if name == "K_h":
            frame[column] = k_h(f_h, masses)  # Eq. 17
        else:
            frame[column] = c_h(_numeric(frame["xi_h"], source, "xi_h"), f_h, masses)  # Eq. 18
        assumed.derived.setdefault((source, where), []).append(name)


def _flag_columns(frame, source, flags, assumed: _Assumed) -> None:
    """The ``*_determined`` flags as bools (True where absent) and ``status`` as lower-case text."""
    for column in flags:
        if column in frame:
            frame[column] = _flags(frame[column], source, column)
        else:
            frame[column] = True
            assumed.unflagged.setdefault(source, []).append(column)
    if "status" in frame:
        frame["status"] = frame["status"].astype(str).str.strip().str.lower()
    else:
        frame["status"] = _STATUS_OK
        assumed.unstatused.append(source)


def _plausibility_columns(frame, source, assumed: _Assumed) -> None:
    """``implausible`` with its reason (checked here when absent) and :data:`ADEQUATE_COLUMN`."""
    if "implausible" in frame:
        frame["implausible"] = _flags(frame["implausible"], source, "implausible")
        reason = frame["implausible_reason"] if "implausible_reason" in frame else pd.Series("", index=frame.index)
        reason = reason.astype(object).where(reason.notna(), "").astype(str)
        frame["implausible_reason"] = reason.where(frame["implausible"], "")
    else:
        checked = frame[[c for c in ["f_b", "f_h", "xi_h", "c_h"] + [f"blf_{i}" for i in range(1, 10)]
                         if c in frame]]
        reasons = implausible_reasons(checked)
        reasons[frame["status"] != _STATUS_OK] = ""
        frame["implausible_reason"] = reasons
        frame["implausible"] = (reasons != "").to_numpy()
        assumed.unchecked.append(source)
    frame[ADEQUATE_COLUMN] = (_flags(frame[ADEQUATE_COLUMN], source, ADEQUATE_COLUMN, missing=True)
                              if ADEQUATE_COLUMN in frame else True)


def read_results(sources, *, parameters=None, mass=None) -> pd.DataFrame:
    """Read and check one or many tables of identified cycles (``results.csv`` of ``identify`` or any other).

    A table needs a column ``f_b`` (Hz) and the columns of the parameters: ``f_h``, ``xi_h``,
    ``k_h``, ``c_h``, ``blf_1..3`` (see :data:`PARAMETERS`). Everything else is optional:

    - no ``status`` column: every row is taken as an identified (``ok``) cycle;
    - no ``*_determined`` column: the cycles are treated as determined;
    - no ``k_h``/``c_h``: computed by Eq. 17-18 from ``f_h``, ``xi_h`` and a ``mass`` column or
      ``mass``; with neither, ``K_h``/``C_h`` are left out (an error when asked for);
    - no ``implausible`` column: the cycles are checked here against the physical limits of
      :func:`smd_statespace.identify.plausibility.implausible_reasons` (no prior is known);
    - no :data:`ADEQUATE_COLUMN`: the cycles are taken as from an adequate model.

    Each of these is said once in ``attrs["notes"]`` of the result.

    Parameters
    ----------
    sources : path, DataFrame or sequence of them
        CSV files or tables (a DataFrame's ``attrs["source"]`` names it in messages, default
        ``<DataFrame i>``).
    parameters : sequence of str or str, optional
        Parameters asked for (names of :data:`PARAMETERS` or their columns, see
        :func:`parse_parameters`): every source must give them. Default: every parameter that
        all sources give; the others are left out with a note.
    mass : float, optional
        Body mass (kg) of the tables without a ``mass`` column, for ``K_h`` and ``C_h``.

    Returns
    -------
    pandas.DataFrame
        All rows of all sources, with a ``source`` column; ``f_b`` (Hz) and the parameter
        columns as floats, ``status`` as lower-case text, the flags (``*_determined``,
        ``implausible``, :data:`ADEQUATE_COLUMN`) as bools, ``implausible_reason`` as text.
        ``attrs["parameters"]`` holds the parameters read, ``attrs["notes"]`` what was assumed
        or left out, ``attrs["noun"]`` what a row is (``"cycles"``, ``"people"`` or, for a mix of
        both, ``"rows"``; see :func:`row_noun`).

    Raises
    ------
    RecordError
        A file that cannot be read or is empty, no ``f_b`` column, a parameter asked for that a
        source cannot give (named with its file and column), no parameter at all, a value that
        is not a number or not True/False, a body mass that is not positive (named with its row).
    OptionError
        An unknown parameter, a bad ``mass``.
    """
    from ..io import check_mass

    if isinstance(sources, (str, os.PathLike, pd.DataFrame)):
        sources = [sources]
    sources = list(sources)
    if not sources:
        raise OptionError("results: give at least one table of identified cycles (results.csv)")
    explicit = parameters is not None
    asked = parse_parameters(PARAMETERS if parameters is None else parameters,
                             option="--parameters" if explicit else "parameters")
    if mass is not None:
        mass = check_mass(mass, "--mass")
    loaded = [_loaded_source(item, index) for index, item in enumerate(sources)]
    chosen, notes = _chosen_parameters(loaded, asked, explicit, mass)
    flags = sorted({flag for name in chosen for flag in PARAMETERS[name].determined_by})
    assumed = _Assumed()
    frames = []
    for frame, source in loaded:
        _parameter_columns(frame, source, chosen, mass, assumed)
        _flag_columns(frame, source, flags, assumed)
        _plausibility_columns(frame, source, assumed)
        frame.insert(0, "source", source)
        frames.append(frame)
    kinds = {row_noun(frame) for frame in frames}
    noun = kinds.pop() if len(kinds) == 1 else "rows"
    notes += assumed.notes(flags, noun)
    table = pd.concat(frames, ignore_index=True, sort=False)
    table.attrs = {"parameters": tuple(chosen), "notes": notes, "noun": noun}
    return table


# ---------------------------------------------------------------------------
# skew-normal fit (Eq. 19)
