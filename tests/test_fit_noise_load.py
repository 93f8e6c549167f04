"""The model-free cell noise must not be inflated by a small load variation the forces follow."""

import numpy as np

from wheelsoil.model.data import cell_noise


def test_cell_noise_absorbs_a_half_percent_load_variation():
    rng = np.random.default_rng(0)
    C = 120
    slip = rng.uniform(0.15, 0.85, C)
    load = 13400.0 * (1.0 + 0.005 * rng.standard_normal(C))  # 0.5 % load scatter
    group = np.repeat(np.arange(10), 12)
    sbin = np.tile(np.arange(12), 10)
    sigma_true = 2.0
    torque = load * (0.22 + 0.02 * slip) + sigma_true * rng.standard_normal(C)  # T ~ W g(s), ~3000 N m
    # the load term alone moves T by ~15 N m RMS, 7 x the noise
    assert np.std(load * 0.23) > 5 * sigma_true
    sigma, _, _ = cell_noise({"torque_nm": torque}, slip, load, np.arange(C, dtype=float), group, sbin,
                             "timeseries", x=np.linspace(-0.5, 0.5, C))
    assert 0.6 * sigma_true < sigma["torque_nm"] < 1.5 * sigma_true
