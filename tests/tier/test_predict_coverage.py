"""Validation tier: ``predict`` on a protocol no fit has seen holds fresh readings at its rate.

Three FSR 402 specimens drawn from the sensor's population on the bench rig (4.9 V divider with
3.3 kΩ, read as the voltage across the fixed resistor at 10 Hz): each is fitted on three
from-rest dead-weight tests of 60 s with the law the bench simulates (Burgers; a 402's default
is log-spectrum-sat), every reading and one level for all placements (the bench lands every
weight alike: no settling, no placement spread), and the fit predicts a staircase of the
same specimen — the three weights put on one after the other, 60 s each, never unloaded — that
it never saw (another noise draw, the load history by superposition). A posterior that is right
puts 90 % of the staircase's readings in their 90 % band, up to the specimen's parameter
uncertainty shared by all its readings; asked here: every specimen inside 0.70–0.995 and the
three pooled inside 0.80–0.98 (the real-sensor acceptance band). A band that ignores the
parameter uncertainty, or a creep law that extrapolates wrongly, falls below.
"""

from dataclasses import replace

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.data.synthetic import draw_specimens
from fsrbayes.inference.fit import FIT_SETTINGS
from fsrbayes.inference.output import save_fit
from fsrbayes.inference.predict import predict

pytestmark = [pytest.mark.validation, pytest.mark.timeout(1800)]

RIG = {"duration_s": 60.0, "rate_hz": 10.0, "weights_g": (150.0, 210.0, 255.0)}
SEEDS = (8101, 8102, 8103)


def _specimen_coverage(root, seed):
    params = draw_specimens(load_sensor("fsr402"), 1, np.random.default_rng(seed))[0]
    fitted, truth = simulate_rig(1, reading="vout_V", seed=seed, specimens=[params], **RIG)
    stairs, _ = simulate_rig(
        1, reading="vout_V", protocol="staircase", seed=seed + 50, specimens=[params], **RIG
    )
    fit_csv = write_rig(fitted, truth, root / f"fit-{seed}.csv")[0]
    stairs_csv = write_rig(stairs, truth, root / f"stairs-{seed}.csv")[0]
    data = read_csv(fit_csv)
    result = fsrbayes.fit(
        data, model="burgers", settle_s=0.0, placement=False, rng=seed,
        settings=replace(FIT_SETTINGS, processes=1),
    )  # fmt: skip
    (root / f"fit-{seed}").mkdir()
    save_fit(result, root / f"fit-{seed}")
    out = predict(root / f"fit-{seed}", read_csv(stairs_csv, readings="optional"), seed=seed)
    return result.converged, out["coverage_90"], out["n_readings"]


def test_a_staircase_never_fitted_falls_in_its_bands_at_their_rate(tmp_path):
    rows = [_specimen_coverage(tmp_path, seed) for seed in SEEDS]
    print(rows)
    assert all(converged for converged, _, _ in rows), rows
    coverage = np.array([c for _, c, _ in rows])
    counts = np.array([n for _, _, n in rows])
    assert np.all((coverage >= 0.70) & (coverage <= 0.995)), coverage
    pooled = float(np.sum(coverage * counts) / counts.sum())
    assert 0.80 <= pooled <= 0.98, pooled
