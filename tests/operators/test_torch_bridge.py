"""The torch bridge around a JAX kernel: same values and gradients as JAX itself."""

import jax
import numpy as np
import pytest
import torch
from rte_reference import random_rays, synthetic_sigma

from operators.rte import RTETables, emission_radiance
from operators.tabulated import PiecewiseCubic
from operators.torch_bridge import torch_function

pytestmark = pytest.mark.usefixtures("x64")  # float64 throughout: the kernel called as JAX's


@pytest.fixture(scope="module")
def kernel():
    wavenumber, temperatures, sigma = synthetic_sigma(n_eta=40)
    tables = RTETables.from_spline(wavenumber, temperatures,
                                   PiecewiseCubic(temperatures, sigma).coef, dtype=np.float64)
    return jax.jit(lambda f, s: emission_radiance(tables, f, s, batch_rays=4))


def test_bridged_emission_kernel_matches_jax_in_float64(kernel):
    fields, lengths = random_rays(n_rays=7, n_seg=9)
    cotangent = np.random.default_rng(3).standard_normal((7, 40))
    expected, pullback = jax.vjp(kernel, fields, lengths)
    expected_fields, expected_lengths = pullback(cotangent)

    f = torch.tensor(fields, requires_grad=True)
    s = torch.tensor(lengths, requires_grad=True)
    radiance = torch_function(kernel)(f, s)
    torch.sum(radiance * torch.tensor(cotangent)).backward()

    assert radiance.dtype == torch.float64 and radiance.shape == (7, 40)
    np.testing.assert_allclose(radiance.detach().numpy(), np.asarray(expected), rtol=1e-13)
    np.testing.assert_allclose(f.grad.numpy(), np.asarray(expected_fields), rtol=1e-12,
                               atol=1e-14 * np.abs(expected_fields).max())
    np.testing.assert_allclose(s.grad.numpy(), np.asarray(expected_lengths), rtol=1e-12,
                               atol=1e-14 * np.abs(expected_lengths).max())


def test_bridge_composes_with_torch_autograd(kernel):
    fields, lengths = random_rays(n_rays=7, n_seg=9, seed=2)
    scale = torch.tensor(1.1, dtype=torch.float64, requires_grad=True)
    s = torch.tensor(lengths)

    def total(c):
        return torch.sum(torch_function(kernel)(torch.tensor(fields) * c, s))

    value = total(scale)
    value.backward()
    h = 1e-6
    with torch.no_grad():
        numeric = (total(scale + h) - total(scale - h)) / (2 * h)
    assert scale.grad.item() == pytest.approx(numeric.item(), rel=1e-6)


def test_bridge_rejects_non_tensors(kernel):
    with pytest.raises(TypeError, match="torch tensors"):
        torch_function(kernel)(np.zeros((4, 1, 1)), torch.zeros((1, 1)))
