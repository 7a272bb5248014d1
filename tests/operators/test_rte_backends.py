r"""Every backend of the emission kernel, in every mode and dtype, against the reference.

The backends are the sweeps :func:`operators.rte.choose_sweeps` can pick on a CPU: JAX's
(``"xla"``), with the exact Planck law and with its spline, and Numba's (``"numba"``, which take
the spline only). The modes are the value (:func:`operators.rte.emission_radiance`), the
forward-mode derivative (:func:`operators.rte.emission_radiance_jvp`) and the reverse-mode one
(:func:`jax.vjp` of the value: the cotangents of the fields, the lengths and the background).
Each is compared with the same quantity of the reference formal solution
(:func:`rte_reference.reference_radiance`, float64, differentiated by JAX) on a random small
scene: random segment counts (rays with padding, zero-length segments inside rays), lengths over
three decades (optically thin to thick), temperatures across the tables, mole fractions, gas
alone or gas with soot in front of a background, rays in batches of a random size.

**Tolerance.** The kernel and the reference evaluate the same discrete model (the same
cross-section spline, and for the spline backends the same Planck spline), on the same inputs
rounded to the kernel's dtype, so they differ by the kernel's rounding alone. A radiance or one
of its derivatives is a sum over at most eight segments of products of a few factors, each a
Horner sum of four rounded terms: a few tens of roundings of the dtype's machine epsilon
:math:`\varepsilon`. Every output is held to :data:`ROUNDINGS` :math:`\varepsilon` of its
largest entry (the derivatives cancel in places, so the entries are not compared one by one);
an error of the model itself, a missing term or a wrong derivative, is of the size of the terms.
"""

import zlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from rte_reference import reference_radiance, synthetic_sigma

from operators.base import precision
from operators.rte import (
    SWEEPS,
    RTETables,
    emission_radiance,
    emission_radiance_jvp,
    rayleigh_soot_constant,
)
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)  # two of the three species absorb
COEF = PiecewiseCubic(NODES, SIGMA).coef
P = 101325.0
N_RAYS, N_SEG = 6, 8
ROUNDINGS = 64
"""The tolerance in machine epsilons of the kernel's dtype (module notes)."""

BACKENDS = [(sweeps, planck) for sweeps in SWEEPS for planck in ("exact", "table")
            if not (sweeps == "numba" and planck == "exact")]


def random_scene(rng, dtype, soot: bool, background: bool):
    """Fields ``(4 [+ 1], N_RAYS, N_SEG)`` (T in K, three mole fractions, the soot volume
    fraction), lengths ``(N_RAYS, N_SEG)`` in m and a background ``(N_RAYS, n_eta)`` in
    W/(m²·sr·cm⁻¹) or None, rounded to ``dtype`` (as float64 arrays)."""
    fields = np.concatenate([rng.uniform(310.0, 2490.0, (1, N_RAYS, N_SEG)),
                             rng.uniform(0.0, 0.3, (3, N_RAYS, N_SEG)),
                             rng.uniform(0.0, 1e-5, (int(soot), N_RAYS, N_SEG))])
    lengths = np.exp(rng.uniform(np.log(1e-4), np.log(0.3), (N_RAYS, N_SEG)))
    lengths[rng.random((N_RAYS, N_SEG)) < 0.1] = 0.0  # zero-length segments inside rays
    counts = rng.integers(1, N_SEG + 1, N_RAYS)
    lengths[np.arange(N_SEG) >= counts[:, None]] = 0.0  # padding
    lengths[np.arange(N_RAYS), counts - 1] = np.exp(rng.uniform(np.log(1e-4), np.log(0.3),
                                                                N_RAYS))
    wall = rng.uniform(0.0, 2.0, (N_RAYS, ETA.size)) if background else None
    return tuple(None if a is None else a.astype(dtype).astype(np.float64)
                 for a in (fields, lengths, wall))


