"""The Numba sweeps for CPUs (forward, forward-mode, reverse) against XLA's, and their float32
exponential."""

import tempfile
from pathlib import Path

import jax
import jax.numpy as jnp
import numba
import numpy as np
import pytest
from rte_reference import random_rays, synthetic_sigma

from operators.base import precision
from operators.rte import (
    SWEEPS,
    choose_sweeps,
    emission_radiance,
    emission_radiance_jvp,
)
from operators.rte.numba_arithmetic import X86, absorptance
from operators.rte.numba_targets import _source_file, target
from operators.rte.tables import RTETables, rayleigh_soot_constant
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)
COEF = PiecewiseCubic(NODES, SIGMA).coef  # two species absorb


def gradients(tables, fields, lengths, background, sweeps):
    """Gradients of a weighted sum of the radiance w.r.t. fields, lengths and background."""
    weights = np.random.default_rng(1).standard_normal((lengths.shape[0], ETA.size))

    def loss(f, s, b):
        return jnp.sum(weights * emission_radiance(tables, f, s, 3, b, sweeps=sweeps))

    with precision(tables.dtype):
        args = (jnp.asarray(a, tables.dtype) for a in (fields, lengths, background))
        return jax.jit(jax.grad(loss, argnums=(0, 1, 2)))(*args)


def assert_same_gradients(xla, ours, rtol):
    """Each gradient within ``rtol`` of the XLA sweep's largest entry."""
    for a, b in zip(xla, ours, strict=True):
        assert np.max(np.abs(a - b)) <= rtol * np.max(np.abs(a))


def scene(dtype, soot, zero_species=(2,)):
    """Seven random rays (two with padding), tables with or without soot (of the three
    species, those in ``zero_species`` do not absorb), a background."""
    fields, lengths = random_rays(n_rays=7, n_seg=9, seed=5)
    if soot:
        fraction = np.random.default_rng(6).uniform(0.0, 5e-6, fields.shape[1:])
        fields = np.concatenate([fields, fraction[None]])
    _, _, sigma = synthetic_sigma(n_eta=ETA.size, zero_species=zero_species)
    tables = RTETables.from_spline(ETA, NODES, PiecewiseCubic(NODES, sigma).coef, 101325.0,
                                   dtype, "table",
                                   soot=rayleigh_soot_constant() if soot else None)
    assert len(tables.species) == 3 - len(zero_species) + soot
    background = np.random.default_rng(2).uniform(0.0, 0.5, (7, ETA.size))
    return tables, fields, lengths, background


CASES = pytest.mark.parametrize("dtype, rtol", [(np.float64, 1e-12), (np.float32, 2e-6)])
SOOT = pytest.mark.parametrize("soot", [False, True])


@CASES
@SOOT
def test_numba_sweep_gives_the_gradients_of_the_xla_sweep(dtype, rtol, soot):
    tables, fields, lengths, background = scene(dtype, soot)
    xla = gradients(tables, fields, lengths, background, "xla")
    ours = gradients(tables, fields, lengths, background, "numba")
    assert_same_gradients(xla, ours, rtol)
    padding = np.arange(lengths.shape[1]) >= np.count_nonzero(lengths, axis=1)[:, None]
    assert padding.any() and not np.any(ours[0][:, padding]) and not np.any(ours[1][padding])
    assert not np.any(xla[1][padding])


@CASES
@SOOT
@pytest.mark.parametrize("with_background", [False, True])
def test_numba_forward_and_forward_mode_sweeps_give_the_xla_values(dtype, rtol, soot,
                                                                   with_background):
    tables, fields, lengths, background = scene(dtype, soot)
    assert_same_values(tables, fields, lengths, background if with_background else None, rtol)


def assert_same_values(tables, fields, lengths, background, rtol):
    """The Numba forward and forward-mode sweeps' radiance and tangent are XLA's."""
    rng = np.random.default_rng(3)
    d_fields = rng.standard_normal(fields.shape) * np.r_[30.0, [0.01] * (fields.shape[0] - 1)][
        :, None, None]
    d_lengths = np.where(lengths > 0, rng.standard_normal(lengths.shape) * 0.01, 0.0)
    results = {}
    for sweeps in SWEEPS:
        with precision(tables.dtype):
            radiance = emission_radiance(tables, fields, lengths, 3, background, sweeps=sweeps)
            value, tangent = emission_radiance_jvp(tables, fields, lengths, d_fields, d_lengths,
                                                   3, background, sweeps=sweeps)
        results[sweeps] = radiance, value, tangent
    xla, ours = results["xla"], results["numba"]
    assert np.abs(xla[0]).max() > 0 and np.abs(xla[2]).max() > 0
    assert_same_gradients(xla, ours, rtol)
    assert_same_gradients(ours[:1], ours[1:2], rtol)  # the JVP's value is the forward's


@CASES
def test_segments_in_one_temperature_interval_are_swept_as_the_xla_sweep_does(dtype, rtol):
    # runs of one, two and three segments in the same interval of NODES (300, 700, 1200,
    # 1800, 2500 K): the forward and forward-mode sweeps take two such segments in one pass,
    # one alone
    tables, fields, lengths, background = scene(dtype, False)
    fields[0] = [400.0, 420.0, 1000.0, 1900.0, 1950.0, 2000.0, 800.0, 810.0, 820.0]
    lengths[:] = lengths[0]  # no padding: every ray has the nine segments
    interval = np.searchsorted(NODES, fields[0][0])
    runs = np.diff(np.flatnonzero(np.diff(np.r_[-1, interval, -1])))
    assert sorted(runs) == [1, 2, 3, 3]
    xla = gradients(tables, fields, lengths, background, "xla")
    assert_same_gradients(xla, gradients(tables, fields, lengths, background, "numba"), rtol)
    assert_same_values(tables, fields, lengths, background, rtol)


