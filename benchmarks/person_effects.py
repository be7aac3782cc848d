"""Hidden-effect study of the record-level loop: ``diagnose`` names the effect, ``identify --effect`` adds it.

Simulated people bounce for 30 s at 100 Hz (1 % BW noise) with one hidden
physical effect, or with none, under **both** generators of cycle-to-cycle
force variation (``jumps`` and ``smooth``), and as a lab exports a whole trial (``lab``, :data:`GENERATORS`: a
person without an effect or whose ``f_h`` drifts or steps). Each record is identified as a
user would (``identify_person`` with its defaults), diagnosed with the
candidates (:func:`smd_statespace.person.diagnose.diagnose_person`: every
registered effect, the user's quadratic damper of docs/effects.md (its
``my_effects.py`` block, read from the page), and the
estimated floor mode when the record has no floor accelerometer), and
identified with the *true* effect added (``identify_person(record,
effects=[...])``, what ``identify --effect`` runs). Counted per row: how often
the true effect is ranked first (and significant), false alarms on clean
records, the person's ``f_h`` and ``xi_h`` errors without and with the true
effect, how often adding it made ``f_h`` worse, the effect parameter's error and
interval coverage, the Ljung-Box pass rate after, and the seconds per record::

    python benchmarks/person_effects.py --jobs 2              # 8 records per kind, size and generator
    python benchmarks/person_effects.py --records 2 --sizes large   # a smaller run
    python benchmarks/person_effects.py --jobs 2 --csv rows.csv --resume   # after a kill: the rest only

A run longer than a session keeps its rows in ``benchmarks/results/`` (``--csv
benchmarks/results/person_effects_seed90.csv --resume``: the ``.jsonl`` beside it
is the journal); every row carries the commit of the code that made it (``code``).

Effects (:data:`KINDS`): extra harmonics 5-6 (``harmonics``), a cubic spring
(``cubic_stiffness``), a floor mode with the floor acceleration measured
(``floor_measured``: the record's ``floor_acc`` kept) and without it
(``floor_unmeasured``: dropped, the candidate ``floor_mode:source=modal``),
the user's quadratic damper (``quadratic_damping``), and three generic terms of the library that ``diagnose``
screens by score tests (``term_abs_u``: a spring stiffer in compression, ``term_v_abs_v``: damping that grows with
speed, ``term_f_drift``: ``f_h`` drifting over the record; simulated with fixed scales, 1 cm, 0.15 m/s and the
record's length, which the library rescales to each record's motion). The effect's size is
measured on every record as the RMS of the GRF difference it makes (same
seed, noise-free, with and without the effect) over the noise sd, and over the person's innovations' sd (in
brackets: the noise the model sees, which on a quiet plate is the misfit of the force's variation, not the
plate's noise).

Everything random comes from ``numpy.random.SeedSequence(--seed)``, one
child per record keyed by its place (generator, kind, size, index): fresh
seeds, not those of the tests or of ``person_accuracy.py``. The rows do not
depend on ``--jobs``, nor on what else is run: ``--records 8 --resume`` on the
CSV of a ``--records 4`` run adds the records 4-7 of every row.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from smd_statespace.effects import EFFECTS, load_effects_file
from smd_statespace.effects.generic import SAME_AS
from smd_statespace.io import G
from smd_statespace.person import identify_person
from smd_statespace.person.detection import change_percent
from smd_statespace.person.diagnose import diagnose_person, label
from smd_statespace.model.fitted import propose
from smd_statespace.person.effect_adapter import fitted_record
from smd_statespace.person.extend import configured_for_record, fit_effects
from smd_statespace.simulation import DEFAULT_BLF, simulate_bouncing, simulate_lab_record

REPO = Path(__file__).resolve().parents[1]
USER_EFFECT_PAGE = REPO / "docs" / "effects.md"
"""The user's effect is the ``my_effects.py`` block of this page, exactly as a user writes it from there."""
DURATION, FS, NOISE = 30.0, 100.0, 0.01

