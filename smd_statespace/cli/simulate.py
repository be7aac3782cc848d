"""``smd-statespace simulate``: write a synthetic GRF record (Eq. 2-4), a phone's accelerometer record of the
person (``--accelerometer``) or a lab's force-plate export of a whole trial (``--lab``), and the truth behind it."""

from __future__ import annotations

from pathlib import Path

from ..applicability import flights
from ..errors import OptionError, SMDInputError
from ..io import G
from ..simulation import VARIATIONS
from ..simulation.phone import PHONE_DEFAULTS
from ..simulation.phone_session import SESSION_DEFAULTS
from .common import _nonnegative, _numbers, _positive, _seed

LAB_OPTIONS = (("stand", ("stand_before", "stand_after"), _numbers, "S[,S]",
                "standing still before and after bouncing (s; default 4)"),
               ("bout", "bout", _positive, "S", "full bouncing between the ramps (s; default 30)"),
               ("ramp", ("ramp_up", "ramp_down"), _numbers, "CYCLES[,CYCLES]",
                "ramp of the force's amplitude up and down, in cycles (default 2)"),
               ("body-sway", "sway", _nonnegative, "N", "RMS of a standing person's sway, below 1.5 Hz (default 2)"),
               ("hum", "hum_frequency", _positive, "HZ", "mains frequency, 50 or 60 (default 50)"),
               ("hum-amplitude", "hum", _numbers, "N,N,...",
                "hum amplitudes of the mains frequency and its harmonics 2, 3, ... (default 5,0,2)"),
               ("hum-variation", "hum_variation", _nonnegative, "FRAC",
                "slow relative modulation of the hum's amplitude, 0-1 (default 0)"),
               ("drift", "drift", _nonnegative, "N", "largest excursion of the plate's drifting zero (default 10)"),
               ("drift-shape", "drift_shape", str, "cubic|settling|walk|steps",
                "the drifting zero's shape: a cubic of time (default), settling, a wandering walk or steps"),
               ("plate-noise", "noise", _nonnegative, "N", "white noise sd of the plate (default 1)"),
               ("tire", "tire", _nonnegative, "FRAC", "fraction of the BLFs lost over the bout, 0-0.9 (default 0)"),
               ("slow", "slow", _nonnegative, "FRAC", "fraction of f_b lost over the bout, 0-0.5 (default 0)"),
               ("fh-change", "f_h_change", float, "FRAC", "relative change of f_h over the bout (default 0)"),
               ("xi-change", "xi_h_change", float, "FRAC", "relative change of xi_h over the bout (default 0)"),
               ("change", "change", str, "drift|step",
                "the change is linear over the bout (drift, default) or a step at --change-time"),
               ("change-time", "change_time", _nonnegative, "S", "time of the step (s; default mid-bout)"))
"""The lab's options of ``simulate --lab``: (flag, keyword(s) of
:func:`~smd_statespace.simulation.simulate_lab_record`, type, metavar, help); a flag with two keywords takes
one value for both or two."""

PERSON_OPTIONS = (("mass", "mass"), ("fb", "f_b"), ("fh", "f_h"), ("xi", "xi_h"), ("fs", "fs"), ("blf", "blf"),
                  ("fb-variation", "fb_variation"), ("coef-variation", "coef_variation"), ("variation", "variation"))
