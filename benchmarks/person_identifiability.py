"""Where the record determines f_h: errors, flags and interval coverage against f_h / f_b.

Reads the per-record CSV of ``benchmarks/person_accuracy.py`` (``--csv``; best
with ``--people wide``, whose people sit at ``f_h / f_b`` 1.05-1.6, the hard
cases near ``f_b`` and near ``1.5 f_b`` included) and asks, per generator of
force variation and per band of ``f_h / f_b``:

- how large the ``f_h`` errors are, and how often the result says that ``f_h``
  is *not determined* (``f_h_determined`` false) or an artefact of the fit;
- whether the flags are where the errors are: the median error of the
  determined and of the undetermined estimates;
- whether the 90 % intervals cover, over all records and over the determined
  ones, and how wide they are (median width over ``f_h``).

It writes a markdown table (stdout, or ``--out``) and a figure (``--figure``):
``|f_h error|`` against the true ``f_h / f_b``, one panel per generator,
determined estimates filled, undetermined ones open, misses of the interval
marked::

    python benchmarks/person_accuracy.py --people wide --records 40 --no-timing-experiment --jobs 2 \\
        --out /tmp/wide.md --csv wide.csv
    python benchmarks/person_identifiability.py wide.csv --figure docs/figures/person_identifiability.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

BANDS = (1.0, 1.15, 1.3, 1.4, 1.6, 2.5)
"""Edges of the ``f_h / f_b`` bands (the middle ones bracket 1.5, between the first two harmonics)."""


def read(path: Path) -> pd.DataFrame:
    """The accuracy CSV's fitted records (``timing`` "model" when present), with the derived columns."""
    frame = pd.read_csv(path, keep_default_na=False, na_values=[""])
    frame["error"] = frame["error"].astype(object).fillna("")
    if "timing" in frame:
        frame = frame[frame["timing"] == "model"]
    frame = frame[frame["error"] == ""].copy()
    for column in ("f_h_determined", "f_h_artefact", "f_h_covered"):
        frame[column] = frame[column].astype(str).str.lower().eq("true")
    frame["ratio"] = frame["f_h"] / frame["f_b"]
    frame["abs_error_pct"] = (100.0 * (frame["f_h_est"] / frame["f_h"] - 1.0)).abs()
    frame["width_pct"] = 100.0 * (frame["f_h_high"] - frame["f_h_low"]) / frame["f_h"]
    frame["band"] = pd.cut(frame["ratio"], BANDS, right=False)
    return frame


def _cell(rows: pd.DataFrame) -> dict:
    determined = rows[rows["f_h_determined"]]
    undetermined = rows[~rows["f_h_determined"]]

    def median(values):
        return f"{values.median():.1f} %" if len(values) else "-"

    return {
        "records": len(rows),
        "f_h error median / worst": f"{rows['abs_error_pct'].median():.1f} / {rows['abs_error_pct'].max():.1f} %",
        "not determined (artefact)": f"{len(undetermined)} ({int(rows['f_h_artefact'].sum())})",
        "error, determined / not": f"{median(determined['abs_error_pct'])} / {median(undetermined['abs_error_pct'])}",
        "coverage all / determined": (f"{100 * rows['f_h_covered'].mean():.0f} / "
                                      + (f"{100 * determined['f_h_covered'].mean():.0f} %" if len(determined)
                                         else "- %")),
        "interval width median, determined / not": (f"{median(determined['width_pct'])} / "
                                                    f"{median(undetermined['width_pct'])}"),
        "determined with error > 8 %": int((determined["abs_error_pct"] > 8.0).sum()),
    }


def table(frame: pd.DataFrame) -> list:
    """Markdown lines: one row per generator (all bands), then per generator and band."""
    rows = []
    for generator, part in frame.groupby("generator", sort=False):
        rows.append({"generator": generator, "f_h / f_b": "all", **_cell(part)})
        for band, cell in part.groupby("band", observed=True):
            rows.append({"generator": generator, "f_h / f_b": f"{band.left:g}-{band.right:g}", **_cell(cell)})
    columns = list(rows[0])
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(str(row[c]) for c in columns) + " |" for row in rows]
    return lines


def figure(frame: pd.DataFrame, path: Path):
    """``|f_h error|`` against ``f_h / f_b`` per generator: filled determined, open not, red ring a miss."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    generators = list(dict.fromkeys(frame["generator"]))
    fig, axes = plt.subplots(1, len(generators), figsize=(3.2 * len(generators), 3.4), sharey=True,
                             squeeze=False)
    top = max(float(frame["abs_error_pct"].max()) * 1.1, 10.0)
    for ax, generator in zip(axes[0], generators):
        part = frame[frame["generator"] == generator]
        for determined, style in ((True, dict(color="C0", label="determined")),
                                  (False, dict(facecolors="none", edgecolors="C1", label="not determined"))):
            rows = part[part["f_h_determined"] == determined]
            ax.scatter(rows["ratio"], rows["abs_error_pct"], s=22, **style)
        missed = part[~part["f_h_covered"]]
        ax.scatter(missed["ratio"], missed["abs_error_pct"], s=70, facecolors="none", edgecolors="red",
                   linewidths=1.0, label="interval misses")
        ax.axhline(8.0, color="0.6", lw=0.8, ls="--")
        ax.axvline(1.5, color="0.8", lw=0.8)
        ax.set_yscale("symlog", linthresh=10.0)
        ax.set_ylim(0, top)
        ticks = [t for t in (0, 3, 8, 20, 50, 100, 200) if t <= top]
        ax.set_yticks(ticks, [str(t) for t in ticks])
        ax.set_title(f"{generator} ({len(part)})", fontsize=9)
        ax.set_xlabel("true f_h / f_b")
    axes[0][0].set_ylabel("|f_h error| (%)")
    axes[0][0].legend(fontsize=7, loc="upper left")
    fig.suptitle("Where the record determines f_h (dashed: 8 %; grey line: f_h = 1.5 f_b)", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv", type=Path, nargs="+", help="per-record CSV(s) of person_accuracy.py --csv")
    parser.add_argument("--out", type=Path, default=None, help="write the table here (default: print it)")
    parser.add_argument("--figure", type=Path, default=None, help="write the figure here (PNG)")
    args = parser.parse_args(argv)
    frame = pd.concat([read(path) for path in args.csv], ignore_index=True)
    if frame.empty:
        raise SystemExit(f"{args.csv[0]}: no fitted records")
    lines = table(frame)
    text = "\n".join(lines) + "\n"
    if args.out:
        args.out.write_text(text, encoding="utf-8")
    else:
        print(text)
    if args.figure:
        figure(frame, args.figure)


if __name__ == "__main__":
    main()
