"""The neural-field renderer refuses what it does not model (background radiance, soot)."""

import pytest

from invflame.representations.neural.renderer import NeuralRenderer


class _Scene:
    """Only what the renderer reads before it refuses."""

    def __init__(self, background=None, soot=None):
        self.background, self.soot = background, soot


@pytest.mark.parametrize("what", ["background", "soot"])
def test_the_neural_renderer_refuses_a_scene_it_would_render_wrongly(what):
    with pytest.raises(ValueError, match="gas alone"):
        NeuralRenderer(_Scene(**{what: object()}))
