"""The neural renderer in front of a background and with known soot, against the voxel map."""

import numpy as np
import pytest
import torch

import operators
from invflame.background import MeasuredBackground
from invflame.representations.neural import NeuralFieldRepresentation, NeuralRenderer
from invflame.representations.neural.renderer import voxel_lookup
from operators.rte.planck import planck


def _per_camera_background(n_cameras: int = 2) -> MeasuredBackground:
    """A different grey-body spectrum behind each camera, W/(m2 sr cm-1)."""
    wavenumber = np.linspace(640.0, 740.0, 51)
    spectra = [e * planck(wavenumber, t) for e, t in zip((0.9, 0.5), (800.0, 450.0),
                                                          strict=True)]
    return MeasuredBackground(wavenumber, np.array(spectra[:n_cameras]))


@pytest.fixture(scope="module")
def dressed64(pixel_scene64, plume):
    """The 4-sub-ray float64 scene in front of a per-camera background, with soot where the
    plume is hot."""
    soot = 2e-6 * (plume[0] - plume[0].min()) / np.ptp(plume[0])
    return pixel_scene64.with_background(_per_camera_background()).with_soot(soot)


def test_a_uniform_medium_renders_as_the_voxel_map_with_background_and_soot(dressed64):
    """In a uniform medium the samples' lengths add up to the voxels' along every sub-ray, so
    the rendering equals the voxel map to round-off: background through the transmittance,
    soot as a fifth field, each camera's own background."""
    scene = dressed64.with_soot(np.full(dressed64.grid.shape, 1e-6))
    values = (1200.0, 0.08, 0.1, 0.01)
    uniform = np.stack([np.full(scene.grid.shape, v) for v in values])

    def field(points):
        return torch.stack([torch.full(points.shape[:-1], v, dtype=torch.float64)
                            for v in values])

    renderer = NeuralRenderer(scene, n_coarse=8, n_fine=4)
    coarse, fine = renderer.render(torch.arange(renderer.n_rays), field, field,
                                   *renderer.deterministic_draws())
    expected = scene.simulate(uniform)
    np.testing.assert_allclose(coarse.numpy(), expected, rtol=1e-10)
    np.testing.assert_allclose(fine.numpy(), expected, rtol=1e-10)
    without = NeuralRenderer(dressed64.with_background(None).with_soot(None), n_coarse=8,
                             n_fine=4)
    bare = without.render(torch.arange(without.n_rays), field, field,
                          *without.deterministic_draws())[1].numpy()
    assert np.all(np.abs(fine.numpy() - bare) > 1e-3 * np.abs(bare))  # the test can fail


def test_rendering_with_background_and_soot_converges_to_the_voxel_map(dressed64, plume):
    """Sampled finely, a voxel field with soot varying per voxel, in front of a background,
    renders as the voxel map does."""
    expected = dressed64.simulate(plume)
    field = voxel_lookup(dressed64.grid, plume)
    renderer = NeuralRenderer(dressed64, n_coarse=256, n_fine=256)
    _, fine = renderer.render(torch.arange(renderer.n_rays), field, field,
                              *renderer.deterministic_draws())
    assert np.abs(fine.numpy() - expected).max() < 0.01 * np.abs(expected).max()
    gas_only = dressed64.with_background(None).with_soot(None).simulate(plume)
    assert np.abs(gas_only - expected).max() > 0.05 * np.abs(expected).max()


def test_the_forward_operator_has_consistent_derivatives_with_background_and_soot(
        dressed64, plume):
    rep = NeuralFieldRepresentation(dressed64, n_coarse=8, n_fine=8, batch_rays=36,
                                    batch_centres=64)
    theta = rep.initial_parameters(plume, iterations=20, lr=3e-3, progress=False)
    forward = rep.problem(dressed64.simulate(plume), "tikhonov", x0=theta).forward
    assert operators.jacobian_dottest(forward, theta, rtol=1e-9).passed


def test_soot_as_an_unknown_is_refused_with_what_to_do(tiny_scene):
    with pytest.raises(ValueError, match=r"cannot reconstruct soot: use representation.kind "
                                         r"= 'voxel'.*known soot field"):
        NeuralRenderer(tiny_scene.with_soot(None, soot_input=True))