"""The options of ``simulate`` that ``--lab`` passes on: (flag, keyword of ``simulate_lab_record``)."""

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
            "and write the record as CSV (time,force[,floor_acc]) and the truth as JSON. With --lab, a lab's "
            "force-plate export of a whole trial: standing, ramping up, bouncing, tiring, ramping down, standing, "
            "with mains hum, a drifting zero and noise."
        ),
    )
    parser.add_argument("--out", required=True, metavar="CSV", help="record file to write")
    parser.add_argument("--truth", metavar="JSON", help="truth file (default: <out stem>_truth.json beside it)")
    parser.add_argument("--mass", type=float, metavar="KG", help="body mass M_h (kg); required")
    parser.add_argument("--fb", type=_positive, metavar="HZ", help="bouncing frequency f_b (Hz); required")
    parser.add_argument("--fh", type=_positive, metavar="HZ", help="SMD natural frequency f_h (Hz); required")
    parser.add_argument("--xi", type=_positive, metavar="RATIO", help="SMD damping ratio xi_h; required")
    parser.add_argument("--duration", type=_positive, metavar="S",
                        help="record length (s); required, but not with --lab (use --stand and --bout)")
    parser.add_argument("--fs", type=_positive, metavar="HZ", help="sampling frequency (default 100; 1000 with --lab)")
    parser.add_argument("--noise", type=_nonnegative, metavar="BW",
                        help="GRF noise SD as a fraction of body weight (default 0.01; with --lab use --plate-noise)")
    parser.add_argument("--seed", type=_seed, metavar="N",
                        help="random seed (default: fresh entropy, recorded in the truth file)")
    parser.add_argument("--blf", type=_numbers, metavar="G,G,...",
                        help="harmonic amplitudes BLF_1..BLF_n in g (default 0.25,0.15,0.05,0.02)")
    parser.add_argument("--fb-variation", type=_nonnegative, metavar="FRAC",
                        help="cycle-to-cycle relative SD of f_b (default 0.02)")
    parser.add_argument("--coef-variation", type=_nonnegative, metavar="FRAC",
                        help="cycle-to-cycle relative SD of the force harmonics (default 0.10)")
    parser.add_argument("--phase-variation", type=_nonnegative, metavar="RAD",
                        help="with --variation jumps: SD of each harmonic's phase jitter on its own, --coef-variation "
                             "then setting only the amplitudes' (default: --coef-variation, the harmonics varying "
                             "alike in size and phase)")
    parser.add_argument("--variation", choices=VARIATIONS,
                        help="how the force varies from cycle to cycle: jumps (each cycle its own frequency and "
                             "harmonics, jumping at the boundaries; default), smooth (frequency and harmonics "
                             "drift continuously, correlated over about 2.5 cycles), coefficients (each Fourier "
                             "coefficient jittered on its own per cycle, the person starting from rest), pulses "
                             "(one squared-sine pulse per cycle, its width, height and timing jittered; the truth "
                             "holds the mean pulse's harmonics) or tempo (a fixed shape under a tempo that ramps "
                             "and wanders by a few --fb-variation over the record; --coef-variation unused); "
                             "with --lab jumps or smooth")
    parser.add_argument("--accelerometer", action="store_true",
                        help="write a phone's accelerometer record instead of a force plate's: phyphox's CSV "
                             "export (three axes with gravity, tilted, swaying, biased, noisy, jittered clock, "
                             "dropped samples; the options below), read by identify --accelerometer")
    for flag, key, unit, what in PHONE_OPTIONS:
        parser.add_argument(f"--{flag}", type=_nonnegative, default=None, metavar=unit,
                            help=f"with --accelerometer: {what} (default {PHONE_DEFAULTS[key]:g})")
    parser.add_argument("--lab", action="store_true",
                        help="write a lab's force-plate export of a whole trial instead: the person stands, ramps "
                             "up, bounces for --bout s (tiring by --tire, slowing by --slow, f_h and xi_h changing "
                             "by --fh-change, --xi-change), ramps down and stands again, on a plate with mains hum, "
                             "a drifting zero and noise (the options below); --mass, --fb, --fh, --xi required "
                             "unless --typical")
    parser.add_argument("--typical", action="store_true",
                        help="with --lab: draw every setting not given (the person's too) over the wide ranges of "
                             "a typical lab record, from --seed")
    for flag, _, kind, unit, what in LAB_OPTIONS:
        parser.add_argument(f"--{flag}", type=kind, default=None, metavar=unit, help=f"with --lab: {what}")
    parser.add_argument("--handling", type=_numbers, default=None, metavar="S[,S]",
                        help="with --lab --accelerometer (a phone's record of the whole trial): the phone picked "
                             "up and strapped on before, taken off and put down after (s; 0 for none; default "
                             f"{SESSION_DEFAULTS['pick_up']:g},{SESSION_DEFAULTS['take_off']:g})")
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

    lab = [flag for flag, *_ in LAB_OPTIONS if getattr(args, flag.replace("-", "_")) is not None]
    lab += ["typical"] if args.typical else []
    if lab and not args.lab:
        raise OptionError(f"--{lab[0]} applies to a lab's record (--lab)")
    out, truth = _out_paths(args)
    if args.phase_variation is not None and (args.lab or args.accelerometer or args.variation not in (None, "jumps")):
        raise OptionError("--phase-variation applies to --variation jumps on a force plate (not --lab or "
                          "--accelerometer)")
    if args.lab:
        return _simulate_lab(args, out, truth)
    missing = [f"--{flag}" for flag in ("mass", "fb", "fh", "xi", "duration") if getattr(args, flag) is None]
    if missing:
        raise OptionError(f"the following arguments are required: {', '.join(missing)}")
    for name, default in (("noise", 0.01), ("fb_variation", 0.02), ("coef_variation", 0.10),
                          ("variation", VARIATIONS[0])):
        setattr(args, name, default if getattr(args, name) is None else getattr(args, name))
    mass = check_mass(args.mass, source="--mass")
    effects = [make_effect(spec, "--effect") for spec in args.effect]
    names = [effect.key for effect in effects]
    if len(set(names)) < len(names):
        raise OptionError(f"--effect {max(names, key=names.count)!r} is given twice; give each effect once")
    given = [(flag, key) for flag, key, _, _ in PHONE_OPTIONS if getattr(args, flag.replace("-", "_")) is not None]
    if given and not args.accelerometer:
        raise OptionError(f"--{given[0][0]} applies to a phone's record (--accelerometer)")
    phone = {key: getattr(args, flag.replace("-", "_")) for flag, key in given}
    if args.accelerometer:
        return _simulate_phone(args, mass, effects, names, out, truth, phone)
    args.fs = 100.0 if args.fs is None else args.fs
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
            phase_variation=args.phase_variation,
        )
    except SMDInputError as exc:
        # The simulator names itself ("simulate_bouncing: ..."); on the command line that is noise.
        raise type(exc)(str(exc).replace("simulate_bouncing: ", "", 1)) from None
    csv_path, truth_path = synthetic.write(out, truth)
    record, info = synthetic.record, synthetic.truth
    extra = _effects_text([effect.spec for effect in effects])
    extra += f", {args.variation} variation"
    seed = f"seed {info['seed']}" if args.seed is not None else "random seed (in the truth file)"
    print(
        f"wrote {csv_path}: {record.duration:.2f} s at {record.fs:g} Hz, {info['n_cycles']} force cycles "
        f"(f_b {args.fb:g} Hz, f_h {args.fh:g} Hz, xi_h {args.xi:g}, {seed}{extra}); truth in {truth_path}"
    )
    fraction = record.force / (mass * G)
    starts, _ = flights(fraction, 1.0 / record.fs)
    if starts.size:
        print(f"warning: the simulated GRF falls to about zero {starts.size} times (lowest {fraction.min():.0%} of "
              "body weight): a person would leave the plate there, which the SMD model cannot (no flight phase); "
              "identify reads these parts as no contact and leaves them out. Lower --blf's first value or raise --xi")
    return 0


