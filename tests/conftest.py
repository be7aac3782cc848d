"""Fixtures shared by the test modules: simulated records and the expensive fits made from them.

Session-scoped, so a record is simulated and a person identified once per test run, whichever
modules use them. Plain helpers (no fixtures) are in ``helpers.py``.
"""

import pytest

from smd_statespace.simulation import simulate_bouncing


@pytest.fixture(scope="session")
def short_sim():
    """An 8 s record (f_b 2 Hz, f_h 2.5 Hz, xi_h 0.3, 1 % BW noise)."""
    return simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=8, seed=1)


@pytest.fixture(scope="session")
def long_sim():
    """A 40 s record with little noise; its true force-cycle boundaries are known."""
    return simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.25, duration=40, noise=0.002, seed=11)


@pytest.fixture(scope="session")
def long_fit(long_sim):
    """The record-level person of :func:`long_sim` (the default ``identify_person``)."""
    from smd_statespace.person import identify_person

    return identify_person(long_sim.record)
