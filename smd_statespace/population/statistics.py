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

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import article
from ..errors import OptionError, RecordError
from ..identify.plausibility import reason_counts
from .bands import Bands
from .results import _STATUS_OK, ADEQUATE_COLUMN, PARAMETERS, read_results
from .skewnormal import A_MAX, N_BOOTSTRAP, SkewNormalResult, bootstrap_skewnorm, fit_skewnorm
from .trends import TREND_DEGREES, TrendResult, _no_spread, _trend_shortfall, fit_trend

__all__ = ["MIN_CYCLES", "CellFit", "PopulationStats", "population_stats", "compare_table2"]


MIN_CYCLES = 10
"""Fewest cycles in a band for a skew-normal fit (three parameters); fewer and the table says so."""


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
              a_max, noun: str = "cycles") -> CellFit:
    values = values[np.isfinite(values)]
    n = int(values.size)
    mean = float(values.mean()) if n else math.nan
    sd = float(values.std(ddof=1)) if n > 1 else math.nan
    common = dict(parameter=parameter, band=band, n=n, excluded=excluded, undetermined=undetermined, mean=mean, sd=sd)
    if n < min_cycles:
        return CellFit(fit=None, note=f"too few {noun}: {n} < {min_cycles}", **common)
    if np.ptp(values) == 0:
        return CellFit(fit=None, note=f"no spread: all {n} values equal", **common)
    fit = fit_skewnorm(values, a_max=a_max)
    if n_bootstrap:
        fit = bootstrap_skewnorm(values, fit, n_bootstrap, rng, confidence=confidence, a_max=a_max)
    return CellFit(fit=fit, **common)