def _out_paths(args) -> tuple:
    """``(out, truth)`` paths (truth None: beside the record), their directories checked."""
    out = Path(args.out)
    truth = None if args.truth is None else Path(args.truth)
    for label, path in (("--out", out), ("--truth", truth)):
        if path is not None and not path.parent.is_dir():
            raise OptionError(f"{label} {path}: directory {path.parent} does not exist")
    return out, truth


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
    extra = _effects_text([effect.spec for effect in effects])
    print(f"wrote {csv_path}: a phone's accelerometer ({settings['fs']:g} Hz, {len(record.time)} samples, "
          f"{settings['n_dropped']} dropped; tilt {settings['tilt_deg']:g} deg, sway {settings['sway_deg']:g} deg, "
          f"noise {settings['noise']:g} m/s^2) on a person bouncing {args.duration:g} s (f_b {args.fb:g} Hz, f_h "
          f"{args.fh:g} Hz, xi_h {args.xi:g}, {args.variation} variation{extra}); truth in {truth_path}; identify it "
          f"with: smd-statespace identify {csv_path} --accelerometer")
    return 0


def _lab_settings(args) -> dict:
    """The keyword arguments of ``simulate_lab_record`` that ``simulate --lab`` was given (checked one by one)."""
    settings = {key: getattr(args, flag.replace("-", "_")) for flag, key in PERSON_OPTIONS
                if getattr(args, flag.replace("-", "_")) is not None}
    for flag, keys, *_ in LAB_OPTIONS:
        value = getattr(args, flag.replace("-", "_"))
        if value is None:
            continue
        if isinstance(keys, str):
            settings[keys] = value
            continue
        if len(value) not in (1, 2) or any(v < 0 for v in value):
            raise OptionError(f"--{flag} takes one or two numbers >= 0 (before and after), got {value!r}")
        settings.update(zip(keys, value if len(value) == 2 else value * 2))
    return settings


