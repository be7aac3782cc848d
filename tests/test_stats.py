"""Population statistics (Section 5): bands, Eq. 19 skew-normal fits, trends, exclusions, the stats command."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import skewnorm

from smd_statespace import article
from smd_statespace.cli import main
from smd_statespace.errors import OptionError, RecordError
from smd_statespace.simulation import sample_population
from smd_statespace.population import (A_MAX, ADEQUATE_COLUMN, PARAMETERS, Bands, bootstrap_skewnorm, fit_skewnorm,
                                  fit_trend, parse_parameters, population_stats, read_results)

# sample_population redraws values outside physical bounds (truncation); these wide bounds switch that
# off so that the drawn people follow Table 2's skew-normals exactly and the round trip tests the statistics.
NO_TRUNCATION = {"f_h": (-50.0, 50.0), "xi_h": (-50.0, 50.0), "blf": (-50.0, 50.0)}
ROUND_TRIP = ("f_h", "xi_h", "BLF1", "BLF2", "BLF3")  # K_h, C_h are drawn by Eq. 17-18, not from Table 2


def results_frame(per_band, seed=0, points=4, bands=article.BANDS):
    """A results.csv-like table of ``per_band`` people per band drawn from Table 2, all ok, determined, plausible.

    ``implausible`` is False as ``identify`` would write it: the skew-normals of Table 2 have tails below
    ``xi_h = 0``, which the physical check of a table without that column would (rightly) leave out.
    """
    frames = []
    children = iter(np.random.SeedSequence(seed).spawn(points * len(bands)))
    for low, high in bands:
        for k in range(points):
            f_b = low + (k + 0.5) * (high - low) / points
            frames.append(sample_population(per_band // points, f_b, seed=np.random.default_rng(next(children)),
                                            bounds=NO_TRUNCATION))
    people = pd.concat(frames, ignore_index=True)
    n = len(people)
    return pd.DataFrame({
        "cycle": np.arange(n), "t_start": 0.5 * np.arange(n), "t_end": 0.5 * np.arange(1, n + 1),
        "f_b": people["f_b"], "f_h": people["f_h"], "f_h_sd": 0.01, "xi_h": people["xi_h"], "xi_h_sd": 0.01,
        "blf_1": people["blf1"], "blf_2": people["blf2"], "blf_3": people["blf3"], "blf_1_sd": 0.01,
        "blf_2_sd": 0.01, "blf_3_sd": 0.01, "a0": 0.0, "k_h": people["K_h"], "c_h": people["C_h"], "passes": 3,
        "converged": True, "log_likelihood": 0.0, "estimator": "ekf", "status": "ok", "reason": "",
        "f_h_determined": True, "xi_h_determined": True, "blf_1_determined": True, "blf_2_determined": True,
        "blf_3_determined": True, "implausible": False, "implausible_reason": "",
    })


def one_band_frame(n, f_b=1.95, seed=1):
    """``n`` ok, determined cycles in the band 1.75-2.15 Hz."""
    return results_frame(n, seed=seed, points=1, bands=[(f_b - 0.01, f_b + 0.01)]).assign(f_b=f_b)


# ---------------------------------------------------------------------------
# skew-normal fit (Eq. 19)


@pytest.mark.parametrize("m, s, a", [
    article.TABLE2["f_h"][0],      # f_h, 1.35-1.75 Hz: a = 3.5
    article.TABLE2["xi_h"][3],     # xi_h, 2.55-2.95 Hz: a = 7.2
    (6717.5, 2714.6, -2.43),       # K_h-like scale, negative skew
])
def test_skewnorm_fit_recovers_known_parameters(m, s, a):
    n = 4000
    x = skewnorm(a, loc=m, scale=s).rvs(size=n, random_state=np.random.default_rng(11))
    fit = fit_skewnorm(x)
    assert fit.converged and not fit.at_bound and fit.n == n
    # The observed-information standard errors match the spread of repeated fits for |a| >= 2.5
    # (test below), so the estimate lies within 4 of them; they shrink as 1/sqrt(n) and are small here.
    for name, true, se in zip("msa", (m, s, a), fit.se):
        assert abs(getattr(fit, name) - true) < 4 * se, name
    assert fit.se[0] < 0.05 * s and fit.se[1] < 0.05 * s and fit.se[2] < 0.2 * abs(a)
    # It is the maximum of the likelihood: at least as high as scipy's own optimiser reaches.
    reference = skewnorm.fit(x)
    assert fit.log_likelihood >= skewnorm.logpdf(x, *reference).sum() - 1e-6
    assert fit.log_likelihood == pytest.approx(skewnorm.logpdf(x, fit.a, fit.m, fit.s).sum(), rel=1e-12)


def test_standard_errors_match_the_spread_of_repeated_fits():
    m, s, a = article.TABLE2["f_h"][0]
    rng = np.random.default_rng(5)
    fits = [fit_skewnorm(skewnorm(a, loc=m, scale=s).rvs(size=1000, random_state=rng)) for _ in range(100)]
    spread = np.std([(f.m, f.s, f.a) for f in fits], axis=0)
    se = np.median([f.se for f in fits], axis=0)
    # 100 repetitions estimate a standard deviation to about 7 %: 25 % is over 3 of those.
    np.testing.assert_allclose(se, spread, rtol=0.25)


def test_skewnorm_fit_at_the_half_normal_limit_is_capped_and_flagged():
    x = np.abs(np.random.default_rng(1).normal(0.0, 0.3, size=200)) + 1.0  # half-normal: a = inf, m = 1, s = 0.3
    # For this sample the likelihood keeps rising with the shape (scipy, shape held fixed):
    profile = [skewnorm.logpdf(x, *skewnorm.fit(x, f0=a, loc=1.0, scale=0.3)).sum() for a in (25.0, 200.0)]
    assert profile[1] > profile[0]
    fit = fit_skewnorm(x)
    assert fit.at_bound and fit.a == A_MAX and fit.converged
    assert math.isnan(fit.se[2])
    assert abs(fit.m - 1.0) < 4 * fit.se[0] and abs(fit.s - 0.3) < 4 * fit.se[1]
    negative = fit_skewnorm(-x, a_max=20.0)
    assert negative.a == -20.0 and negative.at_bound and negative.converged
    assert negative.m == pytest.approx(-fit.m, abs=4 * fit.se[0])
    # A half-normal sample can also have a finite maximum below the cap; then it is not flagged.
    finite = fit_skewnorm(np.abs(np.random.default_rng(2).normal(0.0, 0.3, size=500)) + 1.0)
    assert not finite.at_bound and 20.0 < finite.a < A_MAX and finite.converged


def test_small_shape_moments_and_bootstrap_interval():
    m, s, a = article.TABLE2["BLF2"][0]  # a = 0.75: near a = 0 the shape is weakly determined
    dist = skewnorm(a, loc=m, scale=s)
    x = dist.rvs(size=2000, random_state=np.random.default_rng(3))
    fit = bootstrap_skewnorm(x, fit_skewnorm(x), 200, rng=np.random.default_rng(4))
    # The moments are well determined whatever the shape: within 4 standard errors of the sample mean and sd.
    assert abs(fit.mean - dist.mean()) < 4 * dist.std() / math.sqrt(x.size)
    assert abs(fit.sd - dist.std()) < 4 * dist.std() / math.sqrt(2 * x.size)
    for name, true in zip("msa", (m, s, a)):
        low, high = fit.ci[name]
        assert low < getattr(fit, name) < high and low < true < high, name
    assert fit.n_bootstrap == 200


def test_bootstrap_interval_width_and_seed():
    m, s, a = article.TABLE2["f_h"][1]
    x = skewnorm(a, loc=m, scale=s).rvs(size=1500, random_state=np.random.default_rng(8))
    fit = fit_skewnorm(x)
    one = bootstrap_skewnorm(x, fit, 300, rng=np.random.SeedSequence(1))
    two = bootstrap_skewnorm(x, fit, 300, rng=np.random.SeedSequence(1))
    other = bootstrap_skewnorm(x, fit, 300, rng=np.random.SeedSequence(2))
    assert one.ci == two.ci and one.ci != other.ci
    assert (one.m, one.s, one.a) == (fit.m, fit.s, fit.a)
    # For a well-determined shape the percentile interval is about +-1.96 standard errors wide.
    for k, name in enumerate("msa"):
        width = one.ci[name][1] - one.ci[name][0]
        assert 0.7 < width / (2 * 1.96 * fit.se[k]) < 1.4, name


def test_fit_needs_spread():
    with pytest.raises(OptionError, match="all 5 values are equal"):
        fit_skewnorm(np.ones(5))
    with pytest.raises(OptionError, match="at least 3"):
        fit_skewnorm([1.0, np.nan, 2.0])


# ---------------------------------------------------------------------------
# bands


def test_article_bands_at_their_edges_agree_with_band_of():
    bands = Bands.article()
    assert bands.is_article and len(bands) == 6
    edges = np.array([edge for band in article.BANDS for edge in band])
    probes = np.concatenate([edges, np.nextafter(edges, 0), np.nextafter(edges, 10), [np.nan, np.inf, 0.0, 5.0],
                             np.random.default_rng(0).uniform(1.0, 4.0, 500)])
    expected = [article.band_of(f) for f in probes]
    np.testing.assert_array_equal(bands.assign(probes), [-1 if e is None else e for e in expected])
    # low <= f_b < high; the last band keeps its upper edge
    np.testing.assert_array_equal(bands.assign([1.35, 1.75, 2.15, 3.35, 3.75, np.nextafter(1.35, 0)]),
                                  [0, 1, 2, 5, 5, -1])


def test_user_bands_edges_gaps_and_validation():
    contiguous = Bands.parse("1,2,3")
    np.testing.assert_array_equal(contiguous.assign([0.99, 1.0, 1.99, 2.0, 3.0, 3.01]), [-1, 0, 0, 1, 1, -1])
    gapped = Bands([(1.0, 2.0), (3.0, 4.0)])
    np.testing.assert_array_equal(gapped.assign([2.0, 2.5, 3.0, 4.0]), [0, -1, 1, 1])
    assert Bands.parse("article") == Bands.article() and Bands.coerce(None) == Bands.article()
    assert not contiguous.is_article and contiguous.labels == ["1-2", "2-3"]
    for text, message in (("foo", "unknown band definition"), ("2,1.5", "increase strictly"),
                          ("2", "at least two"), ("1,,2", "unknown band definition"), ("-1,2", "positive"),
                          ("1,nan", "finite")):
        with pytest.raises(OptionError, match=message):
            Bands.parse(text)
    with pytest.raises(OptionError, match="overlap"):
        Bands([(1.0, 2.5), (2.0, 3.0)])
    with pytest.raises(OptionError, match="reversed"):
        Bands([(2.0, 1.0)])


# ---------------------------------------------------------------------------
# trends


def test_linear_trend_recovered():
    rng = np.random.default_rng(21)
    f_b = rng.uniform(1.4, 3.7, 600)
    y = 0.2 + 1.3 * f_b + rng.normal(0.0, 0.1, f_b.size)
    trend = fit_trend(f_b, y, 1, parameter="f_h")
    np.testing.assert_allclose(trend.params, np.polyfit(f_b, y, 1)[::-1], rtol=1e-10)  # it is least squares
    for k, true in enumerate((0.2, 1.3)):
        assert trend.conf_int[k, 0] < true < trend.conf_int[k, 1]
        assert abs(trend.params[k] - true) < 4 * trend.bse[k]
    assert trend.bse[1] < 0.02 and trend.pvalues[1] < 1e-100
    assert trend.vertex is None and trend.rsquared > 0.9
    mean, low, high = trend.predict([2.0])
    assert low[0] < mean[0] < high[0] and mean[0] == pytest.approx(0.2 + 1.3 * 2.0, abs=0.02)


@pytest.mark.parametrize("curvature, kind", [(0.05, "minimum"), (-0.04, "maximum")])
def test_quadratic_trend_vertex_recovered(curvature, kind):
    rng = np.random.default_rng(22)
    f_b = rng.uniform(1.4, 3.7, 800)
    y = 0.3 + curvature * (f_b - 2.7) ** 2 + rng.normal(0.0, 0.01, f_b.size)
    trend = fit_trend(f_b, y, 2, parameter="xi_h", n_bootstrap=400, rng=np.random.default_rng(1))
    np.testing.assert_allclose(trend.params, [0.3 + curvature * 2.7 ** 2, -2 * 2.7 * curvature, curvature],
                               atol=5 * trend.bse.max())
    assert trend.vertex_kind == kind
    assert abs(trend.vertex - 2.7) < 4 * trend.vertex_se and trend.vertex_se < 0.02
    for low, high in (trend.vertex_ci_delta, trend.vertex_ci_bootstrap):
        assert low < 2.7 < high
    # with this much curvature the ratio is nearly normal: both intervals about as wide
    delta = np.diff(trend.vertex_ci_delta)[0]
    assert 0.7 < np.diff(trend.vertex_ci_bootstrap)[0] / delta < 1.4
    frame = trend.to_frame()
    assert list(frame["term"][:3]) == ["const", "f_b", "f_b^2"]
    assert frame["method"].str.contains("delta method").any() and frame["method"].str.contains("bootstrap").any()


def test_trend_needs_enough_cycles():
    with pytest.raises(OptionError, match="too few cycles"):
        fit_trend([2.0, 2.0, 2.0, 2.0, 2.0], [1, 2, 3, 4, 5], 1)


# ---------------------------------------------------------------------------
# which cycles count


def test_undetermined_cycles_are_left_out_and_counted():
    frame = one_band_frame(40)
    frame.loc[0:6, "f_h_determined"] = False  # 7 cycles
    frame.loc[5:9, "xi_h_determined"] = False  # 5 cycles, two of them shared
    frame.loc[0:6, "f_h"] = 50.0  # undetermined values far off, so using them would show
    extra = pd.DataFrame({"f_b": [1.95, 1.95, 1.95, 5.0], "status": ["failed", "failed", "skipped", "ok"]})
    extra = extra.assign(**{c: frame[c].iloc[-1] for c in frame.columns if c not in extra})
    frame = pd.concat([frame, extra], ignore_index=True)
    stats = population_stats(frame, n_bootstrap=0)
    cells = {p: stats.cells[p, 1] for p in stats.parameters}
    assert (cells["f_h"].n, cells["f_h"].excluded) == (33, 7)
    assert (cells["K_h"].n, cells["K_h"].excluded) == (33, 7)  # K_h follows f_h (Eq. 17)
    assert (cells["xi_h"].n, cells["xi_h"].excluded) == (35, 5)
    assert (cells["C_h"].n, cells["C_h"].excluded) == (30, 10)  # C_h needs both (Eq. 18)
    assert (cells["BLF1"].n, cells["BLF1"].excluded) == (40, 0)
    ok = frame[(frame["status"] == "ok") & (frame["f_b"] < 3.75)]
    assert cells["f_h"].mean == pytest.approx(ok.loc[ok["f_h_determined"], "f_h"].mean(), rel=1e-12)
    assert stats.counts["by_status"] == {"ok": 41, "failed": 2, "skipped": 1}
    assert stats.counts["outside_bands"] == 1 and stats.counts["in_bands"] == 40
    text = stats.summary()
    assert "f_h: 33 cycles used, 7 undetermined left out" in text
    assert "C_h: 30 cycles used, 10 undetermined left out" in text
    assert "2 failed, 1 skipped left out" in text and "1 ok cycles outside the bands" in text
    assert stats.exclusions().loc["C_h", "excluded"] == 10

    kept = population_stats(frame, n_bootstrap=0, include_undetermined=True)
    assert (kept.cells["f_h", 1].n, kept.cells["f_h", 1].excluded, kept.cells["f_h", 1].undetermined) == (40, 0, 7)
    assert kept.cells["f_h", 1].mean > cells["f_h"].mean + 5.0
    assert "f_h: 40 cycles used, 7 of them undetermined (included)" in kept.summary()


def test_too_few_cycles_band_is_reported_not_fitted():
    frame = pd.concat([one_band_frame(40), one_band_frame(4, f_b=2.35, seed=2)], ignore_index=True)
    stats = population_stats(frame, n_bootstrap=20)
    thin = stats.cells["f_h", 2]
    assert thin.n == 4 and thin.fit is None and thin.note == "too few cycles: 4 < 10"
    assert stats.cells["f_h", 1].fit is not None and stats.cells["f_h", 0].note == "too few cycles: 0 < 10"
    table = stats.table2()
    assert table.loc["f_h (Hz)", "2.15-2.55"] == "too few cycles: 4 < 10"
    assert table.loc["f_h (Hz)", "1.75-2.15"].count(",") == 2  # "m, s, a"
    frame2 = stats.to_frame()
    assert math.isnan(frame2.loc[("f_h", 2), "m"]) and frame2.loc[("f_h", 2), "note"] == "too few cycles: 4 < 10"
    assert frame2.loc[("f_h", 2), "mean"] == pytest.approx(frame[frame["f_b"] == 2.35]["f_h"].mean())
    assert math.isnan(stats.compare_table2().loc[("f_h", 2), "ks"])
    assert population_stats(frame, n_bootstrap=0, min_cycles=4).cells["f_h", 2].fit is not None


def test_same_seed_same_statistics_and_user_bands():
    frame = results_frame(60, seed=4)
    options = dict(n_bootstrap=20, parameters=("f_h", "BLF1"))
    one = population_stats(frame, seed=7, **options).to_frame()
    two = population_stats(frame, seed=7, **options).to_frame()
    other = population_stats(frame, seed=8, **options).to_frame()
    assert list(one.index.get_level_values("parameter").unique()) == ["f_h", "BLF1"]
    pd.testing.assert_frame_equal(one, two)
    np.testing.assert_array_equal(one["m"], other["m"])  # point fits do not depend on the seed
    assert not np.array_equal(one["m_low"], other["m_low"])
    alone = population_stats(frame, seed=7, n_bootstrap=20, parameters=("BLF1",)).to_frame()
    pd.testing.assert_frame_equal(alone, one.loc[["BLF1"]])  # a cell's intervals do not depend on the others
    wide = population_stats(frame, bands="1.35,2.55,3.75", n_bootstrap=0, parameters=("f_h",))
    assert [wide.cells["f_h", b].n for b in range(2)] == [180, 180]
    with pytest.raises(OptionError, match="article's bands"):
        wide.compare_table2()


def test_reader_checks_and_tags_sources(tmp_path):
    frame = one_band_frame(12)
    path = tmp_path / "a.csv"
    frame.to_csv(path, index=False)
    table = read_results([path, frame])
    assert list(table["source"].unique()) == [str(path), "<DataFrame 1>"] and len(table) == 24
    assert table["f_h_determined"].dtype == bool
    assert table.attrs["parameters"] == tuple(PARAMETERS) and table.attrs["notes"] == []
    frame.drop(columns=["f_b"]).to_csv(tmp_path / "b.csv", index=False)
    with pytest.raises(RecordError, match=r"b\.csv: no column 'f_b' \(the bouncing frequency"):
        read_results(tmp_path / "b.csv")
    # Not asked for: a missing parameter is left out with a note; asked for: an error naming file and column.
    frame.drop(columns=["xi_h", "blf_2"]).to_csv(tmp_path / "c.csv", index=False)
    partial = read_results(tmp_path / "c.csv")
    assert partial.attrs["parameters"] == ("f_h", "K_h", "C_h", "BLF1", "BLF3")
    assert f"BLF2 left out: no column 'blf_2' for BLF2 in {tmp_path / 'c.csv'}" in partial.attrs["notes"]
    with pytest.raises(RecordError, match=r"c\.csv: no column 'xi_h' for xi_h, asked for by --parameters"):
        read_results(tmp_path / "c.csv", parameters="f_h,xi_h")
    with pytest.raises(OptionError, match=r"--parameters: unknown parameter 'zeta'; valid: f_h, xi_h, K_h"):
        read_results(frame, parameters=["f_h", "zeta"])
    assert parse_parameters("blf_1, F_H,k_h") == ("BLF1", "f_h", "K_h")


def test_histogram_and_trend_figures_show_what_was_fitted(tmp_path):
    frame = pd.concat([one_band_frame(60), one_band_frame(4, f_b=2.35, seed=2)], ignore_index=True)
    stats = population_stats(frame, n_bootstrap=0)
    fig = stats.plot_histograms("f_h", tmp_path / "h.png")
    fitted = [ax for ax in fig.axes if any(line.get_label() == "fit (Eq. 19)" for line in ax.get_lines())]
    published = [ax for ax in fig.axes if any(line.get_label() == "Table 2 (article)" for line in ax.get_lines())]
    assert len(fitted) == 1 and len(published) == 6  # one band fitted, Table 2 drawn in all six
    assert (tmp_path / "h.png").stat().st_size > 10_000
    own = population_stats(frame, bands="1.5,2,2.5", n_bootstrap=0)
    fig = own.plot_histograms("f_h")
    assert not any(line.get_label() == "Table 2 (article)" for ax in fig.axes for line in ax.get_lines())
    fig = stats.plot_trends()
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 8  # seven parameters and the counts


# ---------------------------------------------------------------------------
# the command


def test_stats_command_recovers_table2(tmp_path, capsys):
    per_band = 1200
    results = results_frame(per_band, seed=2019)
    failed = results.iloc[:30].assign(status="failed", f_h=np.nan, reason="filter diverged")
    first, second = tmp_path / "r1.csv", tmp_path / "r2.csv"
    results.iloc[: len(results) // 2].to_csv(first, index=False)
    pd.concat([results.iloc[len(results) // 2:], failed]).to_csv(second, index=False)
    out = tmp_path / "out"
    assert main(["stats", str(first), str(second), "--out", str(out), "--bootstrap", "40", "--seed", "3"]) == 0
    printed = capsys.readouterr().out
    assert "7230 cycles read from 2 file(s): 7200 ok, 30 failed left out" in printed
    assert "Skew-normal fits (Eq. 19)" in printed and "1.35-1.75" in printed and "vertex (minimum)" in printed
    for name in ("bands.csv", "table2.csv", "table2_vs_article.csv", "trends.csv", "trends.png", "hist_f_h.png",
                 "hist_blf_3.png"):
        assert (out / name).stat().st_size > 0, name
    comparison = pd.read_csv(out / "table2_vs_article.csv", index_col=[0, 1])
    recovered = comparison.loc[list(ROUND_TRIP)]
    assert (recovered["n"] == per_band).all()
    # The fitted distribution functions lie within 1.95 / sqrt(n) of Table 2's everywhere (the 0.1 %
    # critical value of the Kolmogorov-Smirnov distance of an empirical one; a 3-parameter fit is closer).
    assert recovered["ks"].max() < 1.95 / math.sqrt(per_band)
    mean_error = abs(recovered["mean"] - recovered["mean_article"])
    assert (mean_error < 4 * recovered["sd_article"] / math.sqrt(per_band)).all()
    table = pd.read_csv(out / "table2.csv", index_col=[0, 1])
    assert (table["m_low"] < table["m"]).all() and (table["m"] < table["m_high"]).all()
    trends = pd.read_csv(out / "trends.csv")
    f_h_slope = trends[(trends["parameter"] == "f_h") & (trends["term"] == "f_b")].iloc[0]
    assert f_h_slope["ci_low"] > 0 and f_h_slope["p_value"] < 1e-10  # f_h rises with f_b (Table 2)


def error_line(capsys):
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("smd-statespace: error: ")
    return lines[0]


@pytest.mark.parametrize("make, extra, fragments", [
    (lambda f, p: f.drop(columns=["f_b"]).to_csv(p, index=False), [], ["bad.csv", "no column 'f_b'", "columns are"]),
    (lambda f, p: f.drop(columns=["xi_h", "blf_2"]).to_csv(p, index=False), ["--parameters", "f_h,BLF2"],
     ["bad.csv", "no column 'blf_2' for BLF2", "--parameters"]),
    (lambda f, p: f.to_csv(p, index=False), ["--parameters", "f_h,stiffness"],
     ["--parameters", "unknown parameter 'stiffness'", "valid: f_h, xi_h, K_h, C_h, BLF1, BLF2, BLF3"]),
    (lambda f, p: f[["f_b", "f_h", "xi_h"]].to_csv(p, index=False), ["--parameters", "K_h"],
     ["bad.csv", "no column 'k_h' for K_h", "'mass' column", "--mass KG"]),
    (lambda f, p: f.drop(columns=["blf_1", "blf_2", "blf_3", "f_h", "xi_h", "k_h", "c_h"]).to_csv(p, index=False), [],
     ["bad.csv", "none of the parameter columns"]),
    (lambda f, p: f[["f_b", "f_h", "xi_h"]].assign(mass=np.where(f.index == 2, -60.0, 60.0)).to_csv(p, index=False),
     [], ["bad.csv", "column 'mass', data row 3", "positive number of kg"]),
    (lambda f, p: f.assign(implausible="maybe").to_csv(p, index=False), [],
     ["bad.csv", "column 'implausible', data row 1", "not True or False"]),
    (lambda f, p: f.assign(implausible=True).to_csv(p, index=False), [],
     ["bad.csv", "all 12 ok cycles are implausible", "--include-implausible"]),
    (lambda f, p: f.to_csv(p, index=False), ["--mass", "-3"], ["--mass", "positive number"]),
    (lambda f, p: p.write_text(""), [], ["bad.csv", "empty file"]),
    (lambda f, p: p.write_text(",".join(f.columns) + "\n"), [], ["bad.csv", "no rows"]),
    (lambda f, p: f.assign(status="failed").to_csv(p, index=False), [], ["bad.csv", "no 'ok' cycles", "12 failed"]),
    (lambda f, p: f.assign(f_b=5.0).to_csv(p, index=False), [], ["none of the 12 ok cycles", "--bands"]),
    (lambda f, p: f.assign(f_h=f["f_h"].astype(object).where(f.index != 3, "abc")).to_csv(p, index=False), [],
     ["bad.csv", "'f_h'", "data row 4", "not a number"]),
    (lambda f, p: f.to_csv(p, index=False), ["--bands", "fast"], ["--bands 'fast'", "unknown band definition"]),
    (lambda f, p: f.to_csv(p, index=False), ["--bands", "2.5,2"], ["--bands '2.5,2'", "increase strictly"]),
    (lambda f, p: f.to_csv(p, index=False), ["--min-cycles", "2"], ["--min-cycles", ">= 3"]),
    (lambda f, p: f.to_csv(p, index=False), ["--bootstrap", "x"], ["--bootstrap", "'x'"]),
    (lambda f, p: None, [], ["bad.csv", "cannot read"]),
])
def test_stats_bad_input_is_one_line_exit_2(tmp_path, capsys, make, extra, fragments):
    path = tmp_path / "bad.csv"
    make(one_band_frame(12), path)
    assert main(["stats", str(path), "--out", str(tmp_path / "out"), *extra]) == 2
    line = error_line(capsys)
    for fragment in fragments:
        assert fragment in line, (fragment, line)


# ---------------------------------------------------------------------------
# any table of cycles; impossible cycles protect nothing


def plain_frame(n=40, seed=3, f_b=(1.6, 2.0, 2.4, 2.8)):
    """A plain table of identified cycles as another tool writes it: f_b, f_h, xi_h, blf_1..3 only."""
    rng = np.random.default_rng(seed)
    f = np.repeat(f_b, n // len(f_b))
    return pd.DataFrame({"f_b": f, "f_h": 0.8 * f + 0.7 + rng.normal(0, 0.15, f.size),
                         "xi_h": rng.uniform(0.15, 0.5, f.size), "blf_1": rng.uniform(0.1, 0.4, f.size),
                         "blf_2": rng.uniform(0.05, 0.3, f.size), "blf_3": rng.uniform(0.0, 0.1, f.size)})


def test_plain_table_reads_with_notes_and_mass(tmp_path, capsys):
    frame = plain_frame()
    stats = population_stats(frame, n_bootstrap=0, bands="1.5,2.6,3")
    assert stats.parameters == ("f_h", "xi_h", "BLF1", "BLF2", "BLF3")
    text = stats.summary()
    assert text.count("treated as determined") == 1 and text.count("every row taken as an identified cycle") == 1
    assert "K_h left out: no column 'k_h' for K_h and no body mass" in text and "C_h left out" in text
    assert stats.cells["f_h", 0].n == 30 and stats.counts["implausible"] == 0
    assert stats.cells["f_h", 0].mean == pytest.approx(frame.f_h[frame.f_b < 2.6].mean(), rel=1e-12)

    # A body mass gives K_h and C_h by Eq. 17-18: from an option, or per row from a mass column.
    with_mass = population_stats(frame, n_bootstrap=0, bands="1.5,2.6,3", mass=70.0, parameters="K_h,C_h")
    expected = 70.0 * (2 * np.pi * frame.f_h[frame.f_b < 2.6]) ** 2
    assert with_mass.cells["K_h", 0].mean == pytest.approx(expected.mean(), rel=1e-12)
    masses = np.where(frame.index % 2 == 0, 60.0, 80.0)
    own = population_stats(frame.assign(mass=masses), n_bootstrap=0, bands="1.5,2.6,3", parameters=["C_h"])
    c_h = 2 * frame.xi_h * masses * 2 * np.pi * frame.f_h
    assert own.cells["C_h", 1].mean == pytest.approx(c_h[frame.f_b > 2.6].mean(), rel=1e-12)
    assert "computed by Eq. 17-18 from f_h, xi_h and its 'mass' column" in own.summary()

    path = tmp_path / "plain.csv"
    frame.to_csv(path, index=False)
    assert main(["stats", str(path), "--out", str(tmp_path / "out"), "--bootstrap", "0", "--bands", "1.5,2.6,3",
                 "--mass", "70"]) == 0
    printed = capsys.readouterr().out
    assert "K_h, C_h computed by Eq. 17-18 from f_h, xi_h and --mass 70 kg" in printed
    assert (tmp_path / "out" / "hist_k_h.png").stat().st_size > 0


def test_implausible_and_inadequate_cycles_are_left_out_and_counted():
    frame = plain_frame(seed=5)
    frame.loc[0:2, "xi_h"] = -0.05                       # negative damping (found by the physical check)
    frame.loc[3, "blf_1"] = 2.5                          # an internal force of 2.5 body weights
    frame.loc[4, ["f_h", "xi_h"]] = (2 * 1.6, 0.01)      # 2nd harmonic at resonance: floor force 0.3 / 0.02 g
    stats = population_stats(frame, n_bootstrap=0, bands="1.5,2.6,3")
    assert stats.counts["implausible"] == 5 and stats.counts["usable"] == 35
    assert stats.counts["implausible_reasons"] == {"xi_h < 0": 3, "BLF_1 > 2 g": 1, "GRF harmonic 2 > 2 g": 1}
    clean = frame.drop(index=range(5))
    assert stats.cells["xi_h", 0].mean == pytest.approx(clean.xi_h[clean.f_b < 2.6].mean(), rel=1e-12)
    assert (stats.cycles.loc[0:4, "band"] == -1).all()
    text = stats.summary()
    assert "of the ok cycles 5 implausible left out" in text
    assert "warning: 5 ok cycles have estimates that cannot be true (xi_h < 0: 3," in text
    kept = population_stats(frame, n_bootstrap=0, bands="1.5,2.6,3", include_implausible=True)
    assert kept.cells["xi_h", 0].n == 30 and kept.counts["implausible"] == 5 and "5 implausible kept" in kept.summary()
    # as identify writes them: implausible cycles have their *_determined flags cleared; kept still means used
    flags = ["f_h_determined", "xi_h_determined", "blf_1_determined", "blf_2_determined", "blf_3_determined"]
    written = frame.assign(implausible=False, implausible_reason="", **dict.fromkeys(flags, True))
    written.loc[0:4, ["implausible", "implausible_reason"]] = (True, "xi_h < 0")
    written.loc[0:4, flags] = False
    again = population_stats(written, n_bootstrap=0, bands="1.5,2.6,3", include_implausible=True)
    assert again.cycles.loc[0:4, "used_xi_h"].all() and again.cycles["used_xi_h"].sum() == kept.cycles["used_xi_h"].sum()

    # identify's own flag is trusted (here it marks a cycle the physical check alone would keep) ...
    flagged = plain_frame(seed=5).assign(implausible=False, implausible_reason="")
    flagged.loc[7, ["implausible", "implausible_reason"]] = (True, "f_h on prior bound")
    one = population_stats(flagged, n_bootstrap=0, bands="1.5,2.6,3")
    assert one.counts["implausible_reasons"] == {"f_h on prior bound": 1} and one.counts["usable"] == 39
    # ... and so is a record-level verdict that the model is inadequate.
    inadequate = plain_frame(seed=5).assign(**{ADEQUATE_COLUMN: np.where(np.arange(40) < 10, False, True)})
    adequate_only = population_stats(inadequate, n_bootstrap=0, bands="1.5,2.6,3")
    assert adequate_only.counts["inadequate"] == 10 and adequate_only.cells["f_h", 0].n == 20
    assert "warning: 10 ok cycles come from a model found inadequate" in adequate_only.summary()


def test_constant_column_has_no_spread_not_minus_infinite_r_squared(tmp_path):
    frame = plain_frame().assign(blf_3=0.05)
    stats = population_stats(frame, n_bootstrap=0, bands="1.5,2.6,3")
    assert stats.trends["BLF3"] == "no trend (no spread: all 40 values equal 0.05)"
    assert stats.cells["BLF3", 0].note == "no spread: all 30 values equal"
    assert "-inf" not in stats.summary() and "BLF3: no trend (no spread" in stats.summary()
    with pytest.raises(OptionError, match="BLF3 trend: no spread: all 40 values equal 0.05"):
        fit_trend(frame.f_b, frame.blf_3, 1, parameter="BLF3")
    fig = stats.plot_trends()
    assert any(t.get_text() == "no trend: no spread" for ax in fig.axes for t in ax.texts)
