"""Lighting environments from HDRIs: the diffuse integral w_avg of an equirect map, and
``prepare-hdri`` (light sources spread under the wall's peak, energy kept).
"""

from ocio_vp.hdri.diffuse import (
    DEFAULT_HDRI_WIDTH,
    FRONT,
    angles_to_directions,
    cosines_to,
    diffuse_integral,
    environments_with_hdri,
    equirect_directions,
    equirect_solid_angles,
    pixel_angles,
    read_equirect,
    w_avg_from_hdri,
)
from ocio_vp.hdri.prepare import (
    PreparedHDRI,
    SpreadSource,
    fit_under_peak,
    label_sources,
    minimum_cap_radius_deg,
    prepare_hdri_file,
    round_down_to,
)

__all__ = [
    "DEFAULT_HDRI_WIDTH",
    "FRONT",
    "PreparedHDRI",
    "SpreadSource",
    "angles_to_directions",
    "cosines_to",
    "diffuse_integral",
    "environments_with_hdri",
    "equirect_directions",
    "equirect_solid_angles",
    "fit_under_peak",
    "label_sources",
    "minimum_cap_radius_deg",
    "pixel_angles",
    "prepare_hdri_file",
    "read_equirect",
    "round_down_to",
    "w_avg_from_hdri",
]