def _lab_error(exc) -> SMDInputError:
    """The simulator's error with its function's name dropped and a keyword it names said as its flag."""
    text = str(exc)
    for prefix in ("simulate_lab_record: ", "draw_lab_settings: "):
        text = text.replace(prefix, "", 1)
    flags = {key: flag for flag, key in PERSON_OPTIONS}
    for flag, keys, *_ in LAB_OPTIONS:
        flags.update({key: flag for key in ((keys,) if isinstance(keys, str) else keys)})
    name = text.split(" ", 1)[0]
    if name in flags:
        text = f"--{flags[name]}{text[len(name):]}"
    return type(exc)(text)


def _simulate_lab(args, out, truth) -> int:
    """``simulate --lab``: a lab's force-plate export of a whole trial, with its truth."""
    from ..io import check_mass
    from ..simulation.lab import simulate_lab_record, simulate_typical_lab_record

    for flag in ("duration", "noise"):
        if getattr(args, flag):
            raise OptionError(f"--{flag} does not apply to --lab (the record's length is --stand, the ramps and "
                              "--bout; its noise --plate-noise N)")
    if args.effect and args.accelerometer:
        raise OptionError("--effect does not apply to --lab --accelerometer (a phone's record of a whole trial is "
                          "of the person without effects)")
    if args.handling is not None and not args.accelerometer:
        raise OptionError("--handling applies to a phone's record of a whole trial (--lab --accelerometer)")
    settings = _lab_settings(args)
    if args.effect:
        settings["effects"] = list(args.effect)
    if "mass" in settings:
        settings["mass"] = check_mass(settings["mass"], source="--mass")
    missing = [f"--{flag}" for flag, key in PERSON_OPTIONS[:4] if key not in settings]
    if missing and not args.typical:
        raise OptionError(f"--lab needs {', '.join(missing)} (or --typical to draw them)")
    if args.accelerometer:
        return _simulate_session(args, settings, out, truth)
    try:
        if args.typical:
            synthetic = simulate_typical_lab_record(seed=args.seed, **settings)
        else:
            synthetic = simulate_lab_record(seed=args.seed, **settings)
    except SMDInputError as exc:
        raise _lab_error(exc) from None
    csv_path, truth_path = synthetic.write(out, truth)
    info, span = synthetic.truth, synthetic.truth["span"]
    hum = info["hum"]
    print(f"wrote {csv_path}: a lab's force-plate export, {info['duration']:.2f} s at {info['fs']:g} Hz; standing "
          f"until {span['bouncing_start_s']:.2f} s and from {span['bouncing_end_s']:.2f} s, full bouncing "
          f"{span['full_start_s']:.2f}-{span['full_end_s']:.2f} s (mass {info['mass']:.1f} kg, f_b "
          f"{info['f_b_start']:.3g} Hz, f_h {info['f_h_start']:.3g}-{info['f_h_end']:.3g} Hz, xi_h "
          f"{info['xi_h_start']:.3g}-{info['xi_h_end']:.3g}, tiring {info['tire']:.2g}, "
          f"{info['variations']['generator']} variation{_effects_text(args.effect)}); hum {hum['frequency_hz']:g} Hz, "
          "drift up to "
          f"{info['drift']['max_abs_n']:.3g} N, noise {info['noise_n']:.3g} N; truth in {truth_path}")
    return 0


