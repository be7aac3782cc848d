"""The noise floor's draw, changed on purpose: ``benchmarks/lab_records.py`` with the draw salted.

A record quieter than the noise floor is fitted with white noise added up to it
(:mod:`smd_statespace.person.noise_floor`), drawn from a generator seeded by the record
(:func:`~smd_statespace.person.noise_floor.record_seed`). This runs ``lab_records.py`` with that seed mixed
with ``SALT``, so the same records are fitted with another draw and nothing else changed; comparing the
CSVs of several salts measures how much the answer depends on the draw, and whether averaging draws helps
(``benchmarks/results/lab_records_record_seed.md``).

Usage::

    python benchmarks/noise_floor_draws.py SALT [lab_records.py's options]
    python benchmarks/noise_floor_draws.py 1 --seed 4349 --records 16 --jobs 2 --rows lab,change,held_out \\
        --csv benchmarks/results/lab_records_draw1_seed4349.csv

The worker processes are forked with the salted seed in place (Linux's default start method).
"""

import hashlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import smd_statespace.person.noise_floor as noise_floor  # noqa: E402

UNSALTED = noise_floor.record_seed


def salted_seed(salt: str):
    """:func:`~smd_statespace.person.noise_floor.record_seed` mixed with ``salt``."""

    def record_seed(samples):
        entropy = UNSALTED(samples).entropy
        digest = hashlib.sha256(f"{entropy} {salt}".encode("ascii")).digest()
        return np.random.SeedSequence(int.from_bytes(digest[:16], "little"))

    return record_seed


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv:
        raise SystemExit("usage: python benchmarks/noise_floor_draws.py SALT [lab_records.py's options]")
    noise_floor.record_seed = salted_seed(argv[0])
    import lab_records

    lab_records.main(argv[1:])


if __name__ == "__main__":
    main()
