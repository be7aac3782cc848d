"""The frequency weightings of what engineers check: W_k against ISO 2631-1's table, W_b against BS 6841's own
rational form, and the weighted measures of a sine."""

import numpy as np
import pytest

from smd_statespace.errors import OptionError
from smd_statespace.structure.response import measures
from smd_statespace.structure.weighting import WEIGHTINGS, weighted, weighting_gain

ISO_2631_1_WK = {0.5: 0.418, 1.0: 0.482, 2.0: 0.531, 4.0: 0.967, 5.0: 1.039, 8.0: 1.036, 16.0: 0.768, 31.5: 0.405,
                 63.0: 0.186}
"""ISO 2631-1:1997 Table 3, W_k (the factors given to three figures, times 1000 in the table)."""


def test_wk_is_the_iso_table():
    frequency = np.array(list(ISO_2631_1_WK))
    np.testing.assert_allclose(np.abs(weighting_gain(frequency, "Wk")), list(ISO_2631_1_WK.values()), atol=1.5e-3)


def test_wb_is_bs_6841s_rational_function_with_its_low_frequency_gain_of_0_4():
    """BS 6841 writes W_b as one rational function, ``K 2 pi f4^2 f6^2 / (f3 f5^2) (s + w3)(s^2 + w5 s / Q5 + w5^2)
    / ((s^2 + w4 s / Q4 + w4^2)(s^2 + w6 s / Q6 + w6^2))`` with ``K = 0.4``, its gain at low frequency; here it is
    the product of ISO 2631's factors with ``K = 1.024``. Without the band limits they are the same function."""
    w = WEIGHTINGS["Wb"]
    frequency = np.linspace(0.5, 80, 400)
    s = 2j * np.pi * frequency
    w3, w4, w5, w6 = (2 * np.pi * f for f in (w.f3, w.f4, w.f5, w.f6))
    bs_6841 = (0.4 * 2 * np.pi * w.f4**2 * w.f6**2 / (w.f3 * w.f5**2) * (s + w3) * (s**2 + w5 * s / w.q5 + w5**2)
               / ((s**2 + w4 * s / w.q4 + w4**2) * (s**2 + w6 * s / w.q6 + w6**2)))
    w1, w2, q = 2 * np.pi * w.f1, 2 * np.pi * w.f2, 1 / np.sqrt(2)
    band = s**2 / (s**2 + w1 * s / q + w1**2) * w2**2 / (s**2 + w2 * s / q + w2**2)
    np.testing.assert_allclose(weighting_gain(frequency, "Wb") / band, bs_6841, rtol=1e-12)
    with pytest.raises(OptionError, match="weighting 'Wz': give one of Wb, Wk"):
        weighting_gain(1.0, "Wz")


def test_weighted_measures_of_a_sine_scale_by_the_weighting():
    fs, amplitude, duration, f = 200.0, 0.5, 20.0, 4.0
    time = np.arange(int(duration * fs)) / fs
    sine = amplitude * np.sin(2 * np.pi * f * time)
    gain = abs(weighting_gain(f, "Wb"))
    middle = slice(int(4 * fs), int(16 * fs))  # away from the ends, where the filter starts and stops from rest
    np.testing.assert_allclose(weighted(sine, fs)[middle], gain * amplitude * np.sin(
        2 * np.pi * f * time[middle] + np.angle(weighting_gain(f, "Wb"))), atol=2e-3 * amplitude)
    values = measures(sine, fs)
    assert values["rms_1s_max_wb"] == pytest.approx(gain * amplitude / np.sqrt(2), rel=0.01)
    assert values["vdv_wb"] == pytest.approx(gain * values["vdv"], rel=0.02)
    assert values["rms_1s_max_wb"] < values["rms_1s_max"]  # at 4 Hz W_b is 0.89
