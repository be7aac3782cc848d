"""What the one-mass SMD reads from a body of two masses: a generator outside the library's own model (held out).

The SMD of the article puts the whole body mass at the centre of mass on one spring and damper (Eq. 1). A body is
not one mass: the trunk moves on the legs. This benchmark simulates a two-mass body -- the legs' mass ``m_1`` on the
leg spring and damper (``k_1``, ``c_1``) to the ground, the trunk ``m_2 = upper * M`` on its own spring and damper
(``k_2``, ``c_2``) above them -- driven by the person's biomechanical force between legs and ground::

    m_1 u_1'' = F_bio - k_1 u_1 - c_1 u_1' + k_2 (u_2 - u_1) + c_2 (u_2' - u_1')
    m_2 u_2'' = -k_2 (u_2 - u_1) - c_2 (u_2' - u_1')
    GRF       = M g + m_1 u_1'' + m_2 u_2''

integrated by ``scipy.integrate.solve_ivp`` (not by the library's discretisation). ``F_bio`` is the library
simulator's force, with its cycle-to-cycle variation (``jumps`` on even records, ``smooth`` on odd ones), read off a
one-mass record's noise-free states by Eq. 2 and interpolated. The record is 30 s at 100 Hz with white GRF noise of
1 % of body weight, after a 5 s run-in.

Per record the people are drawn: ``f_b`` 1.8-2.8 Hz; the leg spring's ``f_1 = sqrt(k_1 / M) / 2 pi`` 2.2-3.6 Hz,
its damping ratio ``c_1 / (2 M w_1)`` 0.15-0.45; the trunk's share ``upper`` 0.4-0.7 of ``M`` (70 kg), its own
frequency on a fixed pelvis 4-8 Hz and damping ratio 0.1-0.4. The two-mass body has two modes; the answer
``identify REC --mass 70`` gives is compared with the lower one (its frequency and its modal damping ratio
``-Re(lambda) / |lambda|`` from the first-order system's eigenvalues), which is the body's bounce on its legs.

::

    python benchmarks/two_mass_body.py --records 16 --seed 5100 --jobs 2 --csv /tmp/two_mass.csv --md /tmp/two_mass.md
    python benchmarks/two_mass_body.py --records 16 --seed 5100 --jobs 2 --csv /tmp/two_mass.csv --diagnose 4

``--diagnose K`` also runs ``diagnose`` (:func:`~smd_statespace.person.diagnose_person`, every default) on the first
``K`` records and reports what it proposes. Record ``k`` is seeded by ``SeedSequence(seed).spawn(records)[k]``, the
same whatever ``--jobs``; a rerun with the same CSV skips the records it holds.
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

MASS = 70.0
DURATION, RATE, NOISE, RUN_IN = 30.0, 100.0, 0.01, 5.0
RANGES = {"f_b": (1.8, 2.8), "f_1": (2.2, 3.6), "xi_1": (0.15, 0.45), "upper": (0.4, 0.7), "f_2": (4.0, 8.0),
          "xi_2": (0.1, 0.4)}
"""The draws of a person (uniform): see the module's docstring."""


def draw_body(child: np.random.SeedSequence) -> dict:
    """The two-mass body of a record and its simulator's and noise's seeds, from the record's own seed."""
    draw, sim, noise = child.spawn(3)
    rng = np.random.default_rng(draw)
    body = {name: float(rng.uniform(*bounds)) for name, bounds in RANGES.items()}
    body["variation"] = "jumps" if child.spawn_key[-1] % 2 == 0 else "smooth"
    body["sim_seed"] = int(sim.generate_state(1)[0])
    body["noise_seed"] = noise
    return body


def matrices(body: dict):
    """``(mass, stiffness, damping)`` matrices of the two-mass body (legs, trunk)."""
    m2 = body["upper"] * MASS
    m1 = MASS - m2
    w1, w2 = 2 * np.pi * body["f_1"], 2 * np.pi * body["f_2"]
    k1, c1 = MASS * w1**2, 2 * body["xi_1"] * MASS * w1
    k2, c2 = m2 * w2**2, 2 * body["xi_2"] * m2 * w2
    M = np.diag([m1, m2])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    C = np.array([[c1 + c2, -c2], [-c2, c2]])
    return M, K, C


def modes(body: dict) -> tuple:
    """``((f_low, xi_low), (f_high, xi_high))``: the damped body's modes, from the first-order system's eigenvalues
    (undamped natural frequency ``|lambda| / 2 pi``, damping ratio ``-Re(lambda) / |lambda|``)."""
    M, K, C = matrices(body)
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K, -Minv @ C]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0] if np.sum(lam.imag > 0) == 2 else lam[:2]
    found = sorted((abs(v) / (2 * np.pi), -v.real / abs(v)) for v in lam)
    return found[0], found[1]


