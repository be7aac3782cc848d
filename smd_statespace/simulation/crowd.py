"""Crowd loads: many people bouncing together, each an SMD model drawn from Table 2.

What a structural engineer needs to check a grandstand or a floor: the
ground reaction forces (GRF) of ``N`` people bouncing at one frequency ``f_b``
and their sum. Each person

- is drawn from the article's skew-normal fits (Table 2, Eq. 19) for the
  band holding ``f_b``, or from a user's own table in the same layout
  (:func:`fit_table`), by :func:`~smd_statespace.simulation.population.sample_population`:
  ``f_h``, ``xi_h``, BLF1-3 independent (the article gives marginals only),
  the body mass from ``N(65, 10)`` kg truncated to 45-100 kg
  (:data:`~smd_statespace.simulation.population.MASS_DISTRIBUTION`), ``K_h`` and ``C_h``
  from Eq. 17-18;
- has its own phase offset (the start of its first cycle uniform over
  ``phase_spread`` of a cycle; 1 = unsynchronised) and its own
  cycle-to-cycle variation of frequency and harmonics, drawn exactly as
  :func:`~smd_statespace.simulation.simulate_bouncing` draws them;
- bounces on a rigid floor: Eq. 2 under the force of Eq. 4 (three harmonics,
  BLF1-3, phases giving a realistic GRF shape,
  :func:`~smd_statespace.simulation.default_phases`), GRF by Eq. 3 without
  measurement noise;
- stays in contact with the floor. The SMD model has no flight phase: where
  its GRF would go below zero the person would have to pull on the floor.
  A draw whose steady periodic GRF dips below zero
  (:func:`periodic_grf_minimum`, closed form) or whose simulated GRF does
  (the cycle-to-cycle variation can push a marginal person under) is
  rejected and the person redrawn from their own next seeds
  (:func:`person_seeds` with ``draw = 1, 2, ...``); the people table and the
  summary count the rejected draws and their reasons. The crowd is therefore
  drawn from Table 2 *conditional on contact*: fewer lightly damped people
  with ``f_h`` near a harmonic of ``f_b`` than Table 2's marginals alone give.

Person ``i``'s GRF is exactly ``simulate_bouncing(mass, f_b, f_h, xi_h,
blf=(BLF1, BLF2, BLF3), noise=0, seed=force_seed)`` (tested to 1e-6 N), but
computed by the exact, vectorised linear solution of
:func:`smd_statespace.simulation.floor.batch_response` instead of one ODE integration
per person: 50 people x 30 s at 200 Hz take well under a second.

Reproducibility: everything comes from one :class:`numpy.random.SeedSequence`;
person ``i``'s draw ``d`` uses the children ``(i, 2 d)`` and ``(i, 2 d + 1)``
for the parameters and the force (draw 0 is the first; redraws take the next
pair), so person ``i`` is the same whatever the number of people, the
chunking or the order of computation. A redraw caused by the cycle-to-cycle
variation depends on the duration (a longer record has more cycles that can
dip), so the same seed gives the same crowd for the same duration.
"""


from __future__ import annotations

import time as _time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .. import article
from ..errors import OptionError
from ..io import G
from ..model import acceleration_frf
from .crowd_forces import CHUNK, N_HARMONICS, _person_cycles, _simulate_forces  # noqa: F401 (CHUNK from here too)
from .crowd_table import TABLE_PARAMETERS, fit_table  # noqa: F401 (TABLE_PARAMETERS from here too)
from .dynamics import _simulation_effects
from .force_shape import steady_grf_shape
from .population import _population_columns, with_stiffness_and_damping

__all__ = [
    "CROWD_SETTINGS",
    "N_HARMONICS",
    "Crowd",
    "DEFAULT_DURATION",
    "MAX_DRAWS",
    "person_seeds",
    "fit_table",
    "draw_people",
    "periodic_grf_minimum",
    "simulate_crowd",
]
CROWD_SETTINGS = {
    "fs": 200.0,
    "fb_variation": 0.02,
    "coef_variation": 0.10,
    "phase_spread": 1.0,
}
"""Defaults of :func:`simulate_crowd`: sampling frequency (Hz), relative SD of
the cycle frequency and of the harmonics from cycle to cycle (as
:func:`~smd_statespace.simulation.simulate_bouncing`), spread of the phase
offsets (fraction of a cycle; 1 = unsynchronised, 0 = all start together)."""

