"""Writing a figure: every plotting function takes ``path=None`` and returns its :class:`~matplotlib.figure.Figure`."""

from __future__ import annotations

__all__ = ["save"]


def save(fig, path, dpi: int = 100):
    """Write ``fig`` as an image at ``path`` (PNG unless the suffix says otherwise) when ``path`` is given, at
    ``dpi`` dots per inch; return ``fig`` either way."""
    if path is not None:
        fig.savefig(path, dpi=dpi)
    return fig
