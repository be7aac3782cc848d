"""The ``floor_mode`` effect: the person bounces on a vibrating floor (human-structure interaction, Section 6)."""

from __future__ import annotations

import copy

import numpy as np

from .. import article
from ..errors import OptionError, check_range
from ..model import coupling
from ..model.core import F_H, TWO_PI, XI_H, Slot
from ..model.effect import Effect, slot_count, spec_value
from .excitation import ambient_floor_excitation, ambient_line_count
from .options import nonnegative, positive

__all__ = ["FloorMode"]


class FloorMode(Effect):
    """The person bounces on a vibrating floor (human-structure interaction, Section 6).

    The leg spring and damper act on the COM motion relative to the floor
    displacement ``z`` (m, upward)::

        u'' = -omega_h^2 (u - z) - 2 xi_h omega_h (u' - z') + F_bio / M_h

    so the effect adds ``omega_h^2 z + 2 xi_h omega_h z'`` to the acceleration
    of Eq. 10 (:func:`smd_statespace.model.coupling.leg_acceleration`, the
    coupling every floor model uses). ``u''`` stays the absolute COM
    acceleration, which the GRF measures through Eq. 3. Where ``z`` comes
    from depends on ``source``:

    ``"measured"``
        The record has a ``floor_acc`` column; its high-passed, integrated
        velocity and displacement (:func:`smd_statespace.signals.preprocess`)
        are exogenous inputs (``requires = ("floor_disp", "floor_vel")``). No
        slots are added.
    ``"modal"``
        No floor measurement: the floor is one modal oscillator whose state
        and parameters are estimated with the person's::

            z'' = -omega_f^2 z - 2 xi_f omega_f z' - mass_ratio u''

        i.e. ``m_f z'' + c_f z' + k_f z = -M_h u''`` divided by the modal mass
        ``m_f = M_h / mass_ratio``: the floor is driven by the dynamic GRF
        (:func:`~smd_statespace.model.coupling.modal_force` with ``phi = 1``).
        Slots ``z`` (m), ``z_dot`` (m/s), then the parameters ``f_f`` (Hz),
        ``xi_f`` (-) and ``mass_ratio`` (-), all three non-linear.

    The default source is ``"modal"`` when any option of the modal floor is
    given, else ``"measured"``.

    A simulation (:func:`~smd_statespace.simulation.simulate_bouncing`,
    ``simulate --effect floor_mode:...``) integrates the modal floor with
    the given ``frequency``, ``damping`` and ``mass_ratio`` as the truth
    (defaults: mode 1 of the article's plate, Table 3: 3.48 Hz, 0.0037, and
    ``M_h / modal_mass`` with ``modal_mass`` 8583 kg), writes the floor
    acceleration as the record's ``floor_acc`` column (white noise of
    ``noise`` times its RMS), and adds ``ambient`` floor vibration from other
    sources (see :func:`~smd_statespace.effects.excitation.ambient_floor_excitation`).

    The simulated record starts in the coupled (person + floor) periodic
    steady state of the first cycle's force: with ``fb_variation=0`` and
    ``coef_variation=0`` the floor amplitude is constant from ``t = 0``.
    With cycle-to-cycle variation it is not, because the default floor mode
    is lightly damped (half-power bandwidth ``2 xi_f f_f`` = 0.026 Hz, decay
    time ``1 / (xi_f w_f)`` = 12 s) and a force harmonic near it (e.g. the
    2nd at ``f_b`` = 1.75 Hz) moves across the resonance as ``f_b`` varies:
    the start is the steady state of the first cycle's frequency alone
    (often off resonance: at a constant ``f_b`` of 1.72, 1.75 and 1.78 Hz
    the floor amplitude is 0.55, 0.95 and 0.33 m/s^2), and the floor then
    takes about its decay time to settle to the response to the varying
    force, which itself wanders (beats) as the cycle frequencies come and
    go. At ``f_b`` 1.75 Hz, ``f_h`` 1.8 Hz, ``xi_h`` 0.33, 70 kg and the
    default variations, the amplitude over the first 5 s averages 0.58
    m/s^2 (SD 0.24 over 30 seeds) against 0.94 m/s^2 (SD 0.18) over the
    last 5 s of 30 s records. Drop the first ~15 s, or set
    ``fb_variation=0``, where a stationary floor response matters. With
    ``variation="smooth"`` the integration starts a run-in of up to 60 s
    (about 5 decay times) before the record, so the floor has settled by
    ``t = 0``.

    Whether the GRF shows ``ambient`` floor vibration depends on its
    frequency, not on periodicity: below about ``n f_b`` a cycle's Fourier
    force absorbs any smooth floor motion (measured: 0.2 m/s^2 at 3.48 Hz
    left nothing in the residual); above it the floor reaches the GRF
    through the leg's transmissibility (about 0.15 at 9 Hz), so about
    1 m/s^2 is needed to stand out of 1 % BW noise.

    =============== ================ =========================================
    symbol          slot / option    meaning (unit)
    =============== ================ =========================================
    ``z``           ``"z"``          floor displacement at the person (m)
    ``z'``          ``"z_dot"``      floor velocity (m/s)
    ``f_f``         ``"f_f"``        floor modal frequency (Hz)
    ``xi_f``        ``"xi_f"``       floor modal damping ratio (-)
    ``M_h / m_f``   ``"mass_ratio"`` person mass over floor modal mass (-)
    =============== ================ =========================================

    Parameters
    ----------
    source : {"measured", "modal"}, optional
        Where the floor motion comes from (see above).
        :meth:`for_record` picks it from the record.
    frequency : float, optional
        ``"modal"``: the floor frequency (Hz). Estimated mode: a seed, e.g. a
        peak of the residual spectrum; the prior of ``f_f`` is then uniform
        on ``frequency * (1 -+ frequency_spread)``. Known mode (with
        ``damping``) and simulation: the value.
    frequency_spread : float, optional
        ``"modal"`` only: relative half-width of that prior (default 0.15).
    frequency_range : (float, float), optional
        ``"modal"`` only: the prior range of ``f_f`` (Hz) given directly;
        default 2-20 Hz when no ``frequency`` is given.
    damping_range : (float, float), optional
        ``"modal"`` only: prior range of ``xi_f`` (default 0.001-0.05). The
        record-level model searches 0-0.05 unless it is given.
    mass_ratio_range : (float, float), optional
        ``"modal"`` only: prior range of ``M_h / m_f`` (default 0.001-0.05;
        one 70 kg person on the article's plate, 8583 kg: 0.008). The
        record-level model searches up to :data:`RECORD_MASS_RATIO_HIGH`
        (0.2) unless it is given.
    damping, mass_ratio : float, optional
        ``"modal"``: a *known* mode. With ``frequency`` and ``damping``
        (and ``mass_ratio``, default 0.008: 70 kg on mode 1 of the article's
        plate) given, ``f_f``, ``xi_f`` and ``M_h / m_f`` are constants, as
        from a modal test of the floor (the article's Table 3), and only the
        floor's motion ``z``, ``z_dot`` is estimated. Fewer values per cycle
        than an estimated mode: a floor mode is one frequency for the whole
        record. In a simulation: the true values.
    displacement, velocity : float, optional
        ``"modal"`` only: nominal magnitudes of ``z`` (m, default 1e-3) and
        ``z'`` (m/s, default 1e-2): the prior spread of the unobserved floor
        state and, times ``process_noise``, its process noise per step. They
        are fixed, not scaled by the person's data, because the floor moves
        one or two orders of magnitude less than the COM.
    modal_mass : float, optional
        Simulation only: the floor's modal mass (kg, default 8583, Table 3)
        when ``mass_ratio`` is not given; the simulated person's mass over it
        is the mass ratio. (Identification reads ``mass_ratio``.)
    noise : float, optional
        Simulation only: floor-acceleration noise as a fraction of its RMS
        (default: the simulation's GRF noise fraction).
    ambient : float, optional
        Simulation only: RMS floor acceleration (m/s^2) from other sources
        (default 0).

    Attributes
    ----------
    requires : tuple of str
        Exogenous signals needed: ``("floor_disp", "floor_vel")`` when
        measured, none when modal.
    requires_columns : tuple of str
        Record columns those signals come from: ``("floor_acc",)`` when measured.
    slot_names : tuple of str
        Names of the slots the ``"modal"`` source estimates, in state order
        (``z``, ``z_dot`` only for a known mode).
    known : bool
        Whether the modal floor's ``f_f``, ``xi_f`` and mass ratio are given constants.

    Examples
    --------
    >>> FloorMode()
    FloorMode(source='measured')
    >>> FloorMode(frequency=3.48).slot_names
    ('z', 'z_dot', 'f_f', 'xi_f', 'mass_ratio')
    >>> FloorMode("modal", frequency=3.48, damping=0.0037).slot_names
    ('z', 'z_dot')
    """

    name = "floor_mode"
    SOURCES = ("measured", "modal")
    MODAL_DEFAULTS = {
        "frequency_spread": 0.15,
        "frequency_range": (2.0, 20.0),
        "damping_range": (0.001, 0.05),
        "mass_ratio_range": (0.001, 0.05),
        "displacement": 1e-3,
        "velocity": 1e-2,
    }
    SIMULATION_ONLY = ("modal_mass", "noise", "ambient")
    KNOWN_MASS_RATIO = 70.0 / article.TABLE3[0].modal_mass
    """Default ``M_h / m_f`` of a known mode: a 70 kg person on mode 1 of the article's plate (0.008)."""
    ALL_SLOTS = ("z", "z_dot", "f_f", "xi_f", "mass_ratio")
    simulated_mass = None
    """The person's mass (kg) of a floor prepared for simulation (:meth:`for_simulation`), else None."""
    known = False

    def __init__(self, source=None, *, frequency=None, frequency_spread=None, frequency_range=None,
                 damping_range=None, mass_ratio_range=None, displacement=None, velocity=None, damping=None,
                 mass_ratio=None, modal_mass=None, noise=None, ambient=None, **unknown):
        where = "floor_mode"
        if unknown:
            valid = ["source", "frequency", "damping", "mass_ratio"] + list(self.MODAL_DEFAULTS) + list(
                self.SIMULATION_ONLY)
            raise OptionError(
                f"effect {where!r}: unknown option {', '.join(map(repr, unknown))}; valid: {', '.join(valid)}"
            )
        modal = {"frequency": frequency, "frequency_spread": frequency_spread, "frequency_range": frequency_range,
                 "damping_range": damping_range, "mass_ratio_range": mass_ratio_range,
                 "displacement": displacement, "velocity": velocity, "damping": damping, "mass_ratio": mass_ratio}
        given = [key for key, value in modal.items() if value is not None]
        if source is None:
            source = "modal" if given else "measured"
        if source not in self.SOURCES:
            raise OptionError(
                f"{where}: source {source!r} is unknown; choose 'measured' (the record has a floor_acc column) "
                "or 'modal' (estimate one floor mode)"
            )
        self.source = source
        self.modal_mass = None if modal_mass is None else positive(modal_mass, "modal_mass (kg)", where)
        self.noise = None if noise is None else nonnegative(noise, "noise", where)
        self.ambient = 0.0 if ambient is None else nonnegative(ambient, "ambient (m/s^2)", where)
        self.simulation_given = {key: value for key, value in
                                 (("modal_mass", modal_mass), ("noise", noise), ("ambient", ambient))
                                 if value is not None}
        self._excitation = None
        self.slot_names = self.ALL_SLOTS
        if source == "measured":
            if given:
                raise OptionError(
                    f"{where}: option {given[0]!r} applies to source='modal' only; the measured floor has no "
                    "parameters to estimate"
                )
            self.requires = ("floor_disp", "floor_vel")
            self.requires_columns = ("floor_acc",)
            self.given = {}
            self.slot_names = ()
            return
        self.requires = ()
        self.requires_columns = ()
        self.given = {key: modal[key] for key in given}
        if frequency is not None and frequency_range is not None:
            raise OptionError(f"{where}: give frequency (a seed) or frequency_range, not both")
        if frequency is None and frequency_spread is not None:
            raise OptionError(f"{where}: frequency_spread needs a seed frequency")
        defaults = self.MODAL_DEFAULTS
        if damping is not None or mass_ratio is not None:
            self._set_known(frequency, damping, mass_ratio, given, where)
        if frequency is not None:
            frequency = positive(frequency, "frequency (Hz)", where)
            spread = positive(defaults["frequency_spread"] if frequency_spread is None else frequency_spread,
                               "frequency_spread", where)
            if spread >= 1.0:
                raise OptionError(f"{where}: frequency_spread must be a fraction below 1, got {spread!r}")
            frequency_range = (frequency * (1.0 - spread), frequency * (1.0 + spread))
        self.frequency = frequency
        self.frequency_range = check_range(frequency_range or defaults["frequency_range"],
                                           f"{where}: frequency_range", positive=True)
        self.damping_range = check_range(damping_range or defaults["damping_range"], f"{where}: damping_range",
                                         positive=True)
        self.mass_ratio_range = check_range(mass_ratio_range or defaults["mass_ratio_range"],
                                            f"{where}: mass_ratio_range", positive=True)
        self.displacement = positive(defaults["displacement"] if displacement is None else displacement,
                                      "displacement (m)", where)
        self.velocity = positive(defaults["velocity"] if velocity is None else velocity, "velocity (m/s)", where)

    def _set_known(self, frequency, damping, mass_ratio, given, where):
        """Make this a known mode (constants ``f_f``, ``xi_f``, ``M_h / m_f``); check the options agree."""
        if frequency is None or damping is None:
            raise OptionError(f"{where}: a known mode needs both frequency (Hz) and damping (ratio); "
                              f"got {', '.join(given)}")
        clash = [key for key in ("frequency_spread", "frequency_range", "damping_range", "mass_ratio_range")
                 if key in given]
        if clash:
            raise OptionError(f"{where}: {clash[0]} is a prior range of an estimated mode; a known mode "
                              "(frequency, damping, mass_ratio given) has none")
        damping = nonnegative(damping, "damping (ratio)", where)
        if damping >= 1.0:
            raise OptionError(f"{where}: damping must be a ratio below 1, got {damping!r}")
        self.known = True
        self.slot_names = ("z", "z_dot")
        self._values = {"f_f": float(frequency), "xi_f": damping,
                        "mass_ratio": positive(self.KNOWN_MASS_RATIO if mass_ratio is None else mass_ratio,
                                                "mass_ratio", where)}

    @classmethod
    def for_record(cls, record, **options) -> "FloorMode":
        """The measured floor when ``record`` has a floor acceleration, else the estimated mode.

        ``record`` is a :class:`~smd_statespace.io.Record` or a
        :class:`~smd_statespace.signals.Preprocessed` (anything with a
        ``floor_acc`` attribute); ``options`` are the ``"modal"`` options and
        are ignored when the floor is measured.
        """
        if getattr(record, "floor_acc", None) is not None:
            return cls("measured")
        return cls("modal", **options)

    RECORD_MASS_RATIO_HIGH = 0.2
    """Upper end of ``M_h / m_f`` searched by the record-level model (unless ``mass_ratio_range`` is given).

    The per-cycle prior stops at 0.05 (a 70 kg person on a 1.4 t mode); a light
    floor or platform goes beyond: on eight simulated records of a 700 kg mode
    (ratios 0.07-0.13) the record-level fit ended on 0.05 on seven and nothing
    was proposed. A search range only boxes the optimiser, so it is wider than
    the prior. Its damping ratio is searched down to 0 (a physical limit, not a
    runaway): at 3.5 Hz a damping of 0.004 has a half-power band ``2 xi_f f_f``
    of 0.03 Hz, below the 0.033 Hz a 30 s record resolves, so the record cannot
    tell it from 0.001 (fits of a 0.0037 floor ended on the old bound 0.001).
    """

    CANDIDATE_DAMPING = 0.01
    """Damping ratio of the modal floor candidate seeded from the residual spectrum (floors: about 0.3-3 %)."""

    @classmethod
    def diagnosis_notes(cls, base, judged) -> list:
        """What the residual cannot say about a measured floor motion (see :mod:`smd_statespace.diagnostics.missing`).

        The floor's coupling is the measured floor's own acceleration term
        (:meth:`~smd_statespace.diagnostics.ModelCheck.effect_terms`) times
        the body mass; the note says how large it is, how much of it a
        cycle's force absorbs and how ``f_h``, ``xi_h`` move with the floor
        modelled.
        """
        pre = base.preprocessed
        if pre.floor_acc is None or any(effect.name == cls.name for effect in base.model.effects):
            return []
        terms = base.effect_terms(cls("measured"))
        if not terms:
            return []
        coupling = pre.mass * next(iter(terms.values()))[base.sample_index]
        size = float(np.sqrt(np.mean(coupling**2)))
        left = float(np.sqrt(np.mean(base.remove_absorbable(coupling) ** 2)))
        absorbed = 1.0 - left / size
        note = (f"floor_mode: the measured floor moves; its coupling M_h (w_h^2 z + 2 xi_h w_h z') is "
                f"{100 * size / base.weight:.2f} % BW RMS, {100 * absorbed:.0f} % of it absorbed by the per-cycle "
                "force")
        if absorbed >= 0.9:
            note += f" (it lies below n f_b = {base.model.n_harmonics * base.f_b:.1f} Hz), so the residual cannot test it"
        with_floor = next((c.check for c in judged if c.name == cls.name), None)
        if with_floor is not None:
            medians = [(check.table.loc[check.table["status"] == "ok", ["f_h", "xi_h"]].median()) for check in
                       (base, with_floor)]
            note += (f"; modelling the floor moves the median f_h {medians[0]['f_h']:.2f} -> {medians[1]['f_h']:.2f} "
                     f"Hz and xi_h {medians[0]['xi_h']:.2f} -> {medians[1]['xi_h']:.2f} (Section 6, Table 4)")
        return [note]

    @classmethod
    def propose(cls, fitted):
        """The floor as a candidate (:func:`~smd_statespace.model.fitted.propose`): the measured floor when the
        record has a floor acceleration; else an estimated floor mode.

        Without an accelerometer a person on a vibrating floor was otherwise read as missing harmonics.
        The record-level person searches the mode's frequency (``modal``, starting at the missed line,
        :meth:`record_starts`); its p-value counts the frequencies it is the best of
        (:meth:`record_search_size`), and on the 30 clean records of ``benchmarks/person_effects.py``
        (seed 92, both generators, where it was a candidate) it was never proposed: its test passed on
        one (p 2.7e-5, LR 42 on 5) and the checks after the test (held-out prediction, bounds,
        whiteness) turned it down; on the others p was 0.004 or more.

        The per-cycle method (``fitted.per_cycle``) cannot estimate one frequency for the whole record:
        the candidate is a known mode at the strongest line the fit misses that is not locked to the
        bouncing cycle (``fitted.innovation_line``, found by
        :meth:`~smd_statespace.diagnostics.ModelCheck.unlocked_line`), damped by
        :data:`CANDIDATE_DAMPING`, none where there is no such line. That frequency, read off the record,
        counts as one fitted parameter (:attr:`record_parameters`).
        """
        if fitted.floor_acc is not None:
            return cls("measured")
        if not fitted.per_cycle:
            return cls("modal")
        line = fitted.innovation_line
        if not np.isfinite(line):
            return None
        effect = cls("modal", frequency=round(line, 3), damping=cls.CANDIDATE_DAMPING)
        effect.record_parameters = 1
        return effect

    RECORD_FREQUENCY_STEP = 0.01
    """Relative spacing of the trial floor frequencies over ``frequency_range`` (1 %: 230 trials over 2-20 Hz).

    A floor mode's likelihood peak is about as narrow as its half-power band
    (``2 xi_f f_f``: 0.07 Hz at 3.5 Hz and ``xi_f`` 0.01); measured on a
    simulated record with the article's plate mode (3.48 Hz, ``xi_f``
    0.0037), the log-likelihood gained 25 at 3.48 Hz and at most 15 at
    3.45 and 3.50 Hz.
    """

    def _trial_count(self) -> int:
        """Trial floor frequencies of the log grid over ``frequency_range`` (:data:`RECORD_FREQUENCY_STEP`)."""
        low, high = self.frequency_range
        return int(np.ceil(np.log(high / low) / np.log1p(self.RECORD_FREQUENCY_STEP))) + 1

    def record_search_size(self, fitted) -> int:
        """A modal floor without a given frequency is the best of the frequencies the record can tell apart.

        Without this, the best of about 230 trial frequencies was referred to one chi-square: on a
        clean simulated record (person at ``f_h`` = ``f_b``) a floor mode at 2.46 Hz came out with LR
        22 on 5 unknowns, p 5e-4, and was proposed. The count is the larger of the grid's trials
        (and the innovations' line) and the frequencies a record of duration ``T`` resolves over
        ``frequency_range``, ``(f_hi - f_lo) T`` (the Rayleigh resolution ``1 / T``; 540 for 30 s over
        2-20 Hz): the search refines ``f_f`` continuously from the best start, and a floor whose damping
        goes to 0 is a line of width ``1 / T``. Counted by the grid alone, an undamped "floor" at 2.64 Hz
        on a clean record whose force drifts smoothly (LR 33 on 5, p 4.6e-6 before the count) was proposed.
        ``fitted`` is the fit without the floor (a :class:`~smd_statespace.model.fitted.FittedRecord`: its
        duration); ``None``: the grid only.
        """
        if not self.modal or self.known or self.frequency:
            return 1
        low, high = self.frequency_range
        resolved = 0 if fitted is None else int(np.ceil((high - low) * fitted.duration))
        return max(self._trial_count(), resolved) + 1

    def record_starts(self, fitted) -> list:
        """A modal floor's trial starts: the innovations' strongest line (or the given frequency) and a fine log grid.

        A floor mode at a harmonic of the bouncing frequency (mode 1 of the
        article's plate, 3.48 Hz, under a person bouncing at 1.74 Hz) hides
        under the force's own harmonic, so the strongest unexplained line
        alone misses it; the grid's best start by likelihood finds it.
        """
        if not self.modal or self.known:
            return []
        low, high = self.frequency_range
        if self.frequency:
            frequencies = [self.frequency]
        else:
            frequencies = ([float(np.clip(fitted.innovation_line, low, high))]
                           + list(np.geomspace(low, high, self._trial_count())))
        d_lo, d_hi = self.damping_range
        m_lo, m_hi = self.mass_ratio_range
        xi_f, mu = float(np.clip(0.01, d_lo, d_hi)), float(np.clip(0.01, m_lo, m_hi))
        return [{"f_f": f, "xi_f": xi_f, "mass_ratio": mu} for f in frequencies]

    def record_grid_start(self) -> int:
        """:meth:`record_starts`' log grid begins after the innovations' line: the search takes its likelihood at
        every other frequency, then around the best of those (close frequencies give close likelihoods: a start 1 %
        off the floor kept 15 of the 25 gained at it, :data:`RECORD_FREQUENCY_STEP`)."""
        return 1

    @property
    def modal(self) -> bool:
        """Whether the floor mode is estimated (``source="modal"``)."""
        return self.source == "modal"

    def slots(self, model):
        if not self.modal:
            return ()
        f_lo, f_hi = self.frequency_range
        d_lo, d_hi = self.damping_range
        m_lo, m_hi = self.mass_ratio_range
        return (
            Slot("z", "dynamic", "m", nominal=self.displacement, description="floor displacement at the person"),
            Slot("z_dot", "dynamic", "m/s", nominal=self.velocity, description="floor velocity at the person"),
            Slot("f_f", "parameter", "Hz", f_lo, f_hi, nominal=0.5 * (f_lo + f_hi),
                 description="floor modal frequency", linear=False),
            Slot("xi_f", "parameter", "-", d_lo, d_hi, nominal=0.5 * (d_lo + d_hi),
                 description="floor modal damping ratio", linear=False,
                 **({} if "damping_range" in self.given else {"search": (0.0, d_hi), "limit": True})),
            Slot("mass_ratio", "parameter", "-", m_lo, m_hi, nominal=0.5 * (m_lo + m_hi),
                 description="person mass over floor modal mass", linear=False,
                 **({} if "mass_ratio_range" in self.given
                    else {"search": (m_lo, max(m_hi, self.RECORD_MASS_RATIO_HIGH))})),
        )

    def floor_motion(self, model, x, t, inputs):
        """Floor displacement ``z`` (m) and velocity ``z'`` (m/s) seen by state(s) ``x`` at ``t``."""
        if self.modal:
            return x[..., model.index("z")], x[..., model.index("z_dot")]
        return inputs.signal("floor_disp", t), inputs.signal("floor_vel", t)

    def acceleration(self, model, x, t, inputs):
        z, z_dot = self.floor_motion(model, x, t, inputs)
        # Section 6: the leg acts on u - z; the model's Eq. 2 gave the u, u' terms, these are the floor's
        return coupling.leg_acceleration(0.0, 0.0, z, z_dot, x[..., F_H], x[..., XI_H])

    def acceleration_jacobian(self, model, x, t, inputs):
        z, z_dot = self.floor_motion(model, x, t, inputs)
        leg = coupling.leg_derivatives(0.0, 0.0, z, z_dot, x[..., F_H], x[..., XI_H])
        jac = np.zeros(x.shape)
        jac[..., F_H], jac[..., XI_H] = leg["f_h"], leg["xi_h"]
        if self.modal:
            jac[..., model.index("z")], jac[..., model.index("z_dot")] = leg["z"], leg["z_dot"]
        return jac

    def slot_rates(self, model, x, t, inputs, acc):
        width = slot_count(model, self)
        rates = np.zeros(x.shape[:-1] + (width,))
        if not width:
            return rates
        z, z_dot = x[..., model.index("z")], x[..., model.index("z_dot")]
        f_f, xi_f, mu = (model.value(x, name) for name in ("f_f", "xi_f", "mass_ratio"))
        omega_f = TWO_PI * f_f
        rates[..., 0] = z_dot
        # the floor's own mode, driven by the reaction -M_h u'' over its modal mass M_h / mu (phi = 1: z is q)
        rates[..., 1] = -(omega_f**2) * z - 2.0 * xi_f * omega_f * z_dot + coupling.modal_force(1.0, mu, acc)
        if self._excitation is not None:  # a simulation's ambient floor vibration
            rates[..., 1] += self._excitation.scalar(t) if np.ndim(t) == 0 else self._excitation(t)
        return rates

    def slot_rates_jacobian(self, model, x, t, inputs, acc, acc_jacobian):
        width = slot_count(model, self)
        jac = np.zeros(x.shape[:-1] + (width, x.shape[-1]))
        if not width:
            return jac
        i_z, i_v = model.index("z"), model.index("z_dot")
        z, z_dot = x[..., i_z], x[..., i_v]
        f_f, xi_f, mu = (model.value(x, name) for name in ("f_f", "xi_f", "mass_ratio"))
        omega_f = TWO_PI * f_f
        jac[..., 0, i_v] = 1.0
        row = coupling.modal_force(1.0, np.asarray(mu)[..., None], acc_jacobian)  # it is linear in u'' and M_h
        row[..., i_z] += -(omega_f**2)
        row[..., i_v] += -2.0 * xi_f * omega_f
        derivatives = {"f_f": -TWO_PI * (2.0 * omega_f * z + 2.0 * xi_f * z_dot), "xi_f": -2.0 * omega_f * z_dot,
                       "mass_ratio": coupling.modal_force(1.0, 1.0, acc)}
        for name, derivative in derivatives.items():
            if name in model.state_names:
                row[..., model.index(name)] += derivative
        jac[..., 1, :] = row
        return jac

    # -- forward simulation ---------------------------------------------------

    def simulation_values(self, mass) -> dict:
        """True ``f_f`` (Hz), ``xi_f`` and ``mass_ratio`` of a simulated floor for a person of ``mass`` (kg)."""
        plate = article.TABLE3[0]
        values = self.values
        ratio = values.get("mass_ratio") if "mass_ratio" in self.given else None
        if ratio is None:
            ratio = mass / (self.modal_mass or plate.modal_mass)
        return {"f_f": values.get("f_f", self.frequency if self.modal and self.frequency else plate.frequency),
                "xi_f": values.get("xi_f", plate.damping), "mass_ratio": float(ratio)}

    def for_simulation(self, model, mass):
        """A known floor mode for a simulated person of ``mass`` (kg): frequency, damping and mass ratio as the truth
        (:meth:`simulation_values`), the simulation's own options (modal mass, noise, ambient) kept."""
        values = self.simulation_values(mass)
        twin = FloorMode("modal", frequency=values["f_f"], damping=values["xi_f"], mass_ratio=values["mass_ratio"],
                         **self.simulation_given)
        twin.simulated_mass = float(mass)
        return twin

    def draw_simulation_inputs(self, rng, duration):
        """A copy of this (simulated) floor with its ambient excitation drawn for ``duration`` s."""
        f_f, xi_f = self.values["f_f"], self.values["xi_f"]
        phases = rng.uniform(0.0, 2.0 * np.pi, ambient_line_count(f_f, duration))
        twin = copy.copy(self)
        twin._excitation = ambient_floor_excitation(self.ambient, f_f, xi_f, duration, phases)
        return twin

    def measured_signals(self, states, normals, noise):
        """The record's ``floor_acc`` column: the simulated floor acceleration ``z''`` (m/s^2) plus noise, ``noise``
        (or the floor's own ``noise`` option) times its RMS, one standard normal of ``normals`` per sample."""
        z_ddot = states["z_ddot"].to_numpy()
        level = noise if self.noise is None else self.noise
        return {"floor_acc": z_ddot + level * float(np.sqrt(np.mean(z_ddot**2))) * normals}

    def simulation_truth(self):
        """The simulated floor's frequency (Hz), damping, mass ratio, noise and ambient level, and its modal mass
        (kg) when the person's mass is known."""
        values = self.values
        truth = {"frequency": values["f_f"], "damping": values["xi_f"], "mass_ratio": values["mass_ratio"],
                 "noise": self.noise, "ambient": self.ambient}
        if self.simulated_mass is not None:
            truth["modal_mass"] = self.simulated_mass / values["mass_ratio"]
        return truth

    @property
    def spec(self) -> str:
        """The floor's source, the options given and the known values they do not imply (``make_effect`` reads it)."""
        given = {**self.given, **self.simulation_given}
        implied = type(self)(source=self.source, **given).values
        given.update({key: value for key, value in self.values.items() if implied.get(key) != value})
        if not given:
            return self.name if not self.modal else f"{self.name}:source=modal"
        options = ",".join(f"{key}={spec_value(value, self.name, key)}" for key, value in given.items())
        return f"{self.name}:source={self.source},{options}"

    def __repr__(self):
        options = "".join(f", {key}={value!r}" for key, value in {**self.given, **self.simulation_given}.items())
        return f"FloorMode(source={self.source!r}{options})"
