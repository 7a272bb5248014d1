"""Planck's law per wavenumber and its temperature spline."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import PPoly

from operators.rte.planck import C1, C2, planck, planck_table

ETA = np.arange(650.0, 725.0 + 1e-9, 0.04)


def test_radiation_constants():
    assert C1 == pytest.approx(1.191042972e-8, rel=1e-9)  # W cm^4 / (m^2 sr)
    assert C2 == pytest.approx(1.438776877, rel=1e-9)  # cm K


def test_radiance_value_and_wien_limit():
    # 1000 K at 700 cm-1: c1 eta^3 / (exp(c2 eta / T) - 1)
    assert planck(700.0, 1000.0) == pytest.approx(C1 * 700.0**3 / np.expm1(C2 * 0.7), rel=1e-14)
    assert planck(700.0, 1000.0) == pytest.approx(2.35, rel=5e-3)  # W/(m2 sr cm-1)
    wien = C1 * 700.0**3 * np.exp(-C2 * 700.0 / 100.0)
    assert planck(700.0, 100.0) == pytest.approx(wien, rel=1e-4)


@pytest.mark.usefixtures("x64")
def test_numpy_and_jax_agree_and_jax_differentiates():
    t = 1234.5
    assert float(planck(jnp.asarray(ETA), t)[10]) == pytest.approx(planck(ETA, t)[10], rel=1e-14)
    slope = jax.grad(lambda temp: planck(jnp.asarray(700.0), temp))(t)
    numeric = (planck(700.0, t + 1e-3) - planck(700.0, t - 1e-3)) / 2e-3
    assert float(slope) == pytest.approx(numeric, rel=1e-7)


@pytest.mark.parametrize("rtol", [1e-6, 1e-7])
def test_table_spline_meets_its_tolerance_between_and_on_nodes(rtol):
    nodes, coef = planck_table(ETA, np.geomspace(250.0, 2500.0, 27), rtol=rtol)
    assert np.all(np.isin(np.geomspace(250.0, 2500.0, 27), nodes))
    spline = PPoly(coef, nodes)  # same layout: powers of (T - node), highest first
    temperatures = np.linspace(250.0, 2500.0, 2001)
    error = np.abs(spline(temperatures) / planck(ETA, temperatures[:, None]) - 1.0)
    assert error.max() <= 1.5 * rtol


def test_table_rejects_bad_nodes():
    with pytest.raises(ValueError, match="strictly increasing positive"):
        planck_table(ETA, [300.0, 300.0, 400.0])
