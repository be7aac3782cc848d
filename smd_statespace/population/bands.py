"""Frequency bands of the bouncing frequency: the article's (Section 5) or your own."""

from __future__ import annotations


import numpy as np

from .. import article
from ..errors import OptionError

__all__ = ["Bands"]


class Bands:
    """Bouncing-frequency bands: validated, ordered, non-overlapping ``(low, high)`` intervals (Hz).

    A frequency ``f_b`` belongs to band ``i`` when ``low_i <= f_b < high_i``; a band's upper edge
    belongs to it when no band starts there (so the last of contiguous bands includes its upper
    edge). For the article's bands this is exactly :func:`smd_statespace.article.band_of`.

    Parameters
    ----------
    intervals : sequence of (float, float)
        Band edges in Hz, increasing, ``0 < low < high``, not overlapping (gaps are allowed).

    Raises
    ------
    OptionError
        Non-numeric, non-finite, non-positive, empty, reversed or overlapping bands.
    """

    def __init__(self, intervals, *, option: str = "bands"):
        try:
            array = np.asarray(intervals, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(
                f"{option}: bands must be (low, high) pairs of numbers in Hz, got {intervals!r}") from None
        if array.ndim != 2 or array.shape[1] != 2 or array.shape[0] < 1:
            raise OptionError(f"{option}: bands must be one or more (low, high) pairs in Hz, got {intervals!r}")
        if not np.all(np.isfinite(array)) or np.any(array <= 0):
            raise OptionError(f"{option}: band edges must be finite positive frequencies in Hz, got {array.tolist()}")
        if np.any(array[:, 1] <= array[:, 0]):
            bad = array[np.argmax(array[:, 1] <= array[:, 0])]
            raise OptionError(f"{option}: band {bad[0]:g}-{bad[1]:g} Hz is empty or reversed (need low < high)")
        if np.any(array[1:, 0] < array[:-1, 1]):
            i = int(np.argmax(array[1:, 0] < array[:-1, 1]))
            raise OptionError(f"{option}: bands {array[i, 0]:g}-{array[i, 1]:g} and {array[i + 1, 0]:g}-"
                              f"{array[i + 1, 1]:g} Hz overlap or are out of order (give increasing bands)")
        self.intervals = tuple((float(low), float(high)) for low, high in array)

    @classmethod
    def article(cls) -> "Bands":
        """The six bands of Section 5, :data:`smd_statespace.article.BANDS` (1.35-3.75 Hz in 0.4 Hz steps)."""
        return cls(article.BANDS)

    @classmethod
    def from_edges(cls, edges, *, option: str = "bands") -> "Bands":
        """Contiguous bands from increasing edges, e.g. ``[1.35, 1.75, 2.15]`` -> 1.35-1.75, 1.75-2.15 Hz."""
        try:
            values = np.asarray(edges, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"{option}: band edges must be numbers in Hz, got {edges!r}") from None
        if values.ndim != 1 or values.size < 2:
            raise OptionError(f"{option}: give at least two band edges in Hz (e.g. 1.35,1.75,2.15), got {edges!r}")
        if not np.all(np.isfinite(values)) or np.any(values <= 0):
            raise OptionError(f"{option}: band edges must be finite positive frequencies in Hz, got {values.tolist()}")
        if np.any(np.diff(values) <= 0):
            raise OptionError(f"{option}: band edges must increase strictly, got {', '.join(f'{v:g}' for v in values)}")
        return cls(np.column_stack([values[:-1], values[1:]]), option=option)

    @classmethod
    def parse(cls, text: str, *, option: str = "--bands") -> "Bands":
        """Bands from text: ``"article"`` or comma-separated increasing edges in Hz (``"1.35,1.75,2.15"``)."""
        spec = str(text).strip()
        if spec.lower() == "article":
            return cls.article()
        parts = [part.strip() for part in spec.split(",")]
        try:
            edges = [float(part) for part in parts]
        except ValueError:
            raise OptionError(f"{option} {spec!r}: unknown band definition; give 'article' or comma-separated "
                              "increasing edges in Hz, e.g. 1.35,1.75,2.15,2.55") from None
        return cls.from_edges(edges, option=f"{option} {spec!r}")

    @classmethod
    def coerce(cls, bands, *, option: str = "bands") -> "Bands":
        """``None`` or ``"article"`` (the article's bands), a :class:`Bands`, text, edges or pairs."""
        if bands is None:
            return cls.article()
        if isinstance(bands, Bands):
            return bands
        if isinstance(bands, str):
            return cls.parse(bands, option=option)
        try:
            array = np.asarray(bands, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"{option}: unknown band definition {bands!r}; give 'article', increasing edges "
                              "in Hz or (low, high) pairs") from None
        return cls.from_edges(array, option=option) if array.ndim == 1 else cls(array, option=option)

    def __len__(self) -> int:
        return len(self.intervals)

    def __iter__(self):
        return iter(self.intervals)

    def __getitem__(self, index):
        return self.intervals[index]

    def __eq__(self, other) -> bool:
        return isinstance(other, Bands) and self.intervals == other.intervals

    def __hash__(self):
        return hash(self.intervals)

    def __repr__(self) -> str:
        return f"Bands({', '.join(self.labels)} Hz)"

    @property
    def is_article(self) -> bool:
        """True when these are the article's six bands (Table 2 can then be compared)."""
        return self.intervals == tuple(article.BANDS)

    @property
    def labels(self) -> list[str]:
        """``"1.35-1.75"`` etc. (Hz)."""
        return [f"{low:g}-{high:g}" for low, high in self.intervals]

    @property
    def centres(self) -> np.ndarray:
        """Band mid-frequencies (Hz)."""
        return np.array([0.5 * (low + high) for low, high in self.intervals])

    def assign(self, f_b) -> np.ndarray:
        """Band index of each bouncing frequency ``f_b`` (Hz), ``-1`` outside every band or not finite.

        Vectorised; agrees with :func:`smd_statespace.article.band_of` for the article's bands.
        """
        f = np.asarray(f_b, dtype=float)
        array = np.asarray(self.intervals)
        low, high = array[:, 0], array[:, 1]
        # The upper edge belongs to a band unless the next band starts there.
        closed = np.ones(len(array), dtype=bool)
        closed[:-1] = low[1:] != high[:-1]
        inside = (f[..., None] >= low) & ((f[..., None] < high) | (closed & (f[..., None] == high)))
        return np.where(inside.any(axis=-1), inside.argmax(axis=-1), -1)


# ---------------------------------------------------------------------------
# reading results.csv
