"""ocio_vp.report.panels: the report's lines for a stage of several panel types."""

from __future__ import annotations

from ocio_vp.pipeline import solve_environment
from ocio_vp.report.panels import panel_facts


def test_each_types_share_and_the_walls_m_comparison(panel_stage_and_measurements):
    _, m = panel_stage_and_measurements
    solution = solve_environment(m, m.environments[0], method="least-squares")
    facts = dict(panel_facts(solution))
    share = round(100 * solution.panels["ceiling"].share)
    assert facts["panel type ceiling"].startswith(f"out of frustum only; {share}% of the light")
    assert "N solved" in facts["panel type wall"]
    assert (
        "with every type driven by wall's M" in facts["lit white vs target, before Q (R / G / B)"]
    )


def test_a_stage_of_one_panel_type_adds_nothing(measurements_dict):
    from ocio_vp.formats.measurements import measurements_from_dict

    m = measurements_from_dict(measurements_dict)
    assert panel_facts(solve_environment(m, m.environments[0])) == []
