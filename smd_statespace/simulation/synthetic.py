"""The simulator's result, :class:`SyntheticRecord`, and the measured record it holds (Eq. 3 plus noise).

:func:`~smd_statespace.simulation.simulate_bouncing` returns a
:class:`SyntheticRecord`; :func:`_measured_record` makes its
:class:`~smd_statespace.io.Record` from the noise-free states. Re-exported by
:mod:`smd_statespace.simulation.bouncing`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ..io import G, Record, make_record, write_record
from .effect_adapter import measured_signals


@dataclass(frozen=True)
class SyntheticRecord:
    """A simulated record with everything that produced it.

    Attributes
    ----------
    record : Record
        The measurement an estimator sees: ``time`` (s), ``force`` (GRF, N,
        Eq. 3 plus noise), ``mass`` (kg) and, with ``floor_mode``,
        ``floor_acc`` (m/s^2, plus noise).
    truth : dict
        JSON-serialisable settings and derived values: ``mass, f_b, f_h,
        xi_h, K_h, C_h`` (Eq. 17-18), ``n_harmonics`` (base harmonics of the
        model, ``n``), ``n_force_harmonics`` (including the ``harmonics``
        effect), ``blf, phases, a0``, ``effects`` (with all parameters),
        ``seed, fs, duration, noise, variations``, ``n_cycles``.
    states : pandas.DataFrame
        Noise-free states per sample: ``time, cycle, u, u_dot, u_ddot,
        force_bio`` (absolute COM, SI; ``force_bio = g F`` in m/s^2) and, with
        a floor, ``z, z_dot, z_ddot``.
    cycles : pandas.DataFrame
        One row per force cycle: ``cycle, t_start, t_end, f_b, a0, a1, b1,
        ..., blf1, ...``: the coefficients of Eq. 4 referred to the cycle's
        own start (``F = a0 + sum a_i cos(2 pi i f_b (t - t_start)) + b_i
        sin(...)``) and the amplitudes (Eq. 5). The first cycle may start
        before ``t = 0`` and the last end after the record.
    """

    record: Record
    truth: dict
    states: pd.DataFrame
    cycles: pd.DataFrame

    def write(self, csv_path, truth_path=None):
        """Write the record as CSV and the truth as JSON.

        Parameters
        ----------
        csv_path : str or path-like
            Record file (columns ``time, force[, floor_acc]``, 6 decimals).
        truth_path : str or path-like, optional
            Truth file; default ``<csv stem>_truth.json`` beside the CSV. It
            holds :attr:`truth` plus ``"cycles"``: the per-cycle table as a
            dict of columns.

        Returns
        -------
        tuple of pathlib.Path
            ``(csv_path, truth_path)``.
        """
        csv_path = Path(csv_path)
        truth_path = csv_path.with_name(f"{csv_path.stem}_truth.json") if truth_path is None else Path(truth_path)
        write_record(csv_path, self.record)
        content = dict(self.truth)
        content["cycles"] = {
            column: [round(float(v), 10) if column != "cycle" else int(v) for v in self.cycles[column]]
            for column in self.cycles.columns
        }
        truth_path.write_text(_format_json(content), encoding="utf-8")
        return csv_path, truth_path


def _format_json(content):
    """JSON text with one top-level key (or one key of a nested dict) per line."""
    lines = []
    for key, value in content.items():
        if isinstance(value, dict) and value:
            inner = [f"  {json.dumps(k)}: {json.dumps(v)}" for k, v in value.items()]
            lines.append(f" {json.dumps(key)}: {{\n" + ",\n".join(inner) + "\n }")
        else:
            lines.append(f" {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


def _measured_record(settings, states, grf_noise, floor_noise):
    """The :class:`Record` an estimator sees: Eq. 3 plus noise (and the noisy floor acceleration)."""
    s = settings
    weight = s.mass * G
    force = s.mass * (G + states["u_ddot"].to_numpy()) + s.noise * weight * grf_noise  # Eq. 3
    columns = {}
    for effect in s.effects:
        columns.update(measured_signals(effect, states, floor_noise, s.noise))
    return make_record(states["time"].to_numpy(), force, s.mass, source="synthetic", **columns)
