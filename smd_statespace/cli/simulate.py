"""``smd-statespace simulate``: write a synthetic GRF record (Eq. 2-4), or a phone's accelerometer record of the
person (``--accelerometer``), and the truth behind it."""

from __future__ import annotations

from pathlib import Path

from ..errors import OptionError, SMDInputError
from ..simulation import VARIATIONS
from ..simulation.phone import PHONE_DEFAULTS
from .common import _nonnegative, _numbers, _positive, _seed

PHONE_OPTIONS = (("tilt", "tilt", "DEG", "tilt of the phone from level"),
                 ("sway", "sway", "DEG", "slow sway amplitude"),
                 ("bias", "bias", "M/S2", "per-axis bias bound"),
                 ("phone-noise", "noise", "M/S2", "noise sd per axis"),
                 ("phone-rate", "fs", "HZ", "sampling rate, 50-500"),
                 ("jitter", "jitter", "S", "clock jitter sd"),
                 ("drop", "drop", "FRAC", "fraction of samples dropped"))
"""The phone's options of ``simulate --accelerometer``: (flag, keyword of
:func:`~smd_statespace.simulation.phone.simulate_phone`, metavar, help)."""


def add_simulate(subparsers):
    """Declare ``smd-statespace simulate``."""
    parser = subparsers.add_parser(
        "simulate",
        help="write a synthetic GRF record with known truth",
        description=(
            "Simulate one person bouncing (SMD model, Eq. 2; Fourier force, Eq. 4; GRF by Eq. 3 plus noise) "
            "and write the record as CSV (time,force[,floor_acc]) and the truth as JSON."
        ),
    )
    parser.add_argument("--out", required=True, metavar="CSV", help="record file to write")
    parser.add_argument("--truth", metavar="JSON", help="truth file (default: <out stem>_truth.json beside it)")
    parser.add_argument("--mass", required=True, type=float, metavar="KG", help="body mass M_h (kg)")
    parser.add_argument("--fb", required=True, type=_positive, metavar="HZ", help="bouncing frequency f_b (Hz)")
    parser.add_argument("--fh", required=True, type=_positive, metavar="HZ", help="SMD natural frequency f_h (Hz)")
    parser.add_argument("--xi", required=True, type=_positive, metavar="RATIO", help="SMD damping ratio xi_h")
    parser.add_argument("--duration", required=True, type=_positive, metavar="S", help="record length (s)")
    parser.add_argument("--fs", type=_positive, default=100.0, metavar="HZ", help="sampling frequency (default 100)")
    parser.add_argument("--noise", type=_nonnegative, default=0.01, metavar="BW",
                        help="GRF noise SD as a fraction of body weight (default 0.01)")
    parser.add_argument("--seed", type=_seed, metavar="N",
                        help="random seed (default: fresh entropy, recorded in the truth file)")
    parser.add_argument("--blf", type=_numbers, metavar="G,G,...",
                        help="harmonic amplitudes BLF_1..BLF_n in g (default 0.25,0.15,0.05,0.02)")
    parser.add_argument("--fb-variation", type=_nonnegative, default=0.02, metavar="FRAC",
                        help="cycle-to-cycle relative SD of f_b (default 0.02)")
    parser.add_argument("--coef-variation", type=_nonnegative, default=0.10, metavar="FRAC",
                        help="cycle-to-cycle relative SD of the force harmonics (default 0.10)")
    parser.add_argument("--variation", choices=VARIATIONS, default=VARIATIONS[0],
                        help="how the force varies from cycle to cycle: jumps (each cycle its own frequency and "
                             "harmonics, jumping at the boundaries; default), smooth (frequency and harmonics "
                             "drift continuously, correlated over about 2.5 cycles), coefficients (each Fourier "
                             "coefficient jittered on its own per cycle, the person starting from rest), pulses "
                             "(one squared-sine pulse per cycle, its width, height and timing jittered; the truth "
                             "holds the mean pulse's harmonics) or tempo (a fixed shape under a tempo that ramps "
                             "and wanders by a few --fb-variation over the record; --coef-variation unused)")
    parser.add_argument("--accelerometer", action="store_true",
                        help="write a phone's accelerometer record instead of a force plate's: phyphox's CSV "
                             "export (three axes with gravity, tilted, swaying, biased, noisy, jittered clock, "
                             "dropped samples; the options below), read by identify --accelerometer")
    for flag, key, unit, what in PHONE_OPTIONS:
        parser.add_argument(f"--{flag}", type=_nonnegative, default=None, metavar=unit,
                            help=f"with --accelerometer: {what} (default {PHONE_DEFAULTS[key]:g})")
    parser.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                        help="physical effect, repeatable: any registered effect (floor_mode, harmonics, "
                             "cubic_stiffness, a user's); keys are its options or its parameters' true values "
                             "(e.g. floor_mode:frequency=3.48, floor_mode:frequency=9.5,ambient=1.0, "
                             "harmonics:blf=0.04/0.03, cubic_stiffness:beta_3=400)")
    return parser


