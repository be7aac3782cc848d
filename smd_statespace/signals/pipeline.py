"""The whole pre-processing of a record (:func:`preprocess`) and its result, :class:`Preprocessed`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from ..errors import MassError, OptionError, RecordError
from ..io import Record
from .cycles import SUPPORTED_FB, Cycle, find_cycles
from .filters import com_acceleration, motion
from .weighing import weigh_record

__all__ = ["OBSERVATION_CHANNELS", "Preprocessed", "preprocess"]


OBSERVATION_CHANNELS = ("u", "u_dot", "u_ddot")
"""Names of the observation channels of Eq. 13: COM displacement (m),
velocity (m/s) and acceleration (m/s^2)."""


@dataclass(frozen=True)
class Preprocessed:
    """Every intermediate signal of the pre-processing of one record.

    Attributes
    ----------
    time : ndarray, shape (T,)
        Sample times (s).
    force : ndarray, shape (T,)
        Measured GRF (N).
    mass : float
        Body mass ``M_h`` (kg).
    fs : float
        Sampling frequency (Hz).
    acc_raw : ndarray, shape (T,)
        COM acceleration from Eq. 3 (m/s^2), unfiltered.
    acc : ndarray, shape (T,)
        High-passed COM acceleration ``u_ddot`` (m/s^2).
    vel : ndarray, shape (T,)
        COM velocity ``u_dot`` (m/s).
    disp : ndarray, shape (T,)
        COM displacement ``u`` from static equilibrium (m).
    peaks : ndarray of int, shape (P,)
        Sample indices of the GRF peaks.
    cycles : list of Cycle
        The ``P - 1`` cycles between consecutive peaks.
    cutoff : float
        High-pass cut-off frequency (Hz).
    floor_acc, floor_vel, floor_disp : ndarray or None, shape (T,)
        High-passed floor acceleration (m/s^2), its velocity (m/s) and
        displacement (m), when the record has a floor acceleration.
    source : str
        Name of the record.
    """

    time: np.ndarray
    force: np.ndarray
    mass: float
    fs: float
    acc_raw: np.ndarray
    acc: np.ndarray
    vel: np.ndarray
    disp: np.ndarray
    peaks: np.ndarray
    cycles: list = field(default_factory=list)
    cutoff: float = 0.5
    floor_acc: np.ndarray | None = None
    floor_vel: np.ndarray | None = None
    floor_disp: np.ndarray | None = None
    source: str = "<arrays>"

    @property
    def duration(self) -> float:
        """Record length (s)."""
        return float(self.time[-1] - self.time[0])

    @property
    def valid_cycles(self) -> list:
        """The cycles flagged valid."""
        return [cycle for cycle in self.cycles if cycle.valid]

    def _cycle(self, cycle) -> Cycle:
        """Accept a :class:`Cycle` or its index and return the Cycle."""
        if isinstance(cycle, Cycle):
            return cycle
        if isinstance(cycle, (int, np.integer)) and not isinstance(cycle, bool):
            if 0 <= cycle < len(self.cycles):
                return self.cycles[int(cycle)]
            raise OptionError(
                f"{self.source}: cycle {cycle} does not exist; the record has {len(self.cycles)} cycles "
                f"(0-{len(self.cycles) - 1})"
            )
        raise OptionError(f"cycle must be a Cycle or a cycle index, got {cycle!r}")

    def to_frame(self) -> pd.DataFrame:
        """The per-sample signals as a DataFrame.

        Returns
        -------
        pandas.DataFrame
            Columns ``time`` (s), ``force`` (N), ``acc_raw``, ``acc``
            (m/s^2), ``vel`` (m/s), ``disp`` (m) and, with a floor signal,
            ``floor_acc`` (m/s^2), ``floor_vel`` (m/s), ``floor_disp`` (m).
        """
        data = {
            "time": self.time,
            "force": self.force,
            "acc_raw": self.acc_raw,
            "acc": self.acc,
            "vel": self.vel,
            "disp": self.disp,
        }
        if self.floor_acc is not None:
            data.update(floor_acc=self.floor_acc, floor_vel=self.floor_vel, floor_disp=self.floor_disp)
        return pd.DataFrame(data)

    def cycle_table(self) -> pd.DataFrame:
        """One row per cycle.

        Returns
        -------
        pandas.DataFrame
            Columns ``cycle`` (index), ``t_start``, ``t_end`` (s),
            ``n_samples``, ``f_b`` (Hz), ``valid`` and ``reason``.
        """
        columns = ["cycle", "t_start", "t_end", "n_samples", "f_b", "valid", "reason"]
        rows = [
            (c.index, c.t_start, c.t_end, c.n_samples, c.f_b, c.valid, c.reason) for c in self.cycles
        ]
        return pd.DataFrame(rows, columns=columns)

    def observations(self, cycle, channels=OBSERVATION_CHANNELS):
        """Observation vectors ``Y_k`` (Eq. 13) over one cycle.

        Parameters
        ----------
        cycle : Cycle or int
            The cycle, or its index.
        channels : sequence of str, default ("u", "u_dot", "u_ddot")
            Channels in the wanted column order: ``"u"`` displacement (m),
            ``"u_dot"`` velocity (m/s), ``"u_ddot"`` high-passed acceleration
            (m/s^2).

        Returns
        -------
        t : ndarray, shape (m,)
            Absolute sample times of the cycle (s), boundary peaks included.
        y : ndarray, shape (m, len(channels))
            The channels, one column each.

        Raises
        ------
        OptionError
            Unknown channel name, empty channel list or unknown cycle.
        """
        if isinstance(channels, str):
            channels = (channels,)
        channels = tuple(channels)
        signals = {"u": self.disp, "u_dot": self.vel, "u_ddot": self.acc}
        if not channels:
            raise OptionError(f"channels is empty; choose from {', '.join(OBSERVATION_CHANNELS)}")
        for name in channels:
            if name not in signals:
                raise OptionError(f"unknown channel {name!r}; choose from {', '.join(OBSERVATION_CHANNELS)}")
        span = self._cycle(cycle).samples
        y = np.column_stack([signals[name][span] for name in channels])
        return self.time[span].copy(), y

    def exogenous(self, cycle) -> dict:
        """Floor motion over one cycle (inputs of the moving-floor model, Section 6).

        Parameters
        ----------
        cycle : Cycle or int
            The cycle, or its index.

        Returns
        -------
        dict of str to ndarray
            ``floor_disp`` (m), ``floor_vel`` (m/s) and ``floor_acc``
            (m/s^2) over the cycle's samples, shape (m,) each; an empty dict
            when the record has no floor acceleration.
        """
        span = self._cycle(cycle).samples
        if self.floor_acc is None:
            return {}
        return {
            "floor_disp": self.floor_disp[span].copy(),
            "floor_vel": self.floor_vel[span].copy(),
            "floor_acc": self.floor_acc[span].copy(),
        }

    def summary(self) -> str:
        """One paragraph describing the pre-processed record.

        Returns
        -------
        str
            Number of cycles (valid ones), median bouncing frequency and its
            range over the valid cycles (Hz), sampling frequency (Hz),
            duration (s), high-pass cut-off (Hz) and RMS of the COM
            acceleration (m/s^2), velocity (m/s) and displacement (m).
        """
        valid = self.valid_cycles
        basis = valid if valid else self.cycles
        f_b = np.array([c.f_b for c in basis])
        which = "valid cycles" if valid else "all cycles, none valid"

        def rms(x):
            return float(np.sqrt(np.mean(np.square(x))))

        text = (
            f"{self.source}: {len(self.cycles)} bouncing cycles ({len(valid)} valid) in "
            f"{self.duration:.2f} s sampled at {self.fs:g} Hz, body mass {self.mass:g} kg. "
            f"Bouncing frequency median {np.median(f_b):.3f} Hz, range {f_b.min():.3f}-{f_b.max():.3f} Hz "
            f"({which}). High-pass cut-off {self.cutoff:g} Hz. RMS of the COM acceleration "
            f"{rms(self.acc):.3g} m/s^2, velocity {rms(self.vel):.3g} m/s, displacement {rms(self.disp):.3g} m."
        )
        if self.floor_acc is not None:
            text += (
                f" Floor RMS acceleration {rms(self.floor_acc):.3g} m/s^2, "
                f"displacement {rms(self.floor_disp):.3g} m."
            )
        return text

    def plot(self, path=None, zoom_cycles=3):
        """Plot every pre-processing step, one row of panels each
        (:func:`~smd_statespace.plotting.pipeline.plot_preprocessed`); saved as PNG (100 dpi) if ``path``."""
        from ..plotting.pipeline import plot_preprocessed  # the pipeline's own figure: matplotlib when drawn

        return plot_preprocessed(self, path, zoom_cycles)


def _check_edge_margin(edge_margin) -> float:
    """``edge_margin`` as a float (s), or an :class:`OptionError` if it is not a non-negative time."""
    try:
        edge_margin = float(edge_margin)
    except (TypeError, ValueError):
        raise OptionError(f"edge_margin={edge_margin!r} must be a time in s") from None
    if not (math.isfinite(edge_margin) and edge_margin >= 0):
        raise OptionError(f"edge_margin={edge_margin!r} must be a non-negative time in s")
    return edge_margin


def _flag_edge_cycles(cycles: list, time: np.ndarray, edge_margin: float) -> list:
    """``cycles`` with those within ``edge_margin`` (s) of either end of ``time`` marked invalid, saying why."""
    t_first, t_last = float(time[0]), float(time[-1])
    flagged = []
    for cycle in cycles:
        near = cycle.t_start - t_first < edge_margin or t_last - cycle.t_end < edge_margin
        if near:
            note = f"within {edge_margin:g} s of a record end (filter edge effects)"
            reason = f"{cycle.reason}; {note}" if cycle.reason else note
            cycle = replace(cycle, valid=False, reason=reason)
        flagged.append(cycle)
    return flagged


def preprocess(record: Record, cutoff=0.5, fb_range=SUPPORTED_FB, *, order=4, padding="predict",
               edge_margin=2.0) -> Preprocessed:
    """Run the whole pre-processing pipeline on one record.

    ``acc_raw`` (Eq. 3) ``--highpass--> acc --integrate--> vel --integrate-->
    disp``, the same for the floor acceleration when present, and the cycles
    from the GRF peaks.

    Parameters
    ----------
    record : Record
        A checked record (see :func:`smd_statespace.io.make_record`).
    cutoff : float, default 0.5
        High-pass cut-off frequency (Hz).
    fb_range : tuple of float, default :data:`SUPPORTED_FB`
        Accepted bouncing frequencies (Hz).
    order : int, default 4
        Butterworth order of one filter pass.
    padding : {"predict", "odd", "even"}, default "predict"
        End treatment of the high-pass; see :func:`highpass`.
    edge_margin : float, default 2.0
        Cycles that start within this time (s) of the record start, or end
        within it of the record end, are flagged invalid: the filtered and
        integrated signals are least accurate there. 0 disables the flag.

    Returns
    -------
    Preprocessed

    Raises
    ------
    CycleError
        No peaks, fewer than two peaks, or median bouncing frequency outside
        ``fb_range`` (the message names ``record.source``).
    OptionError
        An invalid option, or a record too short for the filter.
    """
    record = weigh_record(record)  # read without a mass: the plate weighs the person
    source = record.source
    edge_margin = _check_edge_margin(edge_margin)
    time = np.asarray(record.time, dtype=float)
    force = np.asarray(record.force, dtype=float)
    fs = float(record.fs)
    peaks, cycles = find_cycles(time, force, fb_range, source=source)
    try:
        acc_raw = com_acceleration(force, record.mass)  # Eq. 3
        acc, vel, disp = motion(acc_raw, fs, cutoff, order, padding=padding)
        floor_acc = floor_vel = floor_disp = None
        if record.floor_acc is not None:
            floor_acc, floor_vel, floor_disp = motion(record.floor_acc, fs, cutoff, order, padding=padding)
    except (OptionError, MassError, RecordError) as exc:
        raise type(exc)(f"{source}: {exc}") from None

    if edge_margin > 0:
        cycles = _flag_edge_cycles(cycles, time, edge_margin)

    return Preprocessed(
        time=time,
        force=force,
        mass=float(record.mass),
        fs=fs,
        acc_raw=acc_raw,
        acc=acc,
        vel=vel,
        disp=disp,
        peaks=peaks,
        cycles=cycles,
        cutoff=float(cutoff),
        floor_acc=floor_acc,
        floor_vel=floor_vel,
        floor_disp=floor_disp,
        source=source,
    )