def assert_matches(ours, reference, dtype, what):
    """``ours`` within :data:`ROUNDINGS` machine epsilons of ``reference``'s largest entry."""
    ours, reference = np.asarray(ours, np.float64), np.asarray(reference, np.float64)
    assert ours.shape == reference.shape, what
    scale = np.max(np.abs(reference))
    assert scale > 0, what
    error = np.max(np.abs(ours - reference)) / scale
    assert error <= ROUNDINGS * np.finfo(dtype).eps, (
        f"{what}: {error:.3g} of the largest entry, {error / np.finfo(dtype).eps:.1f} eps")


def directions(rng, mode, fields, lengths, dtype):
    """For ``"jvp"``, tangents of the fields (K, then fractions) and of the lengths (m; none
    where a length is zero, padding included); for ``"vjp"``, a cotangent of the radiance; none
    for ``"forward"``; rounded to ``dtype`` (as float64 arrays)."""
    if mode == "jvp":
        scale = np.array([30.0, 0.05, 0.05, 0.05, 1e-6])[:fields.shape[0], None, None]
        d_lengths = np.where(lengths > 0, rng.standard_normal(lengths.shape) * lengths, 0.0)
        found = (rng.standard_normal(fields.shape) * scale, d_lengths)
    elif mode == "vjp":
        found = (rng.standard_normal((N_RAYS, ETA.size)),)
    else:
        found = ()
    return tuple(a.astype(dtype).astype(np.float64) for a in found)


@pytest.mark.parametrize(("soot", "with_background"), [(False, False), (True, True)],
                         ids=["gas", "gas and soot before a background"])
@pytest.mark.parametrize("mode", ["forward", "jvp", "vjp"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64], ids=["float32", "float64"])
@pytest.mark.parametrize("sweeps, planck_mode", BACKENDS, ids=[f"{s}-{p}" for s, p in BACKENDS])
def test_every_backend_matches_the_reference(sweeps, planck_mode, dtype, mode, soot,
                                             with_background):
    if sweeps == "numba" and jax.default_backend() != "cpu":
        pytest.skip("the Numba sweeps run on CPUs")
    case = f"{sweeps} {planck_mode} {np.dtype(dtype)} {mode} {soot} {with_background}"
    rng = np.random.default_rng(zlib.crc32(case.encode()))
    scene = [a for a in random_scene(rng, dtype, soot, with_background) if a is not None]
    given = directions(rng, mode, *scene[:2], dtype)
    batch_rays = int(rng.integers(1, N_RAYS + 3))  # the last batch padded with rays, or not
    soot_constant = rayleigh_soot_constant() if soot else None
    tables = RTETables.from_spline(ETA, NODES, COEF, P, dtype, planck_mode, soot=soot_constant)

    def reference(f, s, *background):
        return reference_radiance(ETA, NODES, SIGMA, f, s, P, *background, soot=soot_constant,
                                  planck_mode=planck_mode)

    with precision(np.float64):
        args = [jnp.asarray(a) for a in scene]
        if mode == "forward":
            expected = (reference(*args),)
        elif mode == "jvp":  # the background held fixed
            expected = jax.jvp(lambda f, s: reference(f, s, *args[2:]), tuple(args[:2]),
                               tuple(jnp.asarray(d) for d in given))
        else:
            expected = jax.vjp(reference, *args)[1](jnp.asarray(given[0]))
    with precision(dtype):
        args = [jnp.asarray(a, dtype) for a in scene]
        background = args[2] if with_background else None
        if mode == "forward":
            got = (emission_radiance(tables, *args[:2], batch_rays, background, sweeps=sweeps),)
        elif mode == "jvp":
            got = emission_radiance_jvp(tables, *args[:2], *given, batch_rays, background,
                                        sweeps=sweeps)
        else:
            def ours(f, s, *background):
                return emission_radiance(tables, f, s, batch_rays, *background, sweeps=sweeps)

            got = jax.vjp(ours, *args)[1](jnp.asarray(given[0], dtype))
    names = {"forward": ["radiance"], "jvp": ["radiance", "tangent"],
             "vjp": ["cotangent of the fields", "of the lengths", "of the background"]}[mode]
    for mine, theirs, what in zip(got, expected, names, strict=False):
        assert_matches(mine, theirs, dtype, what)
    assert len(got) == len(expected)