# ---------------------------------------------------------------------------
# trends


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
    noun : str
        What a row is, in the plural, for the report: ``"cycles"`` (per-cycle results),
        ``"people"`` (record-level results, one person per record) or ``"rows"`` (a mix).
    """

    cycles: pd.DataFrame
    bands: Bands
    parameters: tuple
    cells: dict
    trends: dict
    counts: dict
    options: dict
    noun: str = "cycles"

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
        c, noun = self.counts, self.noun
        others = ", ".join(f"{n} {status}" for status, n in sorted(c["by_status"].items()) if status != _STATUS_OK)
        verb = "kept" if self.options["include_implausible"] else "left out"
        flagged = [f"{c['implausible']} implausible"] if c["implausible"] else []
        flagged += [f"{c['inadequate']} from an inadequate model"] if c["inadequate"] else []
        return (f"{c['rows']} {noun} read from {len(c['sources'])} file(s): {c['ok']} ok"
                + (f", {others} left out" if others else "")
                + (f"; of the ok {noun} {' and '.join(flagged)} {verb}" if flagged else "")
                + f"; {c['outside_bands']} ok {noun} outside the bands; {c['in_bands']} in {len(self.bands)} bands "
                  f"({', '.join(self.bands.labels)} Hz)")

    def implausible_lines(self) -> list[str]:
        """What the cycles left out (or kept) as impossible were: one line each for reasons and models."""
        c, lines = self.counts, []
        verb = "kept (include_implausible)" if self.options["include_implausible"] else "left out"
        if c["implausible"]:
            why = ", ".join(f"{reason}: {n}" for reason, n in c["implausible_reasons"].items())
            lines.append(f"warning: {c['implausible']} ok {self.noun} have estimates that cannot be true ({why}); {verb}")
        if c["inadequate"]:
            lines.append(f"warning: {c['inadequate']} ok {self.noun} come from a model found inadequate for their record "
                         f"({ADEQUATE_COLUMN} False); {verb}")
        return lines

    def exclusion_lines(self) -> list[str]:
        """Per parameter, how many cycles did not determine it and whether they were left out."""
        lines = []
        table = self.exclusions()
        for parameter, row in table.iterrows():
            if self.options["include_undetermined"]:
                text = (f"{parameter}: {int(row['used'])} {self.noun} used, {int(row['undetermined'])} of them "
                        "undetermined (included)")
            else:
                text = f"{parameter}: {int(row['used'])} {self.noun} used, {int(row['excluded'])} undetermined left out"
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
            parts.append(f"{self.noun} that did not determine a parameter (*_determined False): "
                         + ("included" if o["include_undetermined"] else "left out of that parameter"))
            parts += ["  " + line for line in self.exclusion_lines()]
            parts += ["", "mean ± sd (n) per band:", self.band_table().to_string()]
            ci = (f"; {o['confidence']:.0%} bootstrap intervals from {o['n_bootstrap']} resamples (seed {o['seed']}) "
                  "in table2.csv") if o["n_bootstrap"] else ""
            parts += ["", f"Skew-normal fits (Eq. 19), cells 'm, s, a', Table 2 layout; fitted when a band has "
                          f">= {o['min_cycles']} {self.noun}{ci}:", self.table2().to_string()]
            if self.bands.is_article:
                comparison = self.compare_table2()
                fitted = comparison.dropna(subset=["ks"])
                if len(fitted):
                    worst = fitted["ks"].idxmax()
                    parts += ["", f"against the published Table 2: largest distance between the fitted and published "
                                  f"distribution functions {fitted['ks'].max():.3f} ({worst[0]}, band {worst[1]}); "
                                  f"median {fitted['ks'].median():.3f} over {len(fitted)} fitted cells "
                                  "(table2_vs_article.csv)"]
            parts += ["", f"Trends in the bouncing frequency (OLS on the {self.noun}):"]
            for parameter, trend in self.trends.items():
                parts.append(trend.summary() if isinstance(trend, TrendResult) else f"{parameter}: {trend}")
        return "\n".join(parts)

    def __str__(self) -> str:
        return self.summary()

    # -- figures -----------------------------------------------------------
    def plot_trends(self, path=None):
        """Parameters against ``f_b`` with band means ± sd and trends (like Fig. 6-8); see :mod:`smd_statespace.plotting.population`."""
        from ..plotting.population import plot_trends

        return plot_trends(self, path)

    def plot_histograms(self, parameter: str, path=None, published: bool = True):
        """Per-band histograms of one parameter with the fitted Eq. 19 densities; see :mod:`smd_statespace.plotting.population`."""
        from ..plotting.population import plot_histograms

        return plot_histograms(self, parameter, path, published=published)


def _check_options(min_cycles, n_bootstrap, confidence, seed, a_max, trend_degrees) -> dict:
    """The trend degree of every parameter: :data:`TREND_DEGREES` with ``trend_degrees``'s overrides.

    Raises an :class:`OptionError` naming the first invalid option of :func:`population_stats`.
    """
    for name, value, minimum in (("min_cycles", min_cycles, 3), ("n_bootstrap", n_bootstrap, 0)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum:
            raise OptionError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    if not 0 < confidence < 1:
        raise OptionError(f"confidence must be between 0 and 1, got {confidence!r}")
    whole = isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0
    if not (isinstance(seed, np.random.SeedSequence) or whole):
        raise OptionError(f"seed must be a non-negative whole number or a numpy SeedSequence, got {seed!r}")
    if not (np.isfinite(a_max) and a_max > 0):
        raise OptionError(f"a_max must be a positive number, got {a_max!r}")
    degrees = dict(TREND_DEGREES)
    for name, degree in dict(trend_degrees or {}).items():
        if name not in PARAMETERS or degree not in (1, 2):
            raise OptionError(f"trend_degrees: {name!r}: {degree!r}; give parameters of {', '.join(PARAMETERS)} "
                              "with degree 1 or 2")
        degrees[name] = degree
    return degrees


def _select_cycles(table: pd.DataFrame, bands: Bands, include_implausible: bool, noun: str) -> tuple:
    """``(counts, implausible)``: the cycles' tallies and the mask of implausible ``ok`` cycles.

    Adds the column ``band`` to ``table`` (-1 for a cycle that is not used or lies outside the
    bands); a :class:`RecordError` when no cycle is ``ok``, usable (plausible, from an adequate
    model, unless ``include_implausible``) or inside the bands.
    """
    sources_read = list(dict.fromkeys(table["source"]))
    by_status = {str(k): int(v) for k, v in table["status"].value_counts().items()}
    ok = (table["status"] == _STATUS_OK).to_numpy()
    if not ok.any():
        detail = ", ".join(f"{n} {s}" for s, n in sorted(by_status.items()))
        raise RecordError(f"{', '.join(sources_read)}: no 'ok' {noun} to analyse ({detail})")
    implausible = ok & table["implausible"].to_numpy(dtype=bool)
    inadequate = ok & ~table[ADEQUATE_COLUMN].to_numpy(dtype=bool)
    usable = ok & ((~implausible & ~inadequate) | include_implausible)
    if not usable.any():
        reasons = reason_counts(table.loc[implausible, "implausible_reason"])
        why = ", ".join(f"{reason}: {n}" for reason, n in reasons.items())
        raise RecordError(f"{', '.join(sources_read)}: all {int(ok.sum())} ok {noun} are implausible ({why or 'none'})"
                          f" or from an inadequate model ({int(inadequate.sum())}); nothing to analyse "
                          "(--include-implausible keeps them)")
    band = np.where(usable, bands.assign(table["f_b"].to_numpy()), -1)
    if not (band >= 0).any():
        f_ok = table.loc[usable, "f_b"]
        raise RecordError(f"{', '.join(sources_read)}: none of the {int(usable.sum())} ok {noun} has f_b inside the "
                          f"bands {bands.intervals[0][0]:g}-{bands.intervals[-1][1]:g} Hz (their f_b: "
                          f"{f_ok.min():.3g}-{f_ok.max():.3g} Hz); choose --bands to cover them")
    table["band"] = band
    counts = {"rows": int(len(table)), "by_status": by_status, "ok": int(ok.sum()),
              "implausible": int(implausible.sum()),
              "implausible_reasons": reason_counts(table.loc[implausible, "implausible_reason"]),
              "inadequate": int(inadequate.sum()), "usable": int(usable.sum()),
              "outside_bands": int((usable & (band < 0)).sum()), "in_bands": int((band >= 0).sum()),
              "sources": sources_read}
    return counts, implausible


def _fit_parameter(table: pd.DataFrame, parameter: str, bands: Bands, implausible: np.ndarray, cells: dict,
                   options: dict, noun: str):
    """Fit one parameter: its Eq. 19 skew-normal in every band (into ``cells``); returns its trend in ``f_b``.

    Adds the column ``used_<parameter>`` (the cycles its fits use) to ``table``. The trend is a
    :class:`TrendResult`, or ``"no trend (why)"`` when too few cycles or no spread.
    """
    include_undetermined, seed = options["include_undetermined"], options["seed"]
    p_index = list(PARAMETERS).index(parameter)  # seeds keyed by the parameter, not by what else is fitted
    spec = PARAMETERS[parameter]
    band = table["band"].to_numpy()
    values = table[spec.column].to_numpy(dtype=float)
    determined = np.logical_and.reduce([table[flag].to_numpy(dtype=bool) for flag in spec.determined_by])
    if options["include_implausible"]:  # identify clears the *_determined flags of implausible cycles; kept means kept
        determined = determined | implausible
    in_band = band >= 0
    used = in_band & np.isfinite(values) & (determined | include_undetermined)
    table[f"used_{parameter}"] = used
    for b in range(len(bands)):
        here = band == b
        undetermined = int((here & ~determined).sum())
        cells[parameter, b] = _fit_cell(
            parameter, b, values[here & used], 0 if include_undetermined else undetermined, undetermined,
            min_cycles=options["min_cycles"], n_bootstrap=options["n_bootstrap"], rng=np.random.default_rng(
                _seed_sequence(seed, 0, p_index, b)), confidence=options["confidence"], a_max=options["a_max"],
            noun=noun)
    f_b = table["f_b"].to_numpy()
    degree = int(options["trend_degrees"].get(parameter, 1))
    shortfall = _trend_shortfall(f_b[used], degree, noun) or _no_spread(values[used])
    return f"no trend ({shortfall})" if shortfall else fit_trend(
        f_b[used], values[used], degree, parameter=parameter, n_bootstrap=options["n_bootstrap"],
        rng=np.random.default_rng(_seed_sequence(seed, 1, p_index)), confidence=options["confidence"],
        cov_type=options["cov_type"])


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
        they are counted either way). Kept, they are used for every parameter: ``identify``
        clears their ``*_determined`` flags, which are then not applied to them.
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
    degrees = _check_options(min_cycles, n_bootstrap, confidence, seed, a_max, trend_degrees)
    table = read_results(sources, parameters=parameters, mass=mass)
    parameters, notes, noun = table.attrs["parameters"], list(table.attrs["notes"]), table.attrs["noun"]
    counts, implausible = _select_cycles(table, bands, include_implausible, noun)
    counts["notes"] = notes
    options = {"min_cycles": int(min_cycles), "n_bootstrap": int(n_bootstrap), "seed": seed,
               "include_undetermined": bool(include_undetermined),
               "include_implausible": bool(include_implausible), "confidence": float(confidence),
               "a_max": float(a_max), "cov_type": cov_type, "trend_degrees": degrees}
    cells, trends = {}, {}
    for parameter in parameters:
        trends[parameter] = _fit_parameter(table, parameter, bands, implausible, cells, options, noun)
    return PopulationStats(cycles=table, bands=bands, parameters=parameters, cells=cells, trends=trends,
                           counts=counts, options=options, noun=noun)


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