KINDS = {
    "clean": [None],
    "harmonics": [{"harmonics": {"blf": (0.022, 0.016)}}, {"harmonics": {"blf": (0.065, 0.048)}}],
    "cubic_stiffness": [{"cubic_stiffness": {"beta_3": 450.0}}, {"cubic_stiffness": {"beta_3": 1500.0}}],
    "floor_measured": [{"floor_mode": {"modal_mass": 2000.0}}, {"floor_mode": {"modal_mass": 700.0}}],
    "floor_unmeasured": [{"floor_mode": {"modal_mass": 2000.0}}, {"floor_mode": {"modal_mass": 700.0}}],
    "quadratic_damping": [{"quadratic_damping": {"c_q": 4.0}}, {"quadratic_damping": {"c_q": 12.0}}],
    "term_abs_u": [{"term": {"kind": "abs_u", "scale": 0.01, "c_abs_u": -0.1}},
                   {"term": {"kind": "abs_u", "scale": 0.01, "c_abs_u": -0.3}}],
    "term_v_abs_v": [{"term": {"kind": "v_abs_v", "scale": 0.15, "c_v_abs_v": 0.2}},
                     {"term": {"kind": "v_abs_v", "scale": 0.15, "c_v_abs_v": 0.5}}],
    "term_f_drift": [{"term": {"kind": "f_drift", "scale": DURATION, "c_f_drift": 0.1}},
                     {"term": {"kind": "f_drift", "scale": DURATION, "c_f_drift": 0.3}}],
    "term_f_step": [{"term": {"kind": "f_step", "scale": DURATION, "c_f_step": 0.1}},
                    {"term": {"kind": "f_step", "scale": DURATION, "c_f_step": 0.3}}],
}
"""Hidden effects at a small and a large size (about 2x and 5x the noise on a typical record)."""

EXPECTED = {"clean": None, "harmonics": "harmonics", "cubic_stiffness": "cubic_stiffness",
            "floor_measured": "floor_mode", "floor_unmeasured": "floor_mode", "quadratic_damping": "quadratic_damping",
            "term_abs_u": "term:abs_u", "term_v_abs_v": "term:v_abs_v", "term_f_drift": "term:f_drift",
            "term_f_step": "term:f_step@0.5"}
"""The right answer of ``diagnose`` per kind (None: nothing proposed)."""

SAME_PHYSICS = {"term_v_abs_v": {"quadratic_damping"}, "quadratic_damping": {"term:v_abs_v"},
                **{name: {f"term:{kind}"} for kind, name in SAME_AS.items()}}
"""Other candidates that name the same physics as :data:`EXPECTED` and are right answers too: the user's quadratic
damper of docs/effects.md (``-c_q r' |r'|``) and the library's ``v_abs_v`` term (``r' |r'|`` times a scale) are one
term, damping that grows with speed, under two names and scales (docs/effects.md, the library's table); so are a
registered effect and the generic term that is it in another unit (``smd_statespace.effects.generic.SAME_AS``:
``cubic_stiffness`` and ``term:u3``, which ``diagnose`` no longer screens beside it, but older runs did)."""


def right_answer(kind: str, proposed) -> bool:
    """Whether ``diagnose`` proposing ``proposed`` (a label, "" or None for nothing) names the hidden ``kind``: its
    :data:`EXPECTED` label, a candidate of the same physics (:data:`SAME_PHYSICS`), or for a step of ``f_h`` a step at
    any time (found by a scan, ``person.breaks``; its time is reported apart)."""
    proposed = proposed or None
    if proposed == EXPECTED[kind] or proposed in SAME_PHYSICS.get(kind, ()):
        return True
    return kind == "term_f_step" and str(proposed).startswith("term:f_step@")

FITTED = {"harmonics": "harmonics:count=2", "cubic_stiffness": "cubic_stiffness", "floor_measured": "floor_mode",
          "floor_unmeasured": "floor_mode:source=modal", "quadratic_damping": "quadratic_damping",
          "term_abs_u": "term:kind=abs_u,scale=0.01", "term_v_abs_v": "term:kind=v_abs_v,scale=0.15",
          "term_f_drift": "term:kind=f_drift", "term_f_step": "term:kind=f_step"}
"""The true effect as ``identify --effect`` adds it (a time term completed by :func:`_true_spec`)."""

