"""The record front end (smd_statespace.signals.frontend): its speed, and the measurements behind its choices.

    python benchmarks/frontend_speed.py            # speed, hum removal, decimation guard, bouts
    python benchmarks/frontend_speed.py --quick    # speed only

Synthetic lab exports (40 s at 1000 Hz): standing 4 s, a ramp of 1-3 cycles, bouncing ~30 s at
1.5-3.5 Hz (four Fourier harmonics), a ramp, standing 3 s; a 2 N-sd white noise, a linear drift
of the plate's zero, 50 Hz + 150 Hz hum whose amplitude varies by 20 % and whose frequency
wanders by 0.03 Hz. Prints:

1. the front end's time (hum found and removed, bouts, decimation to 100 Hz): median of repeats;
2. hum removal, the sliding Hann-window fit (window 1, 2, 4 s) against zero-phase notches
   (iirnotch, Q 25, 50, 100): the hum left (% RMS), what it did to the band below 30 Hz (N), and
   white noise with hum, cleaned and decimated to 100 Hz: Ljung-Box (20 lags) rejections at 5 %;
3. the decimation's guard band (0 to 1 Hz): the same whiteness, a 50 Hz line's remains, the
   error on a noise-free bouncing force;
4. the bouts found against the truth (cycles), and the mass and drift read from standing.
"""

import argparse
import time

import numpy as np
from scipy import signal, stats

from smd_statespace.io import G, make_record
from smd_statespace.signals import decimation, decimate_record
from smd_statespace.signals.frontend import HUM_WINDOW, find_bouts, front_end, mains_hum, remove_hum


def lab_record(rng, fs=1000.0, bounce=30.0, hum=(1.5, 0.6), noise=2.0, wander=0.03, am=0.2, force_on=True):
    """A synthetic lab export and its truth."""
    fb, ramp, mass, drift = rng.uniform(1.5, 3.5), int(rng.integers(1, 4)), rng.uniform(50, 100), rng.uniform(-5, 5)
    t0 = 4.0
    t1, t2 = t0 + ramp / fb, t0 + ramp / fb + bounce
    t3 = t2 + ramp / fb
    t = np.arange(0.0, t3 + 3.0, 1 / fs)
    env = np.clip((t - t0) / (t1 - t0), 0, 1) * np.clip((t3 - t) / (t3 - t2), 0, 1) * force_on
    phase = 2 * np.pi * fb * (t - t0)
    amps = rng.uniform([0.3, 0.05, 0.01, 0.005], [0.6, 0.2, 0.06, 0.02])
    shape = sum(a * np.sin((k + 1) * phase + rng.uniform(0, 2 * np.pi)) for k, a in enumerate(amps))
    sway = 0.006 * np.sin(2 * np.pi * 0.25 * t + rng.uniform(0, 6)) + 0.004 * np.sin(2 * np.pi * 0.11 * t)
    force = mass * G * (1 + env * shape + sway * (1 - env)) + drift * t / t[-1]
    mains = 2 * np.pi * 50 * t + 2 * np.pi * wander * 17 / (2 * np.pi) * (1 - np.cos(2 * np.pi * t / 17))
    size = 1 + am * np.sin(2 * np.pi * t / 13 + rng.uniform(0, 6))
    hum_wave = size * (hum[0] * np.sin(mains + rng.uniform(0, 6)) + hum[1] * np.sin(3 * mains + rng.uniform(0, 6)))
    measured = force + hum_wave + rng.normal(0, noise, t.size)
    truth = dict(start=t1, end=t2, period=1 / fb, mass=mass, drift_rate=drift / t[-1],
                 force=force, hum=hum_wave)
    return make_record(t, measured, mass), truth


def rejected(x, lags=20):
    """Ljung-Box p-value < 0.05, and the lag-1 autocorrelation."""
    x = x - x.mean()
    r = np.array([np.dot(x[:-k], x[k:]) for k in range(1, lags + 1)]) / np.dot(x, x)
    q = x.size * (x.size + 2) * np.sum(r ** 2 / (x.size - np.arange(1, lags + 1)))
    return stats.chi2.sf(q, lags) < 0.05, r[0]


