"""Choosing lambda from the data: discrepancy principle and L-curve on problems with known answers.

The toy is linear Tikhonov with a diagonal operator, J(x) = |A x - d|^2 / M + lam * mean(x^2),
A = [diag(s); 0] (M x n): the last M - n measurements are not modelled, so their residual is the
data itself. Its minimizer x_i = s_i d_i / (s_i^2 + lam M / n) gives chi2(lam) and Phi(lam) in
closed form.
"""

import json
import math
import warnings

import numpy as np
import pylops
import pytest
from scipy.optimize import brentq

import operators as op
import solvers

N_PARAMS, N_DATA = 40, 60


class DiagonalTikhonov:
    """The toy problem; calling it with lam returns (x, chi2, phi) and records the call.

    Parameters
    ----------
    bias : float
        Offset added to the unmodelled measurements (a model error, in noise units).
    """

    def __init__(self, bias=0.0, seed=0):
        i = np.arange(N_PARAMS)
        self.s = 50.0 * np.exp(-0.25 * i)
        truth = np.exp(-0.05 * i) * (1 + 0.3 * np.sin(i))
        exact = np.concatenate([self.s * truth, np.full(N_DATA - N_PARAMS, bias)])
        self.data = exact + np.random.default_rng(seed).standard_normal(N_DATA)
        self.calls = []

    def solution(self, lam):
        s = self.s
        return s * self.data[:N_PARAMS] / (s**2 + lam * N_DATA / N_PARAMS)

    def parts(self, x):
        residual = self.data.copy()
        residual[:N_PARAMS] -= self.s * x
        return float(residual @ residual), float(np.mean(x**2))

    def __call__(self, lam):
        self.calls.append(lam)
        x = self.solution(lam)
        return (x, *self.parts(x))

    def root(self, target):
        """lam with chi2(lam) = target, from the closed form."""
        return math.exp(brentq(lambda u: self(math.exp(u))[1] - target, -30.0, 30.0,
                               xtol=1e-14, rtol=1e-14))


@pytest.fixture
def no_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def test_problem_weight_puts_the_normalized_objective_on_the_problem_scale():
    toy = DiagonalTikhonov()
    a = np.vstack([np.diag(toy.s), np.zeros((N_DATA - N_PARAMS, N_PARAMS))])
    mean_square = op.Composite(op.SquaredL2(scale=1 / N_PARAMS),
                               op.aslinearoperator(pylops.Identity(N_PARAMS)))
    lam = 0.7
    problem = solvers.Problem(op.aslinearoperator(pylops.MatrixMult(a)), toy.data,
                              regularizer=mean_square,
                              lam=solvers.problem_weight(lam, N_DATA))
    x = toy.solution(lam)
    chi2, phi = toy.parts(x)
    assert problem.objective(x) == pytest.approx(N_DATA * (chi2 / N_DATA + lam * phi),
                                                 rel=1e-13)
    grad = problem.evaluate(x).grad
    assert np.linalg.norm(grad) < 1e-10 * np.linalg.norm(2 * a.T @ toy.data)
    assert np.linalg.norm(problem.evaluate(toy.solution(1.1 * lam)).grad) > 1e-3


@pytest.mark.parametrize("lam, count", [(-1.0, 10), (np.nan, 10), (1.0, 0), (1.0, 2.5)])
def test_problem_weight_rejects_bad_input(lam, count):
    with pytest.raises(ValueError, match="lam|n_measurements"):
        solvers.problem_weight(lam, count)


def test_the_toy_misfit_grows_and_its_regularizer_falls_with_lambda():
    toy = DiagonalTikhonov()
    points = np.array([toy(lam)[1:] for lam in np.logspace(-8, 6, 300)])
    assert np.all(np.diff(points[:, 0]) > 0)
    assert np.all(np.diff(points[:, 1]) < 0)
    assert points[0, 0] < N_DATA < points[-1, 0]


@pytest.mark.parametrize("tau, refine", [(1.0, 5), (1.1, 3), (1.0, 0)])
def test_discrepancy_lands_within_the_final_bracket_below_the_root(tau, refine, no_warnings):
    toy = DiagonalTikhonov()
    root = toy.root(tau * N_DATA)
    toy.calls.clear()
    choice = solvers.discrepancy_principle(toy, N_DATA, lam_max=1e6, lam_min=1e-8, tau=tau,
                                           refine=refine)
    ratio = 10.0 ** (2.0**-refine)
    assert choice.reached and choice.rule == "discrepancy"
    assert root / ratio < choice.lam <= root
    assert choice.chi2[choice.index] <= tau * N_DATA == choice.target
    failing = choice.lams[choice.chi2 > choice.target]
    assert root < failing.min() <= choice.lam * ratio * (1 + 1e-12)
    np.testing.assert_array_equal(choice.theta, toy.solution(choice.lam))
    # down the ladder (powers of ten) to the first pass, then `refine` calls inside the bracket
    passed = [toy.parts(toy.solution(lam))[0] <= choice.target for lam in toy.calls]
    first_pass = passed.index(True)
    ladder, bisection = toy.calls[:first_pass + 1], toy.calls[first_pass + 1:]
    np.testing.assert_allclose(ladder, 10.0 ** (6.0 - np.arange(first_pass + 1)), rtol=1e-12)
    assert len(bisection) == refine
    assert all(ladder[-1] < lam < ladder[-2] for lam in bisection)


