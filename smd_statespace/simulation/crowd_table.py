"""The skew-normal fits (Eq. 19) a crowd is drawn from: the article's Table 2 or a user's table.

:func:`fit_table` reads a table in the layout of
:func:`smd_statespace.article.table2_frame` (what ``smd-statespace stats``
writes) and returns the fits of the band holding a bouncing frequency, in the
layout :func:`~smd_statespace.simulation.population.sample_population` takes.
Re-exported by :mod:`smd_statespace.simulation.crowd`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from .. import article
from ..errors import OptionError

TABLE_PARAMETERS = ("f_h", "xi_h", "BLF1", "BLF2", "BLF3")
"""Parameters a fit table must give (the others of Table 2 are not used)."""


def _parameter_name(text):
    key = str(text).strip().lower().replace("_", "")
    names = {"fh": "f_h", "xih": "xi_h", "kh": "K_h", "ch": "C_h", "blf1": "BLF1", "blf2": "BLF2", "blf3": "BLF3"}
    return names.get(key, str(text))


def fit_table(source, f_b):
    """Skew-normal fits (Eq. 19) for bouncing frequency ``f_b``, in the layout :func:`sample_population` takes.

    Parameters
    ----------
    source : None, mapping, pandas.DataFrame, str or path-like
        None: the article's Table 2. A mapping in the layout of
        :data:`article.TABLE2` is used as it is. A DataFrame or CSV file in
        the layout of :func:`article.table2_frame` (what ``smd-statespace
        stats`` writes as ``table2.csv``): one row per (parameter, band) with
        columns ``parameter, band, m, s, a`` (location, scale, shape) and
        optionally ``low, high`` (band edges, Hz). With ``low, high`` the row
        whose band holds ``f_b`` is used; without, ``band`` indexes the
        article's bands. Parameter names ``f_h, xi_h, BLF1..3`` (also
        ``blf_1``...).
    f_b : float
        Bouncing frequency (Hz).

    Returns
    -------
    mapping
        ``table[parameter][band] = (m, s, a)`` for the article band of ``f_b``.

    Raises
    ------
    OptionError
        Unreadable file, missing columns or parameters, no row for ``f_b``,
        or a fit that is missing (e.g. a band with too few cycles) or invalid.
    """
    if source is None:
        return article.TABLE2
    if isinstance(source, Mapping):
        return source
    band = article.band_of(f_b)
    if band is None:
        edges = ", ".join(f"{lo:g}-{hi:g}" for lo, hi in article.BANDS)
        raise OptionError(f"crowd: f_b = {f_b!r} Hz is outside the article's bands ({edges} Hz)")
    label = "table"
    if isinstance(source, pd.DataFrame):
        frame = source.reset_index() if isinstance(source.index, pd.MultiIndex) or source.index.name else source
    else:
        label = str(source)
        try:
            frame = pd.read_csv(source)
        except FileNotFoundError:
            raise OptionError(f"--table {label}: no such file") from None
        except (OSError, ValueError, pd.errors.ParserError) as exc:
            raise OptionError(f"--table {label}: cannot read it as CSV ({exc})") from None
    frame = frame.rename(columns=lambda c: str(c).strip())
    missing = [c for c in ("parameter", "m", "s", "a") if c not in frame.columns]
    has_edges = {"low", "high"} <= set(frame.columns)
    if not has_edges and "band" not in frame.columns:
        missing.append("band (or low, high)")
    if missing:
        raise OptionError(f"{label}: missing column(s) {', '.join(missing)}; expected the layout of "
                          "article.table2_frame(): parameter, band, m, s, a[, low, high]")
    frame = frame.assign(parameter=frame["parameter"].map(_parameter_name))
    fits = {}
    for parameter in TABLE_PARAMETERS:
        rows = frame[frame["parameter"] == parameter]
        if has_edges:
            low, high = rows["low"].astype(float), rows["high"].astype(float)
            rows = rows[(low <= f_b) & ((f_b < high) | ((f_b == high) & (high == high.max())))]
        else:
            rows = rows[pd.to_numeric(rows["band"], errors="coerce") == band]
        if rows.empty:
            where = f"a band holding f_b = {f_b:g} Hz" if has_edges else f"band {band}"
            raise OptionError(f"{label}: no row for parameter {parameter!r} in {where}")
        row = rows.iloc[0]
        try:
            m, s, a = (float(row[c]) for c in ("m", "s", "a"))
        except (TypeError, ValueError):
            raise OptionError(f"{label}: the fit of {parameter!r} at f_b = {f_b:g} Hz is not numeric") from None
        if not all(np.isfinite((m, s, a))):
            note = f" ({row['note']})" if "note" in row.index and isinstance(row["note"], str) and row["note"] else ""
            raise OptionError(f"{label}: no fit for {parameter!r} at f_b = {f_b:g} Hz{note}; "
                              "give a table with a fit in that band")
        if s <= 0:
            raise OptionError(f"{label}: scale s of {parameter!r} at f_b = {f_b:g} Hz must be > 0, got {s:g}")
        fits[parameter] = {band: (m, s, a)}
    return fits