def speed(repeats):
    record, _ = lab_record(np.random.default_rng(1))
    front_end(record)  # warm up (imports, FFT plans)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        front_end(record)
        times.append(time.perf_counter() - start)
    print(f"front end on {record.duration:.0f} s at {record.fs:.0f} Hz ({record.time.size} samples): "
          f"median {np.median(times) * 1e3:.0f} ms of {repeats} (min {min(times) * 1e3:.0f}, max {max(times) * 1e3:.0f})")


def notch(record, hum, q):
    x = np.asarray(record.force, float)
    for f in hum.harmonics[hum.lines]:
        b, a = signal.iirnotch(f, q, fs=record.fs)
        x = signal.filtfilt(b, a, x, method="gust")
    return x


def hum_methods(count):
    methods = [(f"sliding fit {w:g} s", ("fit", w)) for w in (2.0, 4.0, 8.0)]
    methods += [(f"notch Q {q:g}", ("notch", q)) for q in (25.0, 50.0, 100.0)]
    low = signal.butter(8, 30.0, fs=1000.0, output="sos")
    rows = {name: [] for name, _ in methods}
    amp_err = []
    for i in range(count):
        rng = np.random.default_rng(100 + i)
        record, truth = lab_record(rng)
        white = make_record(record.time, record.mass * G + truth["hum"] + rng.normal(0, 2.0, record.time.size),
                            record.mass)  # white noise and the same hum
        for name, (kind, value) in methods:
            hums = [mains_hum(r, window=value if kind == "fit" else 2.0) for r in (record, white)]
            cleaned = [remove_hum(r, h).force if kind == "fit" else notch(r, h, value) for r, h in zip((record, white), hums)]
            left = cleaned[0] - (record.force - truth["hum"])  # the hum left less the noise taken
            inner = slice(3000, -3000)
            coherent = [np.dot(left[inner], truth["hum"][inner]) / np.dot(truth["hum"][inner], truth["hum"][inner]),
                        np.dot(left, truth["hum"]) / np.dot(truth["hum"], truth["hum"])]
            band = signal.sosfiltfilt(low, cleaned[0] - record.force)[inner]
            decimated, _, _ = decimate_record(make_record(white.time, cleaned[1], white.mass), 100.0)
            rej, lag1 = rejected(decimated.force[30:-30])
            rows[name].append((*coherent, np.std(left - coherent[1] * truth["hum"]), np.abs(band).max(), rej, lag1))
            if name == f"sliding fit {HUM_WINDOW:g} s":
                amp_err.append(hums[0].amplitudes[[0, 2]])
    print(f"\nhum removal, {count} records (hum 1.5 N at 50 Hz + 0.6 N at 150 Hz, +-20 % amplitude, 0.03 Hz wander):")
    print("hum left: the part of the true hum still there (inner: 3 s from the ends left out); noise taken: the sd (N)"
          " of what else was removed; band: the largest change below 30 Hz (N); LB: white noise with the same hum,"
          " cleaned, decimated to 100 Hz")
    print(f"{'method':<18}{'hum left (inner)':>18}{'hum left (all)':>16}{'noise taken':>13}{'band < 30 Hz':>14}"
          f"{'LB rejected':>13}{'lag-1':>9}")
    for name, values in rows.items():
        v = np.array(values)
        print(f"{name:<18}{100 * np.abs(v[:, 0]).max():>16.2f} %{100 * np.abs(v[:, 1]).max():>14.2f} %"
              f"{v[:, 2].mean():>13.3f}{v[:, 3].max():>14.4f}{100 * v[:, 4].mean():>11.0f} %{v[:, 5].mean():>+9.4f}")
    a = np.array(amp_err)
    print(f"amplitudes found (sliding fit {HUM_WINDOW:g} s, median over time): 50 Hz {a[:, 0].mean():.3f} N (sd {a[:, 0].std():.3f}),"
          f" 150 Hz {a[:, 1].mean():.3f} N (sd {a[:, 1].std():.3f}); the truth's mean amplitude 1.5, 0.6 N")