DEFAULT_DURATION = 30.0
"""Default length (s) of :func:`simulate_crowd` and ``smd-statespace crowd``: 40-110 cycles over
the article's bands, enough to resolve the total force's harmonics to ``1/30`` Hz."""

MAX_DRAWS = 50
"""Draws of one person before :func:`simulate_crowd` gives up finding one who stays in contact."""


# ---------------------------------------------------------------------------
# seeds


def _root(seed) -> np.random.SeedSequence:
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if seed is None:
        return np.random.SeedSequence()
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise OptionError(f"crowd: seed must be None, a non-negative whole number or a SeedSequence, got {seed!r}")
    return np.random.SeedSequence(int(seed))


def person_seeds(seed, index, draw=0):
    """Seeds of person ``index``'s draw ``draw``: ``(parameters, force)`` SeedSequences.

    They are the children ``2 draw`` and ``2 draw + 1`` of
    ``SeedSequence(entropy, spawn_key=(..., index))`` (draw 0: what
    ``spawn(2)`` gives), so they depend only on the crowd's seed, the
    person's index and the draw number.

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        The crowd's seed.
    index : int
        Person number, from 0.
    draw : int
        0 for the first draw; ``1, 2, ...`` for the redraws of a person who
        lost contact (the ``draw`` column of :attr:`Crowd.people`).

    Returns
    -------
    tuple of numpy.random.SeedSequence
    """
    root = _root(seed)
    key = tuple(root.spawn_key) + (int(index),)
    return tuple(np.random.SeedSequence(root.entropy, spawn_key=key + (2 * int(draw) + j,), pool_size=root.pool_size)
                 for j in (0, 1))


# ---------------------------------------------------------------------------
# people


def _check_count(n, name="n"):
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1:
        raise OptionError(f"crowd: {name} must be a whole number >= 1, got {n!r}")
    return int(n)


def _band_fits(table, f_b):
    """The skew-normal fits of the band holding ``f_b``; an error in words outside the article's bands."""
    if article.band_of(f_b) is None:
        edges = ", ".join(f"{lo:g}-{hi:g}" for lo, hi in article.BANDS)
        raise OptionError(f"crowd: f_b = {f_b!r} Hz is outside the article's bands ({edges} Hz), "
                          "the only ones Table 2 has fits for")
    return fit_table(table, f_b)


def draw_people(n, f_b, seed=None, table=None, bounds=None) -> pd.DataFrame:
    """Draw ``n`` people bouncing at ``f_b``: the crowd's parameters, without simulating forces.

    Person ``i`` is :func:`~smd_statespace.simulation.population.sample_population` of one
    person with the parameter seed of :func:`person_seeds` ``(seed, i)``.

    Parameters
    ----------
    n : int
        Number of people.
    f_b : float
        Bouncing frequency (Hz), within the article's bands 1.35-3.75 Hz.
    seed : None, int or numpy.random.SeedSequence
        The crowd's seed (None: fresh entropy).
    table : see :func:`fit_table`
        Default the article's Table 2.
    bounds : dict, optional
        Overrides of :data:`~smd_statespace.simulation.population.POPULATION_BOUNDS`.

    Returns
    -------
    pandas.DataFrame
        One row per person: ``person``, ``f_b`` (Hz), ``f_h`` (Hz), ``xi_h``,
        ``blf1, blf2, blf3`` (g), ``mass`` (kg), ``K_h`` (N/m), ``C_h`` (N s/m).
    """
    n = _check_count(n)
    root, fits = _root(seed), _band_fits(table, f_b)
    people = pd.DataFrame(_draw_parameters(root, np.arange(n), np.zeros(n, dtype=int), f_b, fits, bounds))
    people.insert(0, "person", np.arange(n))
    return people