TRUE_PARAMETER = {"cubic_stiffness": ("beta_3", "beta_3"), "quadratic_damping": ("c_q", "c_q"),
                  "floor_unmeasured": ("f_f", "frequency"), "term_abs_u": ("c_abs_u", "c_abs_u"),
                  "term_v_abs_v": ("c_v_abs_v", "c_v_abs_v"), "term_f_drift": ("c_f_drift", "c_f_drift"),
                  "term_f_step": ("c_f_step", "c_f_step")}
"""The effect parameter whose error is counted: ``(estimated name, key of the simulation's truth)``."""

GENERATORS = ("jumps", "smooth", "lab", "lab_smooth", "jumps_phase", "jumps_size")
"""The two generators of force variation of :func:`simulate_bouncing`, and ``lab``: a lab's force-plate export of a
whole trial (:func:`simulate_lab_record`: standing 4 s before and after, ramps, 1000 Hz, mains hum, a drifting zero,
1 N noise; jumps variation), which the fit reaches through the record front end as a user's export would; and
``lab_smooth``: the same with the smooth variation (a force that changes continuously from cycle to cycle, as a
person's does, where the jumps variation's force jumps at every cycle boundary). ``jumps_phase`` and ``jumps_size``
break the record-level model's assumption that each harmonic varies alike in size and phase
(:data:`JUMPS_SETTINGS`; ``benchmarks/even_terms_variation.py``): the harmonics' phases alone jitter (0.1 rad), or
their sizes alone (10 %), the frequency by 2 % in both."""

JUMPS_SETTINGS = {"jumps_phase": {"coef_variation": 0.0, "phase_variation": 0.1},
                  "jumps_size": {"phase_variation": 0.0}}
"""``simulate_bouncing``'s settings of the jumps generators that vary the force one way (variation "jumps")."""

LAB_KINDS = {"clean", "term_f_drift", "term_f_step", "cubic_stiffness"}
"""What the lab generator makes: a person without an effect, whose ``f_h`` drifts or steps over the bout (the
lab simulator's ``f_h_change``), or with a cubic spring (its ``effects``, since 2026-12-01)."""


def lab_change(effects) -> dict:
    """``simulate_lab_record``'s options for a drift or step term: the change of ``f_h`` over the bout that the
    term's ``c`` makes (``w_h^2`` from ``1 - c/2`` to ``1 + c/2`` times the middle's); for another effect, the
    effect itself."""
    if not effects:
        return {}
    if "term" not in effects:  # an effect in the equation of motion: the lab simulator takes it as it is
        return {"effects": effects}
    term = effects["term"]
    c = term[f"c_{term['kind']}"]
    return {"f_h_change": float(np.sqrt((1 + c / 2) / (1 - c / 2)) - 1),
            "change": "step" if term["kind"] == "f_step" else "drift"}


def _load_user_effect():
    """Register the quadratic damper of docs/effects.md (its ``file=my_effects.py`` block) in this process."""
    import re
    import tempfile

    if "quadratic_damping" in EFFECTS:
        return
    text = USER_EFFECT_PAGE.read_text(encoding="utf-8")
    code = re.search(r"```python file=my_effects.py\n(.*?)```", text, re.S).group(1)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "my_effects.py"
        path.write_text(code, encoding="utf-8")
        load_effects_file(path)


def tasks(records: int, seed: int, sizes=("small", "large"), generators=GENERATORS, kinds=tuple(KINDS)) -> list:
    """``(kind, size, generator, index, person, sim_seed, effects)`` for every record; clean records twice as many."""
    out = []
    for g, generator in enumerate(GENERATORS):
        for k, (kind, kind_sizes) in enumerate(KINDS.items()):
            for size, effects in enumerate(kind_sizes):
                for i in range(records * (2 if kind == "clean" else 1)):
                    # each record's seed from its place (generator, kind, size, index): a record is the same
                    # person whatever else is run, so a run with more --records extends a smaller one (--resume)
                    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(g, k, size, i)))
                    person = {"f_b": rng.uniform(1.5, 3.5), "f_h": rng.uniform(1.8, 4.2),
                              "xi_h": rng.uniform(0.1, 0.5), "mass": rng.uniform(50.0, 90.0),
                              "blf": tuple(np.array(DEFAULT_BLF) * rng.uniform(0.7, 1.3, 4))}
                    label = ("small", "large")[size] if effects else "-"
                    if generator.startswith("lab") and kind not in LAB_KINDS:
                        continue
                    if generator in generators and kind in kinds and (effects is None or label in sizes):
                        out.append((kind, label, generator, i, person, int(rng.integers(2**31)), effects))
    return out


