"""ocio_vp/commands/simulate.py: the ``ocio-vp simulate`` verb."""

from __future__ import annotations

import yaml

from ocio_vp.cli import main


def test_default_environments_leave_out_a_white_the_leds_cannot_mix(tmp_path, capsys):
    # Sigma's overlapping sensitivities with 620/535/455 nm LEDs: a camera-neutral mix needs
    # negative green, so the paper's seven minus rgb_led_white, with a warning, not a refusal.
    out = tmp_path / "stage.yaml"
    argv = ["simulate", "--out", str(out), "--camera", "Sigma SDMerill (NPL)"]
    assert main([*argv, "--leds", "620/20,535/35,455/22"]) == 0
    written = [e["name"] for e in yaml.safe_load(out.read_text())["environments"]]
    assert written == [
        "warm_white_led",
        "incandescent",
        "indoor_daylight",
        "sodium_vapour",
        "outdoor_shade",
        "direct_sun",
    ]
    err = capsys.readouterr().err
    # the neutral mix's drive (-0.794 green with the wall's peak at the location's white; the
    # default wall is 4x brighter, so a quarter of it)
    assert "warning: rgb_led_white left out" in err and "G -0.199" in err
    # Named, it is refused on one line (exit 2), the file left as it was.
    before = out.read_bytes()
    assert main([*argv, "--leds", "620/20,535/35,455/22", "--environment", "rgb_led_white"]) == 2
    assert capsys.readouterr().err.count("\n") == 1 and out.read_bytes() == before
