"""The shipped sample record: its settings and where its files are.

``data/sample.csv`` and ``data/sample_truth.json`` in the package are
:func:`~smd_statespace.simulation.simulate_bouncing` with
:data:`SAMPLE_SETTINGS`; :func:`~smd_statespace.simulation.bouncing.write_sample`
regenerates them. Re-exported by :mod:`smd_statespace.simulation.bouncing`.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

SAMPLE_SETTINGS = {
    "mass": 70.0,
    "f_b": 2.0,
    "f_h": 2.5,
    "xi_h": 0.3,
    "duration": 30.0,
    "fs": 100.0,
    "seed": 2019,
}
"""Settings of the shipped sample record (other arguments at their defaults)."""

SAMPLE_CSV = "sample.csv"
SAMPLE_TRUTH = "sample_truth.json"


def sample_path() -> Path:
    """Path of the shipped sample record ``data/sample.csv`` (70 kg, see :data:`SAMPLE_SETTINGS`)."""
    return Path(str(resources.files("smd_statespace").joinpath("data", SAMPLE_CSV)))


def sample_truth_path() -> Path:
    """Path of the truth of the shipped sample, ``data/sample_truth.json``."""
    return Path(str(resources.files("smd_statespace").joinpath("data", SAMPLE_TRUTH)))
