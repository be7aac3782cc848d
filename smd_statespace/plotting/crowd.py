"""The figure of a simulated crowd (:func:`smd_statespace.simulation.crowd.simulate_crowd`): a few people's GRFs,
the total crowd force and its amplitude spectrum."""

from __future__ import annotations

from matplotlib.figure import Figure

from ..simulation.crowd import N_HARMONICS, Crowd
from .save import save

__all__ = ["plot_crowd"]


def plot_crowd(crowd: Crowd, path=None, n_people=3, window=4.0) -> Figure:
    """A few individual GRFs, the total crowd force, and the total's amplitude spectrum.

    Parameters
    ----------
    crowd : Crowd
    path : str or path-like, optional
        PNG to write.
    n_people : int
        Individual GRFs drawn (the first ``n_people``), in body weights.
    window : float
        Seconds shown of the individual GRFs (from the start).

    Returns
    -------
    matplotlib.figure.Figure
    """
    s = crowd.settings
    time = crowd.time
    fig = Figure(figsize=(8.0, 7.2))
    ax_people, ax_total, ax_spec = fig.subplots(3, 1)
    shown = time <= window
    for i in range(min(n_people, s["n"])):
        person = crowd.people.iloc[i]
        column = crowd.forces.columns[1 + i]
        ax_people.plot(time[shown], crowd.forces[column].to_numpy()[shown] / person["weight"], lw=1.0,
                       label=f"person {i}: {person['mass']:.0f} kg, $f_h$ {person['f_h']:.2f} Hz, "
                             f"$\\xi_h$ {person['xi_h']:.2f}")
    ax_people.set_ylabel("GRF / body weight")
    ax_people.set_xlabel("time (s)")
    ax_people.set_title(f"Individual GRFs (first {window:g} s)", fontsize=10)
    low, high = ax_people.get_ylim()
    ax_people.set_ylim(low, high + 0.45 * (high - low))  # room for the legend above the curves
    ax_people.legend(fontsize=7, loc="upper center", ncol=min(n_people, 3))

    ax_total.plot(time, crowd.total / 1000.0, lw=0.6, color="tab:red")
    ax_total.axhline(crowd.weight / 1000.0, color="0.4", lw=0.8, ls="--", label="total weight")
    ax_total.set_ylabel("total force (kN)")
    ax_total.set_xlabel("time (s)")
    ax_total.set_title(f"Total crowd force: {s['n']} people at $f_b$ = {s['f_b']:g} Hz", fontsize=10)
    ax_total.legend(fontsize=8, loc="upper right")

    frequency, amplitude = crowd.spectrum()
    upper = min(s["fs"] / 2.0, 5.0 * s["f_b"])
    keep = frequency <= upper
    ax_spec.plot(frequency[keep], amplitude[keep] / 1000.0, lw=0.8, color="tab:red")
    for k in range(1, N_HARMONICS + 1):
        ax_spec.axvline(k * s["f_b"], color="0.6", lw=0.6, ls=":")
    ax_spec.set_xlabel("frequency (Hz)")
    ax_spec.set_ylabel("amplitude (kN)")
    ax_spec.set_title("Spectrum of the total dynamic force (dotted: $k f_b$)", fontsize=10)
    fig.tight_layout()
    return save(fig, path, 90)
