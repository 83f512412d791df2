"""Deprecated: a non-linear post-correction's config files are built by :mod:`ocio_vp.ocio.bake`
(for every non-linear model, not only the root-polynomial). The module's tuning constants
(``LUT_SIZE``, ``SCALE_RANGE``, ...) and helpers (``baked_transform``, ``content_box``) have no
alias: the bake they tuned was replaced, and :mod:`ocio_vp.ocio.bake` has its own."""

from ocio_vp.deprecation import deprecated_names

__getattr__ = deprecated_names(
    __name__,
    {
        "RootPolynomialOutputs": (
            "ocio_vp.ocio.bake.ModelOutputs",
            "ocio_vp.ocio.bake:ModelOutputs",
        ),
        "root_polynomial_outputs": (
            "ocio_vp.ocio.bake.model_outputs",
            "ocio_vp.ocio.bake:model_outputs",
        ),
    },
)
