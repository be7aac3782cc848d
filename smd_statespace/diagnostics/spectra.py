"""Welch spectra of a series and its peaks above the noise floor, labelled by bouncing harmonic.

Functions over arrays, used by :meth:`ModelCheck.residual_spectrum
<smd_statespace.diagnostics.check.ModelCheck.residual_spectrum>` and
:meth:`~smd_statespace.diagnostics.check.ModelCheck.measured_spectrum`:

- :func:`welch_spectrum`: Welch power spectral density with a segment of
  :data:`SEGMENT_CYCLES` bouncing periods;
- :func:`welch_dof`: the equivalent chi-square degrees of freedom of that estimate;
- :func:`peak_threshold`: the level pure noise exceeds in some bin with a given probability;
- :func:`spectral_peaks`: the peaks above it, labelled "harmonic k" or "non-harmonic";
- :func:`residual_spectrum`: all of them on one series.

Frequencies in Hz, power spectral densities in the series' unit squared per Hz
(N^2/Hz for a force).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["HARMONIC_TOLERANCE", "PEAK_FALSE_ALARM", "SEGMENT_CYCLES", "segment_length", "welch_spectrum",
           "welch_dof", "peak_threshold", "refine_peak", "harmonic_label", "spectral_peaks", "residual_spectrum"]

HARMONIC_TOLERANCE = 0.05
"""A spectral peak within this fraction of ``f_b`` (or 1.5 frequency bins,
whichever is larger) of ``k f_b`` is labelled "harmonic k"."""

PEAK_FALSE_ALARM = 0.01
"""Probability that pure noise puts at least one bin of a residual spectrum
above the peak threshold (sets the threshold from the Welch estimate's
chi-square distribution)."""

SEGMENT_CYCLES = 6.0
"""Default Welch segment length in bouncing cycles: frequency resolution
about ``f_b / 6`` (0.33 Hz at 2 Hz), enough to tell harmonic ``k`` from
``k +- 1/2``, while a 10 s stretch still gives several segments to average."""

PEAK_COLUMNS = ["frequency", "power", "ratio_to_floor", "label", "k", "f_over_fb"]


def segment_length(n, fs, f_b, nperseg=None) -> int:
    """Welch segment length (samples) for a series of ``n`` samples.

    Parameters
    ----------
    n : int
        Length of the series (samples).
    fs : float
        Sampling frequency (Hz).
    f_b : float
        Bouncing frequency (Hz).
    nperseg : int, optional
        Requested length; default :data:`SEGMENT_CYCLES` bouncing periods,
        ``round(SEGMENT_CYCLES fs / f_b)``.

    Returns
    -------
    int
        The length, at least 16 and at most ``n``.
    """
    if nperseg is None:
        nperseg = int(round(SEGMENT_CYCLES * fs / f_b))
    return int(min(max(nperseg, 16), n))


def welch_spectrum(values, fs, f_b, nperseg=None):
    """Welch power spectral density (Hann window, 50 % overlap, mean removed per segment).

    Parameters
    ----------
    values : ndarray, shape (T,)
        The series (e.g. a force in N).
    fs : float
        Sampling frequency (Hz).
    f_b : float
        Bouncing frequency (Hz), for the default segment length (:func:`segment_length`).
    nperseg : int, optional
        Segment length (samples).

    Returns
    -------
    freq : ndarray, shape (F,)
        Frequencies (Hz).
    psd : ndarray, shape (F,)
        Power spectral density (the series' unit squared per Hz).
    """
    from scipy import signal  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

    nperseg = segment_length(len(values), fs, f_b, nperseg)
    return signal.welch(values, fs=fs, nperseg=nperseg, detrend="constant", scaling="density")


def welch_dof(n, nperseg) -> float:
    """Equivalent degrees of freedom of a Hann-window, 50 %-overlap Welch estimate.

    Parameters
    ----------
    n : int
        Length of the series (samples).
    nperseg : int
        Segment length (samples).

    Returns
    -------
    float
        ``2 K / (1 + 2 c^2 (K - 1) / K)`` for ``K`` segments, ``c = 0.167``
        the overlap correlation of two Hann segments at 50 % (Welch 1967;
        Percival & Walden): a bin of the estimate of white noise of level
        ``S`` is distributed as ``S chi2(dof) / dof``.
    """
    segments = max(1, 1 + (n - nperseg) // (nperseg // 2))
    # Overlap correlation of two Hann segments at 50 %: c = 0.167 (Welch 1967; Percival & Walden).
    return 2.0 * segments / (1.0 + 2.0 * 0.167**2 * (segments - 1) / segments)


def peak_threshold(floor, n_bins, dof, false_alarm=PEAK_FALSE_ALARM) -> float:
    """The level white noise of median PSD ``floor`` exceeds in some of ``n_bins`` bins with chance ``false_alarm``.

    A bin of the noise PSD is ``level chi2(dof) / dof``, whose median is
    ``level chi2.median(dof) / dof``; each bin gets the false-alarm
    probability ``false_alarm / n_bins`` (Bonferroni).

    Parameters
    ----------
    floor : float
        Median PSD of the noise (unit^2/Hz).
    n_bins : int
        Number of bins searched.
    dof : float
        Degrees of freedom of the estimate (:func:`welch_dof`).
    false_alarm : float
        Chance that pure noise gives at least one peak.

    Returns
    -------
    float
        The threshold (unit^2/Hz).
    """
    from scipy import stats  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

    ratio = stats.chi2.isf(false_alarm / max(n_bins, 1), dof) / stats.chi2.median(dof)
    return floor * ratio


def refine_peak(freq, psd, i) -> float:
    """Frequency (Hz) of the peak at bin ``i``, refined by parabolic interpolation of the log PSD.

    Parameters
    ----------
    freq, psd : ndarray, shape (F,)
        Equally spaced frequencies (Hz) and the PSD there.
    i : int
        The bin of a local maximum.

    Returns
    -------
    float
        ``freq[i]`` moved by at most half a bin (unchanged at either end of the spectrum).
    """
    f_peak = float(freq[i])
    if 0 < i < len(psd) - 1:
        a, b, c = np.log(psd[i - 1:i + 2])
        denominator = a - 2.0 * b + c
        if denominator < 0:
            f_peak += 0.5 * (a - c) / denominator * float(freq[1] - freq[0])
    return f_peak


def harmonic_label(frequency, f_b, tolerance):
    """Label of a spectral line: ``("harmonic k", k)`` within ``tolerance`` (Hz) of ``k f_b`` (``k >= 1``),
    else ``("non-harmonic", pandas.NA)``."""
    k = int(np.round(frequency / f_b))
    if k >= 1 and abs(frequency - k * f_b) <= tolerance:
        return f"harmonic {k}", k
    return "non-harmonic", pd.NA


def spectral_peaks(freq, psd, f_b, dof, min_frequency, false_alarm=PEAK_FALSE_ALARM, tolerance=None) -> pd.DataFrame:
    """The peaks of a PSD above its noise floor, labelled by bouncing harmonic.

    The noise floor is the median PSD above ``min_frequency`` (measurement
    noise is white, and model error occupies a minority of the bins). A
    peak is a local maximum above ``min_frequency`` whose PSD exceeds
    :func:`peak_threshold`. Peak frequencies are refined by
    :func:`refine_peak` and labelled by :func:`harmonic_label`.

    Parameters
    ----------
    freq, psd : ndarray, shape (F,)
        Equally spaced frequencies (Hz) and the PSD (unit^2/Hz), e.g. of :func:`welch_spectrum`.
    f_b : float
        Bouncing frequency (Hz).
    dof : float
        Degrees of freedom of the estimate (:func:`welch_dof`).
    min_frequency : float
        Lowest frequency searched (Hz), e.g. the high-pass cut-off.
    false_alarm : float
        Chance that pure noise gives at least one peak.
    tolerance : float, optional
        Largest distance (Hz) from ``k f_b`` for the label "harmonic k";
        default the larger of :data:`HARMONIC_TOLERANCE` ``* f_b`` and 1.5
        frequency bins.

    Returns
    -------
    pandas.DataFrame
        One row per peak, strongest first: ``frequency`` (Hz), ``power``
        (unit^2/Hz), ``ratio_to_floor``, ``label`` ("harmonic k" or
        "non-harmonic"), ``k`` (nearest harmonic order, or <NA> for a
        non-harmonic peak) and ``f_over_fb``. ``attrs`` holds
        ``noise_floor``, ``threshold`` (unit^2/Hz), ``f_b``, ``tolerance``
        (Hz) and ``resolution`` (Hz).
    """
    from scipy import signal  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

    resolution = float(freq[1] - freq[0])
    band = freq > float(min_frequency)
    floor = float(np.median(psd[band]))
    threshold = peak_threshold(floor, int(band.sum()), dof, false_alarm)
    tol = max(HARMONIC_TOLERANCE * f_b, 1.5 * resolution) if tolerance is None else float(tolerance)
    where, _ = signal.find_peaks(psd)
    rows = []
    for i in where[band[where] & (psd[where] > threshold)]:
        f_peak = refine_peak(freq, psd, i)
        label, k = harmonic_label(f_peak, f_b, tol)
        rows.append({"frequency": f_peak, "power": float(psd[i]), "ratio_to_floor": float(psd[i] / floor),
                     "label": label, "k": k, "f_over_fb": f_peak / f_b})
    peaks = pd.DataFrame(rows, columns=PEAK_COLUMNS)
    peaks["k"] = peaks["k"].astype("Int64")
    peaks = peaks.sort_values("power", ascending=False).reset_index(drop=True)
    peaks.attrs.update(noise_floor=floor, threshold=threshold, f_b=f_b, tolerance=tol, resolution=resolution)
    return peaks


def residual_spectrum(values, fs, f_b, nperseg=None, false_alarm=PEAK_FALSE_ALARM, tolerance=None,
                      min_frequency=0.5):
    """Welch spectrum of a series and its peaks above the noise floor (:func:`spectral_peaks`).

    A missing force harmonic leaves a line at ``k f_b`` in a model's
    residual; a floor mode leaves content at its own frequency, in general
    not a multiple of ``f_b``; a nonlinearity (cubic spring) leaves
    harmonics above those the force model has.

    Parameters
    ----------
    values : ndarray, shape (T,)
        The series (N for a GRF residual).
    fs : float
        Sampling frequency (Hz).
    f_b : float
        Bouncing frequency (Hz).
    nperseg : int, optional
        Welch segment length (samples); default :data:`SEGMENT_CYCLES`
        bouncing periods (frequency resolution about ``f_b / 6``).
    false_alarm, tolerance, min_frequency
        As in :func:`spectral_peaks` (``min_frequency`` in Hz: the high-pass cut-off).

    Returns
    -------
    freq : ndarray, shape (F,)
        Frequencies (Hz).
    psd : ndarray, shape (F,)
        Power spectral density (unit^2/Hz).
    peaks : pandas.DataFrame
        :func:`spectral_peaks`.
    """
    freq, psd = welch_spectrum(values, fs, f_b, nperseg)
    n = len(values)
    dof = welch_dof(n, segment_length(n, fs, f_b, nperseg))
    return freq, psd, spectral_peaks(freq, psd, f_b, dof, min_frequency, false_alarm, tolerance)