def simulate(body: dict):
    """The record (a :class:`~smd_statespace.io.Record`, 30 s at 100 Hz) of a two-mass body bouncing."""
    from scipy.integrate import solve_ivp
    from scipy.interpolate import CubicSpline

    from smd_statespace.io import G, make_record
    from smd_statespace.simulation import simulate_bouncing

    total = DURATION + RUN_IN
    one = simulate_bouncing(mass=MASS, f_b=body["f_b"], f_h=body["f_1"], xi_h=body["xi_1"], duration=total, fs=1000.0,
                            noise=0.0, seed=body["sim_seed"], variation=body["variation"])
    s = one.states
    w = 2 * np.pi * body["f_1"]
    f_bio = MASS * (s["u_ddot"] + 2 * body["xi_1"] * w * s["u_dot"] + w**2 * s["u"]).to_numpy()  # Eq. 2
    force = CubicSpline(s["time"].to_numpy(), f_bio)
    M, K, C = matrices(body)
    Minv = np.linalg.inv(M)

    def rhs(t, x):
        acc = Minv @ (np.array([force(t), 0.0]) - K @ x[:2] - C @ x[2:])
        return np.r_[x[2:], acc]

    t = np.arange(0.0, total, 1.0 / RATE)
    solution = solve_ivp(rhs, (0.0, t[-1]), np.zeros(4), t_eval=t, max_step=1.0 / 200.0, rtol=1e-8, atol=1e-10)
    acc = np.array([rhs(tk, x)[2:] for tk, x in zip(t, solution.y.T)])
    grf = MASS * G + acc @ np.diag(M)
    keep = t >= RUN_IN
    rng = np.random.default_rng(body["noise_seed"])
    grf = grf[keep] + NOISE * MASS * G * rng.standard_normal(int(keep.sum()))
    return make_record(t[keep] - RUN_IN, grf, MASS, source="two_mass_body")


def run_record(task) -> dict:
    """Simulate and identify record ``k``; never raises (a failure is the row's ``error``)."""
    seed, n, k, diagnose = task
    body = draw_body(np.random.SeedSequence(seed).spawn(n)[k])
    (f_low, xi_low), (f_high, _) = modes(body)
    out = {"seed": seed, "record": k, **{key: body[key] for key in (*RANGES, "variation")}, "f_low": f_low,
           "xi_low": xi_low, "f_high": f_high, "error": "", "proposed": ""}
    try:
        from smd_statespace.person import identify_person
        from smd_statespace.person.diagnose import diagnose_person

        record = simulate(body)
        start = time.perf_counter()
        result = identify_person(record)
        out["seconds"] = time.perf_counter() - start
        d = result.to_dict()
        low, high = (float(v) for v in result.intervals["f_h"])
        out.update(f_h=result.f_h, f_h_err_pct=100 * (result.f_h / f_low - 1), f_h_low=low, f_h_high=high,
                   covered=bool(low <= f_low <= high), determined=bool(d["f_h_determined"]), xi_h=result.xi_h,
                   xi_h_err=result.xi_h - xi_low, ljung_box_p=d["ljung_box_p"], model=result.model.variation,
                   warnings=" | ".join(w[:90] for w in result.warnings))
        if diagnose:
            diagnosis = diagnose_person(result)
            out["proposed"] = ", ".join(diagnosis.missing) or "nothing"
            out["verdict"] = diagnosis.verdict()[:300]
    except Exception as exc:  # noqa: BLE001 - one record must never stop the run
        out["error"] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:200] if str(exc) else ''}"
    return out


def summary(frame: pd.DataFrame) -> list:
    """The markdown table: per variation generator and in all."""
    lines = ["| force | records (failed) | f_h error against the lower mode, median / worst | determined | "
             "error where determined, median / worst | f_h 90 % coverage | xi_h error against the lower mode's, "
             "median | Ljung-Box p >= 0.01 |", "|---|---|---|---|---|---|---|---|"]
    for name, part in [*frame.groupby("variation"), ("all", frame)]:
        ok = part[part["error"].fillna("").astype(str) == ""]
        det = ok[ok["determined"].astype(bool)]
        err = ok["f_h_err_pct"].abs()
        derr = det["f_h_err_pct"].abs()
        lines.append(
            f"| {name} | {len(part)} ({len(part) - len(ok)}) | {err.median():.1f} % / {err.max():.1f} % | "
            f"{len(det)}/{len(ok)} | " + (f"{derr.median():.1f} % / {derr.max():.1f} %" if len(det) else "-")
            + f" | {ok['covered'].astype(bool).mean():.0%} | {ok['xi_h_err'].median():+.3f} | "
            f"{(ok['ljung_box_p'] >= 0.01).mean():.0%} |")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=16)
    parser.add_argument("--seed", type=int, default=5100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--csv", type=Path, required=True, help="one row per record (resumed when it exists)")
    parser.add_argument("--md", type=Path, help="write the summary table here too")
    parser.add_argument("--diagnose", type=int, default=0, metavar="K", help="run diagnose on the first K records")
    args = parser.parse_args(argv)
    done = pd.read_csv(args.csv) if args.csv.exists() else pd.DataFrame()
    have = set(done["record"][done["seed"] == args.seed]) if len(done) else set()
    tasks = [(args.seed, args.records, k, k < args.diagnose) for k in range(args.records) if k not in have]
    start = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        for out in pool.map(run_record, tasks):
            pd.DataFrame([out]).to_csv(args.csv, mode="a", header=not args.csv.exists(), index=False)
            print(f"record {out['record']}: f_h {out.get('f_h', float('nan')):.3f} against the lower mode "
                  f"{out['f_low']:.3f} Hz {out['error']}", flush=True)
    frame = pd.read_csv(args.csv, keep_default_na=True)
    frame = frame[(frame["seed"] == args.seed) & (frame["record"] < args.records)].drop_duplicates("record", keep="last")
    lines = [f"`python benchmarks/two_mass_body.py --records {args.records} --seed {args.seed} --jobs {args.jobs}` "
             f"({time.perf_counter() - start:.0f} s this call)", "", *summary(frame)]
    if args.diagnose:
        lines += ["", "diagnose proposed:", *(f"- record {r.record}: {r.proposed}: {r.verdict}"
                                              for r in frame[frame["record"] < args.diagnose].itertuples())]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.md:
        args.md.write_text(text)


if __name__ == "__main__":
    main()