def test_discrepancy_not_reached_returns_the_smallest_misfit_flagged():
    toy = DiagonalTikhonov(bias=2.0)
    assert toy(1e-12)[1] > N_DATA  # the unmodelled rows alone exceed the noise level
    with pytest.warns(RuntimeWarning, match="not reached"):
        choice = solvers.discrepancy_principle(toy, N_DATA, lam_max=1e2, lam_min=1e-4)
    assert not choice.reached
    assert "not reached" in choice.message
    assert choice.lam == choice.lams[np.argmin(choice.chi2)] == pytest.approx(1e-4)
    assert np.all(choice.chi2 > choice.target)
    np.testing.assert_array_equal(choice.theta, toy.solution(choice.lam))


def test_discrepancy_met_at_lam_max_says_the_range_is_open_above():
    toy = DiagonalTikhonov()
    lam_max = toy.root(N_DATA) / 5
    toy.calls.clear()
    with pytest.warns(RuntimeWarning, match="increase lam_max"):
        choice = solvers.discrepancy_principle(toy, N_DATA, lam_max=lam_max, lam_min=1e-8)
    assert choice.reached and choice.lam == lam_max
    assert toy.calls == [lam_max]


def test_discrepancy_reports_a_non_monotone_misfit_and_still_brackets_a_crossing():
    lam_stuck = 0.1

    def solve(lam):  # chi2 = M sqrt(2 lam), except a solve that got stuck at lam_stuck
        chi2 = 5.0 * N_DATA if lam == lam_stuck else N_DATA * math.sqrt(2 * lam)
        return None, chi2, 1 / lam

    with pytest.warns(RuntimeWarning, match="chi2 is not non-decreasing"):
        choice = solvers.discrepancy_principle(solve, N_DATA, lam_max=100.0, lam_min=1e-3,
                                               refine=4)
    assert choice.reached
    assert choice.chi2[choice.index] <= choice.target
    above = choice.lams[choice.index + 1]
    assert choice.chi2[choice.index + 1] > choice.target
    assert above / choice.lam == pytest.approx(10 ** (1 / 16))


@pytest.mark.parametrize("kwargs, match", [
    ({"lam_max": 0.0}, "lam_min < lam_max"),
    ({"lam_min": -1.0}, "lam_min < lam_max"),
    ({"lam_min": 2.0, "lam_max": 1.0}, "lam_min < lam_max"),
    ({"lam_max": np.inf}, "lam_min < lam_max"),
    ({"tau": 0.9}, "tau"),
    ({"factor": 1.0}, "factor"),
    ({"refine": -1}, "refine"),
    ({"refine": 2.5}, "refine"),
    ({"n_measurements": 0}, "n_measurements"),
])
def test_discrepancy_rejects_bad_input(kwargs, match):
    args = {"solve": DiagonalTikhonov(), "n_measurements": N_DATA, "lam_max": 1.0,
            "lam_min": 1e-3} | kwargs
    with pytest.raises(ValueError, match=match):
        solvers.discrepancy_principle(**args)


def test_discrepancy_stops_on_a_nan_misfit():
    with pytest.raises(ValueError, match=r"solve\(0\.01\) returned chi2=nan.*diverge"):
        solvers.discrepancy_principle(
            lambda lam: (None, 2.0 * N_DATA if lam > 0.01 else np.nan, 1.0), N_DATA,
            lam_max=1.0, lam_min=1e-4)


def hyperbola(t, a, b):
    """L-curve points on (x + 1)(y - 2) = a b in (log chi2, log Phi); its vertex (largest
    curvature) is at t = log(b / a) / 2."""
    return np.exp(t), np.exp(-1 + a * np.exp(t)), np.exp(2 + b * np.exp(-t))


