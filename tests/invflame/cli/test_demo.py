"""The operator demo: its dot-product and Taylor tests pass."""

from invflame.cli import main


def test_demo_passes_its_checks(capsys):
    assert main(["demo", "--seed", "3"]) == 0
    out = capsys.readouterr().out
    assert out.count("PASS") == 4 and "FAIL" not in out