def _draw_parameters(root, indices, draws, f_b, fits, bounds):
    """Parameters of people ``indices`` at their draws ``draws``: arrays, as :func:`sample_population`."""
    rows = [_population_columns(1, f_b, person_seeds(root, i, d)[0], fits, bounds) for i, d in zip(indices, draws)]
    return with_stiffness_and_damping({key: np.concatenate([row[key] for row in rows]) for key in rows[0]})


def periodic_grf_minimum(f_b, f_h, xi_h, blf, points=2048):
    """Least value of a person's steady periodic GRF over body weight (closed form, vectorised).

    With the force phases of :func:`~smd_statespace.simulation.default_phases`,
    harmonic ``k`` of the steady dynamic GRF is ``|H(k f_b)| BLF_k cos(k theta
    - pi/4)`` body weights (``H`` of
    :func:`~smd_statespace.model.acceleration_frf`), so the GRF is ``1 +
    sum_k |H(k f_b)| BLF_k cos(k theta - pi/4)`` body weights; its minimum over
    a cycle is taken on ``points`` phases (error below ``(pi/points)^2 / 2 sum
    k^2 |H_k| BLF_k``, about 1e-5 body weights). Below zero the person would
    pull on the floor: the model needs a flight phase there.

    Parameters
    ----------
    f_b : float
        Bouncing frequency (Hz).
    f_h, xi_h : array_like, shape (P,)
        SMD natural frequency (Hz) and damping ratio of each person.
    blf : array_like, shape (P, K)
        Force harmonics BLF_1..K (g).
    points : int
        Phases per cycle on which the minimum is taken.

    Returns
    -------
    ndarray, shape (P,)
        Minimum GRF over body weight (-).
    """
    f_h = np.atleast_1d(np.asarray(f_h, dtype=float))
    xi_h = np.atleast_1d(np.asarray(xi_h, dtype=float))
    blf = np.atleast_2d(np.asarray(blf, dtype=float))
    orders = np.arange(1, blf.shape[1] + 1)
    amplitude = np.abs(acceleration_frf(orders * f_b, f_h[:, None], xi_h[:, None])) * blf
    _, shape = steady_grf_shape(amplitude, points)
    return 1.0 + shape.min(axis=1)


# ---------------------------------------------------------------------------
# the crowd