@pytest.mark.parametrize("a, b", [(1.0, 1.0), (0.3, 2.0), (5.0, 0.2)])
@pytest.mark.parametrize("step, offset", [(0.2, 0.3), (0.5, 0.45), (1.0, 0.1)])
def test_l_curve_picks_the_sweep_point_nearest_the_vertex_of_a_hyperbola(a, b, step, offset,
                                                                        no_warnings):
    vertex = 0.5 * math.log(b / a)
    t = vertex + step * (offset + np.arange(-5, 6))
    choice = solvers.l_curve(*hyperbola(t, a, b))
    assert choice.reached and choice.rule == "l-curve"
    assert math.log(choice.lam) == pytest.approx(t[np.argmin(np.abs(t - vertex))], abs=1e-12)
    assert np.isnan(choice.curvature[[0, -1]]).all() and np.all(choice.curvature[1:-1] > 0)


def tikhonov_corner(toy):
    """lam of largest curvature of the toy's continuous L-curve (dense finite differences)."""
    u = np.linspace(math.log(1e-6), math.log(1e4), 4001)
    points = np.log([toy(lam)[1:] for lam in np.exp(u)])
    x1, y1 = (np.gradient(v, u) for v in points.T)
    x2, y2 = np.gradient(x1, u), np.gradient(y1, u)
    return math.exp(u[np.argmax((x1 * y2 - y1 * x2) / (x1**2 + y1**2) ** 1.5)])


@pytest.mark.parametrize("points_per_decade", [1, 2, 4])
def test_l_curve_of_tikhonov_is_within_one_step_of_the_curvature_maximum(points_per_decade,
                                                                          no_warnings):
    toy = DiagonalTikhonov()
    lams = 10.0 ** np.arange(-8, 6 + 1e-9, 1 / points_per_decade)
    chi2, phi = np.array([toy(lam)[1:] for lam in lams]).T
    choice = solvers.l_curve(lams, chi2, phi, n_measurements=N_DATA)
    corner = tikhonov_corner(toy)
    assert abs(math.log10(choice.lam / corner)) < 1 / points_per_decade
    shuffled = np.random.default_rng(1).permutation(lams.size)
    rescaled = solvers.l_curve(lams[shuffled], 7.0 * chi2[shuffled], 1e-3 * phi[shuffled])
    assert rescaled.lam == choice.lam
    np.testing.assert_allclose(rescaled.curvature, choice.curvature, rtol=1e-9)


def test_l_curve_without_a_bend_is_flagged():
    t = np.linspace(0.1, 2.0, 6)  # y = -x^2 in the log-log plane turns clockwise
    with pytest.warns(RuntimeWarning, match="no point bends"):
        choice = solvers.l_curve(np.exp(t), np.exp(t), np.exp(-t**2))
    assert not choice.reached
    assert np.nanmax(choice.curvature) < 0


def test_l_curve_reports_jittering_points():
    lams, chi2, phi = hyperbola(np.linspace(-2, 2, 9), 1.0, 1.0)
    phi[1] = phi[0] * 1.01
    with pytest.warns(RuntimeWarning, match="phi is not non-increasing"):
        solvers.l_curve(lams, chi2, phi)


def test_l_curve_skips_repeated_points():
    lams, chi2, phi = hyperbola(np.linspace(-2, 2, 9), 1.0, 1.0)
    repeated = np.insert(chi2, 4, chi2[4]), np.insert(phi, 4, phi[4])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        choice = solvers.l_curve(np.insert(lams, 4, lams[4] * 1.001), *repeated)
    assert choice.lam == lams[4]
    assert np.isnan(choice.curvature[5])


@pytest.mark.parametrize("lams, chi2, phi, match", [
    ([1, 2, 3], [1, 2, 3], [3, 2, 1], "at least 4 points"),
    ([1, 2, 3, 4], [1, 2, np.nan, 4], [4, 3, 2, 1], "chi2 must be finite and > 0"),
    ([0, 2, 3, 4], [1, 2, 3, 4], [4, 3, 2, 1], "lams must be finite and > 0"),
    ([1, 2, 3, 4], [1, 2, 3, 4], [4, 3, 2, 0], "phi must be finite and > 0"),
    ([1, 2, 3, 4], [1, 2, 3], [4, 3, 2, 1], "one length"),
    ([1, 2, 2, 4], [1, 2, 3, 4], [4, 3, 2, 1], "distinct"),
    ([1, 2, 3, 4], [1, 1, 1, 1], [2, 2, 2, 2], "points differ"),
])
def test_l_curve_rejects_bad_input(lams, chi2, phi, match):
    with pytest.raises(ValueError, match=match):
        solvers.l_curve(lams, chi2, phi)


def test_choice_serializes_to_json():
    choice = solvers.l_curve(*hyperbola(np.linspace(-2, 2, 9), 1.0, 1.0), n_measurements=9)
    record = json.loads(json.dumps(choice.as_dict(), allow_nan=False))
    assert record["lam"] == choice.lam and record["rule"] == "l-curve"
    assert record["curvature"][0] is None and record["curvature"][4] > 0
    assert record["lams"] == choice.lams.tolist()
