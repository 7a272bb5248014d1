"""Configurations written as TOML read back to the same values; one setting read from text."""

import math
import tomllib

import pytest

from invflame.experiments import config
from invflame.experiments.config_text import parse_setting


def test_validated_configuration_round_trips_through_a_file(tmp_path):
    cfg = config.validate({
        "seed": 7,
        "truth": {"grid": 12},
        "regularizer": {"kind": "tv", "lambda": "discrepancy", "lambda_range": [1e-5, 3.5]},
        "solver": {"name": "lbfgs", "iterations": 50,
                   "options": {"rtol_loss": 1e-3, "loss_window": 10}},
        "init": {"kind": "ambient", "ambient": [295.5, 3e-4, 0.01, 0.0]},
    })
    path = tmp_path / "run.toml"
    path.write_text(config.dumps(cfg))
    assert config.load(path) == cfg


def test_every_value_kind_is_written_back_exactly():
    raw = {
        "seed": 3,
        "section": {
            "text": 'quote " backslash \\ tab \t newline \n unicode λ ≈ 0',
            "smallest": 5e-324,
            "largest": 1.7976931348623157e308,
            "third": 1 / 3,
            "negative_zero": -0.0,
            "flag": False,
            "big_integer": 2**62,
            "numbers": [1.5, -2, 0.1],
            "options": {"nested": {"deeper": "x"}, "empty": {}},
        },
    }
    back = tomllib.loads(config.dumps(raw))
    assert back == raw
    assert type(back["section"]["big_integer"]) is int
    assert math.copysign(1.0, back["section"]["negative_zero"]) == -1.0


def test_value_without_a_toml_form_is_refused_with_its_type():
    with pytest.raises(TypeError, match="NoneType"):
        config.dumps({"noise": {"nesr": None}})


def test_a_setting_reads_as_section_key_and_toml_value_or_says_what_is_wrong():
    assert parse_setting("solver.iterations=400") == ("solver", "iterations", 400)
    assert parse_setting('solver.name = "adam"') == ("solver", "name", "adam")
    assert parse_setting("representation.factor_range=[0.5, 2]") == (
        "representation", "factor_range", [0.5, 2])
    for text, problem in (("iterations=400", "SECTION.KEY=VALUE"),
                          ("seed.x=1", "SECTION one of"), ("solver.iterations=", "SECTION"),
                          ("solver.name=adam", "not TOML")):
        with pytest.raises(ValueError, match=problem):
            parse_setting(text)