def guard_band(count):
    saved = decimation.GUARD_BAND
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 30.0, 0.001)
    smooth = 700 * (1 + 0.4 * np.sin(2 * np.pi * 2.2 * t + .3) + 0.1 * np.sin(2 * np.pi * 4.4 * t)
                    + 0.05 * np.sin(2 * np.pi * 13.1 * t) + 0.015 * np.sin(2 * np.pi * 30 * t))
    print(f"\ndecimation 1000 -> 100 Hz, guard band below 50 Hz; white noise: {count} records of 30 s:")
    print(f"{'guard (Hz)':>10}{'LB rejected':>13}{'lag-1':>9}{'lag-2':>9}{'variance':>10}"
          f"{'50 Hz line left (inner, RMS)':>30}{'near the ends (max)':>21}{'bouncing err, 0.3 s in (N)':>28}")
    try:
        for guard in (0.0, 0.1, 0.25, 0.5, 1.0):
            decimation.GUARD_BAND = guard
            out = []
            for _ in range(count):
                d, _, _ = decimate_record(make_record(t, 700 + rng.normal(0, 1, t.size), 71.4), 100.0)
                out.append((*rejected(d.force), np.dot(*(lambda x: (x[:-2], x[2:]))(d.force - d.force.mean()))
                            / np.dot(d.force - d.force.mean(), d.force - d.force.mean()), d.force.var() * 10))
            o = np.array(out)
            line = decimate_record(make_record(t, 700 + np.sin(2 * np.pi * 50 * t + 0.7), 71.4), 100.0)[0].force - 700
            bounce = (decimate_record(make_record(t, smooth, 71.4), 100.0)[0].force - smooth[::10])[30:-30]
            print(f"{guard:>10g}{100 * o[:, 0].mean():>11.1f} %{o[:, 1].mean():>+9.4f}{o[:, 2].mean():>+9.4f}"
                  f"{o[:, 3].mean():>10.4f}{np.sqrt(np.mean(line[300:-300] ** 2)):>30.3f}"
                  f"{np.abs(line).max():>21.2f}{np.abs(bounce).max():>28.3f}")
    finally:
        decimation.GUARD_BAND = saved


def bouts(count):
    errors = []
    for i in range(count):
        record, truth = lab_record(np.random.default_rng(500 + i))
        found = find_bouts(remove_hum(record))
        if len(found.bouts) != 1:
            errors.append((np.inf, np.inf, np.nan, np.nan))
            continue
        b = found.bouts[0]
        standing = [s for s in found.segments if s.kind == "standing"]
        middles = [(s.start + s.end) / 2 for s in (standing[0], standing[-1])]
        errors.append(((b.start - truth["start"]) / truth["period"], (b.end - truth["end"]) / truth["period"],
                       found.mass / truth["mass"] - 1, found.drift - truth["drift_rate"] * np.diff(middles)[0]))
    e = np.array(errors)
    print(f"\nbouts on {count} records (1.5-3.5 Hz, ramps of 1-3 cycles): one bout found on "
          f"{np.isfinite(e[:, 0]).sum()}; start - truth {e[:, 0].min():+.2f} to {e[:, 0].max():+.2f} cycles, end - truth "
          f"{e[:, 1].min():+.2f} to {e[:, 1].max():+.2f} cycles; mass from standing {100 * np.nanmin(e[:, 2]):+.2f} to "
          f"{100 * np.nanmax(e[:, 2]):+.2f} %; drift - truth {np.nanmin(e[:, 3]):+.2f} to {np.nanmax(e[:, 3]):+.2f} N")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the speed only")
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    speed(args.repeats)
    if not args.quick:
        hum_methods(20)
        guard_band(400)
        bouts(40)


if __name__ == "__main__":
    main()
