"""Physics checks of the generated 12C16O2 line list (no external data needed)."""

import numpy as np
import pytest

from invflame.spectroscopy import co2_constants as const
from invflame.spectroscopy import co2_lines
from invflame.spectroscopy.linelist import read_par, write_par


@pytest.fixture(scope="module")
def lines():
    return co2_lines.generate_co2_lines(600.0, 800.0, S_min=0.0)


def _band(lines, upper, lower):
    v = co2_lines.levels()
    return (lines.V_upper == v[upper].hitran_v) & (lines.V_lower == v[lower].hitran_v)


def _branch_j_sym(lines):
    q = lines.Q_lower
    return (
        np.array([s[5] for s in q]),
        np.array([int(s[6:9]) for s in q]),
        np.array([s[9] for s in q]),
    )


def test_fundamental_q_branch_head_near_667_4(lines):
    branch, J, _ = _branch_j_sym(lines)
    q = _band(lines, "01101", "00001") & (branch == "Q")
    assert q.sum() > 50
    assert lines.nu[q].min() == pytest.approx(667.38, abs=0.01)
    # the Q branch is degraded to the violet: B(01101 f) > B(00001)
    order = np.argsort(J[q])
    assert np.all(np.diff(lines.nu[q][order]) > 0)


def test_strongest_fundamental_lines_have_hitran_magnitude(lines):
    # Q lines (J'' ≈ 16) near 3e-19 cm/molecule; P and R lines about half of that
    branch, J, _ = _branch_j_sym(lines)
    for name, (low, high) in {
        "Q": (2.5e-19, 3.5e-19),
        "P": (1.0e-19, 2.0e-19),
        "R": (1.2e-19, 2.0e-19),
    }.items():
        sel = _band(lines, "01101", "00001") & (branch == name)
        strongest = np.argmax(lines.S296[sel])
        assert low < lines.S296[sel][strongest] < high
        assert 10 <= J[sel][strongest] <= 22


def test_fundamental_band_sums_to_published_band_intensity():
    v = co2_lines.levels()
    bl = co2_lines.band_lines(v["00001"], v["01101"], 120)
    scale = co2_lines._intensity_scale(120)
    assert scale * bl.relative_strength.sum() == pytest.approx(const.FUNDAMENTAL_BAND_INTENSITY_296)


def test_nuclear_spin_statistics(lines):
    _, J, sym = _branch_j_sym(lines)
    ground = lines.V_lower == co2_lines.levels()["00001"].hitran_v
    assert ground.sum() > 100
    assert np.all(J[ground] % 2 == 0) and np.all(sym[ground] == "e")
    # in 01101 each J keeps one of e/f: e for odd J, f for even J
    pi = lines.V_lower == co2_lines.levels()["01101"].hitran_v
    assert np.all((J[pi] % 2 == 1) == (sym[pi] == "e"))
    # Σu+ (00011): odd J only
    sigma_u = lines.V_lower == co2_lines.levels()["00011"].hitran_v
    assert sigma_u.any() and np.all(J[sigma_u] % 2 == 1)


def test_statistical_weights_and_quanta_fields(lines):
    branch, J, _ = _branch_j_sym(lines)
    dJ = np.select([branch == "P", branch == "Q", branch == "R"], [-1, 0, 1])
    assert np.array_equal(lines.g_lower, 2 * J + 1)
    assert np.array_equal(lines.g_upper, 2 * (J + dJ) + 1)
    assert set(np.char.str_len(lines.V_upper.astype(str))) == {15}
    assert lines.V_upper[0].startswith("       ")
    assert np.all(lines.Q_upper == " " * 15)


def test_hoenl_london_sum_rule():
    J = np.arange(3, 40)
    for l_low, l_up in [(0, 1), (1, 2), (1, 0), (2, 3), (2, 1)]:
        total = sum(co2_lines.hoenl_london(J, l_low, J + d, l_up) for d in (-1, 0, 1))
        np.testing.assert_allclose(total, 2 * J + 1, rtol=1e-12)
    # Σ–Π values of Herzberg
    np.testing.assert_allclose(co2_lines.hoenl_london(J, 0, J + 1, 1), (J + 2) / 2)
    np.testing.assert_allclose(co2_lines.hoenl_london(J, 0, J - 1, 1), (J - 1) / 2)


def test_fermi_compositions_are_orthonormal():
    lv = co2_lines.levels()
    for group in (["10002", "10001"], ["20003", "20002", "20001"], ["21103", "21102", "21101"]):
        basis = sorted({b for label in group for _, b in lv[label].composition})
        m = np.array(
            [[dict((b, c) for c, b in lv[s].composition)[x] for x in basis] for s in group]
        )
        np.testing.assert_allclose(m @ m.T, np.eye(len(group)), atol=1e-10)


def test_hot_band_strength_follows_harmonic_scaling(lines):
    # S(02201<-01101)/S(fundamental) at 296 K ≈ 2·exp(-c2·667.4/296) (degeneracy 2, |R|² equal)
    strong = lines.select(lines.S296 > 0)
    fund = strong.S296[_band(strong, "01101", "00001")].sum()
    hot = strong.S296[_band(strong, "02201", "01101")].sum()
    assert hot / fund == pytest.approx(2 * np.exp(-co2_lines.C2 * 667.38 / 296.0), rel=0.1)


def test_einstein_a_matches_hitran_r30_of_fundamental(lines):
    branch, J, sym = _branch_j_sym(lines)
    i = np.flatnonzero(_band(lines, "01101", "00001") & (branch == "R") & (J == 30))[0]
    assert lines.A[i] == pytest.approx(0.9153, rel=0.1)  # HITRAN value of R(30)e


def test_broadening_decreases_with_m():
    widths = co2_lines.broadening(np.array([1, 10, 30, 60, 100, 150]))
    assert np.all(np.diff(widths["gamma_air"]) <= 0) and np.all(np.diff(widths["gamma_self"]) <= 0)
    assert widths["gamma_air"][2] == pytest.approx(0.069, abs=0.002)
    assert np.all((widths["n_air"] > 0.5) & (widths["n_air"] < 0.8))


def test_write_and_read_back(tmp_path):
    lines = co2_lines.generate_co2_lines(667.0, 668.0, S_min=1e-24)
    path = tmp_path / "co2.par"
    write_par(lines, path)
    back = read_par(path)
    assert len(back) == len(lines)
    np.testing.assert_allclose(back.nu, lines.nu, atol=1e-6)
    np.testing.assert_allclose(back.S296, lines.S296, rtol=1e-3)
    assert np.array_equal(back.Q_lower, lines.Q_lower)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"nu_min": 700.0, "nu_max": 650.0}, "nu_min < nu_max"),
        ({"J_max": 0}, "J_max"),
        ({"S_min": -1.0}, "S_min"),
    ],
)
def test_bad_input_is_rejected(kwargs, message):
    with pytest.raises(ValueError, match=message):
        co2_lines.generate_co2_lines(**kwargs)
