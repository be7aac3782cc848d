"""Population statistics of identified cycles: bands, skew-normal fits, trends (Section 5).

Input is one or many tables of identified cycles, one row per cycle: the
``results.csv`` files written by ``smd-statespace identify``, or any table
(CSV or DataFrame) with a column ``f_b`` and the parameter columns asked for,
for example from the article's own data or another tool. The cycles
are assigned to bouncing-frequency bands (the article's six bands of
:data:`smd_statespace.article.BANDS`, or the user's own edges); per band, each
parameter gets its count, mean and standard deviation and a skew-normal fit
(Eq. 19) by maximum likelihood with bootstrap confidence intervals, laid out
like the article's Table 2; trend regressions in the bouncing frequency
``f_b`` (statsmodels OLS) give the "preferred frequency" at the vertex of the
quadratic trends of ``xi_h`` and BLF1.

================== =========== =========== ========================================
symbol (article)   name here   column      unit
================== =========== =========== ========================================
``f_b``            ``f_b``     ``f_b``     Hz, bouncing frequency of the cycle
``f_h``            ``f_h``     ``f_h``     Hz, SMD natural frequency
``xi_h``           ``xi_h``    ``xi_h``    -, damping ratio
``K_h`` (Eq. 17)   ``K_h``     ``k_h``     N/m, stiffness
``C_h`` (Eq. 18)   ``C_h``     ``c_h``     N*s/m, damping coefficient
``BLF_i`` (Eq. 5)  ``BLF1..3`` ``blf_1..3`` g, biomechanical load factors
``m, s, a``        ``m, s, a`` -           location, scale, shape of Eq. 19
================== =========== =========== ========================================

Which cycles count
------------------
Rows whose ``status`` is not ``"ok"`` (``failed``, ``skipped``) are left out
and counted; a table without a ``status`` column has every row taken as an
identified cycle. Cycles whose estimates cannot be true are left out and
counted unless ``include_implausible=True``: those flagged in an
``implausible`` column (written by ``identify``), or, in a table without that
column, those failing the physical limits of :mod:`smd_statespace.identify.plausibility`
(``xi_h < 0``, ``C_h < 0``, a BLF or floor-force harmonic beyond 2 g); so are
cycles of a record whose model was found inadequate (a column
:data:`ADEQUATE_COLUMN` that is False). ``ok`` cycles whose ``f_b`` lies
outside every band are counted and left out. A
cycle that did not determine a parameter (its ``*_determined`` flag is False:
the posterior sd was not under a quarter of the prior sd, see
:data:`smd_statespace.identify.runner.DETERMINED_RATIO`) is left out of that
parameter's statistics unless ``include_undetermined=True``, and the report
says how many; a table without the ``*_determined`` columns has its cycles
treated as determined, and the report says so once. ``K_h`` and ``C_h`` are
computed from ``f_h``, ``xi_h`` and the body mass (Eq. 17-18), so a cycle
determines ``K_h`` when it determines ``f_h``, and ``C_h`` when it determines
both ``f_h`` and ``xi_h``. A table without ``k_h``/``c_h`` columns gets them
by Eq. 17-18 from a ``mass`` column or the ``mass`` argument; with neither,
``K_h`` and ``C_h`` are left out with a note (an error when asked for).

Skew-normal fit (Eq. 19)
------------------------
``f(x) = (2/s) phi((x-m)/s) Phi(a (x-m)/s)`` (``scipy.stats.skewnorm(a,
loc=m, scale=s)``), fitted by maximum likelihood (the article used a genetic
algorithm) with a damped Newton (Levenberg-Marquardt) iteration on
``(m, log s, a)`` using the analytic gradient and Hessian, started from the
method of moments. The iteration is vectorised over starting points and over
bootstrap resamples. The likelihood of a skew-normal sample can keep rising
as ``|a|`` grows (the half-normal limit, common for small or strongly skewed
samples), so ``|a|`` is capped at ``a_max`` (default 50, three times the
largest shape of Table 2) and such fits are flagged ``at_bound``. Confidence
intervals are bootstrap percentiles (cycles resampled with replacement);
standard errors from the observed information are also given.

Trends (Section 5)
------------------
Ordinary least squares on the individual cycles (statsmodels ``OLS``,
heteroscedasticity-robust ``HC3`` covariance by default because the spread
grows with ``f_b`` in Table 2): ``f_h``, ``K_h``, ``C_h``, BLF2 and BLF3
linear in ``f_b``; ``xi_h`` and BLF1 quadratic, ``y = b0 + b1 f_b + b2 f_b^2``,
whose vertex ``f* = -b1 / (2 b2)`` is the "preferred frequency" (lowest
damping, highest BLF1). Its confidence interval is given two ways: the delta
method on the OLS covariance of ``(b1, b2)``, and the bootstrap percentile
interval over resampled cycles (better when ``b2`` is near zero and the ratio
is far from normal).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import pandas as pd
from scipy.special import log_ndtr

from .. import article
from ..errors import OptionError, RecordError
from ..identify.plausibility import implausible_reasons, reason_counts

__all__ = [
    "ParameterSpec",
    "PARAMETERS",
    "TREND_DEGREES",
    "MIN_CYCLES",
    "N_BOOTSTRAP",
    "A_MAX",
    "ADEQUATE_COLUMN",
    "Bands",
    "parse_parameters",
    "read_results",
    "SkewNormalResult",
    "fit_skewnorm",
    "bootstrap_skewnorm",
    "CellFit",
    "TrendResult",
    "fit_trend",
    "PopulationStats",
    "population_stats",
    "compare_table2",
]


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

TREND_DEGREES = MappingProxyType({"f_h": 1, "xi_h": 2, "K_h": 1, "C_h": 1, "BLF1": 2, "BLF2": 1, "BLF3": 1})
"""Polynomial degree in ``f_b`` of each trend (Section 5: ``f_h`` linear, ``xi_h`` and BLF1 parabolic)."""

MIN_CYCLES = 10
"""Fewest cycles in a band for a skew-normal fit (three parameters); fewer and the table says so."""

N_BOOTSTRAP = 200
"""Default number of bootstrap resamples for the confidence intervals."""

A_MAX = 50.0
"""Cap on the skew-normal shape ``|a|`` (the likelihood can rise without bound towards the half-normal)."""

ADEQUATE_COLUMN = "model_adequate"
"""Optional True/False column: False marks the cycles of a record whose model was found inadequate
(for example by ``smd-statespace diagnose``); they are left out like implausible cycles. Blank: adequate."""

_STATUS_OK = "ok"
_LOG_NORM = np.log(2.0) - 0.5 * np.log(2.0 * np.pi)  # log(2 / sqrt(2 pi)) of Eq. 19
_MAX_SKEW = 0.99  # sample skewness used for the moment start is clipped below skewnorm's limit 0.9953


# ---------------------------------------------------------------------------
# bands


class Bands:
    """Bouncing-frequency bands: validated, ordered, non-overlapping ``(low, high)`` intervals (Hz).

    A frequency ``f_b`` belongs to band ``i`` when ``low_i <= f_b < high_i``; a band's upper edge
    belongs to it when no band starts there (so the last of contiguous bands includes its upper
    edge). For the article's bands this is exactly :func:`smd_statespace.article.band_of`.

    Parameters
    ----------
    intervals : sequence of (float, float)
        Band edges in Hz, increasing, ``0 < low < high``, not overlapping (gaps are allowed).

    Raises
    ------
    OptionError
        Non-numeric, non-finite, non-positive, empty, reversed or overlapping bands.
    """

    def __init__(self, intervals, *, option: str = "bands"):
        try:
            array = np.asarray(intervals, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(
                f"{option}: bands must be (low, high) pairs of numbers in Hz, got {intervals!r}") from None
        if array.ndim != 2 or array.shape[1] != 2 or array.shape[0] < 1:
            raise OptionError(f"{option}: bands must be one or more (low, high) pairs in Hz, got {intervals!r}")
        if not np.all(np.isfinite(array)) or np.any(array <= 0):
            raise OptionError(f"{option}: band edges must be finite positive frequencies in Hz, got {array.tolist()}")
        if np.any(array[:, 1] <= array[:, 0]):
            bad = array[np.argmax(array[:, 1] <= array[:, 0])]
            raise OptionError(f"{option}: band {bad[0]:g}-{bad[1]:g} Hz is empty or reversed (need low < high)")
        if np.any(array[1:, 0] < array[:-1, 1]):
            i = int(np.argmax(array[1:, 0] < array[:-1, 1]))
            raise OptionError(f"{option}: bands {array[i, 0]:g}-{array[i, 1]:g} and {array[i + 1, 0]:g}-"
                              f"{array[i + 1, 1]:g} Hz overlap or are out of order (give increasing bands)")
        self.intervals = tuple((float(low), float(high)) for low, high in array)

    @classmethod
    def article(cls) -> "Bands":
        """The six bands of Section 5, :data:`smd_statespace.article.BANDS` (1.35-3.75 Hz in 0.4 Hz steps)."""
        return cls(article.BANDS)

    @classmethod
    def from_edges(cls, edges, *, option: str = "bands") -> "Bands":
        """Contiguous bands from increasing edges, e.g. ``[1.35, 1.75, 2.15]`` -> 1.35-1.75, 1.75-2.15 Hz."""
        try:
            values = np.asarray(edges, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"{option}: band edges must be numbers in Hz, got {edges!r}") from None
        if values.ndim != 1 or values.size < 2:
            raise OptionError(f"{option}: give at least two band edges in Hz (e.g. 1.35,1.75,2.15), got {edges!r}")
        if not np.all(np.isfinite(values)) or np.any(values <= 0):
            raise OptionError(f"{option}: band edges must be finite positive frequencies in Hz, got {values.tolist()}")
        if np.any(np.diff(values) <= 0):
            raise OptionError(f"{option}: band edges must increase strictly, got {', '.join(f'{v:g}' for v in values)}")
        return cls(np.column_stack([values[:-1], values[1:]]), option=option)

    @classmethod
    def parse(cls, text: str, *, option: str = "--bands") -> "Bands":
        """Bands from text: ``"article"`` or comma-separated increasing edges in Hz (``"1.35,1.75,2.15"``)."""
        spec = str(text).strip()
        if spec.lower() == "article":
            return cls.article()
        parts = [part.strip() for part in spec.split(",")]
        try:
            edges = [float(part) for part in parts]
        except ValueError:
            raise OptionError(f"{option} {spec!r}: unknown band definition; give 'article' or comma-separated "
                              "increasing edges in Hz, e.g. 1.35,1.75,2.15,2.55") from None
        return cls.from_edges(edges, option=f"{option} {spec!r}")

    @classmethod
    def coerce(cls, bands, *, option: str = "bands") -> "Bands":
        """``None`` or ``"article"`` (the article's bands), a :class:`Bands`, text, edges or pairs."""
        if bands is None:
            return cls.article()
        if isinstance(bands, Bands):
            return bands
        if isinstance(bands, str):
            return cls.parse(bands, option=option)
        try:
            array = np.asarray(bands, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"{option}: unknown band definition {bands!r}; give 'article', increasing edges "
                              "in Hz or (low, high) pairs") from None
        return cls.from_edges(array, option=option) if array.ndim == 1 else cls(array, option=option)

    def __len__(self) -> int:
        return len(self.intervals)

    def __iter__(self):
        return iter(self.intervals)

    def __getitem__(self, index):
        return self.intervals[index]

    def __eq__(self, other) -> bool:
        return isinstance(other, Bands) and self.intervals == other.intervals

    def __hash__(self):
        return hash(self.intervals)

    def __repr__(self) -> str:
        return f"Bands({', '.join(self.labels)} Hz)"

    @property
    def is_article(self) -> bool:
        """True when these are the article's six bands (Table 2 can then be compared)."""
        return self.intervals == tuple(article.BANDS)

    @property
    def labels(self) -> list[str]:
        """``"1.35-1.75"`` etc. (Hz)."""
        return [f"{low:g}-{high:g}" for low, high in self.intervals]

    @property
    def centres(self) -> np.ndarray:
        """Band mid-frequencies (Hz)."""
        return np.array([0.5 * (low + high) for low, high in self.intervals])

    def assign(self, f_b) -> np.ndarray:
        """Band index of each bouncing frequency ``f_b`` (Hz), ``-1`` outside every band or not finite.

        Vectorised; agrees with :func:`smd_statespace.article.band_of` for the article's bands.
        """
        f = np.asarray(f_b, dtype=float)
        array = np.asarray(self.intervals)
        low, high = array[:, 0], array[:, 1]
        # The upper edge belongs to a band unless the next band starts there.
        closed = np.ones(len(array), dtype=bool)
        closed[:-1] = low[1:] != high[:-1]
        inside = (f[..., None] >= low) & ((f[..., None] < high) | (closed & (f[..., None] == high)))
        return np.where(inside.any(axis=-1), inside.argmax(axis=-1), -1)


# ---------------------------------------------------------------------------
# reading results.csv


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


def _columns(frame: pd.DataFrame) -> str:
    names = [str(c) for c in frame.columns]
    return ", ".join(names[:15]) + (f", ... ({len(names)} columns)" if len(names) > 15 else "")


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
        or left out.

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
    from ..model import c_h, k_h

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
    loaded = []
    for index, item in enumerate(sources):
        frame, source = _one_source(item, index)
        frame.columns = [str(c).strip() for c in frame.columns]
        if frame.empty:
            raise RecordError(f"{source}: no rows (a header only; expected one row per cycle)")
        if "f_b" not in frame:
            raise RecordError(f"{source}: no column 'f_b' (the bouncing frequency of each cycle, Hz); "
                              f"the columns are {_columns(frame)}")
        loaded.append((frame, source))

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
    specs = [PARAMETERS[name] for name in chosen]
    flags = sorted({flag for spec in specs for flag in spec.determined_by})
    unflagged, unstatused, unchecked, derived = {}, [], [], {}
    frames = []
    for frame, source in loaded:
        frame["f_b"] = _numeric(frame["f_b"], source, "f_b")
        for name in chosen:
            column = PARAMETERS[name].column
            if column in frame:
                frame[column] = _numeric(frame[column], source, column)
                continue
            # K_h or C_h by Eq. 17-18 from f_h, xi_h and the body mass
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
                frame[column] = k_h(f_h, masses)
            else:
                frame[column] = c_h(_numeric(frame["xi_h"], source, "xi_h"), f_h, masses)
            derived.setdefault((source, where), []).append(name)
        for column in flags:
            if column in frame:
                frame[column] = _flags(frame[column], source, column)
            else:
                frame[column] = True
                unflagged.setdefault(source, []).append(column)
        if "status" in frame:
            frame["status"] = frame["status"].astype(str).str.strip().str.lower()
        else:
            frame["status"] = _STATUS_OK
            unstatused.append(source)
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
            unchecked.append(source)
        frame[ADEQUATE_COLUMN] = (_flags(frame[ADEQUATE_COLUMN], source, ADEQUATE_COLUMN, missing=True)
                                  if ADEQUATE_COLUMN in frame else True)
        frame.insert(0, "source", source)
        frames.append(frame)
    for (source, where), names in derived.items():
        notes.append(f"{', '.join(names)} computed by Eq. 17-18 from f_h, xi_h and {where} ({source})")
    if unstatused:
        notes.append(f"no status column in {', '.join(unstatused)}: every row taken as an identified cycle")
    for source, columns in unflagged.items():
        named = "*_determined columns" if len(columns) == len(flags) > 1 else (
            f"{', '.join(columns)} column{'s' if len(columns) > 1 else ''}")
        notes.append(f"no {named} in {source}: its cycles are treated as determined")
    if unchecked:
        notes.append(f"no implausible column in {', '.join(unchecked)}: cycles checked here against the physical "
                     "limits (xi_h < 0, C_h < 0, BLF or floor-force harmonic > 2 g)")
    table = pd.concat(frames, ignore_index=True, sort=False)
    table.attrs = {"parameters": tuple(chosen), "notes": notes}
    return table


# ---------------------------------------------------------------------------
# skew-normal fit (Eq. 19)


def _skewnorm_nll(x, theta, derivatives: bool = True):
    """Negative log-likelihood of Eq. 19, with gradient and Hessian in ``(m, log s, a)``.

    ``x`` is ``(B, n)`` (one sample per row) or ``(n,)`` shared by every row of ``theta`` ``(B, 3)``.
    With ``r = phi(u) / Phi(u)`` at ``u = a z``, ``z = (x - m) / s``, the log-density is
    ``log 2 - log s - log sqrt(2 pi) - z^2 / 2 + log Phi(u)``; as ``m``, ``s`` and ``a`` are
    constant along a row, the derivatives need only the row sums below.
    """
    n = x.shape[-1]
    m, tau, a = theta[:, 0:1], theta[:, 1], theta[:, 2]
    s = np.exp(tau)
    z = (x - m) / s[:, None]
    u = z * a[:, None]
    logcdf = log_ndtr(u)
    zz = z * z
    sum_zz = zz.sum(-1)
    nll = -(n * (_LOG_NORM - tau) - 0.5 * sum_zz + logcdf.sum(-1))
    if not derivatives:
        return nll
    r = np.exp(-0.5 * u * u - 0.5 * np.log(2.0 * np.pi) - logcdf)  # phi(u) / Phi(u), stable for u << 0
    dr = -r * (u + r)  # d r / d u
    sum_z, sum_r, sum_dr = z.sum(-1), r.sum(-1), dr.sum(-1)
    sum_zr, sum_zdr, sum_zzdr = (np.einsum("ij,ij->i", z, r), np.einsum("ij,ij->i", z, dr),
                                 np.einsum("ij,ij->i", zz, dr))
    grad = np.stack([(sum_z - a * sum_r) / s, sum_zz - n - a * sum_zr, sum_zr], axis=-1)
    h_mm = (a * a * sum_dr - n) / (s * s)
    h_mt = (a * a * sum_zdr + a * sum_r - 2.0 * sum_z) / s
    h_ma = -(sum_r + a * sum_zdr) / s
    h_tt = a * a * sum_zzdr - 2.0 * sum_zz + a * sum_zr
    h_ta = -(sum_zr + a * sum_zzdr)
    h_aa = sum_zzdr
    hess = np.stack([np.stack([h_mm, h_mt, h_ma], -1), np.stack([h_mt, h_tt, h_ta], -1),
                     np.stack([h_ma, h_ta, h_aa], -1)], axis=-2)
    return nll, -grad, -hess


def _pinned(theta, grad, a_max):
    """Rows whose shape sits at the cap ``|a| = a_max`` with the descent direction pointing further out."""
    return (np.abs(theta[:, 2]) >= a_max) & (grad[:, 2] * theta[:, 2] < 0)


def _minimise(x, theta, a_max: float, max_iter: int = 100):
    """Damped Newton (Levenberg-Marquardt) on :func:`_skewnorm_nll`, vectorised over the rows of ``theta``.

    ``|a|`` is projected onto ``[0, a_max]``; a row whose shape is held at the cap continues in
    ``(m, log s)`` alone. Returns ``(theta, nll, converged)``: converged rows have a (projected)
    gradient under 1e-3 of the curvature's standard deviation in every coordinate.
    """
    with np.errstate(over="ignore", divide="ignore", invalid="ignore", under="ignore"):  # bad trials are rejected
        return _newton(x, theta, a_max, max_iter)


def _newton(x, theta, a_max, max_iter):
    theta = np.array(theta, dtype=float)
    theta[:, 2] = np.clip(theta[:, 2], -a_max, a_max)
    nll, grad, hess = _skewnorm_nll(x, theta)
    damping = np.full(len(theta), 1e-3)
    done = np.zeros(len(theta), dtype=bool)
    eye = np.eye(3)
    for _ in range(max_iter):
        rows = np.flatnonzero(~done)
        if not rows.size:
            break
        xa = x[rows] if x.ndim == 2 else x
        t, g, h = theta[rows], grad[rows].copy(), hess[rows]
        pinned = _pinned(t, g, a_max)
        g[pinned, 2] = 0.0
        scale = np.abs(np.diagonal(h, axis1=-2, axis2=-1)) + 1e-12
        system = h + damping[rows, None, None] * scale[:, :, None] * eye
        system[pinned, 2, :] = 0.0
        system[pinned, :, 2] = 0.0
        system[pinned, 2, 2] = 1.0
        try:
            step = -np.linalg.solve(system, g[..., None])[..., 0]
        except np.linalg.LinAlgError:
            step = -g / scale
        trial = t + step
        trial[:, 2] = np.clip(trial[:, 2], -a_max, a_max)
        f_trial, g_trial, h_trial = _skewnorm_nll(xa, trial)
        better = np.isfinite(f_trial) & (f_trial <= nll[rows])
        moved = np.abs(trial - t).max(axis=-1)
        small = (moved < 1e-10) | (better & (nll[rows] - f_trial <= 1e-12 * (1.0 + np.abs(nll[rows])))
                                   & (damping[rows] < 1.0))
        accepted = rows[better]
        theta[accepted], nll[accepted] = trial[better], f_trial[better]
        grad[accepted], hess[accepted] = g_trial[better], h_trial[better]
        damping[rows] = np.where(better, np.maximum(damping[rows] / 10.0, 1e-9), damping[rows] * 10.0)
        done[rows[small | (damping[rows] > 1e12)]] = True
    curvature = np.sqrt(np.abs(np.diagonal(hess, axis1=-2, axis2=-1))) + 1e-12
    free = np.abs(grad) / curvature  # distance to the optimum in standard deviations, per coordinate
    free[:, 2] = np.where(_pinned(theta, grad, a_max), 0.0, free[:, 2])
    return theta, nll, (free < 1e-3).all(axis=-1)


def _moment_start(z: np.ndarray) -> np.ndarray:
    """Method-of-moments ``(m, log s, a)`` of a standardised sample (mean 0, sd 1)."""
    gamma = float(np.clip(np.mean(z ** 3), -_MAX_SKEW, _MAX_SKEW))
    g23 = abs(gamma) ** (2.0 / 3.0)
    delta = math.copysign(math.sqrt(0.5 * math.pi * g23 / (g23 + (0.5 * (4.0 - math.pi)) ** (2.0 / 3.0))), gamma)
    scale = 1.0 / math.sqrt(1.0 - 2.0 * delta * delta / math.pi)
    return np.array([-scale * delta * math.sqrt(2.0 / math.pi), math.log(scale), delta / math.sqrt(1 - delta ** 2)])


def _start_with_shape(a: float) -> np.ndarray:
    """``(m, log s, a)`` with shape ``a`` and the mean 0 and sd 1 of a standardised sample."""
    delta = a / math.sqrt(1.0 + a * a)
    scale = 1.0 / math.sqrt(1.0 - 2.0 * delta * delta / math.pi)
    return np.array([-scale * delta * math.sqrt(2.0 / math.pi), math.log(scale), a])


@dataclass(frozen=True)
class SkewNormalResult:
    """Maximum-likelihood skew-normal fit (Eq. 19) of one sample.

    Attributes
    ----------
    m, s, a : float
        Location, scale (same unit as the data) and shape (-) of
        ``scipy.stats.skewnorm(a, loc=m, scale=s)``.
    n : int
        Sample size.
    log_likelihood : float
        Maximised log-likelihood.
    se : tuple of float
        Standard errors of ``(m, s, a)`` from the observed information (NaN for ``a`` at its cap).
    at_bound : bool
        ``|a|`` reached ``a_max``: the likelihood still rises towards the half-normal limit.
    converged : bool
        The Newton iteration met its tolerances.
    ci : dict or None
        ``{"m": (low, high), "s": ..., "a": ...}`` bootstrap percentile intervals.
    confidence : float
        Level of ``ci``.
    n_bootstrap : int
        Bootstrap resamples whose fit converged (those behind ``ci``).
    """

    m: float
    s: float
    a: float
    n: int
    log_likelihood: float
    se: tuple = (math.nan, math.nan, math.nan)
    at_bound: bool = False
    converged: bool = True
    ci: dict | None = None
    confidence: float = 0.95
    n_bootstrap: int = 0

    @property
    def params(self) -> article.SkewNormalFit:
        """``(m, s, a)`` as :class:`smd_statespace.article.SkewNormalFit` (the layout of Table 2)."""
        return article.SkewNormalFit(self.m, self.s, self.a)

    def dist(self):
        """The frozen ``scipy.stats.skewnorm`` distribution."""
        return self.params.dist()

    @property
    def mean(self) -> float:
        """Mean of the fitted distribution, ``m + s delta sqrt(2/pi)``, ``delta = a / sqrt(1 + a^2)``."""
        return float(self.dist().mean())

    @property
    def sd(self) -> float:
        """Standard deviation of the fitted distribution, ``s sqrt(1 - 2 delta^2 / pi)``."""
        return float(self.dist().std())

    def summary(self) -> str:
        """One line: ``m, s, a`` with standard errors or intervals."""
        parts = []
        for name in ("m", "s", "a"):
            value = getattr(self, name)
            if self.ci is not None:
                low, high = self.ci[name]
                parts.append(f"{name} = {value:.5g} [{low:.5g}, {high:.5g}]")
            else:
                parts.append(f"{name} = {value:.5g}")
        tail = f" ({self.confidence:.0%} bootstrap, {self.n_bootstrap} resamples)" if self.ci is not None else ""
        bound = f"; |a| at the cap {abs(self.a):g}" if self.at_bound else ""
        return f"skew-normal (Eq. 19), n = {self.n}: " + ", ".join(parts) + tail + bound


def _as_sample(values) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size < 3:
        raise OptionError(f"fit_skewnorm: need at least 3 finite values, got {x.size}")
    if np.ptp(x) == 0:
        raise OptionError(f"fit_skewnorm: all {x.size} values are equal ({x[0]:g}); no spread to fit")
    return x


def fit_skewnorm(values, *, a_max: float = A_MAX) -> SkewNormalResult:
    """Fit Eq. 19 to a sample by maximum likelihood.

    Parameters
    ----------
    values : array_like
        The sample (non-finite values are dropped); at least 3 values, not all equal.
    a_max : float
        Cap on ``|a|`` (default :data:`A_MAX`).

    Returns
    -------
    SkewNormalResult
        ``m, s, a`` (``scipy.stats.skewnorm(a, loc=m, scale=s)``), log-likelihood, standard errors.

    Notes
    -----
    The sample is standardised (the fit is equivariant), the damped Newton iteration is run from
    the method-of-moments estimate and from shapes 0.5, 3 and 20 (signed like the sample skewness)
    at once, and the best converged optimum is kept.
    """
    x = _as_sample(values)
    centre, spread = float(x.mean()), float(x.std())
    z = (x - centre) / spread
    sign = 1.0 if np.mean(z ** 3) >= 0 else -1.0
    starts = np.vstack([_moment_start(z)] + [_start_with_shape(sign * a) for a in (0.5, 3.0, 20.0)])
    theta, nll, ok = _minimise(z, starts, a_max)
    best = int(np.argmin(np.where(ok, nll, np.inf))) if ok.any() else int(np.argmin(nll))
    t = theta[best]
    at_bound = bool(abs(t[2]) >= a_max * (1 - 1e-9))
    _, _, hess = _skewnorm_nll(z, t[None])
    se = (math.nan, math.nan, math.nan)
    try:
        cov = np.linalg.inv(hess[0])
        if np.all(np.diag(cov) > 0):
            sd = np.sqrt(np.diag(cov))
            s_hat = spread * math.exp(t[1])
            se = (spread * sd[0], s_hat * sd[1], math.nan if at_bound else sd[2])  # d s = s d(log s)
    except np.linalg.LinAlgError:
        pass
    return SkewNormalResult(
        m=centre + spread * float(t[0]), s=spread * math.exp(float(t[1])), a=float(t[2]), n=int(x.size),
        log_likelihood=float(-nll[best] - x.size * math.log(spread)), se=tuple(float(v) for v in se),
        at_bound=at_bound, converged=bool(ok[best]),
    )


def bootstrap_skewnorm(values, fit: SkewNormalResult, n_bootstrap: int = N_BOOTSTRAP, rng=None, *,
                       confidence: float = 0.95, a_max: float = A_MAX) -> SkewNormalResult:
    """Bootstrap percentile intervals of ``(m, s, a)`` for a fit of :func:`fit_skewnorm`.

    The sample is resampled with replacement ``n_bootstrap`` times and every resample is refitted,
    all at once (one vectorised Newton iteration started from ``fit``).

    Parameters
    ----------
    values : array_like
        The sample ``fit`` was made on.
    fit : SkewNormalResult
        The point fit.
    n_bootstrap : int
        Resamples (>= 1).
    rng : numpy.random.Generator, int or SeedSequence, optional
        Source of the resampling (:func:`numpy.random.default_rng`).
    confidence : float
        Level of the intervals, in (0, 1).

    Returns
    -------
    SkewNormalResult
        ``fit`` with ``ci``, ``confidence`` and ``n_bootstrap`` (converged resamples) set.
    """
    if not 0 < confidence < 1:
        raise OptionError(f"confidence must be between 0 and 1, got {confidence!r}")
    if int(n_bootstrap) < 1:
        raise OptionError(f"n_bootstrap must be >= 1, got {n_bootstrap!r}")
    x = _as_sample(values)
    rng = np.random.default_rng(rng)
    centre, spread = float(x.mean()), float(x.std())
    z = (x - centre) / spread
    samples = z[rng.integers(0, z.size, size=(int(n_bootstrap), z.size))]
    start = np.array([(fit.m - centre) / spread, math.log(fit.s / spread), fit.a])
    theta, _, ok = _minimise(samples, np.tile(start, (int(n_bootstrap), 1)), a_max)
    theta = theta[ok]
    if not len(theta):
        return dataclasses.replace(fit, ci=None, confidence=confidence, n_bootstrap=0)
    draws = {"m": centre + spread * theta[:, 0], "s": spread * np.exp(theta[:, 1]), "a": theta[:, 2]}
    tail = 50.0 * (1.0 - confidence)
    ci = {name: tuple(float(v) for v in np.percentile(d, [tail, 100.0 - tail])) for name, d in draws.items()}
    return dataclasses.replace(fit, ci=ci, confidence=confidence, n_bootstrap=int(len(theta)))


# ---------------------------------------------------------------------------
# one band x parameter cell


@dataclass(frozen=True)
class CellFit:
    """Statistics of one parameter in one band.

    Attributes
    ----------
    parameter : str
        Name in :data:`PARAMETERS`.
    band : int
        Index into the :class:`Bands`.
    n : int
        Cycles used.
    excluded : int
        ``ok`` cycles of the band left out because they did not determine the parameter
        (0 with ``include_undetermined``).
    undetermined : int
        ``ok`` cycles of the band that did not determine the parameter (used or not).
    mean, sd : float
        Sample mean and standard deviation (``ddof=1``) of the cycles used, in the parameter's unit.
    fit : SkewNormalResult or None
        The Eq. 19 fit, None when not fitted (see ``note``).
    note : str
        Why there is no fit, e.g. ``"too few cycles: 4 < 10"``; empty when fitted.
    """

    parameter: str
    band: int
    n: int
    excluded: int
    undetermined: int
    mean: float
    sd: float
    fit: SkewNormalResult | None
    note: str = ""

    def cell(self, digits: int = 5) -> str:
        """The Table 2 cell: ``"m, s, a"`` or the reason there is no fit."""
        if self.fit is None:
            return self.note
        return ", ".join(f"{v:.{digits}g}" for v in (self.fit.m, self.fit.s, self.fit.a)) + (
            " (a at cap)" if self.fit.at_bound else "")


def _fit_cell(parameter, band, values, excluded, undetermined, *, min_cycles, n_bootstrap, rng, confidence,
              a_max) -> CellFit:
    values = values[np.isfinite(values)]
    n = int(values.size)
    mean = float(values.mean()) if n else math.nan
    sd = float(values.std(ddof=1)) if n > 1 else math.nan
    common = dict(parameter=parameter, band=band, n=n, excluded=excluded, undetermined=undetermined, mean=mean, sd=sd)
    if n < min_cycles:
        return CellFit(fit=None, note=f"too few cycles: {n} < {min_cycles}", **common)
    if np.ptp(values) == 0:
        return CellFit(fit=None, note=f"no spread: all {n} values equal", **common)
    fit = fit_skewnorm(values, a_max=a_max)
    if n_bootstrap:
        fit = bootstrap_skewnorm(values, fit, n_bootstrap, rng, confidence=confidence, a_max=a_max)
    return CellFit(fit=fit, **common)


# ---------------------------------------------------------------------------
# trends


@dataclass
class TrendResult:
    """Polynomial trend of one parameter in the bouncing frequency, ``y = b0 + b1 f_b (+ b2 f_b^2)``.

    Attributes
    ----------
    parameter : str
        Name in :data:`PARAMETERS`.
    degree : int
        1 (linear) or 2 (quadratic).
    n : int
        Cycles in the regression.
    params, bse, pvalues : numpy.ndarray
        Coefficients ``b0, b1[, b2]`` (units of the parameter per Hz^k), standard errors and
        two-sided p-values (t-tests, ``cov_type`` covariance).
    conf_int : numpy.ndarray
        ``(degree + 1, 2)`` confidence intervals of the coefficients.
    rsquared : float
        Coefficient of determination.
    cov_type : str
        statsmodels covariance type (default ``"HC3"``, robust to the spread growing with ``f_b``).
    vertex : float or None
        Quadratics: ``f* = -b1 / (2 b2)`` (Hz), the "preferred frequency"; None for lines.
    vertex_kind : str
        ``"minimum"`` (``b2 > 0``) or ``"maximum"``; empty for lines.
    vertex_se, vertex_ci_delta : float, (float, float)
        Delta-method standard error and interval of ``f*``.
    vertex_ci_bootstrap : (float, float) or None
        Bootstrap percentile interval of ``f*`` (cycles resampled), None without bootstrap.
    f_b_range : (float, float)
        Range of the bouncing frequencies fitted (Hz).
    ols : statsmodels RegressionResults
        The full statsmodels result (``.summary()``, ``.get_prediction``).
    """

    parameter: str
    degree: int
    n: int
    params: np.ndarray
    bse: np.ndarray
    pvalues: np.ndarray
    conf_int: np.ndarray
    rsquared: float
    cov_type: str
    confidence: float
    f_b_range: tuple
    ols: object = field(repr=False)
    vertex: float | None = None
    vertex_kind: str = ""
    vertex_se: float = math.nan
    vertex_ci_delta: tuple | None = None
    vertex_ci_bootstrap: tuple | None = None
    n_bootstrap: int = 0

    @property
    def terms(self) -> list[str]:
        """Coefficient names: ``const``, ``f_b``, ``f_b^2``."""
        return ["const", "f_b", "f_b^2"][: self.degree + 1]

    def predict(self, f_b, confidence: float | None = None):
        """Trend and confidence band of the mean at ``f_b`` (Hz): ``(mean, low, high)`` arrays."""
        f = np.atleast_1d(np.asarray(f_b, dtype=float))
        design = np.vander(f, self.degree + 1, increasing=True)
        prediction = self.ols.get_prediction(design)
        frame = prediction.summary_frame(alpha=1.0 - (confidence or self.confidence))
        return (frame["mean"].to_numpy(), frame["mean_ci_lower"].to_numpy(), frame["mean_ci_upper"].to_numpy())

    def to_frame(self) -> pd.DataFrame:
        """One row per coefficient (and one for the vertex of a quadratic)."""
        pct = f"{self.confidence:.0%}"
        rows = [{"parameter": self.parameter, "term": term, "estimate": self.params[k], "se": self.bse[k],
                 "ci_low": self.conf_int[k, 0], "ci_high": self.conf_int[k, 1], "p_value": self.pvalues[k],
                 "method": f"OLS {self.cov_type} ({pct})"} for k, term in enumerate(self.terms)]
        if self.vertex is not None:
            low, high = self.vertex_ci_delta
            rows.append({"parameter": self.parameter, "term": f"vertex ({self.vertex_kind})", "estimate": self.vertex,
                         "se": self.vertex_se, "ci_low": low, "ci_high": high, "p_value": math.nan,
                         "method": f"delta method ({pct})"})
            if self.vertex_ci_bootstrap is not None:
                low, high = self.vertex_ci_bootstrap
                rows.append({"parameter": self.parameter, "term": f"vertex ({self.vertex_kind})",
                             "estimate": self.vertex, "se": math.nan, "ci_low": low, "ci_high": high,
                             "p_value": math.nan, "method": f"bootstrap percentile, {self.n_bootstrap} ({pct})"})
        frame = pd.DataFrame(rows)
        frame["n"] = self.n
        frame["r_squared"] = self.rsquared
        return frame

    def summary(self) -> str:
        """A few lines: the fitted polynomial, coefficients with intervals and p-values, the vertex."""
        unit = PARAMETERS[self.parameter].unit
        kind = "linear" if self.degree == 1 else "quadratic"
        lines = [f"{self.parameter} ({unit}) {kind} in f_b, n = {self.n}, R^2 = {self.rsquared:.3f}, "
                 f"{self.cov_type} covariance, f_b {self.f_b_range[0]:.2f}-{self.f_b_range[1]:.2f} Hz"]
        for k, term in enumerate(self.terms):
            lines.append(f"  {term:<6} {self.params[k]: .5g}  [{self.conf_int[k, 0]: .5g}, {self.conf_int[k, 1]: .5g}]"
                         f"  p = {self.pvalues[k]:.3g}")
        if self.vertex is not None:
            where = ("inside" if self.f_b_range[0] <= self.vertex <= self.f_b_range[1] else "outside")
            low, high = self.vertex_ci_delta
            line = f"  vertex ({self.vertex_kind}) f* = {self.vertex:.3f} Hz, delta method [{low:.3f}, {high:.3f}]"
            if self.vertex_ci_bootstrap is not None:
                line += f", bootstrap [{self.vertex_ci_bootstrap[0]:.3f}, {self.vertex_ci_bootstrap[1]:.3f}]"
            lines.append(line + f" ({where} the data)")
        return "\n".join(lines)


def _trend_shortfall(f: np.ndarray, degree: int) -> str:
    """Why ``f`` cannot carry a polynomial trend of ``degree`` (empty when it can)."""
    distinct = np.unique(f[np.isfinite(f)]).size
    if f.size < degree + 3 or distinct < degree + 1:
        return (f"too few cycles: need {degree + 3} at {degree + 1} or more distinct bouncing frequencies, "
                f"got {f.size} at {distinct}")
    return ""


def _no_spread(y: np.ndarray) -> str:
    """``"no spread: all n values equal v"`` when ``y`` is constant (R^2 is then undefined), else empty."""
    y = y[np.isfinite(y)]
    if y.size and np.ptp(y) == 0:
        return f"no spread: all {y.size} values equal {y[0]:.4g}"
    return ""


def fit_trend(f_b, values, degree: int, *, parameter: str = "f_h", n_bootstrap: int = 0, rng=None,
              confidence: float = 0.95, cov_type: str = "HC3") -> TrendResult:
    """Fit ``values`` as a polynomial of degree 1 or 2 in ``f_b`` by OLS (statsmodels).

    Parameters
    ----------
    f_b : array_like
        Bouncing frequencies (Hz), one per cycle.
    values : array_like
        The parameter, one per cycle (unit of the parameter); not all equal (a constant has no
        trend and no R^2: an OptionError says "no spread").
    degree : int
        1 (linear) or 2 (quadratic, with the vertex).
    parameter : str
        Name of the parameter (labels only).
    n_bootstrap : int
        Case-resampling bootstrap resamples for the vertex interval (0: delta method only).
    rng : numpy.random.Generator, int or SeedSequence, optional
        Source of the resampling.
    confidence : float
        Level of the intervals.
    cov_type : str
        statsmodels covariance type: ``"HC3"`` (default), ``"nonrobust"``, ``"HC0"``...

    Returns
    -------
    TrendResult
    """
    import statsmodels.api as sm
    from scipy.stats import norm

    if degree not in (1, 2):
        raise OptionError(f"trend degree must be 1 or 2, got {degree!r}")
    f = np.asarray(f_b, dtype=float)
    y = np.asarray(values, dtype=float)
    keep = np.isfinite(f) & np.isfinite(y)
    f, y = f[keep], y[keep]
    shortfall = _trend_shortfall(f, degree) or _no_spread(y)
    if shortfall:
        raise OptionError(f"{parameter} trend: {shortfall}")
    design = np.vander(f, degree + 1, increasing=True)
    ols = sm.OLS(y, design).fit(cov_type=cov_type)
    alpha = 1.0 - confidence
    result = TrendResult(parameter=parameter, degree=degree, n=int(f.size), params=np.asarray(ols.params),
                         bse=np.asarray(ols.bse), pvalues=np.asarray(ols.pvalues),
                         conf_int=np.asarray(ols.conf_int(alpha=alpha)), rsquared=float(ols.rsquared),
                         cov_type=cov_type, confidence=confidence, f_b_range=(float(f.min()), float(f.max())), ols=ols)
    if degree == 2:
        b1, b2 = result.params[1], result.params[2]
        vertex = -b1 / (2.0 * b2)
        cov = np.asarray(ols.cov_params())[1:, 1:]
        gradient = np.array([-1.0 / (2.0 * b2), b1 / (2.0 * b2 * b2)])
        se = float(np.sqrt(gradient @ cov @ gradient))
        half = norm.ppf(1.0 - alpha / 2.0) * se
        result.vertex, result.vertex_se = float(vertex), se
        result.vertex_kind = "minimum" if b2 > 0 else "maximum"
        result.vertex_ci_delta = (float(vertex - half), float(vertex + half))
        if n_bootstrap:
            rng = np.random.default_rng(rng)
            index = rng.integers(0, f.size, size=(int(n_bootstrap), f.size))
            xb, yb = design[index], y[index]
            gram = np.einsum("bni,bnj->bij", xb, xb)
            coef = np.linalg.solve(gram, np.einsum("bni,bn->bi", xb, yb)[..., None])[..., 0]
            vertices = -coef[:, 1] / (2.0 * coef[:, 2])
            tail = 50.0 * alpha
            result.vertex_ci_bootstrap = tuple(float(v) for v in np.percentile(vertices, [tail, 100.0 - tail]))
            result.n_bootstrap = int(n_bootstrap)
    return result


# ---------------------------------------------------------------------------
# the whole population


def _seed_sequence(seed, *key) -> np.random.SeedSequence:
    """A child seed for one (kind, parameter, band) cell: reproducible whatever else is fitted."""
    if isinstance(seed, np.random.SeedSequence):
        return np.random.SeedSequence(seed.entropy, spawn_key=tuple(seed.spawn_key) + tuple(key))
    return np.random.SeedSequence(seed, spawn_key=tuple(key))


@dataclass
class PopulationStats:
    """Statistics of a population of identified cycles (Section 5); made by :func:`population_stats`.

    Attributes
    ----------
    cycles : pandas.DataFrame
        Every row read, with ``band`` (-1: outside or not ``ok``) and ``used_<parameter>`` columns.
    bands : Bands
    parameters : tuple of str
    cells : dict
        ``(parameter, band) -> CellFit``.
    trends : dict
        ``parameter -> TrendResult`` (or the reason it could not be fitted, a str).
    counts : dict
        ``rows``, ``by_status`` (dict), ``ok``, ``implausible`` (ok cycles flagged implausible),
        ``implausible_reasons`` (reason -> cycles), ``inadequate`` (ok cycles from an inadequate
        model), ``usable`` (ok cycles kept), ``outside_bands``, ``in_bands``, ``sources`` and
        ``notes`` (what the reader assumed or left out, see :func:`read_results`).
    options : dict
        ``min_cycles``, ``n_bootstrap``, ``seed``, ``include_undetermined``, ``include_implausible``,
        ``confidence``, ``a_max``.
    """

    cycles: pd.DataFrame
    bands: Bands
    parameters: tuple
    cells: dict
    trends: dict
    counts: dict
    options: dict

    # -- tables ---------------------------------------------------------
    def to_frame(self) -> pd.DataFrame:
        """Long table, index ``(parameter, band)``: band edges, counts, mean, sd, ``m, s, a`` with intervals."""
        rows, index = [], []
        for (parameter, band), cell in self.cells.items():
            low, high = self.bands[band]
            fit = cell.fit
            row = {"low": low, "high": high, "n": cell.n, "excluded": cell.excluded, "undetermined": cell.undetermined,
                   "mean": cell.mean, "sd": cell.sd}
            for name in ("m", "s", "a"):
                row[name] = getattr(fit, name) if fit else math.nan
                ci = fit.ci[name] if fit is not None and fit.ci is not None else (math.nan, math.nan)
                row[f"{name}_low"], row[f"{name}_high"] = ci
            row["log_likelihood"] = fit.log_likelihood if fit else math.nan
            row["at_bound"] = bool(fit.at_bound) if fit else False
            row["note"] = cell.note
            rows.append(row)
            index.append((parameter, band))
        return pd.DataFrame(rows, index=pd.MultiIndex.from_tuples(index, names=["parameter", "band"]))

    def band_table(self) -> pd.DataFrame:
        """Parameter x band: ``"mean ± sd (n)"`` of the cycles used (the spread per band)."""
        table = {}
        for parameter in self.parameters:
            table[f"{parameter} ({PARAMETERS[parameter].unit})"] = [
                (f"{c.mean:.4g} ± {c.sd:.3g} ({c.n})" if c.n > 1 else f"{c.mean:.4g} ({c.n})" if c.n else "- (0)")
                for c in (self.cells[parameter, band] for band in range(len(self.bands)))]
        return pd.DataFrame(table, index=pd.Index(self.bands.labels, name="f_b band (Hz)")).T

    def table2(self, digits: int = 5) -> pd.DataFrame:
        """The article's Table 2 layout: parameter x band, cells ``"m, s, a"`` or the reason for no fit."""
        return pd.DataFrame(
            {label: [self.cells[p, band].cell(digits) for p in self.parameters]
             for band, label in enumerate(self.bands.labels)},
            index=pd.Index([f"{p} ({PARAMETERS[p].unit})" for p in self.parameters], name="parameter"))

    def exclusions(self) -> pd.DataFrame:
        """Per parameter: ``ok`` cycles in the bands, undetermined, excluded, missing values, used."""
        rows = {}
        ok = self.cycles[self.cycles["band"] >= 0]
        for parameter in self.parameters:
            spec = PARAMETERS[parameter]
            undetermined = sum(c.undetermined for (p, _), c in self.cells.items() if p == parameter)
            excluded = sum(c.excluded for (p, _), c in self.cells.items() if p == parameter)
            used = sum(c.n for (p, _), c in self.cells.items() if p == parameter)
            rows[parameter] = {"in_bands": len(ok), "undetermined": undetermined, "excluded": excluded,
                               "missing_value": int(ok[spec.column].isna().sum()), "used": used}
        return pd.DataFrame(rows).T

    def trend_frame(self) -> pd.DataFrame:
        """Coefficients, intervals and p-values of every trend, and the vertices (see :meth:`TrendResult.to_frame`)."""
        frames = [t.to_frame() for t in self.trends.values() if isinstance(t, TrendResult)]
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

    def compare_table2(self) -> pd.DataFrame:
        """The fitted table beside the published Table 2 (see :func:`compare_table2`)."""
        return compare_table2(self)

    # -- report -----------------------------------------------------------
    def counts_line(self) -> str:
        """One line: rows read, left out by status, implausible, outside the bands, used."""
        c = self.counts
        others = ", ".join(f"{n} {status}" for status, n in sorted(c["by_status"].items()) if status != _STATUS_OK)
        verb = "kept" if self.options["include_implausible"] else "left out"
        flagged = [f"{c['implausible']} implausible"] if c["implausible"] else []
        flagged += [f"{c['inadequate']} from an inadequate model"] if c["inadequate"] else []
        return (f"{c['rows']} cycles read from {len(c['sources'])} file(s): {c['ok']} ok"
                + (f", {others} left out" if others else "")
                + (f"; of the ok cycles {' and '.join(flagged)} {verb}" if flagged else "")
                + f"; {c['outside_bands']} ok cycles outside the bands; {c['in_bands']} in {len(self.bands)} bands "
                  f"({', '.join(self.bands.labels)} Hz)")

    def implausible_lines(self) -> list[str]:
        """What the cycles left out (or kept) as impossible were: one line each for reasons and models."""
        c, lines = self.counts, []
        verb = "kept (include_implausible)" if self.options["include_implausible"] else "left out"
        if c["implausible"]:
            why = ", ".join(f"{reason}: {n}" for reason, n in c["implausible_reasons"].items())
            lines.append(f"warning: {c['implausible']} ok cycles have estimates that cannot be true ({why}); {verb}")
        if c["inadequate"]:
            lines.append(f"warning: {c['inadequate']} ok cycles come from a model found inadequate for their record "
                         f"({ADEQUATE_COLUMN} False); {verb}")
        return lines

    def exclusion_lines(self) -> list[str]:
        """Per parameter, how many cycles did not determine it and whether they were left out."""
        lines = []
        table = self.exclusions()
        for parameter, row in table.iterrows():
            if self.options["include_undetermined"]:
                text = (f"{parameter}: {int(row['used'])} cycles used, {int(row['undetermined'])} of them "
                        "undetermined (included)")
            else:
                text = f"{parameter}: {int(row['used'])} cycles used, {int(row['excluded'])} undetermined left out"
            if row["missing_value"]:
                text += f", {int(row['missing_value'])} without a value"
            lines.append(text)
        return lines

    def summary(self) -> str:
        """The report: counts, exclusions, spread per band, Table 2 layout, comparison, trends."""
        o = self.options
        width = 200
        with pd.option_context("display.width", width, "display.max_columns", 50, "display.max_colwidth", 60):
            parts = ["Population statistics (Wang, Chen & Nagayama 2019, Section 5)", self.counts_line()]
            parts += self.implausible_lines()
            parts += [f"note: {note}" for note in self.counts.get("notes", [])]
            parts.append("cycles that did not determine a parameter (*_determined False): "
                         + ("included" if o["include_undetermined"] else "left out of that parameter"))
            parts += ["  " + line for line in self.exclusion_lines()]
            parts += ["", "mean ± sd (n) per band:", self.band_table().to_string()]
            ci = (f"; {o['confidence']:.0%} bootstrap intervals from {o['n_bootstrap']} resamples (seed {o['seed']}) "
                  "in table2.csv") if o["n_bootstrap"] else ""
            parts += ["", f"Skew-normal fits (Eq. 19), cells 'm, s, a', Table 2 layout; fitted when a band has "
                          f">= {o['min_cycles']} cycles{ci}:", self.table2().to_string()]
            if self.bands.is_article:
                comparison = self.compare_table2()
                fitted = comparison.dropna(subset=["ks"])
                if len(fitted):
                    worst = fitted["ks"].idxmax()
                    parts += ["", f"against the published Table 2: largest distance between the fitted and published "
                                  f"distribution functions {fitted['ks'].max():.3f} ({worst[0]}, band {worst[1]}); "
                                  f"median {fitted['ks'].median():.3f} over {len(fitted)} fitted cells "
                                  "(table2_vs_article.csv)"]
            parts += ["", "Trends in the bouncing frequency (OLS on the cycles):"]
            for parameter, trend in self.trends.items():
                parts.append(trend.summary() if isinstance(trend, TrendResult) else f"{parameter}: {trend}")
        return "\n".join(parts)

    def __str__(self) -> str:
        return self.summary()

    # -- figures -----------------------------------------------------------
    def plot_trends(self, path=None):
        """Parameters against ``f_b`` with band means ± sd and trends (like Fig. 6-8); see :mod:`.stats_plots`."""
        from ..plotting.population import plot_trends

        return plot_trends(self, path)

    def plot_histograms(self, parameter: str, path=None, published: bool = True):
        """Per-band histograms of one parameter with the fitted Eq. 19 densities; see :mod:`.stats_plots`."""
        from ..plotting.population import plot_histograms

        return plot_histograms(self, parameter, path, published=published)


def population_stats(sources, *, bands=None, parameters=None, mass=None, min_cycles: int = MIN_CYCLES,
                     n_bootstrap: int = N_BOOTSTRAP, seed=0, include_undetermined: bool = False,
                     include_implausible: bool = False, confidence: float = 0.95, a_max: float = A_MAX,
                     trend_degrees=None, cov_type: str = "HC3") -> PopulationStats:
    """Section 5 statistics of identified cycles: per band counts, mean, sd, Eq. 19 fits; trends in ``f_b``.

    Parameters
    ----------
    sources : path, DataFrame or sequence of them
        ``results.csv`` of ``smd-statespace identify`` or any table with ``f_b`` and parameter
        columns (see :func:`read_results`).
    bands : None, "article", Bands, text, edges or (low, high) pairs
        Bouncing-frequency bands (Hz); default the article's six (:data:`article.BANDS`).
    parameters : sequence of str or str, optional
        Parameters to analyse, from :data:`PARAMETERS` (or their columns); every source must give
        them. Default: those of Table 2's seven that the sources give (the others are noted).
    mass : float, optional
        Body mass (kg) for ``K_h`` and ``C_h`` of tables without ``k_h``/``c_h`` or ``mass`` columns.
    min_cycles : int
        Fewest cycles in a band for a skew-normal fit (>= 3, default :data:`MIN_CYCLES`).
    n_bootstrap : int
        Bootstrap resamples for the intervals of ``m, s, a`` and of the trend vertices (0: none).
    seed : int or SeedSequence
        Root of the bootstrap's random numbers: each (parameter, band) cell and each trend draws
        from its own child :class:`numpy.random.SeedSequence`, so results do not depend on which
        other cells are fitted.
    include_undetermined : bool
        Keep cycles whose ``*_determined`` flag is False (default: leave them out of that parameter).
    include_implausible : bool
        Keep cycles flagged implausible or from an inadequate model (default: leave them out;
        they are counted either way).
    confidence : float
        Level of every interval (default 0.95).
    a_max : float
        Cap on the skew-normal shape ``|a|`` (default :data:`A_MAX`).
    trend_degrees : dict, optional
        Overrides of :data:`TREND_DEGREES` (1 or 2 per parameter).
    cov_type : str
        statsmodels covariance of the trends (default ``"HC3"``).

    Returns
    -------
    PopulationStats

    Raises
    ------
    RecordError
        Unreadable, empty or incomplete results (named by file and column), no ``ok`` cycles,
        no plausible ``ok`` cycle, no ``ok`` cycle inside the bands.
    OptionError
        Invalid bands, ``min_cycles``, ``n_bootstrap``, ``confidence`` or parameters.
    """
    bands = Bands.coerce(bands)
    for name, value, minimum in (("min_cycles", min_cycles, 3), ("n_bootstrap", n_bootstrap, 0)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum:
            raise OptionError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    if not 0 < confidence < 1:
        raise OptionError(f"confidence must be between 0 and 1, got {confidence!r}")
    if not (isinstance(seed, np.random.SeedSequence) or (isinstance(seed, (int, np.integer))
                                                          and not isinstance(seed, bool) and seed >= 0)):
        raise OptionError(f"seed must be a non-negative whole number or a numpy SeedSequence, got {seed!r}")
    if not (np.isfinite(a_max) and a_max > 0):
        raise OptionError(f"a_max must be a positive number, got {a_max!r}")
    degrees = dict(TREND_DEGREES)
    for name, degree in dict(trend_degrees or {}).items():
        if name not in PARAMETERS or degree not in (1, 2):
            raise OptionError(f"trend_degrees: {name!r}: {degree!r}; give parameters of {', '.join(PARAMETERS)} "
                              "with degree 1 or 2")
        degrees[name] = degree
    table = read_results(sources, parameters=parameters, mass=mass)
    parameters, notes = table.attrs["parameters"], list(table.attrs["notes"])
    sources_read = list(dict.fromkeys(table["source"]))
    by_status = {str(k): int(v) for k, v in table["status"].value_counts().items()}
    ok = (table["status"] == _STATUS_OK).to_numpy()
    if not ok.any():
        detail = ", ".join(f"{n} {s}" for s, n in sorted(by_status.items()))
        raise RecordError(f"{', '.join(sources_read)}: no 'ok' cycles to analyse ({detail})")
    implausible = ok & table["implausible"].to_numpy(dtype=bool)
    inadequate = ok & ~table[ADEQUATE_COLUMN].to_numpy(dtype=bool)
    usable = ok & ((~implausible & ~inadequate) | include_implausible)
    if not usable.any():
        why = ", ".join(f"{reason}: {n}" for reason, n in reason_counts(table.loc[implausible,
                                                                                   "implausible_reason"]).items())
        raise RecordError(f"{', '.join(sources_read)}: all {int(ok.sum())} ok cycles are implausible ({why or 'none'})"
                          f" or from an inadequate model ({int(inadequate.sum())}); nothing to analyse "
                          "(--include-implausible keeps them)")
    band = np.where(usable, bands.assign(table["f_b"].to_numpy()), -1)
    if not (band >= 0).any():
        f_ok = table.loc[usable, "f_b"]
        raise RecordError(f"{', '.join(sources_read)}: none of the {int(usable.sum())} ok cycles has f_b inside the "
                          f"bands {bands.intervals[0][0]:g}-{bands.intervals[-1][1]:g} Hz (their f_b: "
                          f"{f_ok.min():.3g}-{f_ok.max():.3g} Hz); choose --bands to cover them")
    table["band"] = band
    counts = {"rows": int(len(table)), "by_status": by_status, "ok": int(ok.sum()),
              "implausible": int(implausible.sum()),
              "implausible_reasons": reason_counts(table.loc[implausible, "implausible_reason"]),
              "inadequate": int(inadequate.sum()), "usable": int(usable.sum()),
              "outside_bands": int((usable & (band < 0)).sum()), "in_bands": int((band >= 0).sum()),
              "sources": sources_read, "notes": notes}
    options = {"min_cycles": int(min_cycles), "n_bootstrap": int(n_bootstrap), "seed": seed,
               "include_undetermined": bool(include_undetermined),
               "include_implausible": bool(include_implausible), "confidence": float(confidence),
               "a_max": float(a_max), "cov_type": cov_type, "trend_degrees": degrees}

    cells, trends = {}, {}
    f_b = table["f_b"].to_numpy()
    for parameter in parameters:
        p_index = list(PARAMETERS).index(parameter)  # seeds keyed by the parameter, not by what else is fitted
        spec = PARAMETERS[parameter]
        values = table[spec.column].to_numpy(dtype=float)
        determined = np.logical_and.reduce([table[flag].to_numpy(dtype=bool) for flag in spec.determined_by])
        in_band = band >= 0
        used = in_band & np.isfinite(values) & (determined | include_undetermined)
        table[f"used_{parameter}"] = used
        for b in range(len(bands)):
            here = band == b
            undetermined = int((here & ~determined).sum())
            cells[parameter, b] = _fit_cell(
                parameter, b, values[here & used], 0 if include_undetermined else undetermined, undetermined,
                min_cycles=min_cycles, n_bootstrap=n_bootstrap, rng=np.random.default_rng(
                    _seed_sequence(seed, 0, p_index, b)), confidence=confidence, a_max=a_max)
        degree = int(degrees.get(parameter, 1))
        shortfall = _trend_shortfall(f_b[used], degree) or _no_spread(values[used])
        trends[parameter] = f"no trend ({shortfall})" if shortfall else fit_trend(
            f_b[used], values[used], degree, parameter=parameter, n_bootstrap=n_bootstrap,
            rng=np.random.default_rng(_seed_sequence(seed, 1, p_index)), confidence=confidence, cov_type=cov_type)
    return PopulationStats(cycles=table, bands=bands, parameters=parameters, cells=cells, trends=trends,
                           counts=counts, options=options)


def _cdf_distance(first, second, points: int = 8001) -> float:
    """Largest distance between two distribution functions (Kolmogorov-Smirnov distance, 0-1).

    The functions are integrated from the densities by the trapezoid rule over +-10 standard
    deviations of both (``skewnorm.cdf`` is two orders of magnitude slower); error below 1e-6.
    """
    low = min(first.mean() - 10 * first.std(), second.mean() - 10 * second.std())
    high = max(first.mean() + 10 * first.std(), second.mean() + 10 * second.std())
    grid = np.linspace(low, high, points)
    difference = first.pdf(grid) - second.pdf(grid)
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (difference[1:] + difference[:-1]) * np.diff(grid))])
    return float(np.max(np.abs(cumulative)))