@dataclass
class Crowd:
    """A simulated crowd (:func:`simulate_crowd`).

    Attributes
    ----------
    people : pandas.DataFrame
        One row per person: ``person``, ``f_b, f_h`` (Hz), ``xi_h``,
        ``blf1..3`` (g), ``mass`` (kg), ``K_h`` (N/m), ``C_h`` (N s/m),
        ``weight`` (N), ``phase_offset`` (fraction of a cycle by which the
        person's first cycle had started at ``t = 0``), ``grf_peak`` (N),
        ``dlf1..3`` (amplitude of the person's GRF at ``f_b, 2 f_b, 3 f_b``
        over the body weight), ``grf_min`` (N, the person's least GRF, >= 0),
        ``draw`` (the draw kept, for :func:`person_seeds`; 0 = the first),
        ``rejected_steady`` and ``rejected_cycles`` (draws of this person
        rejected because their steady periodic GRF, or a simulated cycle's GRF
        with its cycle-to-cycle variation, went below zero), ``seed``,
        ``spawn_key``.
    forces : pandas.DataFrame
        ``time`` (s), one GRF column per person ``person_000, ...`` (N,
        including the body weight) and ``total`` (N, their sum).
    settings : dict
        ``n, f_b, duration, fs, fb_variation, coef_variation, phase_spread,
        seed`` (the root entropy), ``table``, ``redrawn`` (people not kept at
        their first draw), ``rejected_steady``, ``rejected_cycles`` (rejected
        draws by reason, summed over people).
    cycles : list of pandas.DataFrame
        Each person's force cycles (layout of ``SyntheticRecord.cycles``).
    seconds : float
        Wall-clock time of the simulation (s).
    """

    people: pd.DataFrame
    forces: pd.DataFrame
    settings: dict
    cycles: list
    seconds: float = 0.0

    @property
    def time(self) -> np.ndarray:
        """Sample times (s)."""
        return self.forces["time"].to_numpy()

    @property
    def total(self) -> np.ndarray:
        """Total crowd force (N), the sum of the people's GRFs."""
        return self.forces["total"].to_numpy()

    @property
    def weight(self) -> float:
        """Total static weight of the crowd (N)."""
        return float(self.people["weight"].sum())

    def spectrum(self):
        """One-sided amplitude spectrum of the total dynamic force.

        Returns
        -------
        frequency : ndarray
            Hz.
        amplitude : ndarray
            N: a sinusoid of amplitude ``A`` N at a bin frequency gives ``A``.
        """
        dynamic = self.total - self.total.mean()
        fs = self.settings["fs"]
        amplitude = 2.0 * np.abs(np.fft.rfft(dynamic)) / dynamic.size
        return np.fft.rfftfreq(dynamic.size, 1.0 / fs), amplitude

    def harmonics(self, count=N_HARMONICS) -> pd.DataFrame:
        """Amplitude of the total force near ``k f_b`` (largest bin within ±10 % of ``f_b``).

        Returns
        -------
        pandas.DataFrame
            Index ``harmonic`` (k); ``frequency`` (Hz), ``amplitude_N`` (N) and
            ``amplitude_per_weight`` (over the crowd's total weight).
        """
        frequency, amplitude = self.spectrum()
        f_b = self.settings["f_b"]
        rows = []
        for k in range(1, count + 1):
            near = np.abs(frequency - k * f_b) <= 0.1 * f_b
            j = np.flatnonzero(near)[np.argmax(amplitude[near])]
            rows.append({"harmonic": k, "frequency": frequency[j], "amplitude_N": amplitude[j],
                         "amplitude_per_weight": amplitude[j] / self.weight})
        return pd.DataFrame(rows).set_index("harmonic")

    def summary(self) -> str:
        """A few lines for the terminal: who, how much force, how fast."""
        s, people = self.settings, self.people
        dynamic = self.total - self.weight
        lines = [
            f"{s['n']} people bouncing at {s['f_b']:g} Hz for {s['duration']:g} s at {s['fs']:g} Hz "
            f"(seed {s['seed']}, {s['table']}); simulated in {self.seconds:.2f} s.",
            f"people: mass {people['mass'].mean():.1f} ± {people['mass'].std(ddof=0):.1f} kg, "
            f"f_h {people['f_h'].median():.2f} Hz (median), xi_h {people['xi_h'].median():.2f}, "
            f"BLF1-3 {people['blf1'].median():.3f} / {people['blf2'].median():.3f} / "
            f"{people['blf3'].median():.3f} g (medians)",
            f"total: weight {self.weight / 1000:.2f} kN, "
            f"dynamic force RMS {np.sqrt(np.mean(dynamic**2)) / 1000:.2f} kN, "
            f"range {dynamic.min() / 1000:+.2f} to {dynamic.max() / 1000:+.2f} kN",
        ]
        parts = [f"{k} f_b: {row.amplitude_N / 1000:.2f} kN ({row.amplitude_per_weight:.3f} W)"
                 for k, row in self.harmonics().iterrows()]
        lines.append("total force harmonics: " + ", ".join(parts))
        lines.append(self.contact_summary())
        return "\n".join(lines)

    def contact_summary(self) -> str:
        """One line: how many people were redrawn because they would have lost contact, and why."""
        s, people = self.settings, self.people
        lowest = people["grf_min"] / people["weight"]
        least = f"least GRF {lowest.min():.2f} body weights (person {int(lowest.idxmin())})"
        if s["redrawn"] == 0:
            return f"contact: every person stays on the floor at the first draw (GRF >= 0); {least}"
        return (f"contact: {s['redrawn']} of {s['n']} people redrawn because their GRF went below zero (they "
                f"would pull on the floor; the SMD model has no flight phase): {s['rejected_steady']} rejected "
                f"draw(s) with a steady periodic GRF below zero, {s['rejected_cycles']} with a cycle's GRF below "
                f"zero under the cycle-to-cycle variation; now {least}")

    def write(self, csv_path, people_path=None):
        """Write the forces and the people table as CSV.

        Parameters
        ----------
        csv_path : str or path-like
            Forces: ``time, person_000, ..., total`` (N, 3 decimals; time 6).
        people_path : str or path-like, optional
            Default ``<csv stem>_people.csv`` beside it.

        Returns
        -------
        tuple of pathlib.Path
        """
        csv_path = Path(csv_path)
        people_path = csv_path.with_name(f"{csv_path.stem}_people.csv") if people_path is None else Path(people_path)
        forces = self.forces.round(3)  # 1 mN
        forces["time"] = self.forces["time"].round(6)
        forces.to_csv(csv_path, index=False)
        self.people.to_csv(people_path, index=False, float_format="%.6g")
        return csv_path, people_path

    def plot(self, path=None, n_people=3):
        """Figure: a few people's GRFs, the total crowd force and its spectrum
        (:func:`~smd_statespace.plotting.crowd.plot_crowd`)."""
        from ..plotting.crowd import plot_crowd  # the crowd's own figure: matplotlib when drawn

        return plot_crowd(self, path, n_people)


