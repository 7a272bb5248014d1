"""The effective-Hamiltonian level model of 12C16O2 against the published constants."""

import numpy as np
import pytest

from invflame.spectroscopy import co2_constants as const
from invflame.spectroscopy import co2_levels
from invflame.spectroscopy.co2_lines import bands


def test_vibrational_model_reproduces_published_term_values():
    vib = co2_levels.vibrational_model()
    assert vib.rms < 0.03
    for key, members in co2_levels._tabulated_polyads().items():
        energies = np.linalg.eigvalsh(vib.hamiltonian(co2_levels.polyad_basis(*key)))
        observed = [const.LEVELS[s].G for s in members]
        np.testing.assert_allclose(energies, observed, atol=0.05)


def test_rotational_model_reproduces_published_rotational_levels():
    vib, rot = co2_levels.vibrational_model(), co2_levels.rotational_model()
    lv = co2_levels.levels()
    J = np.array([30.0, 60.0])
    x = J * (J + 1)
    for key, members in co2_levels._tabulated_polyads().items():
        term = rot.term_values(vib, co2_levels.polyad_basis(*key), x)
        for k, label in enumerate(reversed(members)):
            level = lv[label]
            model_e = term[:, k] - 0.5 * co2_levels.q_effective(level) * x
            published_e = level.E_e[J.astype(int)]
            assert abs(model_e[0] - published_e[0]) < 0.12, label
            assert abs(model_e[1] - published_e[1]) < 0.35, label


def test_bending_ladder_extrapolates_smoothly():
    lv = co2_levels.levels()
    ladder = [lv[f"0{v}{v}01"].G for v in range(1, 10)]
    spacing = np.diff(ladder)
    # anharmonic bending: spacings grow slowly from 667.75 (01101->02201) by about 0.3-0.4 per step
    assert np.all((np.diff(spacing) > 0.1) & (np.diff(spacing) < 0.6))
    assert 668.0 < spacing[-1] < 672.0


def test_x33_enters_only_through_v3_2():
    vib = co2_levels.vibrational_model()
    g = [vib.hamiltonian([(0, 0, 0, v3)])[0, 0] for v3 in (0, 1, 2)]
    assert g[0] == 0.0
    assert g[2] - 2 * g[1] == pytest.approx(2 * const.X33, abs=1e-9)
    # the published 00011 term value is reproduced, so 00021 lies 2·|x33| below 2·G(00011)
    lv = co2_levels.levels()
    assert 2 * lv["00011"].G - lv["00021"].G == pytest.approx(-2 * const.X33, abs=0.01)


def test_polyads_are_complete_and_orthonormal():
    lv = co2_levels.levels()
    groups = {}
    for level in lv.values():
        groups.setdefault((level.polyad, level.l, level.v3), []).append(level)
    for key, members in groups.items():
        if any(m.G > co2_levels.MAX_ENERGY - 1500 for m in members):
            continue
        basis = co2_levels.polyad_basis(*key)
        assert sorted(m.r for m in members) == list(range(1, len(basis) + 1))
        m = np.array([[c for c, _ in level.composition] for level in members])
        np.testing.assert_allclose(m @ m.T, np.eye(len(members)), atol=1e-10)
    assert {"06601", "07701", "08801", "14401", "14402", "22201", "22202", "22203"} <= set(lv)
    assert {"30001", "30004", "31101", "31104", "11111", "11112", "21111", "00021"} <= set(lv)


def test_members_are_ranked_from_the_top():
    lv = co2_levels.levels()
    assert lv["30001"].G > lv["30002"].G > lv["30003"].G > lv["30004"].G
    assert lv["14401"].G > lv["14402"].G


def test_l_doubling_of_model_levels():
    level = co2_levels.levels()["31102"]
    J = np.arange(1, 60)
    split = level.E_f[J] - level.E_e[J]
    np.testing.assert_allclose(split, co2_levels.q_effective(level) * J * (J + 1), rtol=1e-9)
    delta = co2_levels.levels()["22202"]
    np.testing.assert_array_equal(delta.E_e, delta.E_f)


def test_hitran_quanta_field():
    lv = co2_levels.levels()
    assert lv["06601"].hitran_v == "       0 6 6 01"
    assert lv["11112"].hitran_v == "       1 1 1 12"
    assert all(len(level.hitran_v) == 15 for level in lv.values())


def test_hot_bands_of_higher_tiers_are_generated():
    pairs = set(bands())
    for lower, upper in [
        ("05501", "06601"),
        ("06601", "07701"),
        ("13301", "14401"),
        ("21102", "22202"),
        ("30002", "31102"),
        ("00011", "01111"),
        ("10011", "11111"),
        ("10012", "11112"),
        ("00021", "01121"),
    ]:
        assert (lower, upper) in pairs