def _with_true_effect(base, diagnosis, spec) -> tuple:
    """The person with the true effect (what ``identify --effect SPEC`` gives) and the seconds its fit took.

    ``identify --effect`` identifies the person without the effect, then adds it
    (:func:`~smd_statespace.person.extend.fit_effects`, the cycle starts re-placed with it);
    diagnose has done both for the candidate it proposes first, so that fit is reused when it is
    the same spec; the others diagnose only screened, and the effect is fitted here.
    """
    effect = configured_for_record(spec, base)  # as identify_person takes it: a bare name configured for the record
    fitted = diagnosis.fits.get(label(effect))
    proposed = bool(diagnosis.missing) and diagnosis.missing[0] == label(effect)
    if proposed and [e.spec for e in fitted.effects] == [effect.spec]:
        return fitted, float(next(row["seconds"] for row in diagnosis.rows if row["effect"] == label(effect)))
    moment = time.perf_counter()
    fitted = fit_effects(base, [spec])
    return fitted, time.perf_counter() - moment


def _lab_record(person, sim_seed, effects, variation="jumps") -> tuple:
    """A lab export of the person (:data:`GENERATORS`) and the effect's size: the RMS of the GRF difference the change
    makes (noise-free) over the plate's noise sd."""
    common = dict(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"], blf=person["blf"],
                  seed=sim_seed, variation=variation)
    sim = simulate_lab_record(**common, **lab_change(effects))
    if not effects:
        return sim, np.nan
    quiet = dict(hum=(0.0, 0.0, 0.0), drift=0.0, noise=0.0)
    plain = simulate_lab_record(**common, **quiet).record.force
    forced = simulate_lab_record(**common, **quiet, **lab_change(effects)).record.force
    return sim, float(np.sqrt(np.mean((forced - plain) ** 2)) / sim.truth["noise_n"])


def _true_spec(kind, base) -> str:
    """The true effect as ``identify --effect`` adds it (:data:`FITTED`); a time term on the fitted record's own time
    axis (a lab export's bouncing starts seconds into it)."""
    if kind in ("term_f_drift", "term_f_step"):
        time = base.model.time
        return f"{FITTED[kind]},scale={time[-1] - time[0]:.6g},start={time[0]:.6g}"
    return FITTED[kind]


def _finite(value):
    """``value`` as a float for JSON, None where it is not finite (not validated)."""
    return float(value) if np.isfinite(value) else None


def simulation_settings(person: dict, sim_seed: int, generator: str) -> dict:
    """``simulate_bouncing``'s arguments for a task's person on one of the generators that are not lab exports (all
    but ``noise`` and ``effects``)."""
    return dict(mass=person["mass"], f_b=person["f_b"], f_h=person["f_h"], xi_h=person["xi_h"], duration=DURATION,
                fs=FS, blf=person["blf"], seed=sim_seed, variation="jumps" if generator in JUMPS_SETTINGS
                else generator, **JUMPS_SETTINGS.get(generator, {}))


def fair_comparison(fitted, name: str, truth: float) -> tuple:
    """``(whole_record, truth_in_range)`` of an effect parameter's estimate against its truth: the record was fitted
    whole (not one of two bouts the front end split it into, where a step's truth is elsewhere) and the truth lies in
    the parameter's search range. Where either is False the comparison is not the estimator's to answer."""
    low, high = fitted.model.bound(name)
    span = fitted.model.time[-1] - fitted.model.time[0]
    return bool(span > 0.9 * DURATION), bool(low <= truth <= high)