def _check_settings(duration, fs, fb_variation, coef_variation, phase_spread, f_b):
    def number(value, name, low=None, high=None, positive=False):
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise OptionError(f"crowd: {name} must be a number, got {value!r}") from None
        if not np.isfinite(value) or (positive and value <= 0) or (low is not None and value < low) or \
                (high is not None and value > high):
            span = "> 0" if positive else f"in {low:g}-{high:g}"
            raise OptionError(f"crowd: {name} must be {span}, got {value!r}")
        return value

    duration = number(duration, "duration (s)", positive=True)
    fs = number(fs, "fs (Hz)", positive=True)
    fb_variation = number(fb_variation, "fb_variation", 0.0, 0.2)
    coef_variation = number(coef_variation, "coef_variation", 0.0, 1.0)
    phase_spread = number(phase_spread, "phase_spread", 0.0, 1.0)
    f_b = number(f_b, "f_b (Hz)", positive=True)
    if duration < 1.0 / f_b:
        raise OptionError(f"crowd: duration {duration:g} s is shorter than one bouncing cycle "
                          f"(1/f_b = {1 / f_b:.3g} s)")
    highest = N_HARMONICS * f_b
    if fs < 4.0 * highest:
        raise OptionError(f"crowd: fs {fs:g} Hz is too low; it must be at least 4 x the highest harmonic "
                          f"({highest:g} Hz), i.e. >= {4 * highest:g} Hz")
    return duration, fs, fb_variation, coef_variation, phase_spread, f_b