def _effects_text(specs) -> str:
    """``, effects A, B`` for the lines that say what was written ("" without effects)."""
    return f", effects {', '.join(specs)}" if specs else ""


PLATE_ONLY = ("hum", "hum-amplitude", "hum-variation", "drift", "drift-shape", "plate-noise", "fs", "typical")
"""Options of ``simulate --lab`` that a phone's record of the trial (``--lab --accelerometer``) does not take."""


def _simulate_session(args, settings, out, truth) -> int:
    """``simulate --lab --accelerometer``: a phone's record of a whole trial, handling included."""
    from ..simulation.phone_session import simulate_phone_session

    plate = [flag for flag in PLATE_ONLY if getattr(args, flag.replace("-", "_")) not in (None, False)]
    if plate:
        raise OptionError(f"--{plate[0]} does not apply to a phone's record (--lab --accelerometer): the phone's "
                          "options are --phone-rate, --tilt, --bias, --phone-noise, --handling")
    unused = [flag for flag in ("sway", "jitter", "drop") if getattr(args, flag) is not None]
    if unused:
        raise OptionError(f"--{unused[0]} does not apply to --lab --accelerometer (the phone is worn still; "
                          "--body-sway is the person's)")
    phone = {key: getattr(args, flag.replace("-", "_")) for flag, key, *_ in PHONE_OPTIONS
             if getattr(args, flag.replace("-", "_")) is not None}
    handling = args.handling
    if handling is not None:
        if len(handling) not in (1, 2) or any(v < 0 for v in handling):
            raise OptionError(f"--handling takes one or two numbers >= 0 (before and after), got {handling!r}")
        phone["pick_up"], phone["take_off"] = (handling * 2)[:2] if len(handling) == 1 else handling
    settings.pop("fs", None)
    try:
        record = simulate_phone_session(seed=args.seed, **settings, **phone)
    except SMDInputError as exc:
        text = str(exc).replace("simulate_phone_session: fs ", "--phone-rate ", 1)
        for key, flag in (("pick_up", "--handling"), ("take_off", "--handling"), ("noise", "--phone-noise")):
            text = text.replace(f"simulate_phone_session: {key} ", f"{flag} ", 1)
        raise _lab_error(type(exc)(text)) from None
    csv_path, truth_path = record.write(out, truth)
    session = record.truth["session"]
    print(f"wrote {csv_path}: a phone's record of a whole trial ({session['fs']:g} Hz, {record.time[-1]:.2f} s): "
          f"picked up until {session['pick_up'][1]:.2f} s, worn {session['worn'][0]:.2f}-{session['worn'][1]:.2f} s "
          f"(bouncing {session['bouncing'][0]:.2f}-{session['bouncing'][1]:.2f} s), taken off until "
          f"{session['take_off'][1]:.2f} s; truth in {truth_path}; identify it with: smd-statespace identify "
          f"{csv_path} --accelerometer")
    return 0
