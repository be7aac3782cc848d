"""The record as read, and what the front end made of it: its parts, the fitted span, its spectrum with the hum.

:func:`plot_record_parts` draws a :class:`~smd_statespace.signals.PreparedRecord`
(:func:`~smd_statespace.signals.prepare_record`): the force over the whole record with its
standing, starting/stopping, bouncing and other parts shaded and the fitted span marked, and the
force's spectrum up to the record's own Nyquist frequency before and after the mains hum was
subtracted, with the hum's lines and the fitting rate's Nyquist frequency marked. ``identify``
writes it as ``person_record.png``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy import signal

from ..io import G
from .person import DPI
from .save import save

__all__ = ["PART_COLORS", "plot_record_parts"]

PART_COLORS = {"standing": "tab:green", "ramp": "tab:orange", "bouncing": "tab:blue", "movement": "0.55",
               "no_contact": "tab:red"}
"""Shade of each kind of part of a record."""

_MOST_POINTS = 40_000  # points of the force drawn (every k-th sample beyond)


def plot_record_parts(prepared, path=None) -> Figure:
    """The record's parts over time (top) and its force spectrum before and after the hum's subtraction (bottom).

    Parameters
    ----------
    prepared : PreparedRecord
        What :func:`~smd_statespace.signals.prepare_record` returned (``PersonResult.prepared``).
    path : str or Path, optional
        Where to save the PNG.
    """
    original = prepared.original
    fig = Figure(figsize=(10.0, 6.4))
    fig.subplots_adjust(left=0.08, right=0.985, bottom=0.08, top=0.95, hspace=0.3)  # fixed: a layout engine, 0.2 s
    top, bottom = fig.subplots(2, 1, height_ratios=(1.1, 1.0))
    step = max(1, original.time.size // _MOST_POINTS)
    top.plot(original.time[::step], original.force[::step], color="k", lw=0.5)
    seen = set()
    for part in (prepared.bouts.segments if prepared.bouts is not None else ()):
        top.axvspan(part.start, part.end, color=PART_COLORS[part.kind], alpha=0.18, lw=0,
                    label=None if part.kind in seen else part.kind.replace("_", " "))
        seen.add(part.kind)
    if prepared.span is not None:
        for edge in prepared.span:
            top.axvline(edge, color="tab:blue", lw=1.4)
        top.annotate("fitted", xy=(float(np.mean(prepared.span)), 0.03), xycoords=("data", "axes fraction"),
                     ha="center", va="bottom", fontsize=9, color="tab:blue", weight="bold")
    weighed = "weighed" if original.extra.get("weighed") else "given"
    top.axhline(original.mass * G, color="tab:purple", lw=0.8, ls="--", label=f"{weighed} mass x g")
    top.set(xlabel="time (s)", ylabel="force (N)", xlim=(original.time[0], original.time[-1]))
    top.legend(fontsize=7, loc="upper right", ncol=3)
    said = next((note for note in prepared.notes if note.startswith(("bouncing", "span"))), "the whole record fitted")
    top.set_title(f"{Path(str(original.source)).name}: {said.split(';')[0]}", fontsize=9, loc="left")
    _spectrum(bottom, prepared)
    return save(fig, path, DPI)


def _spectrum(ax, prepared):
    """Welch spectra (4 s segments) of the force as read and with the hum subtracted; hum lines and the new Nyquist."""
    original = prepared.original
    fs = original.fs
    hum = prepared.hum is not None and prepared.hum.found
    curves = [(original, "0.55", 2.0, "as read" if hum else "as read (no mains hum found)")]
    if hum:  # a second curve only when something was subtracted
        curves.append((replace(original, force=original.force - prepared.hum.waveform), "tab:blue", 0.7,
                       "hum subtracted"))
    segment = min(original.time.size, int(4 * fs))
    for record, color, width, label in curves:
        frequency, power = signal.welch(record.force - np.mean(record.force), fs=fs, nperseg=segment)
        ax.semilogy(frequency[1:], power[1:], color=color, lw=width, label=label)
    if hum:
        for frequency, amplitude, line in zip(prepared.hum.harmonics, prepared.hum.amplitudes, prepared.hum.lines):
            if line:
                ax.axvline(frequency, color="tab:red", lw=0.8, ls=":")
                ax.annotate(f"{frequency:.0f} Hz, {amplitude:.2g} N", xy=(frequency, 0.97),
                            xycoords=("data", "axes fraction"), rotation=90, ha="right", va="top", fontsize=7,
                            color="tab:red")
    nyquist = 0.5 * prepared.record.fs
    ax.axvline(nyquist, color="k", lw=1.0, ls="--", label=f"fitting rate's Nyquist frequency ({nyquist:.3g} Hz)")
    ax.set(xlabel="frequency (Hz)", ylabel="force PSD (N^2/Hz)", xlim=(0, 0.5 * fs))
    ax.legend(fontsize=7, loc="upper right")

