"""Human-structure interaction: a bouncing person on a modal floor (Section 6).

The article's Section 6 puts one person bouncing at 1.75 Hz at mid-span of a
10 m x 6 m, 16.5 t pre-stressed concrete plate (Table 3: six modes) so that the
second force harmonic (3.5 Hz) excites the first plate mode (3.48 Hz), and
compares the person's identified parameters with those on a rigid floor
(Table 4: ``f_h`` -17.7 %, ``xi_h`` +24.2 %, BLF1 +44.4 %, BLF2 -20.3 %, BLF3
-43.9 %). This module simulates that experiment with a person whose own
parameters do *not* change, identifies them with and without the floor motion,
and says how much of the article's shift such a person reproduces.

The person on the floor is simulated exactly by :mod:`smd_statespace.simulation.floor`
(the coupled model, the mode-shape assumption at mid-span and the integration are
described there); the identification is the library's own, per cycle, with and without
the floor's motion as an input.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .. import article
from ..errors import OptionError
from ..io import G, make_record
from ..simulation.floor import FloorModel, coupled_response, simulate_on_floor

__all__ = [
    "HSI_PERSON",
    "HSI_SETTINGS",
    "pooled_least_squares",
    "HSIStudy",
    "hsi_study",
]

REPORTED = ("f_h", "xi_h", "blf_1", "blf_2", "blf_3")
"""Parameters compared with Table 4 (Hz, -, g, g, g)."""

TABLE4_KEYS = {"f_h": "f_h", "xi_h": "xi_h", "blf_1": "BLF1", "blf_2": "BLF2", "blf_3": "BLF3"}

HSI_PERSON = {
    "mass": 70.0,
    "f_b": article.TABLE4_CONDITIONS["f_b"],
    "f_h": article.TABLE4["rigid_floor"]["f_h"],
    "xi_h": article.TABLE4["rigid_floor"]["xi_h"],
    "blf": (article.TABLE4["rigid_floor"]["BLF1"], article.TABLE4["rigid_floor"]["BLF2"],
            article.TABLE4["rigid_floor"]["BLF3"], 0.02),
}
"""The simulated person of :func:`hsi_study`: the article's rigid-floor values (Table 4).