def run_simulate(args) -> int:
    """Run ``smd-statespace simulate``."""
    from ..effects import make_effect
    from ..io import check_mass
    from ..simulation.bouncing import DEFAULT_BLF, simulate_bouncing

    mass = check_mass(args.mass, source="--mass")
    effects = [make_effect(spec, "--effect") for spec in args.effect]
    names = [effect.name for effect in effects]
    if len(set(names)) < len(names):
        raise OptionError(f"--effect {max(names, key=names.count)!r} is given twice; give each effect once")
    out = Path(args.out)
    truth = None if args.truth is None else Path(args.truth)
    for label, path in (("--out", out), ("--truth", truth)):
        if path is not None and not path.parent.is_dir():
            raise OptionError(f"{label} {path}: directory {path.parent} does not exist")
    given = [(flag, key) for flag, key, _, _ in PHONE_OPTIONS if getattr(args, flag.replace("-", "_")) is not None]
    if given and not args.accelerometer:
        raise OptionError(f"--{given[0][0]} applies to a phone's record (--accelerometer)")
    phone = {key: getattr(args, flag.replace("-", "_")) for flag, key in given}
    if args.accelerometer:
        return _simulate_phone(args, mass, effects, names, out, truth, phone)
    try:
        synthetic = simulate_bouncing(
            mass=mass,
            f_b=args.fb,
            f_h=args.fh,
            xi_h=args.xi,
            duration=args.duration,
            fs=args.fs,
            blf=DEFAULT_BLF if args.blf is None else args.blf,
            fb_variation=args.fb_variation,
            coef_variation=args.coef_variation,
            noise=args.noise,
            effects=effects or None,
            seed=args.seed,
            variation=args.variation,
        )
    except SMDInputError as exc:
        # The simulator names itself ("simulate_bouncing: ..."); on the command line that is noise.
        raise type(exc)(str(exc).replace("simulate_bouncing: ", "", 1)) from None
    csv_path, truth_path = synthetic.write(out, truth)
    record, info = synthetic.record, synthetic.truth
    extra = f", effects {', '.join(names)}" if effects else ""
    extra += f", {args.variation} variation"
    seed = f"seed {info['seed']}" if args.seed is not None else "random seed (in the truth file)"
    print(
        f"wrote {csv_path}: {record.duration:.2f} s at {record.fs:g} Hz, {info['n_cycles']} force cycles "
        f"(f_b {args.fb:g} Hz, f_h {args.fh:g} Hz, xi_h {args.xi:g}, {seed}{extra}); truth in {truth_path}"
    )
    return 0


def _simulate_phone(args, mass, effects, names, out, truth, phone) -> int:
    """``simulate --accelerometer``: the person recorded by a phone at the waist, in phyphox's format."""
    from ..simulation.bouncing import DEFAULT_BLF
    from ..simulation.phone import simulate_phone

    try:
        record = simulate_phone(mass=mass, f_b=args.fb, f_h=args.fh, xi_h=args.xi, duration=args.duration,
                                seed=args.seed, blf=DEFAULT_BLF if args.blf is None else args.blf,
                                fb_variation=args.fb_variation, coef_variation=args.coef_variation,
                                effects=effects or None, variation=args.variation, **phone)
    except SMDInputError as exc:
        raise type(exc)(str(exc).replace("simulate_bouncing: ", "", 1).replace("simulate_phone: ", "", 1)) from None
    csv_path, truth_path = record.write(out, truth)
    settings = record.truth["phone"]
    extra = f", effects {', '.join(names)}" if effects else ""
    print(f"wrote {csv_path}: a phone's accelerometer ({settings['fs']:g} Hz, {len(record.time)} samples, "
          f"{settings['n_dropped']} dropped; tilt {settings['tilt_deg']:g} deg, sway {settings['sway_deg']:g} deg, "
          f"noise {settings['noise']:g} m/s^2) on a person bouncing {args.duration:g} s (f_b {args.fb:g} Hz, f_h "
          f"{args.fh:g} Hz, xi_h {args.xi:g}, {args.variation} variation{extra}); truth in {truth_path}; identify it "
          f"with: smd-statespace identify {csv_path} --accelerometer")
    return 0
