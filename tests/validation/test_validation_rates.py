"""The bookkeeping of the diagnose validation's rates (``validation/rates.py``)."""

import pytest

from validation.rates import Rate, outcome, rate, rates


def test_wilson_interval_matches_known_values():
    assert Rate(0, 20).interval == pytest.approx((0.0, 0.1611), abs=1e-4)
    assert Rate(10, 20).interval == pytest.approx((0.2993, 0.7007), abs=1e-4)
    assert Rate(20, 20).interval == pytest.approx((0.8389, 1.0), abs=1e-4)
    assert str(rate([True, False, False, False])) == "1/4 = 0.25 (95 %: 0.05–0.70)"


def test_outcomes_tell_right_and_false_names_apart():
    right = outcome("missing-effect", ["log-creep"], ("log-creep", "power-law-creep"))
    assert right == {
        "right_name": True,
        "false_name": False,
        "false_adequate": False,
        "false_refusal": None,
    }
    wrong = outcome("missing-effect", ["area-growth"], ("gain-drift",))
    assert wrong["false_name"] and not wrong["right_name"]
    # a refusal is neither a right nor a false name; adequate on a hidden cause is false adequate
    refused = outcome("unexplained", [], ("gain-drift",))
    assert refused["right_name"] is False and not refused["false_name"]
    assert outcome("adequate", [], ("gain-drift",))["false_adequate"]
    # nothing in the catalogue is right for correlated noise: no right-name rate, any name false
    noise = outcome("missing-effect", ["area-creep"], ())
    assert noise["right_name"] is None and noise["false_name"]
    # null data: anything but adequate is a false refusal; any name a false name
    assert outcome("partially-explained", ["area-creep"], (), null=True)["false_refusal"]
    assert not outcome("adequate", [], (), null=True)["false_refusal"]
    counted = rates([right, wrong, refused, noise])
    assert counted["right_name"] == (1, 3) and counted["false_name"] == (2, 4)
    assert counted["false_refusal"] == (0, 0)