def compare_table2(stats: PopulationStats, published=None) -> pd.DataFrame:
    """The fitted skew-normal table beside the published Table 2, cell by cell.

    Parameters
    ----------
    stats : PopulationStats
        Fitted on the article's bands.
    published : DataFrame, optional
        Default :func:`smd_statespace.article.table2_frame`.

    Returns
    -------
    pandas.DataFrame
        Index ``(parameter, band)``; columns ``n``, ``m, m_article, s, s_article, a, a_article``,
        the implied means and sds (``mean, mean_article, sd, sd_article``: the location, scale
        and shape trade off, the moments are the stable comparison), ``ks`` (largest distance
        between the two distribution functions, 0-1) and ``m_in_ci, s_in_ci, a_in_ci`` (the
        published value lies in the bootstrap interval; None without one). Unfitted cells are NaN.

    Raises
    ------
    OptionError
        The bands are not the article's.
    """
    from scipy.stats import skewnorm

    if not stats.bands.is_article:
        raise OptionError(f"the published Table 2 uses the article's bands; these are {stats.bands.labels}")
    published = article.table2_frame() if published is None else published
    rows, index = [], []
    for parameter in stats.parameters:
        for band in range(len(stats.bands)):
            cell = stats.cells[parameter, band]
            pub = published.loc[(parameter, band)]
            pub_dist = skewnorm(pub["a"], loc=pub["m"], scale=pub["s"])
            row = {"n": cell.n, "m_article": pub["m"], "s_article": pub["s"], "a_article": pub["a"],
                   "mean_article": float(pub_dist.mean()), "sd_article": float(pub_dist.std())}
            fit = cell.fit
            if fit is None:
                row.update({k: math.nan for k in ("m", "s", "a", "mean", "sd", "ks")})
                row.update({f"{k}_in_ci": None for k in ("m", "s", "a")})
            else:
                row.update(m=fit.m, s=fit.s, a=fit.a, mean=fit.mean, sd=fit.sd)
                row["ks"] = _cdf_distance(fit.dist(), pub_dist)
                for k in ("m", "s", "a"):
                    row[f"{k}_in_ci"] = (None if fit.ci is None else
                                         bool(fit.ci[k][0] <= pub[k] <= fit.ci[k][1]))
            rows.append(row)
            index.append((parameter, band))
    columns = ["n", "m", "m_article", "s", "s_article", "a", "a_article", "mean", "mean_article", "sd", "sd_article",
               "ks", "m_in_ci", "s_in_ci", "a_in_ci"]
    return pd.DataFrame(rows, index=pd.MultiIndex.from_tuples(index, names=["parameter", "band"]))[columns]