def simulate_crowd(n, f_b, duration=DEFAULT_DURATION, fs=None, seed=None, table=None, bounds=None, fb_variation=None,
                   coef_variation=None, phase_spread=None, effects=None) -> Crowd:
    """Simulate ``n`` people bouncing at ``f_b`` on a rigid floor: their GRFs and the total crowd force.

    Parameters
    ----------
    n : int
        Number of people, >= 1.
    f_b : float
        Bouncing frequency (Hz), within 1.35-3.75 Hz (the article's bands).
    duration : float
        Length (s), default :data:`DEFAULT_DURATION` (30 s); samples at ``0,
        1/fs, ..., duration``.
    fs : float
        Sampling frequency (Hz), default 200; at least 4 x ``3 f_b``.
    seed : None, int or numpy.random.SeedSequence
        The crowd's seed; None draws fresh entropy (``settings["seed"]``
        records it so the crowd can be repeated).
    table : see :func:`fit_table`
        Skew-normal fits; default the article's Table 2.
    bounds : dict, optional
        Overrides of :data:`~smd_statespace.simulation.population.POPULATION_BOUNDS`.
    fb_variation, coef_variation : float
        Cycle-to-cycle relative SD of the frequency (0-0.2) and of the
        harmonics (0-1); defaults in :data:`CROWD_SETTINGS`.
    phase_spread : float
        Phase offsets uniform on ``[0, phase_spread)`` cycles (0-1, default 1).
    effects : list of Effect or str, or dict, optional
        Physical effects every person has, as for
        :func:`~smd_statespace.simulation.simulate_bouncing` (any registered
        effect; a ``floor_mode`` is a floor under each person alone, a floor
        shared by the crowd is :mod:`smd_statespace.simulation.floor`'s). Each person's
        model is then integrated numerically (about 1-2 s per person for
        30 s) instead of solved exactly; the contact check stays exact on
        the simulated GRF, the quick steady-state pre-check is the rigid
        floor's.

    Returns
    -------
    Crowd
        Every person's GRF is >= 0 at every sample: a draw that would pull
        on the floor is rejected and the person redrawn (module docstring;
        ``Crowd.settings["redrawn"]`` and the people table count them).

    Raises
    ------
    OptionError
        Bad arguments, or a person still out of contact after
        :data:`MAX_DRAWS` draws (fits that put almost everyone out of contact).
    """
    started = _time.perf_counter()
    n = _check_count(n)
    settings = dict(CROWD_SETTINGS)
    for key, value in (("fs", fs), ("fb_variation", fb_variation), ("coef_variation", coef_variation),
                       ("phase_spread", phase_spread)):
        if value is not None:
            settings[key] = value
    duration, fs, fb_variation, coef_variation, phase_spread, f_b = _check_settings(
        duration, settings["fs"], settings["fb_variation"], settings["coef_variation"], settings["phase_spread"], f_b)
    root, fits = _root(seed), _band_fits(table, f_b)
    effects = () if effects is None else effects
    checked = _simulation_effects(effects, 70.0, where="crowd")  # a bad effect fails before any person is drawn
    n_samples = int(np.floor(duration * fs + 1e-9)) + 1
    time = np.arange(n_samples) / fs

    parameters, cycles, offsets, forces, draw, rejected = _draw_in_contact(
        n, f_b, root, fits, bounds, time, duration, fb_variation, coef_variation, phase_spread, effects)
    people, frame = _people_and_forces(parameters, forces, offsets, draw, rejected, root, time, f_b, fs)
    table_label = "Table 2" if table is None else ("a user table" if not isinstance(table, (str, Path))
                                                   else f"table {table}")
    settings.update(n=n, f_b=f_b, duration=duration, fs=fs, fb_variation=fb_variation,
                    coef_variation=coef_variation, phase_spread=phase_spread, seed=root.entropy, table=table_label,
                    redrawn=int(np.count_nonzero(draw)), rejected_steady=int(rejected["steady"].sum()),
                    rejected_cycles=int(rejected["cycles"].sum()), effects=[effect.spec for effect in checked])
    return Crowd(people=people, forces=frame, settings=settings, cycles=cycles,
                 seconds=_time.perf_counter() - started)


