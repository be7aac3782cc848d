"""Figures of the human-structure interaction study (:mod:`smd_statespace.studies.hsi`), like the article's
Fig. 10-11.

- :func:`plot_floor`: the plate's mid-span acceleration and its spectrum, harmonics and plate modes marked;
- :func:`plot_parameters`: the person's identified parameters on the rigid floor and on the plate, against
  the person's own values, the estimator-free fits and Table 4.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .. import article
from ..simulation.floor import FloorModel
from ..studies.hsi import REPORTED, HSIStudy
from .save import save

__all__ = ["plot_floor", "plot_parameters"]

LABELS = {"f_h": r"$f_h$ (Hz)", "xi_h": r"$\xi_h$ (-)", "blf_1": r"BLF$_1$ (g)", "blf_2": r"BLF$_2$ (g)",
          "blf_3": r"BLF$_3$ (g)"}


def plot_floor(study: HSIStudy, path=None) -> Figure:
    """The mid-span floor acceleration of the main plate record (like the article's Fig. 10).

    Top: time history of the measured (noisy) floor acceleration. Bottom: its
    amplitude spectrum with the force harmonics ``k f_b`` and the plate modes
    of Table 3 marked, and the mode-1-only simulation for comparison.

    Parameters
    ----------
    study : HSIStudy
    path : str or path-like, optional
        PNG to write.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plate = FloorModel.table3()
    record = study.records[plate.name]
    f_b = study.settings["person"]["f_b"]
    fig = Figure(figsize=(8.0, 5.6))
    ax_time, ax_spec = fig.subplots(2, 1)
    ax_time.plot(record.time, record.floor_acc, lw=0.5, color="tab:blue")
    rms = float(np.sqrt(np.mean(record.floor_acc**2)))
    ax_time.set_title(f"Mid-span acceleration, one person bouncing at {f_b:g} Hz on the Table 3 plate "
                      f"(RMS {rms:.2f} m/s$^2$)", fontsize=10)
    ax_time.set_xlabel("time (s)")
    ax_time.set_ylabel("acceleration (m/s$^2$)")

    def spectrum(signal):
        amplitude = 2.0 * np.abs(np.fft.rfft(signal - signal.mean())) / signal.size
        return np.fft.rfftfreq(signal.size, record.dt), amplitude

    frequency, amplitude = spectrum(record.floor_acc)
    keep = frequency <= 20.0
    ax_spec.semilogy(frequency[keep], amplitude[keep], lw=0.8, color="tab:blue", label=plate.name)
    one = FloorModel.table3([1]).name
    if one in study.states:
        f1, a1 = spectrum(study.states[one]["z_ddot"].to_numpy())
        ax_spec.semilogy(f1[keep], a1[keep], lw=0.8, color="tab:orange", alpha=0.8, label=f"{one} (noise-free)")
    top = amplitude[keep].max()
    for k in range(1, 12):
        if k * f_b <= 20.0:
            ax_spec.axvline(k * f_b, color="0.5", lw=0.6, ls=":")
    for mode in article.TABLE3:
        ax_spec.axvline(mode.frequency, color="tab:red", lw=0.6, ls="--")
        ax_spec.text(mode.frequency, top * 2.0, f"{mode.mode}", color="tab:red", fontsize=7, ha="center")
    ax_spec.set_ylim(top * 1e-4, top * 5.0)
    ax_spec.set_xlabel("frequency (Hz)")
    ax_spec.set_ylabel("amplitude (m/s$^2$)")
    ax_spec.set_title("Spectrum (dotted: harmonics $k f_b$; dashed red: plate modes of Table 3)", fontsize=10)
    ax_spec.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return save(fig, path, 90)


def plot_parameters(study: HSIStudy, path=None) -> Figure:
    """Identified parameters on the rigid floor and on the plate (like the article's Fig. 11).

    One panel per parameter: per-cycle estimates of the library's
    identification as box plots (rigid floor; plate with the rigid-floor
    model; plate with the ``floor_mode`` effect), the simulated person's own
    value (dashed), the estimator-free fits (stars) and the article's Table 4
    (diamonds).

    Parameters
    ----------
    study : HSIStudy
    path : str or path-like, optional
        PNG to write.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plate = FloorModel.table3().name
    keys = ["rigid floor / rigid model", f"{plate} / rigid model", f"{plate} / floor_mode model"]
    ticks = ["rigid\nfloor", "plate", "plate +\nfloor_mode"]
    least = study.least_squares
    fig = Figure(figsize=(11.0, 3.6))
    axes = fig.subplots(1, len(REPORTED))
    for ax, name in zip(axes, REPORTED):
        if all(key in study.cycles for key in keys):
            data = [study.cycles[key].loc[study.cycles[key]["status"] == "ok", name].to_numpy() for key in keys]
            ax.boxplot(data, positions=[1, 2, 3], widths=0.55, showfliers=False, medianprops={"color": "tab:blue"})
        row = study.table.loc[name]
        ax.axhline(row["truth"], color="k", ls="--", lw=0.8, label="person's own value")
        ls_rigid = least[(least["condition"] == "rigid floor")][name].mean()
        ls_plate = least[(least["condition"] == plate) & (least["model"] == "rigid")][name].mean()
        ls_floor = least[(least["condition"] == plate) & (least["model"] == "floor_mode")][name].mean()
        ax.plot([1, 2, 3], [ls_rigid, ls_plate, ls_floor], "*", color="tab:green", ms=10,
                label="least squares, exact states")
        ax.plot([1, 2], [row["article_rigid"], row["article_plate"]], "D", color="tab:red", ms=6,
                label="article, Table 4")
        ax.set_xticks([1, 2, 3])
        ax.set_xticklabels(ticks, fontsize=7)
        ax.set_title(f"{LABELS[name]}\nEKF {row['ekf_change_%']:+.0f} %, LS {row['ls_change_%']:+.0f} %, "
                     f"article {row['article_change_%']:+.0f} %", fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(f"Same person (own parameters unchanged), same force, rigid floor vs plate; boxes: "
                 f"{study.settings['estimator']} per cycle with the rigid-floor model (and with floor_mode)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 0.97))
    return save(fig, path, 90)