def study_of_tasks(description: str, kinds, function, argv=None, generators=("jumps", "smooth")) -> tuple:
    """A small study over :func:`tasks` (its people, on ``generators``, of ``kinds``): the command line (``--records``,
    ``--seed``, ``--jobs``, ``--out``; one line and exit 2 when misused), then ``function`` of every task in
    ``--jobs`` processes. Returns ``(args, rows as a DataFrame, started)`` (``time.perf_counter()`` at the start)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--records", type=int, default=8, help="records per kind, size and generator (clean: twice)")
    parser.add_argument("--seed", type=int, default=92, help="seed of the people (person_effects.tasks)")
    parser.add_argument("--jobs", type=int, default=2, help="processes")
    parser.add_argument("--out", type=Path, help="markdown file to write (default: print only)")
    args = parser.parse_args(argv)
    if args.records < 1 or args.jobs < 1:
        parser.error("--records and --jobs must be at least 1")
    started = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = pd.DataFrame(list(pool.map(function, tasks(args.records, args.seed, generators=generators,
                                                          kinds=kinds))))
    return args, rows, started


def one(task) -> dict:
    """Simulate, identify, diagnose and identify with the true effect one record; never raises."""
    _load_user_effect()
    kind, size, generator, index, person, sim_seed, effects = task
    row = {"kind": kind, "size": size, "generator": generator, "index": index,
           **{k: v for k, v in person.items() if k != "blf"}}
    common = simulation_settings(person, sim_seed, generator)
    started = time.perf_counter()
    try:
        if generator.startswith("lab"):
            sim, row["effect_size"] = _lab_record(person, sim_seed, effects, "smooth" if generator == "lab_smooth"
                                                  else "jumps")
            row["f_h"] = sim.truth["f_h"]  # the bout's mean f_h
        else:
            sim = simulate_bouncing(noise=NOISE, effects=effects, **common)
            if effects:
                plain = simulate_bouncing(noise=0.0, **common).record.force
                forced = simulate_bouncing(noise=0.0, effects=effects, **common).record.force
                row["effect_size"] = float(np.sqrt(np.mean((forced - plain) ** 2)) / (NOISE * person["mass"] * G))
        record = sim.record
        if kind == "floor_unmeasured":
            record = dataclasses.replace(record, floor_acc=None)
        moment = time.perf_counter()
        # the person without any effect, where the loop starts: a record's measured floor, which identify adds by
        # default (measured_floor), is left out so that diagnose can be asked to find it
        base = identify_person(record, measured_floor=False)
        base_seconds = time.perf_counter() - moment
        if effects:  # the effect against the noise the model sees: its innovations' sd (N), not the plate's
            newton = row["effect_size"] * (sim.truth["noise_n"] if generator.startswith("lab")
                                           else NOISE * person["mass"] * G)
            row["effect_vs_innovations"] = newton / (base.sigma * person["mass"])
        candidates = [propose(cls, fitted_record(base)) for cls in EFFECTS.values()]
        candidates = [c for c in candidates if c is not None]  # without floor_acc the floor is the estimated mode
        diagnosis = diagnose_person(base, candidates=candidates, library=True)
        row["diagnose_seconds"] = time.perf_counter() - started
        top = diagnosis.missing[0] if diagnosis.missing else None
        table = diagnosis.table()
        row["candidates"] = json.dumps({name: {"lr": round(float(r["lr"]), 3), "df": int(r["df"]),
                                               "p": float(r["p_value"]), "significant": bool(r["significant"]),
                                               "held_out_z": _finite(r["held_out_z"]),
                                               "folds": len((diagnosis.validation.get(name) or {}).get("folds", ()))}
                                        for name, r in table.iterrows()} if not table.empty else {})
        suggested = diagnosis.fits[top] if top else base  # what following diagnose's verdict gives
        row.update(f_h_suggested=suggested.f_h, f_h_sd_suggested=float(suggested.se[0]))
        limits = ((base.change or {}).get("time") or {}).get("limits", {})  # what "no change found" would say
        row.update({f"limit_{kind}": limit["percent"] for kind, limit in limits.items()},
                   change_found="f_h" in (base.change or {}).get("changed", []))
        if kind in ("term_f_drift", "term_f_step"):  # the true change of f_h, as the limits say it (%)
            term = effects["term"]
            row["change_percent"] = change_percent(term["kind"], term[f"c_{term['kind']}"])
        row.update(proposed=top or "", variation=base.model.variation, f_h_before=base.f_h, xi_h_before=base.xi_h,
                   ljung_box_before=base.test_pvalues()["ljung_box_p"], misfit_share_before=base.misfit_share,
                   f_h_determined_before=base.determined("f_h"),
                   f_h_covered_before=bool(base.intervals["f_h"][0] <= person["f_h"] <= base.intervals["f_h"][1]))
        if kind in FITTED:
            fitted, seconds = _with_true_effect(base, diagnosis, _true_spec(kind, base))
            row["identify_effect_seconds"] = base_seconds + seconds
            row.update(f_h_after=fitted.f_h, xi_h_after=fitted.xi_h, f_h_sd_after=float(fitted.se[0]),
                       misfit_share_after=fitted.misfit_share, f_h_determined_after=fitted.determined("f_h"),
                       ljung_box_after=fitted.test_pvalues()["ljung_box_p"],
                       f_h_covered=bool(fitted.intervals["f_h"][0] <= person["f_h"] <= fitted.intervals["f_h"][1]))
            # a lab record's change of f_h is its simulator's f_h_change, not the term's parameter
            if kind in TRUE_PARAMETER and not (generator.startswith("lab") and kind.startswith("term_f")):
                name, key = TRUE_PARAMETER[kind]
                truth = sim.truth["effects"][next(iter(effects))][key]
                estimate = fitted.effect_estimates().loc[name]
                row.update(parameter=name, parameter_truth=truth, parameter_estimate=estimate["value"],
                           parameter_covered=bool(estimate["low"] <= truth <= estimate["high"]),
                           parameter_fair=all(fair_comparison(fitted, name, truth)))
    except Exception as exc:  # noqa: BLE001 - one record must never kill the study
        row.update(error=f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}",
                   seconds=time.perf_counter() - started)
        return row
    row.update(error="", seconds=time.perf_counter() - started)
    row["correct"] = right_answer(kind, top)
    if top and top.startswith("term:f_step@"):
        row["step_time_s"] = float(next(t for e in diagnosis.fits[top].effects for t in e.breaks))
        if generator.startswith("lab") and sim.truth["change"].get("time_s") is not None:
            row["step_time_error_s"] = row["step_time_s"] - float(sim.truth["change"]["time_s"])
    return row


def summary(frame: pd.DataFrame) -> list:
    """Markdown table: one row per kind, size and generator."""
    lines = ["| hidden effect | size | generator | records (failed) | effect / noise (/ innovations' sd) | "
             "ranked first | "
             "what came first | \\|f_h error\\| without -> with the true effect | f_h worse with it (by > 1 sd) | "
             "\\|xi_h error\\| without -> with | effect parameter error, covered (fitted whole, truth in range) | "
             "Ljung-Box passes before -> after | "
             "f_h determined before -> after; covered | s per record (diagnose, identify --effect) | "
             "after diagnose's suggestion: \\|f_h error\\| median, within 3 %, worse by > 1 sd |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (kind, size, generator), rows in frame.groupby(["kind", "size", "generator"], sort=False):
        ok = rows[rows["error"] == ""]
        n = len(ok)
        if n == 0:
            lines.append(f"| {kind} | {size} | {generator} | {len(rows)} ({len(rows)}) |" + " |" * 10)
            continue
        ok = ok.assign(correct=[right_answer(kind, top) for top in ok["proposed"].fillna("")])  # older runs' rows too
        proposed = ok["proposed"].replace("", "nothing").str.replace(r"f_step@[0-9.]+", "f_step@t", regex=True)
        firsts = ", ".join(f"{k} {v}" for k, v in proposed.value_counts().items())
        effect = f"{ok['effect_size'].median():.1f}" if "effect_size" in ok and ok["effect_size"].notna().any() else "-"
        if "effect_vs_innovations" in ok and ok["effect_vs_innovations"].notna().any():
            effect += f" ({ok['effect_vs_innovations'].median():.1f})"
        passes_before = int((ok["ljung_box_before"] >= 0.01).sum())
        if kind in FITTED:
            before = (100 * (ok["f_h_before"] / ok["f_h"] - 1)).abs()
            after = (100 * (ok["f_h_after"] / ok["f_h"] - 1)).abs()
            f_text = f"{before.median():.1f} % -> {after.median():.1f} %"
            beyond = (after - before) > 100 * ok["f_h_sd_after"] / ok["f_h"]  # worse by more than its own sd
            worse = f"{int((after > before).sum())}/{n} ({int(beyond.sum())})"
            x_text = (f"{(ok['xi_h_before'] - ok['xi_h']).abs().median():.3f} -> "
                      f"{(ok['xi_h_after'] - ok['xi_h']).abs().median():.3f}")
            passes = f"{passes_before}/{n} -> {int((ok['ljung_box_after'] >= 0.01).sum())}/{n}"
        else:
            f_text = f"{(100 * (ok['f_h_before'] / ok['f_h'] - 1)).abs().median():.1f} %"
            worse, x_text, passes = "-", f"{(ok['xi_h_before'] - ok['xi_h']).abs().median():.3f}", f"{passes_before}/{n}"
        if "parameter" in ok and ok["parameter"].notna().any():
            error = (100 * (ok["parameter_estimate"] / ok["parameter_truth"] - 1)).abs().median()
            fair = (ok["parameter_fair"].fillna(False).astype(bool) if "parameter_fair" in ok
                    else pd.Series(True, index=ok.index))  # runs before 2026-11-30 did not say
            covered = int(ok.loc[fair, "parameter_covered"].astype(bool).sum())
            parameter = f"{ok['parameter'].iloc[0]} {error:.0f} %, {covered}/{int(fair.sum())}"
        else:
            parameter = "-"
        determined = "-"
        if "f_h_determined_before" in ok and ok["f_h_determined_before"].notna().all():
            counts = [int(ok[column].astype(bool).sum()) for column in ("f_h_determined_before", "f_h_covered_before")]
            determined = f"{counts[0]}/{n}; {counts[1]}/{n}"
            if kind in FITTED and "f_h_determined_after" in ok:
                after_counts = [int(ok[c].astype(bool).sum()) for c in ("f_h_determined_after", "f_h_covered")]
                determined = f"{counts[0]}/{n} -> {after_counts[0]}/{n}; {counts[1]}/{n} -> {after_counts[1]}/{n}"
        seconds = f"{ok['diagnose_seconds'].median():.0f}"
        if "identify_effect_seconds" in ok and ok["identify_effect_seconds"].notna().any():
            seconds += f", {ok['identify_effect_seconds'].median():.0f}"
        lines.append(f"| {kind} | {size} | {generator} | {len(rows)} ({len(rows) - n}) | {effect} | "
                     f"{int(ok['correct'].sum())}/{n} ({EXPECTED[kind] or 'nothing'}) | {firsts} | {f_text} | "
                     f"{worse} | {x_text} | {parameter} | {passes} | {determined} | {seconds} | "
                     f"{_suggested(ok)} |")
    return lines


def detectable(frame: pd.DataFrame) -> list:
    """Markdown: the changes of ``f_h`` in time ranked first where the record can show them, by its own words.

    ``identify`` says a person changes where its tests find it; where they find none it prints the change they would
    find 80 % of the time or more if ``f_h`` is determined, and that a change of ``f_h`` is out of reach if it is not
    (:mod:`smd_statespace.person.detection`). Split by what it said: a change found; none found, ``f_h`` determined and
    the true change at or above the printed limit (the limit's promise); below it; ``f_h`` not determined.
    """
    if "change_percent" not in frame:
        return []
    lines = ["", "| hidden effect | size | generator | identify found a change: ranked first | none found, f_h "
             "determined, change >= the printed limit | change below the limit | f_h not determined (\"neither is a "
             "change of it\") |", "|---|---|---|---|---|---|---|"]
    for (kind, size, generator), rows in frame.groupby(["kind", "size", "generator"], sort=False):
        ok = rows[(rows["error"] == "") & rows["change_percent"].notna()]
        if ok.empty:
            continue
        limit = ok["limit_f_step" if kind == "term_f_step" else "limit_f_drift"]
        found, determined = ok["change_found"].astype(bool), ok["f_h_determined_before"].astype(bool)
        above = ~found & determined & (ok["change_percent"] >= limit)
        parts = [ok[mask] for mask in (found, above, ~found & determined & ~above, ~found & ~determined)]
        lines.append(f"| {kind} | {size} | {generator} | "
                     + " | ".join(f"{int(part['correct'].sum())}/{len(part)}" for part in parts) + " |")
    return lines


def _suggested(ok: pd.DataFrame) -> str:
    """|f_h error| after following diagnose's verdict (its proposed effect, or the person as it is): the median,
    the share within 3 %, and how many are worse than without it by more than their sd."""
    if "f_h_suggested" not in ok or ok["f_h_suggested"].isna().all():
        return "-"
    n = len(ok)
    before = (100 * (ok["f_h_before"] / ok["f_h"] - 1)).abs()
    after = (100 * (ok["f_h_suggested"] / ok["f_h"] - 1)).abs()
    beyond = (after - before) > 100 * ok["f_h_sd_suggested"] / ok["f_h"]
    return f"{after.median():.1f} %, {int((after <= 3.0).sum())}/{n}, {int(beyond.sum())}/{n}"


def code_version() -> str:
    """The library's commit (``git rev-parse --short HEAD``), with ``+changes`` when its files differ from it:
    stamped on every row, so that a run resumed across sessions says which code made each row."""
    import subprocess

    def git(*args):
        return subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True).stdout.strip()

    commit = git("rev-parse", "--short", "HEAD") or "unknown"
    return commit + ("+changes" if git("status", "--porcelain", "--", "smd_statespace") else "")


def _key(task) -> tuple:
    """A task's identity in the CSV: ``(kind, size, generator, index)``."""
    return task[0], task[1], task[2], task[3]


def _resumed(journal, work) -> tuple:
    """Rows already in ``journal`` (JSON lines) for this run's tasks, and their keys (an absent file: none)."""
    if journal is None or not journal.exists():
        return [], set()
    keys = {_key(task) for task in work}
    rows = [json.loads(line) for line in journal.read_text(encoding="utf-8").splitlines() if line.strip()]
    rows = [row for row in rows if (row["kind"], row["size"], row["generator"], int(row["index"])) in keys]
    return rows, {(row["kind"], row["size"], row["generator"], int(row["index"])) for row in rows}


class _Serial:
    """In-process stand-in for a pool: ``map`` one task after the other."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    @staticmethod
    def map(function, tasks):
        return map(function, tasks)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=8, help="records per kind and size (default 8; clean: 2x)")
    parser.add_argument("--seed", type=int, default=77, help="root of the SeedSequence (default 77)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--csv", type=Path, default=None,
                        help="also write every record's row here (and, as each ends, to the same name .jsonl)")
    parser.add_argument("--resume", action="store_true", help="keep the rows already in the .jsonl, run the rest")
    parser.add_argument("--sizes", default="small,large", help="effect sizes to run (default small,large)")
    parser.add_argument("--generators", default=",".join(GENERATORS[:4]),
                        help=f"generators of force variation, of {','.join(GENERATORS)} (default: the first four)")
    parser.add_argument("--kinds", default=",".join(KINDS), help=f"kinds of record (default all: {', '.join(KINDS)})")
    args = parser.parse_args(argv)
    work = tasks(args.records, args.seed, tuple(args.sizes.split(",")), tuple(args.generators.split(",")),
                 tuple(args.kinds.split(",")))
    started = time.perf_counter()
    code = code_version()
    journal = args.csv.with_suffix(".jsonl") if args.csv else None
    rows, done = _resumed(journal, work) if args.resume else ([], set())
    todo = [task for task in work if _key(task) not in done]
    if journal and not args.resume and journal.exists():
        journal.unlink()
    with tqdm(total=len(work), initial=len(work) - len(todo), desc="records", unit="record", file=sys.stderr) as bar:
        with ProcessPoolExecutor(args.jobs) if args.jobs > 1 else _Serial() as pool:
            for row in pool.map(one, todo):
                row["code"] = code
                rows.append(row)
                if journal:  # every record as it ends (rows differ in their columns): --resume reads them back
                    with journal.open("a", encoding="utf-8") as out:
                        out.write(json.dumps(row, default=float) + "\n")
                bar.update()
    order = {_key(task): i for i, task in enumerate(work)}
    rows.sort(key=lambda row: order[(row["kind"], row["size"], row["generator"], int(row["index"]))])
    frame = pd.DataFrame(rows)
    if args.csv:
        frame.to_csv(args.csv, index=False)
    print("\n".join(summary(frame) + detectable(frame)))
    failed = frame[frame["error"] != ""]
    for _, row in failed.iterrows():
        print(f"failed: {row['kind']} {row['size']} {row['generator']} #{row['index']}: {row['error']}")
    print(f"\n{len(frame)} records, {(time.perf_counter() - started) / 60:.1f} min, {args.jobs} process(es)")


if __name__ == "__main__":
    main()