def _draw_in_contact(n, f_b, root, fits, bounds, time, duration, fb_variation, coef_variation, phase_spread, effects):
    """Draw every person, and redraw those who would lose contact, until all stay on the floor.

    A draw is rejected when its steady periodic GRF dips below zero
    (:func:`periodic_grf_minimum`) or its simulated GRF does; the person is
    redrawn from their next seeds (:func:`person_seeds`).

    Returns
    -------
    parameters : dict of ndarray
        The kept draws' parameters (:func:`draw_people`'s columns), per person.
    cycles : list of pandas.DataFrame
        Each person's force cycles.
    offsets : ndarray
        Each person's phase offset (fraction of a cycle).
    forces : ndarray, shape (n, samples)
        Each person's GRF (N).
    draw : ndarray of int
        The draw kept per person (0: the first).
    rejected : dict of ndarray
        ``"steady"`` and ``"cycles"``: rejected draws per person by reason.

    Raises
    ------
    OptionError
        A person still out of contact after :data:`MAX_DRAWS` draws.
    """
    n_samples = time.size
    draw = np.zeros(n, dtype=int)
    rejected = {"steady": np.zeros(n, dtype=int), "cycles": np.zeros(n, dtype=int)}
    parameters, cycles, offsets = {}, [None] * n, np.empty(n)
    forces = np.empty((n, n_samples))
    pending = np.arange(n)
    while pending.size:
        worst = int(draw[pending].max())
        if worst >= MAX_DRAWS:
            i = int(pending[np.argmax(draw[pending])])
            raise OptionError(f"crowd: person {i} lost contact with the floor (GRF < 0) in all {MAX_DRAWS} draws "
                              f"at f_b = {f_b:g} Hz; the fits put almost everyone out of contact there")
        drawn = _draw_parameters(root, pending, draw[pending], f_b, fits, bounds)
        for key, values in drawn.items():
            parameters.setdefault(key, np.empty(n))[pending] = values
        blf = np.column_stack([drawn[f"blf{k}"] for k in range(1, N_HARMONICS + 1)])
        steady = periodic_grf_minimum(f_b, drawn["f_h"], drawn["xi_h"], blf) < 0.0
        rejected["steady"][pending[steady]] += 1
        kept = pending[~steady]
        for i in kept:
            person_blf = np.array([parameters[f"blf{k}"][i] for k in range(1, N_HARMONICS + 1)])
            cycles[i], offsets[i] = _person_cycles(person_seeds(root, i, draw[i])[1], f_b, parameters["f_h"][i],
                                                   parameters["xi_h"][i], person_blf, duration, fb_variation,
                                                   coef_variation, phase_spread)
        _simulate_forces(kept, parameters, cycles, time, forces, effects)
        dipped = kept[forces[kept].min(axis=1) < 0.0]
        rejected["cycles"][dipped] += 1
        pending = np.sort(np.concatenate([pending[steady], dipped]))
        draw[pending] += 1
    return parameters, cycles, offsets, forces, draw, rejected


def _people_and_forces(parameters, forces, offsets, draw, rejected, root, time, f_b, fs):
    """The people table and the forces frame of :class:`Crowd` from the kept draws and their GRFs.

    Returns
    -------
    people : pandas.DataFrame
        :attr:`Crowd.people`: the parameters plus weight, phase offset, GRF
        peak and minimum, dynamic load factors, draws and seeds.
    frame : pandas.DataFrame
        :attr:`Crowd.forces`: ``time``, one GRF column per person, ``total``.
    """
    n, n_samples = forces.shape
    people = pd.DataFrame(parameters)
    people.insert(0, "person", np.arange(n))
    mass = people["mass"].to_numpy()
    width = max(3, len(str(n - 1)))
    names = [f"person_{i:0{width}d}" for i in range(n)]
    frame = pd.DataFrame(forces.T, columns=names)
    frame.insert(0, "time", time)
    frame["total"] = forces.sum(axis=0)

    weight = mass * G
    spectrum = np.abs(np.fft.rfft(forces - forces.mean(axis=1, keepdims=True), axis=1)) * 2.0 / n_samples
    frequency = np.fft.rfftfreq(n_samples, 1.0 / fs)
    people["weight"] = weight
    people["phase_offset"] = offsets
    people["grf_peak"] = forces.max(axis=1)
    people["grf_min"] = forces.min(axis=1)
    for k in range(1, N_HARMONICS + 1):
        near = np.abs(frequency - k * f_b) <= 0.1 * f_b
        people[f"dlf{k}"] = spectrum[:, near].max(axis=1) / weight
    people["draw"] = draw
    people["rejected_steady"] = rejected["steady"]
    people["rejected_cycles"] = rejected["cycles"]
    people["seed"] = str(root.entropy)
    people["spawn_key"] = [" ".join(map(str, tuple(root.spawn_key) + (i,))) for i in range(n)]
    return people, frame