``mass`` (kg; the article does not give the participant's mass), ``f_b``
(Hz, 1.75 as in Section 6), ``f_h`` (Hz), ``xi_h`` (-), ``blf`` (g): BLF1-3
of Table 4 and BLF4 = 0.02 g (Table 4 has none; the identification model has
four harmonics, as the article's).
"""

HSI_SETTINGS = {
    "duration": 30.0,
    "warmup": 20.0,
    "fs": 100.0,
    "noise": 0.01,
    "fb_variation": 0.02,
    "coef_variation": 0.10,
    "estimator": "ekf",
    "max_passes": 8,
    "repeats": 10,
    "mass_scales": (1.0, 0.5, 0.25),
}
"""Defaults of :func:`hsi_study`: record length after the warm-up (s), warm-up
dropped so that the lightly damped plate is past its start (s), sampling (Hz,
the insoles' 100 Hz), GRF noise (fraction of body weight; floor acceleration
noise the same fraction of its RMS), cycle-to-cycle variations (as
:func:`~smd_statespace.simulation.simulate_bouncing`), estimator and passes, records
of the estimator-free fit and modal-mass factors of the sensitivity table."""


def pooled_least_squares(states, cycles, floor=False, n_harmonics=4):
    """Estimator-free identification: Eq. 2 fitted by least squares to exact states over many cycles.

    ``f_h`` and ``xi_h`` are shared by all cycles (the person does not
    change); each cycle has its own force coefficients ``a0, a_i, b_i`` (Eq. 4,
    referred to the cycle's own start and frequency). With
    ``theta_1 = w_h^2`` and ``theta_2 = 2 xi_h w_h`` the residual
    ``u'' + theta_1 r + theta_2 r' - g F_j(t)`` (``r = u``, or ``u - z`` with
    ``floor=True``) is linear in everything, so the fit is one linear least
    squares after projecting out each cycle's Fourier basis: no estimator,
    prior or noise model. On noise-free states of a rigid floor it returns
    the true ``f_h`` and ``xi_h`` (to rounding); what it returns from a
    vibrating floor with ``floor=False`` is the pure model error of ignoring
    the floor motion.

    Parameters
    ----------
    states : pandas.DataFrame
        ``time, u, u_dot, u_ddot`` (and ``z, z_dot`` with ``floor=True``),
        e.g. from :func:`coupled_response`.
    cycles : pandas.DataFrame
        Force cycles (``t_start, t_end, f_b``); the fit uses the samples inside them.
    floor : bool
        Spring and damper on the motion relative to the floor (the
        ``floor_mode`` effect with a measured floor).
    n_harmonics : int
        Harmonics of the force per cycle (4 as in the article).

    Returns
    -------
    dict
        ``f_h`` (Hz), ``xi_h`` (-), ``blf_1..n`` (g; medians over cycles of
        Eq. 5), ``cycles`` (number used) and ``per_cycle`` (DataFrame of
        each cycle's BLFs).
    """
    time = states["time"].to_numpy()
    r, r_dot, acc = (states[c].to_numpy() for c in ("u", "u_dot", "u_ddot"))
    if floor:
        r, r_dot = r - states["z"].to_numpy(), r_dot - states["z_dot"].to_numpy()
    blocks, targets, bases, spans = [], [], [], []
    for t_start, t_end, f_b in cycles[["t_start", "t_end", "f_b"]].itertuples(index=False):
        span = (time >= t_start) & (time < t_end)
        if span.sum() < 2 * (2 * n_harmonics + 1):
            continue
        theta = 2.0 * np.pi * f_b * (time[span] - t_start)
        orders = np.arange(1, n_harmonics + 1)
        basis = np.column_stack([np.ones(theta.size), np.cos(np.outer(theta, orders)),
                                 np.sin(np.outer(theta, orders))])
        q, _ = np.linalg.qr(basis)
        project = lambda x: x - q @ (q.T @ x)  # noqa: E731
        blocks.append(np.column_stack([project(r[span]), project(r_dot[span])]))
        targets.append(-project(acc[span]))
        bases.append(basis)
        spans.append(span)
    if len(blocks) < 2:
        raise OptionError("pooled_least_squares: fewer than two complete cycles inside the states")
    theta, *_ = np.linalg.lstsq(np.vstack(blocks), np.concatenate(targets), rcond=None)
    if theta[0] <= 0:
        raise OptionError("pooled_least_squares: the fitted stiffness is not positive")
    omega = float(np.sqrt(theta[0]))
    rows = []
    for basis, span in zip(bases, spans):
        force_g = acc[span] + theta[0] * r[span] + theta[1] * r_dot[span]  # g F = u'' + w^2 r + 2 xi w r'
        coef, *_ = np.linalg.lstsq(basis, force_g / G, rcond=None)
        rows.append({f"blf_{i}": float(np.hypot(coef[i], coef[n_harmonics + i])) for i in range(1, n_harmonics + 1)})
    per_cycle = pd.DataFrame(rows)
    result = {"f_h": omega / (2.0 * np.pi), "xi_h": float(theta[1] / (2.0 * omega))}
    result.update({name: float(per_cycle[name].median()) for name in per_cycle})
    result.update(cycles=len(rows), per_cycle=per_cycle)
    return result


def _cut(record, start):
    """The part of ``record`` from ``start`` (s) on, with its time restarted at 0."""
    keep = record.time >= start - 1e-9
    floor_acc = None if record.floor_acc is None else record.floor_acc[keep]
    return make_record(record.time[keep] - record.time[keep][0], record.force[keep], record.mass,
                       floor_acc=floor_acc, source=record.source)


@dataclass
class HSIStudy:
    """Result of :func:`hsi_study`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per parameter (``f_h`` Hz, ``xi_h`` -, ``blf_1..3`` g):
        ``truth`` (the simulated person's own value, the same on both
        floors); the library's identification (medians over cycles) on the
        rigid floor (``ekf_rigid``), on the plate ignoring its motion
        (``ekf_plate``, change ``ekf_change_%``) and with the ``floor_mode``
        effect (``ekf_plate_floor_mode``, change ``ekf_floor_mode_change_%``);
        the estimator-free fit (:func:`pooled_least_squares` on exact states,
        mean and SD over the repeats of the change rigid -> plate,
        ``ls_change_%``, ``ls_change_sd_%``; the same with mode 1 only,
        ``ls_mode1_change_%``; with the floor term, ``ls_floor_mode_change_%``);
        and the article's Table 4 (``article_rigid``, ``article_plate``,
        ``article_change_%``). Changes are ``100 (plate / rigid - 1)``.
    sensitivity : pandas.DataFrame
        The estimator-free change (mean over repeats, %) against the floor
        response: one row per modal-mass scale (1 = Table 3; 0.5 halves every
        modal mass, roughly doubling the floor acceleration), with the mean
        RMS floor acceleration (m/s^2).
    floors : pandas.DataFrame
        Main record: per plate condition, RMS and peak floor acceleration at
        mid-span (m/s^2) and the RMS and peak change of the GRF from the rigid
        floor (fraction of body weight).
    least_squares : pandas.DataFrame
        Every estimator-free fit: repeat, condition, model, parameters.
    records : dict of str to Record
        The main records (with noise) identified, by condition.
    states : dict of str to pandas.DataFrame
        Noise-free states of the main records, by condition (time as in the records).
    cycles : dict of str to pandas.DataFrame
        Per-cycle identification tables, by ``"condition / model"``.
    settings : dict
        Everything needed to repeat the study.
    seconds : float
        Wall-clock time (s).
    """

    table: pd.DataFrame
    sensitivity: pd.DataFrame
    floors: pd.DataFrame
    least_squares: pd.DataFrame
    records: dict
    states: dict
    cycles: dict
    settings: dict
    seconds: float = 0.0

    def write(self, directory) -> list:
        """Write the tables and main records as CSV into ``directory``; return the paths.

        ``hsi_table.csv``, ``hsi_sensitivity.csv``, ``hsi_floors.csv``,
        ``hsi_least_squares.csv``, ``hsi_cycles.csv`` (every identified cycle,
        with its condition) and ``hsi_record_<condition>.csv`` (``time, force
        [, floor_acc]``, readable by ``smd-statespace identify``).
        """
        from ..io import write_record

        directory = Path(directory)
        paths = {name: directory / f"hsi_{name}.csv" for name in ("table", "sensitivity", "floors", "least_squares",
                                                                   "cycles")}
        self.table.to_csv(paths["table"], float_format="%.6g")
        self.sensitivity.to_csv(paths["sensitivity"], float_format="%.6g")
        self.floors.to_csv(paths["floors"], float_format="%.6g")
        self.least_squares.to_csv(paths["least_squares"], index=False, float_format="%.6g")
        frames = [table.assign(condition=name) for name, table in self.cycles.items()]
        if frames:
            pd.concat(frames, ignore_index=True).to_csv(paths["cycles"], index=False, float_format="%.6g")
        else:
            del paths["cycles"]
        out = list(paths.values())
        for name, record in self.records.items():
            path = directory / f"hsi_record_{_slug(name)}.csv"
            write_record(path, record)
            out.append(path)
        return out

    def finding(self) -> str:
        """The study's answer in plain sentences, with its numbers.

        Each parameter's estimator-free change (mean over the repeats) is
        compared with the article's: ``artefact`` when it has the article's
        sign and at least half its size, ``partly`` when it has the sign but
        less than half the size, ``not reproduced`` otherwise.
        """
        table = self.table
        repeats = self.settings["repeats"]
        estimator = self.settings["estimator"]
        identified = bool(np.isfinite(table["ekf_change_%"]).all())

        def changes(column, sd=None):
            parts = []
            for name in REPORTED:
                text = f"{name} {table.loc[name, column]:+.1f}"
                if sd is not None and repeats > 1:
                    text += f" ± {table.loc[name, sd]:.1f}"
                parts.append(text + " %")
            return "; ".join(parts)

        lines = [f"Article (Table 4), plate vs rigid floor: {changes('article_change_%')}.",
                 "Simulated person whose own parameters do NOT change, same force on both floors, floor motion "
                 "ignored (rigid-floor model):"]
        lines.append(f"  estimator-free least squares on exact states (mean ± SD over {repeats} records): "
                     f"{changes('ls_change_%', 'ls_change_sd_%')}.")
        if identified:
            lines.append(f"  library identification ({estimator}, medians over cycles, one record): "
                         f"{changes('ekf_change_%')}.")
        verdicts = {"artefact": [], "partly": [], "not reproduced": []}
        for name in REPORTED:
            share = table.loc[name, "ls_change_%"] / table.loc[name, "article_change_%"]
            verdict = "artefact" if share >= 0.5 else "partly" if share > 0 else "not reproduced"
            verdicts[verdict].append(f"{name} ({share:.0%} of the article's change)")
        if verdicts["artefact"]:
            lines.append("Could be an artefact of ignoring the floor motion (same sign, at least half the size): "
                         + ", ".join(verdicts["artefact"]) + ".")
        if verdicts["partly"]:
            lines.append("Same sign but less than half the size, so mostly NOT an artefact: "
                         + ", ".join(verdicts["partly"]) + ".")
        if verdicts["not reproduced"]:
            lines.append("Not reproduced (opposite sign): " + ", ".join(verdicts["not reproduced"]) + ".")
        sens = self.sensitivity
        if len(sens) > 1:
            parts = [f"x{scale:g} ({row.floor_acc_rms:.2g} m/s^2 RMS): f_h {row['f_h_change_%']:+.1f} %, "
                     f"xi_h {row['xi_h_change_%']:+.1f} %" for scale, row in sens.iterrows()]
            lines.append("With smaller modal masses (a livelier floor): " + "; ".join(parts) + ".")
        floor_ls = float(np.max(np.abs(table["ls_floor_mode_change_%"])))
        text = (f"With the floor term and the measured floor motion, the least squares recover the rigid-floor "
                f"values (largest change {floor_ls:.1g} %)")
        if identified:
            text += f"; the {estimator} with the floor_mode effect gives {changes('ekf_floor_mode_change_%')}"
        lines.append(text + ".")
        return "\n".join(lines)


def _slug(name):
    slug = "".join(c if c.isalnum() else "_" for c in name).strip("_")
    while "__" in slug:
        slug = slug.replace("__", "_")
    return slug


def _median_parameters(table):
    ok = table[table["status"] == "ok"]
    return {name: float(ok[name].median()) if len(ok) else np.nan for name in REPORTED}, len(ok)


def _settings(overrides):
    settings = dict(HSI_SETTINGS)
    for key, value in overrides.items():
        if value is not None:
            settings[key] = value
    for key in ("duration", "fs"):
        value = settings[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value <= 0:
            raise OptionError(f"hsi_study: {key} must be a positive number, got {value!r}")
    if not (np.isfinite(float(settings["warmup"])) and float(settings["warmup"]) >= 0):
        raise OptionError(f"hsi_study: warmup must be >= 0 s, got {settings['warmup']!r}")
    if float(settings["duration"]) < 8.0:
        raise OptionError(
            f"hsi_study: duration {settings['duration']:g} s is too short; the pipeline drops 2 s at each end "
            "and needs several cycles between (give at least 8 s)"
        )
    repeats = settings["repeats"]
    if isinstance(repeats, bool) or int(repeats) != repeats or repeats < 1:
        raise OptionError(f"hsi_study: repeats must be a whole number >= 1, got {repeats!r}")
    settings["repeats"] = int(repeats)
    scales = tuple(float(v) for v in settings["mass_scales"])
    if not scales or any(not (np.isfinite(v) and v > 0) for v in scales):
        raise OptionError(f"hsi_study: mass_scales must be positive numbers, got {settings['mass_scales']!r}")
    settings["mass_scales"] = scales
    return settings


def _scaled(floor: FloorModel, scale: float) -> FloorModel:
    if scale == 1.0:
        return floor
    return FloorModel(floor.frequency, floor.damping, tuple(m * scale for m in floor.modal_mass), floor.shape,
                      name=f"{floor.name}, modal masses x{scale:g}")


def _person(person) -> dict:
    """:data:`HSI_PERSON` with the overrides in ``person``, or an :class:`OptionError` naming unknown keys."""
    who = dict(HSI_PERSON)
    if person:
        unknown = set(person) - set(HSI_PERSON)
        if unknown:
            raise OptionError(f"hsi_study: unknown person keys {sorted(unknown)}; valid: {', '.join(HSI_PERSON)}")
        who.update(person)
    return who


def hsi_study(duration=None, seed=0, warmup=None, person=None, estimator=None, max_passes=None, fs=None,
              noise=None, repeats=None, mass_scales=None, identify=True, progress=False) -> HSIStudy:
    """Simulate Section 6 with a person whose parameters do not change, and identify them.

    Steps:

    1. A rigid-floor record of the person (:data:`HSI_PERSON`: Table 4's
       rigid-floor values, bouncing at 1.75 Hz) from
       :func:`~smd_statespace.simulation.simulate_bouncing`, ``warmup +
       duration`` long.
    2. The same force cycles and GRF noise on the plate of Table 3 at
       mid-span (:func:`simulate_on_floor`): all six modes (main condition)
       and mode 1 alone (to measure what modes 2-6 add). The first
       ``warmup`` seconds are dropped, so the lightly damped plate (decay
       time ``1 / (xi_1 w_1)`` = 12 s) is past its start.
    3. The library's identification of every cycle (:class:`~smd_statespace.identify.runner.CycleRunner`,
       ``estimator``) on the rigid record and on the plate record with the
       rigid-floor model, and on the plate record with the ``floor_mode``
       effect (measured ``floor_acc``).
    4. The estimator-free fit (:func:`pooled_least_squares`, exact states,
       true force cycles) on ``repeats`` records (the first is the main
       one): the model error of ignoring the floor, without the estimator's
       own bias and scatter; repeated with the modal masses scaled by
       ``mass_scales`` to see how the artefact grows with the floor response.
    5. Changes rigid -> plate compared with Table 4.

    Parameters
    ----------
    duration : float
        Length (s) of each identified record (default 30, about the article's).
    seed : int
        Seed of everything random (forces, GRF and floor noise); repeat ``k``
        uses child ``k`` of ``numpy.random.SeedSequence(seed)``.
    warmup : float
        Simulated time dropped before each record (s), default 20.
    person : dict, optional
        Overrides of :data:`HSI_PERSON` (``mass, f_b, f_h, xi_h, blf``).
    estimator : str
        Estimator (default ``"ekf"``, the fastest; see docs/benchmarks.md).
    max_passes : int
        Repeated passes per cycle (default 8).
    fs : float
        Sampling frequency (Hz), default 100 (the insoles').
    noise : float
        GRF noise (fraction of body weight; floor-acceleration noise the same
        fraction of its RMS), default 0.01.
    repeats : int
        Records of the estimator-free fit (default 10).
    mass_scales : sequence of float
        Modal-mass factors of the sensitivity table (default 1, 0.5, 0.25).
    identify : bool
        Run step 3 (the slow part, about 15 s per 30 s record on one core);
        with False the ``ekf_*`` columns are NaN and ``cycles`` is empty.
    progress : bool
        Progress bars of the runner.

    Returns
    -------
    HSIStudy
    """
    started = _time.perf_counter()
    settings = _settings({"duration": duration, "warmup": warmup, "estimator": estimator, "max_passes": max_passes,
                          "fs": fs, "noise": noise, "repeats": repeats, "mass_scales": mass_scales})
    who = _person(person)
    plate, mode1 = FloorModel.table3(), FloorModel.table3([1])
    ls_rows, records, states, floor_rows = _simulate_conditions(who, settings, seed, plate, mode1)

    tables, medians, counts = _identify_conditions(records, plate, settings, seed, identify, progress)

    least = pd.DataFrame(ls_rows)
    table = _table4(least, medians, who, plate, mode1)
    sensitivity = _sensitivity(least, settings, plate)

    settings.update(seed=seed, person={k: (list(v) if isinstance(v, tuple) else v) for k, v in who.items()},
                    cycles_identified=counts, mass_scales=list(settings["mass_scales"]))
    return HSIStudy(table=table, sensitivity=sensitivity, floors=pd.DataFrame(floor_rows).set_index("floor"),
                    least_squares=least, records=records, states=states, cycles=tables, settings=settings,
                    seconds=_time.perf_counter() - started)


def _simulate_conditions(who, settings, seed, plate, mode1):
    """Steps 1, 2 and 4 of :func:`hsi_study`: every repeat's records on each floor and their least-squares fits.

    Returns ``(least-squares rows, records, states, floor rows)``; the records
    and states are those of the first repeat (the main ones).
    """
    from ..simulation.bouncing import simulate_bouncing

    warm, length = float(settings["warmup"]), float(settings["duration"])
    weight = who["mass"] * G
    ls_rows, records, states, floor_rows = [], {}, {}, []
    for repeat, child in enumerate(np.random.SeedSequence(seed).spawn(settings["repeats"])):
        force_seed, floor_seed = child.spawn(2)
        synthetic = simulate_bouncing(
            mass=who["mass"], f_b=who["f_b"], f_h=who["f_h"], xi_h=who["xi_h"], blf=who["blf"],
            duration=warm + length, fs=settings["fs"], noise=settings["noise"],
            fb_variation=settings["fb_variation"], coef_variation=settings["coef_variation"], seed=force_seed,
        )
        inside = synthetic.cycles[(synthetic.cycles["t_start"] >= warm) & (synthetic.cycles["t_end"] <= warm + length)]
        time = synthetic.record.time
        late = time >= warm - 1e-9
        conditions = {"rigid floor": (synthetic.states, None)}
        for scale in settings["mass_scales"]:
            floor = _scaled(plate, scale)
            conditions[floor.name] = (coupled_response(synthetic.cycles, time, who["mass"], who["f_h"], who["xi_h"],
                                                       floor), scale)
        conditions[mode1.name] = (coupled_response(synthetic.cycles, time, who["mass"], who["f_h"], who["xi_h"],
                                                   mode1), None)
        for name, (frame, scale) in conditions.items():
            models = (False, True) if name == plate.name else (False,)
            for with_floor in models:
                fit = pooled_least_squares(frame, inside, floor=with_floor)
                ls_rows.append({"repeat": repeat, "condition": name, "model": "floor_mode" if with_floor else "rigid",
                                "mass_scale": scale,
                                "floor_acc_rms": float(np.sqrt(np.mean(frame["z_ddot"][late] ** 2)))
                                if "z_ddot" in frame else 0.0,
                                **{k: fit[k] for k in REPORTED}, "cycles": fit["cycles"]})
        if repeat:
            continue
        # the main records: with noise, identified by the library
        records["rigid floor"] = _cut(synthetic.record, warm)
        rigid_acc = synthetic.states["u_ddot"].to_numpy()[late]
        for floor, floor_child in zip((plate, mode1), floor_seed.spawn(2)):
            record, coupled = simulate_on_floor(synthetic, floor, seed=floor_child)
            kept = coupled[late].assign(time=lambda f: f["time"] - warm).reset_index(drop=True)
            states[floor.name] = kept
            change = who["mass"] * (kept["u_ddot"].to_numpy() - rigid_acc)
            floor_rows.append({"floor": floor.name, "modes": floor.n_modes,
                               "floor_acc_rms": float(np.sqrt(np.mean(kept["z_ddot"] ** 2))),
                               "floor_acc_peak": float(np.max(np.abs(kept["z_ddot"]))),
                               "grf_change_rms_bw": float(np.sqrt(np.mean(change**2)) / weight),
                               "grf_change_peak_bw": float(np.max(np.abs(change)) / weight)})
            if floor is plate:
                records[plate.name] = _cut(record, warm)
        states["rigid floor"] = synthetic.states[late].assign(time=lambda f: f["time"] - warm).reset_index(drop=True)
    return ls_rows, records, states, floor_rows


def _identify_conditions(records, plate, settings, seed, identify, progress):
    """Step 3 of :func:`hsi_study`: the library's identification; returns ``(tables, medians, counts)``."""
    from ..effects import FloorMode
    from ..model import SMDModel
    from ..identify.runner import CycleRunner
    from ..signals import preprocess

    tables, counts = {}, {}
    nan = {name: np.nan for name in REPORTED}
    medians = {key: nan for key in ("rigid floor / rigid model", f"{plate.name} / rigid model",
                                    f"{plate.name} / floor_mode model")}
    runs = (("rigid floor", "rigid"), (plate.name, "rigid"), (plate.name, "floor_mode")) if identify else ()
    for condition, model_name in runs:
        model = SMDModel(effects=[FloorMode()]) if model_name == "floor_mode" else SMDModel()
        runner = CycleRunner(model, estimator=settings["estimator"], max_passes=int(settings["max_passes"]),
                             seed=seed, progress=progress, keep_results=False)
        key = f"{condition} / {model_name} model"
        tables[key] = runner.run(preprocess(records[condition]))
        medians[key], counts[key] = _median_parameters(tables[key])
    return tables, medians, counts


def _ls_changes(least, condition, model="rigid"):
    """Change (%) of each repeat's least-squares parameters from the rigid floor to ``condition``."""
    base = least[(least["condition"] == "rigid floor")].set_index("repeat")[list(REPORTED)]
    other = least[(least["condition"] == condition) & (least["model"] == model)].set_index("repeat")[list(REPORTED)]
    return 100.0 * (other / base - 1.0)


def _table4(least, medians, who, plate, mode1):
    """Step 5 of :func:`hsi_study`: Table 4's comparison, one row per parameter."""
    main_change, mode1_change = _ls_changes(least, plate.name), _ls_changes(least, mode1.name)
    floor_change = _ls_changes(least, plate.name, "floor_mode")
    ekf_rigid = medians["rigid floor / rigid model"]
    ekf_plate = medians[f"{plate.name} / rigid model"]
    ekf_floor = medians[f"{plate.name} / floor_mode model"]
    truth = {"f_h": who["f_h"], "xi_h": who["xi_h"], "blf_1": who["blf"][0], "blf_2": who["blf"][1],
             "blf_3": who["blf"][2]}
    rows = []
    for name in REPORTED:
        key = TABLE4_KEYS[name]
        rows.append({
            "parameter": name,
            "truth": truth[name],
            "ekf_rigid": ekf_rigid[name],
            "ekf_plate": ekf_plate[name],
            "ekf_change_%": 100.0 * (ekf_plate[name] / ekf_rigid[name] - 1.0),
            "ekf_plate_floor_mode": ekf_floor[name],
            "ekf_floor_mode_change_%": 100.0 * (ekf_floor[name] / ekf_rigid[name] - 1.0),
            "ls_change_%": float(main_change[name].mean()),
            "ls_change_sd_%": float(main_change[name].std(ddof=1)) if len(main_change) > 1 else np.nan,
            "ls_mode1_change_%": float(mode1_change[name].mean()),
            "ls_floor_mode_change_%": float(floor_change[name].mean()),
            "article_rigid": article.TABLE4["rigid_floor"][key],
            "article_plate": article.TABLE4["vibrating_plate"][key],
            "article_change_%": 100.0 * article.TABLE4["difference"][key],
        })
    table = pd.DataFrame(rows).set_index("parameter")
    return table


def _sensitivity(least, settings, plate):
    """Step 4 of :func:`hsi_study` with scaled modal masses: parameter changes against the floor response."""
    sens_rows = []
    for scale in settings["mass_scales"]:
        name = _scaled(plate, scale).name
        change = _ls_changes(least, name)
        level = least[(least["condition"] == name) & (least["model"] == "rigid")]["floor_acc_rms"].mean()
        row = {"mass_scale": scale, "floor_acc_rms": float(level)}
        for parameter in REPORTED:
            row[f"{parameter}_change_%"] = float(change[parameter].mean())
            row[f"{parameter}_change_sd_%"] = float(change[parameter].std(ddof=1)) if len(change) > 1 else np.nan
        sens_rows.append(row)
    sensitivity = pd.DataFrame(sens_rows).set_index("mass_scale")
    return sensitivity