@pytest.mark.parametrize("zero_species", [(1, 2), ()], ids=["one gas", "three gases"])
def test_numba_sweeps_written_out_for_one_and_three_gases_give_the_xla_results(zero_species):
    tables, fields, lengths, background = scene(np.float64, True, zero_species)
    xla = gradients(tables, fields, lengths, background, "xla")
    assert_same_gradients(xla, gradients(tables, fields, lengths, background, "numba"), 1e-12)
    assert_same_values(tables, fields, lengths, background, 1e-12)


def test_the_sweeps_source_is_written_once_and_elsewhere_when_the_cache_cannot_be(tmp_path,
                                                                                monkeypatch):
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path))
    path = _source_file("x = 1\n", "probe")
    assert path.parent == tmp_path / "sweeps" and path.read_text() == "x = 1\n"
    written = path.stat().st_mtime_ns
    assert _source_file("x = 1\n", "probe") == path and path.stat().st_mtime_ns == written
    assert _source_file("x = 2\n", "probe") != path  # other source, other file
    blocked = tmp_path / "a file"
    blocked.write_text("")
    monkeypatch.setenv("INVFLAME_CACHE", str(blocked))  # no folder can be made in a file
    assert _source_file("x = 1\n", "probe").parent == (Path(tempfile.gettempdir())
                                                        / "invflame-sweeps")


def test_the_sweeps_refuse_more_than_one_soot_row():
    with pytest.raises(ValueError, match="at most one soot row; got n_gas = 2, n_tau = 4"):
        target("reverse", 2, 4, "float32")


def test_the_sweeps_refuse_an_unknown_kind_or_dtype():
    with pytest.raises(ValueError, match="unknown sweep 'backward'; choose one of"):
        target("backward", 2, 2, "float32")
    with pytest.raises(ValueError, match="run in float32 or float64; got float16"):
        target("reverse", 2, 2, "float16")


def test_float64_stays_float64_with_64_bit_mode_in_the_callers_thread_only():
    """`precision(float64)` turns on JAX's 64-bit mode in the calling thread only; XLA runs the
    Numba sweeps on threads of its own, and nothing may round to float32 on the way."""
    fields, lengths = random_rays(n_rays=7, n_seg=9, seed=5)
    background = np.zeros((7, ETA.size))
    with jax.enable_x64(False), precision(np.float64):
        tables = RTETables.from_spline(ETA, NODES, COEF, 101325.0, np.float64, "table")
        xla = gradients(tables, fields, lengths, background, "xla")
        ours = gradients(tables, fields, lengths, background, "numba")
    assert all(a.dtype == b.dtype == np.float64 for a, b in zip(xla, ours, strict=True))
    assert_same_gradients(xla, ours, 1e-12)


@numba.njit(fastmath=True)
def _compiled_absorptance(x):
    """The sweeps' absorptance over an array, in a loop Numba vectorizes as theirs."""
    a = np.empty_like(x)
    for j in range(x.size):
        a[j] = absorptance(x[j])
    return a


@pytest.mark.parametrize("dtype, ulps", [(np.float32, 4), (np.float64, 2)])
def test_the_absorptance_is_within_a_few_units_in_the_last_place(dtype, ulps):
    x = np.concatenate([np.logspace(-10, 0, 20_001), np.linspace(0, 80, 20_001)]).astype(dtype)
    exact = -np.expm1(-x.astype(np.float64))
    a = _compiled_absorptance(x)
    assert a.dtype == dtype
    inside = x > 0
    assert np.max(np.abs(a[inside] - exact[inside]) / exact[inside]) < ulps * np.finfo(dtype).eps
    assert np.all(a[~inside] == 0)


def test_the_sweeps_default_to_numba_on_a_cpu_and_refuse_unknown_names():
    assert SWEEPS == ("xla", "numba")
    assert choose_sweeps() == ("numba" if jax.default_backend() == "cpu" else "xla")
    assert choose_sweeps("xla") == "xla"
    with pytest.raises(ValueError, match=r"unknown sweeps 'c'; choose one of"):
        choose_sweeps("c")


@pytest.mark.skipif(not X86, reason="the sweeps set the flush on x86 processors only")
def test_sweeps_flush_subnormals_whichever_thread_started_numbas_threads(script_report):
    """Numba's threads inherit the floating-point mode of the thread that starts them: XLA's
    threads flush subnormal numbers to zero, Python's main thread does not. Each sweep flushes
    them itself, as XLA's sweeps do, so that its results do not depend on where Numba's
    threads started, and gives the threads back their mode after."""
    result = script_report(Path(__file__).with_name("subnormal_check.py"))
    for sweep in ("forward", "forward_mode", "reverse"):  # 1e-40 and more kept
        assert result[sweep] == 0.0, (sweep, result[sweep])
    assert result["threads_after"] == pytest.approx(1e-40, rel=1e-3)


def test_sweeps_are_compiled_for_the_processors_widest_vectors(script_report, tmp_path):
    """LLVM tunes Intel's AVX-512 processors to 256-bit vectors; each sweep's loop body asks
    for 512-bit ones, and where the processor has AVX-512 its code uses them."""
    report = script_report(Path(__file__).with_name("vector_width_check.py"),
                           INVFLAME_CACHE=str(tmp_path))
    for sweep in ("forward", "forward_mode", "reverse"):
        assert report[sweep]["attribute"], sweep
        if report["avx512f"]:
            assert report[sweep]["zmm"] > 0, (sweep, report[sweep])
