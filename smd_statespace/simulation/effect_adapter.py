"""How the simulator uses an effect: its truth, its random inputs, its force harmonics, its measured columns.

An :class:`~smd_statespace.model.Effect` declares slots and terms only. The
simulator needs five more things of it; each has a default derived from the
declaration here, and an effect that knows better implements the method the
matching ``Protocol`` names (the built-in floor mode and extra harmonics do):

========================= =================================== ===============================================
function                  protocol                            default
========================= =================================== ===============================================
:func:`for_simulation`    :class:`SimulationSetup`            given values, then ``simulation_defaults``
:func:`draw_inputs`       :class:`SimulationInputs`           the effect unchanged (nothing random)
:func:`force_harmonics`   :class:`ForceHarmonics`             None (the effect is a term, not a force)
:func:`measured_signals`  :class:`MeasuredSignals`            no column
:func:`simulation_truth`  :class:`SimulationTruth`            the known values
========================= =================================== ===============================================
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ..errors import OptionError

if TYPE_CHECKING:  # annotations only
    import numpy as np
    import pandas as pd

    from ..model import Effect, SMDModel

__all__ = ["ForceHarmonics", "MeasuredSignals", "SimulationInputs", "SimulationSetup", "SimulationTruth",
           "draw_inputs", "for_simulation", "force_harmonics", "measured_signals", "simulation_truth"]


@runtime_checkable
class SimulationSetup(Protocol):
    """An effect that turns its own options into a simulation's truth (a floor's modal mass into a mass ratio)."""

    def for_simulation(self, model: "SMDModel", mass: float) -> "Effect":
        """This effect with every parameter slot at a known value, for a person of ``mass`` (kg)."""


@runtime_checkable
class SimulationInputs(Protocol):
    """An effect that needs random numbers of its own in a simulation (a floor's ambient excitation)."""

    def draw_simulation_inputs(self, rng: "np.random.Generator", duration: float) -> "Effect":
        """A copy of this effect with its random inputs drawn from ``rng`` for a record ``duration`` s long."""


@runtime_checkable
class ForceHarmonics(Protocol):
    """An effect that is more harmonics of the force (Eq. 4), which the simulator puts into the force itself."""

    def force_harmonics(self, model: "SMDModel"):
        """``(blf, phases)``: amplitudes (g) and phases (rad, or None for the default) of orders ``n+1, n+2, ...``."""


@runtime_checkable
class MeasuredSignals(Protocol):
    """An effect whose simulation writes record columns (a floor's measured acceleration ``floor_acc``)."""

    def measured_signals(self, states: "pd.DataFrame", normals, noise: float) -> dict:
        """Columns to add: ``states`` is the simulated states table, ``normals`` one standard normal per sample."""


@runtime_checkable
class SimulationTruth(Protocol):
    """An effect whose simulated truth is more than its known values (a floor's modal mass)."""

    def simulation_truth(self) -> dict:
        """What the simulation records as the effect's truth."""


def for_simulation(effect: "Effect", model: "SMDModel", mass: float) -> "Effect":
    """``effect`` ready for forward simulation: every parameter slot at a known value.

    Default: the given :attr:`~smd_statespace.model.Effect.values`, then
    :attr:`~smd_statespace.model.Effect.simulation_defaults`; a parameter with
    neither is an error naming it. ``model`` is the simulated person's model
    (base options set), ``mass`` the body mass (kg).

    Raises
    ------
    OptionError
        The effect needs measured signals and cannot say how to simulate
        them, or a parameter has no true value.
    """
    if isinstance(effect, SimulationSetup):
        return effect.for_simulation(model, mass)
    if effect.requires:
        raise OptionError(
            f"effect {effect.name!r} needs measured signals ({', '.join(effect.requires)}); it cannot be simulated"
        )
    values = {**effect.simulation_defaults, **effect.values}
    missing = [slot.name for slot in effect.slots(model) if slot.kind == "parameter" and slot.name not in values]
    if missing:
        raise OptionError(
            f"effect {effect.name!r}: give the true value of {', '.join(missing)} to simulate it, "
            f"e.g. {effect.name}:{missing[0]}=VALUE"
        )
    return effect.with_values(**values)


def draw_inputs(effect: "Effect", rng: "np.random.Generator", duration: float) -> "Effect":
    """``effect`` with its random simulation inputs drawn (default: the effect itself, nothing drawn).

    Called on what :func:`for_simulation` returned, after the person's own
    random numbers, so that an effect leaves those unchanged.
    """
    if isinstance(effect, SimulationInputs):
        return effect.draw_simulation_inputs(rng, duration)
    return effect


def force_harmonics(effect: "Effect", model: "SMDModel"):
    """Extra force harmonics the simulator adds to the force of Eq. 4 for ``effect``, or None (default)."""
    return effect.force_harmonics(model) if isinstance(effect, ForceHarmonics) else None


def measured_signals(effect: "Effect", states: "pd.DataFrame", normals, noise: float) -> dict:
    """Record columns a simulation of ``effect`` adds (default: none).

    ``states`` is the simulator's states table (columns ``u, u_dot,
    u_ddot``, every dynamic slot and its rate), ``normals`` standard normal
    numbers (one per sample) for measurement noise, ``noise`` the
    simulation's noise fraction.
    """
    return effect.measured_signals(states, normals, noise) if isinstance(effect, MeasuredSignals) else {}


def simulation_truth(effect: "Effect") -> dict:
    """What a simulation with ``effect`` records as its truth (default: its known values)."""
    return effect.simulation_truth() if isinstance(effect, SimulationTruth) else effect.values
